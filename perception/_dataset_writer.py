"""Taps appended one at a time to a tap dataset file, resuming it (`perception.dataset`)."""

from __future__ import annotations

import contextlib
import json
import pathlib

import numpy as np

from _shared import atomic_path, write_error

from ._dataset_checks import _ARRAYS, COUNT_ATTRIBUTE, SCHEMA, _check_arrays, _check_schema, _complete_count
from ._dataset_container import Dataset
from ._dataset_file import _open_hdf5, _read_attributes, _text, _write_attributes
from .errors import DatasetError

__all__ = ["DatasetWriter"]


class DatasetWriter:
    """Append taps one at a time to a dataset file, resuming it if it exists.

    Each `append` writes the tap straight to the file (no chunk cache, one chunk per tap, so a
    write error surfaces at once), flushes it, and only then counts it in the ``complete_taps``
    attribute (flushed again): a tap whose data did not reach the disk (disk full, crash, Ctrl-C)
    is never counted, and a resumed file keeps only the counted taps. Opening an existing file
    checks that its schema, tap shape, front end, units, dim names, sensor description and
    protocol match.

    Parameters
    ----------
    path : str or os.PathLike
        Dataset file, created if missing.
    samples, dims : int
        Shape ``(samples, dims)`` of every tap.
    front_end : {"tactip", "taxel"}
    location_unit, identity_unit : str
    dim_names : sequence of str
        One name per dimension; empty generates ``("dim00", ...)``.
    sensor : dict or None
        JSON-serialisable sensor description.
    protocol : dict or None
        JSON-serialisable description of the collection protocol (seed, depths, repeats, ...):
        stored in a new file; a resumed file must hold the same (the message names the setting).

    Raises
    ------
    DatasetError
        The existing file does not match (the message names the field).
    OSError
        Disk full or permission denied, named so (the taps stored before stay intact).

    Examples
    --------
    >>> with DatasetWriter("train.h5", samples=40, dims=80, front_end="tactip") as writer:  # doctest: +SKIP
    ...     writer.append(tap, location=1.5, identity=0.25)
    """

    def __init__(self, path, *, samples: int, dims: int, front_end: str, location_unit: str = "mm",
                 identity_unit: str = "mm", dim_names=(), sensor: dict | None = None, protocol: dict | None = None):
        import h5py

        # Validate every knob through the Dataset contract (an empty dataset of this shape).
        template = Dataset(np.zeros((0, int(samples), int(dims)), np.float32), np.zeros(0), np.zeros(0), None,
                           front_end, location_unit, identity_unit, tuple(dim_names), sensor or {})
        try:
            protocol_text = None if protocol is None else json.dumps(protocol, sort_keys=True)
        except (TypeError, ValueError) as exc:
            raise DatasetError(f"protocol must be a JSON-serialisable dict: {exc}") from None
        self.path = pathlib.Path(path)
        self._shape = (template.samples, template.dims)
        self._file = None
        self._count = 0
        if not self.path.exists():
            # Made under a temporary name and renamed: a crash here leaves no half-made file to refuse.
            with atomic_path(self.path) as tmp:
                with h5py.File(tmp, "w") as f:
                    _write_attributes(f, template.front_end, template.location_unit, template.identity_unit,
                                      template.dim_names, template.sensor)
                    if protocol_text is not None:
                        f.attrs["protocol"] = protocol_text
                    f.create_dataset("taps", shape=(0, *self._shape), dtype=np.float32, chunks=(1, *self._shape),
                                     maxshape=(None, *self._shape))
                    for name in ("location", "identity"):
                        f.create_dataset(name, shape=(0,), dtype=np.float64, chunks=(1024,), maxshape=(None,))
                    f.attrs[COUNT_ATTRIBUTE] = 0
        # No chunk cache: every write goes to the file at once, so its error is raised by that write.
        self._file = _open_hdf5(self.path, "r+", rdcc_nbytes=0)
        try:
            self._check_resume(template, protocol)
            self._arrays = {name: self._file[name] for name in (*_ARRAYS, "lateral") if name in self._file}
        except BaseException:
            self._file.close()
            raise

    def _check_resume(self, template: Dataset, protocol: dict | None) -> None:
        f = self._file
        _check_schema(f, self.path)
        missing = [name for name in _ARRAYS if name not in f]
        if missing:
            raise DatasetError(f"{self.path} misses {', '.join(missing)} (required by {SCHEMA})")
        _check_arrays(f, self.path)
        stored = _read_attributes(f, self.path)
        shape = f["taps"].shape[1:]
        if shape != self._shape:
            raise DatasetError(f"{self.path} holds taps of (samples, dims) {shape}, not {self._shape}")
        for name, value in stored.items():
            if value != getattr(template, name):
                raise DatasetError(f"{self.path} has {name} {value!r}, not {getattr(template, name)!r}")
        if protocol is not None and "protocol" in f.attrs:
            try:
                old = json.loads(_text(f.attrs["protocol"]))
            except ValueError:
                raise DatasetError(f"{self.path}: protocol attribute is not JSON") from None
            new = json.loads(json.dumps(protocol, sort_keys=True))
            differ = sorted(k for k in set(old) | set(new) if old.get(k) != new.get(k))
            if differ:
                k = differ[0]
                raise DatasetError(f"{self.path} was collected with protocol {k} = {old.get(k)!r}, not "
                                   f"{new.get(k)!r}: resuming would mix two collections (restore the setting, "
                                   f"or collect into another folder)")
        # An interrupted append may have grown some arrays and not others, or grown them without
        # its data reaching the disk: keep the complete taps only.
        names = [name for name in (*_ARRAYS, "lateral") if name in f]
        count = min(f[name].shape[0] for name in names)
        complete = _complete_count(f)
        if complete is not None:
            count = min(count, complete)
        try:
            for name in names:
                if f[name].shape[0] != count:
                    f[name].resize(count, axis=0)
            if complete is None or complete != count:
                f.attrs[COUNT_ATTRIBUTE] = count
            f.flush()
        except OSError as exc:
            raise write_error(exc, self.path) from None
        self._count = int(count)

    @property
    def count(self) -> int:
        """Number of complete taps stored."""
        return self._count

    def labels(self) -> dict[str, np.ndarray]:
        """The labels of the complete taps: ``location``, ``identity`` and (if stored) ``lateral``, (count,) each."""
        return {name: self._arrays[name][:self._count] for name in ("location", "identity", "lateral")
                if name in self._arrays}

    def append(self, tap, location: float, identity: float, lateral: float | None = None) -> None:
        """Store one tap with its labels, flush it to disk, then count it.

        Parameters
        ----------
        tap : (samples, dims) array
            Sensor values of the tap; NaN where missing.
        location, identity : float
            Labels in the dataset's units.
        lateral : float or None
            Lateral offset in mm; give it for every tap of a file or for none.

        Raises
        ------
        DatasetError
            Wrong tap shape, infinite values or no observed value, labels not finite, or `lateral`
            given for some taps only.
        OSError
            Disk full or permission denied, named so. The tap is not counted and the writer is
            closed; the taps before it stay intact and a rerun resumes after them.
        """
        if self._file is None or not self._file.id.valid:
            raise DatasetError(f"{self.path}: the writer is closed")
        tap = np.asarray(tap, dtype=np.float32)
        if tap.shape != self._shape:
            raise DatasetError(f"tap must have shape (samples, dims) {self._shape}, got {tap.shape}")
        if np.isinf(tap).any():
            raise DatasetError("tap holds infinite values")
        if np.isnan(tap).all():
            raise DatasetError("tap has no observed value (all NaN)")
        labels = {"location": location, "identity": identity}
        if lateral is not None:
            labels["lateral"] = lateral
        for name, value in labels.items():
            if not np.isfinite(value):
                raise DatasetError(f"{name} must be finite, got {value}")
        f = self._file
        n = self.count
        if lateral is not None and "lateral" not in self._arrays:
            if n:
                raise DatasetError(f"lateral given for tap {n} but not for the {n} taps before it")
        elif lateral is None and "lateral" in self._arrays:
            raise DatasetError(f"lateral missing for tap {n}; the file has lateral for every tap")
        try:
            if lateral is not None and "lateral" not in self._arrays:
                self._arrays["lateral"] = f.create_dataset("lateral", shape=(0,), dtype=np.float64, chunks=(1024,),
                                                           maxshape=(None,))
            arrays = self._arrays
            arrays["taps"].resize(n + 1, axis=0)
            arrays["taps"][n] = tap
            for name, value in labels.items():
                arrays[name].resize(n + 1, axis=0)
                arrays[name][n] = float(value)
            f.flush()
            # P(tap n complete) only once its data is on the disk.
            f.attrs[COUNT_ATTRIBUTE] = n + 1
            f.flush()
            self._count = n + 1
        except OSError as exc:
            error = write_error(exc, self.path)
            with contextlib.suppress(OSError, RuntimeError):  # the file is closed; the first error is the one
                self.close()
            raise error from None

    def close(self) -> None:
        """Flush and close the file (idempotent; a write error at close is named, the counted taps stay)."""
        if self._file is None or not self._file.id.valid:
            return
        self._arrays = {}
        try:
            self._file.close()
        except (OSError, RuntimeError) as exc:  # h5py reports a failed flush at close as a RuntimeError
            raise write_error(exc, self.path) from None

    def __enter__(self) -> DatasetWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        count = self._count if self._file is not None and self._file.id.valid else "closed"
        return f"DatasetWriter({str(self.path)!r}, samples={self._shape[0]}, dims={self._shape[1]}, count={count})"
