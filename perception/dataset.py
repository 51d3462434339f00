"""The tap dataset: the contract between front ends, calibration and perception.

A dataset is a set of taps, each a ``(samples, dims)`` time series of sensor values, labelled
with the location (e.g. depth in mm) and identity (e.g. gap width in mm) it was collected at.
On disk it is one HDF5 file of schema ``tactip-dataset/1``:

==============  ==========================  ============================================
name            kind                        content
==============  ==========================  ============================================
``taps``        float32 (N, samples, dims)  sensor values of each tap; NaN where missing
``location``    float64 (N,)                location of each tap (``location_unit``)
``identity``    float64 (N,)                identity of each tap (``identity_unit``)
``lateral``     float64 (N,), optional      lateral placement offset of each tap, mm
``schema``      attribute                   ``"tactip-dataset/1"``
``front_end``   attribute                   ``"tactip"`` (pin displacements) or ``"taxel"``
``location_unit``, ``identity_unit``        attributes, e.g. ``"mm"`` (``"none"`` for a constant)
``dim_names``   attribute, list of str      one name per dimension (``"pin03_x"``, ``"taxel07"``)
``sensor``      attribute, JSON string      sensor description (kind, pins or taxels, preset, ...)
``identity_period``  attribute, optional    period of a circular identity (e.g. 360 for an angle in deg)
``identity_names``   attribute, optional    class names of a named identity (its values are indices 0..K-1)
==============  ==========================  ============================================

A missing value is NaN: a TacTip tap holds NaN in the dx and dy dimensions of a feature pin unseen
for the whole tap (`tactip.pipeline.contact_features`); every likelihood model marginalises such
dimensions (`perception.likelihood`). Labels are never missing, no value is infinite, and every tap
has at least one observed value.

`save_dataset` writes a whole dataset atomically; `DatasetWriter` appends taps one at a time
(flushing each, so a crash loses at most the tap in progress) and resumes an existing file.

Example
-------
>>> import numpy as np
>>> taps = np.zeros((2, 40, 80), np.float32)
>>> ds = Dataset(taps, np.array([0.0, 0.5]), np.array([1.0, 1.0]), None, "tactip")
>>> ds.dims, ds.samples, ds.dim_names[0]
(80, 40, 'dim00')
"""

from __future__ import annotations

import contextlib
import json
import os
import pathlib
import re
from dataclasses import dataclass, field

import numpy as np

from _shared import atomic_path, hdf5_in_memory, write_error

from .errors import DatasetError

__all__ = ["SCHEMA", "FRONT_ENDS", "Dataset", "save_dataset", "load_dataset", "DatasetWriter", "check_identity_labels"]

SCHEMA = "tactip-dataset/1"
FRONT_ENDS = ("tactip", "taxel")
_ARRAYS = ("taps", "location", "identity")
#: Attribute holding how many taps are complete: written (and flushed) after each tap's data, so a
#: tap whose data never reached the disk (full disk, crash) is not counted, and never read back.
COUNT_ATTRIBUTE = "complete_taps"


@dataclass(frozen=True)
class Dataset:
    """Labelled taps of one front end, validated on construction.

    Parameters
    ----------
    taps : (N, samples, dims) array, converted to float32
        Sensor values of each tap (pin displacements in px, or taxel readings); NaN where missing
        (e.g. the dimensions of a pin unseen during the tap).
    location : (N,) array, converted to float64
        Location of each tap in ``location_unit`` (e.g. depth in mm).
    identity : (N,) array, converted to float64
        Identity of each tap in ``identity_unit`` (e.g. gap width in mm).
    lateral : (N,) array or None
        Lateral placement offset of each tap in mm (paper 002, Fig. 11), or None.
    front_end : {"tactip", "taxel"}
        The sensor front end that produced the taps.
    location_unit, identity_unit : str
        Units of `location` and `identity` (``"none"`` for a constant identity).
    dim_names : tuple of str
        One name per dimension; empty generates ``("dim00", "dim01", ...)``.
    sensor : dict
        JSON-serialisable sensor description (kind, pins or taxels, preset, ...).
    identity_period : float or None
        Period of a circular identity in ``identity_unit`` (e.g. 360 for a slide direction in deg):
        errors between identities wrap (315 and 0 deg are 45 deg apart). None: not circular.
    identity_names : tuple of str
        Names of a named identity (e.g. shapes): identity k is class ``identity_names[k]``, and
        errors between names are only right or wrong. Empty: the identity is a number.

    Raises
    ------
    DatasetError
        Naming the field: wrong shapes, NaN or infinite labels, infinite tap values, a tap with no
        observed value, unknown front end, wrong number of dim names, a sensor description that is not JSON.
    """

    taps: np.ndarray
    location: np.ndarray
    identity: np.ndarray
    lateral: np.ndarray | None
    front_end: str
    location_unit: str = "mm"
    identity_unit: str = "mm"
    dim_names: tuple[str, ...] = ()
    sensor: dict = field(default_factory=dict)
    identity_period: float | None = None
    identity_names: tuple[str, ...] = ()

    def __post_init__(self):
        taps = np.asarray(self.taps, dtype=np.float32)
        if taps.ndim != 3 or taps.shape[1] < 1 or taps.shape[2] < 1:
            raise DatasetError(f"taps must have shape (N, samples, dims) with samples, dims >= 1, got {taps.shape}")
        n = taps.shape[0]
        arrays = {"taps": taps}
        for name in ("location", "identity", "lateral"):
            value = getattr(self, name)
            if value is None and name == "lateral":
                continue
            value = np.asarray(value, dtype=np.float64)
            if value.shape != (n,):
                raise DatasetError(f"{name} must have shape ({n},) to match taps {taps.shape}, got {value.shape}")
            arrays[name] = value
        for name, value in arrays.items():
            bad = np.isinf(value) if name == "taps" else ~np.isfinite(value)
            if bad.any():
                first = int(np.argwhere(bad)[0][0])
                kind = "infinite values" if name == "taps" else "NaN or infinite values"
                raise DatasetError(f"{name} holds {kind} (first in tap {first})")
        _check_observed(taps)
        if self.front_end not in FRONT_ENDS:
            raise DatasetError(f"front_end must be one of {FRONT_ENDS}, got {self.front_end!r}")
        dims = taps.shape[2]
        names = tuple(str(n) for n in self.dim_names) or tuple(f"dim{k:02d}" for k in range(dims))
        if len(names) != dims:
            raise DatasetError(f"dim_names has {len(names)} names for {dims} dims")
        try:
            sensor = json.loads(json.dumps(dict(self.sensor or {})))
        except (TypeError, ValueError) as exc:
            raise DatasetError(f"sensor must be a JSON-serialisable dict: {exc}") from None
        for name, value in arrays.items():
            object.__setattr__(self, name, value)
        object.__setattr__(self, "dim_names", names)
        object.__setattr__(self, "sensor", sensor)
        period, labels = check_identity_labels(self.identity_period, self.identity_names, arrays["identity"])
        object.__setattr__(self, "identity_period", period)
        object.__setattr__(self, "identity_names", labels)

    def __repr__(self) -> str:
        return f"<Dataset {self.describe()}>"

    def __len__(self) -> int:
        """Number of taps N."""
        return self.taps.shape[0]

    @property
    def samples(self) -> int:
        """Time samples per tap."""
        return self.taps.shape[1]

    @property
    def observed(self) -> np.ndarray:
        """(N, samples, dims) bool: the values that are not missing (not NaN)."""
        return ~np.isnan(self.taps)

    @property
    def complete(self) -> bool:
        """Whether no value of any tap is missing."""
        return not np.isnan(self.taps).any()

    @property
    def dims(self) -> int:
        """Data dimensions per sample (2 per pin for the TacTip, 1 per taxel)."""
        return self.taps.shape[2]

    def subset(self, index) -> Dataset:
        """The dataset restricted to some taps.

        Parameters
        ----------
        index : (N,) bool array or int array
            Which taps to keep (a mask, or tap indices).
        """
        index = np.asarray(index)
        lateral = None if self.lateral is None else self.lateral[index]
        return Dataset(self.taps[index], self.location[index], self.identity[index], lateral, self.front_end,
                       self.location_unit, self.identity_unit, self.dim_names, self.sensor, self.identity_period,
                       self.identity_names)

    def describe(self) -> str:
        """One line: front end, taps, samples x dims, location and identity ranges."""
        def span(values, unit):
            if len(values) == 0:
                return "-"
            return f"{values.min():g}..{values.max():g} {unit} ({len(np.unique(values))} values)"
        incomplete = int(np.isnan(self.taps).any(axis=(1, 2)).sum())
        missing = f" ({incomplete} with missing dims)" if incomplete else ""
        return (f"{self.front_end} dataset: {len(self)} taps of {self.samples} samples x {self.dims} dims{missing}; "
                f"location {span(self.location, self.location_unit)}; identity {span(self.identity, self.identity_unit)}")


def check_identity_labels(period, names, identity=None) -> tuple[float | None, tuple[str, ...]]:
    """The checked ``(identity_period, identity_names)`` of a dataset or model.

    Parameters
    ----------
    period : float or None
        Finite and > 0, or None.
    names : sequence of str
        Distinct non-empty names; with names, every identity must be an index 0..len(names)-1.
    identity : array, optional
        The identities to check against the names.

    Raises
    ------
    DatasetError
        Naming what is wrong.
    """
    if period is not None:
        try:
            period = float(period)
        except (TypeError, ValueError):
            raise DatasetError(f"identity_period must be a number > 0 or None, got {period!r}") from None
        if not (np.isfinite(period) and period > 0):
            raise DatasetError(f"identity_period must be a finite number > 0 or None, got {period!r}")
    names = tuple(str(n) for n in (names or ()))
    if names:
        if period is not None:
            raise DatasetError("a named identity has no period: give identity_names or identity_period, not both")
        if len(set(names)) != len(names) or not all(names):
            raise DatasetError(f"identity_names must be distinct and non-empty, got {list(names)[:10]}")
        if identity is not None and len(identity):
            bad = (identity != np.round(identity)) | (identity < 0) | (identity >= len(names))
            if bad.any():
                raise DatasetError(f"a named identity holds class indices 0..{len(names) - 1}, got "
                                   f"{identity[bad][0]:g} (tap {int(np.argmax(bad))})")
    return period, names


def _check_observed(taps: np.ndarray) -> None:
    """Raise DatasetError for a tap without a single observed value (nothing to classify it by)."""
    if taps.size == 0:
        return
    empty = np.isnan(taps).all(axis=(1, 2))
    if empty.any():
        raise DatasetError(f"taps holds {int(empty.sum())} tap(s) with no observed value (all NaN; first: tap "
                           f"{int(np.argmax(empty))}); leave such taps out")


def save_dataset(path, dataset: Dataset, *, inputs=()) -> None:
    """Write a dataset to an HDF5 file atomically (temporary file, fsync, then rename).

    Parameters
    ----------
    path : str or os.PathLike
        Destination file; replaced if it exists.
    dataset : Dataset
        The taps and their labels.
    inputs : iterable of path
        Files the caller read: ``path`` must not be one of them.

    Raises
    ------
    OSError
        Disk full or permission denied (named so); ``path`` keeps its old content.
    FileExistsError
        ``path`` is one of ``inputs``.
    """
    if not isinstance(dataset, Dataset):
        raise DatasetError(f"dataset must be a Dataset, got {type(dataset).__name__}")
    path = pathlib.Path(path)
    with atomic_path(path, inputs=inputs) as tmp:
        with hdf5_in_memory(tmp) as f:  # a full disk is an OSError, not a crash inside HDF5
            _write_attributes(f, dataset.front_end, dataset.location_unit, dataset.identity_unit,
                              dataset.dim_names, dataset.sensor, dataset.identity_period, dataset.identity_names)
            f.create_dataset("taps", data=dataset.taps, chunks=_taps_chunks(dataset.samples, dataset.dims),
                             maxshape=(None, dataset.samples, dataset.dims))
            for name in ("location", "identity", "lateral"):
                value = getattr(dataset, name)
                if value is not None:
                    f.create_dataset(name, data=value, chunks=(1024,), maxshape=(None,))
            f.attrs[COUNT_ATTRIBUTE] = len(dataset)


def load_dataset(path) -> Dataset:
    """Read a ``tactip-dataset/1`` HDF5 file.

    Parameters
    ----------
    path : str or os.PathLike
        The dataset file.

    Returns
    -------
    Dataset

    Raises
    ------
    DatasetError
        The file is not HDF5, has another schema, misses a field, or holds mismatched shapes or NaNs.
    FileNotFoundError
        No such file.
    PermissionError
        The file cannot be read.

    Notes
    -----
    Only the complete taps are read: those counted by the ``complete_taps`` attribute that
    `DatasetWriter` updates after each tap's data reached the disk.
    """
    path = pathlib.Path(path)
    f = _open_hdf5(path, "r")
    with f:
        _check_schema(f, path)
        missing = [name for name in _ARRAYS if name not in f]
        missing += [name for name in ("front_end", "location_unit", "identity_unit", "dim_names", "sensor")
                    if name not in f.attrs]
        if missing:
            raise DatasetError(f"{path} misses {', '.join(missing)} (required by {SCHEMA})")
        _check_arrays(f, path)
        lengths = {name: f[name].shape[0] for name in (*_ARRAYS, "lateral") if name in f}
        complete = _complete_count(f)
        short = len(set(lengths.values())) > 1 if complete is None else min(lengths.values()) < complete
        if short:
            raise DatasetError(f"{path} has mismatched lengths: " + ", ".join(f"{k} {v}" for k, v in lengths.items()))
        n = min(lengths.values()) if complete is None else min(complete, *lengths.values())
        arrays = {name: f[name][:n] for name in (*_ARRAYS, "lateral") if name in f}
        attrs = _read_attributes(f, path)
    try:
        return Dataset(arrays["taps"], arrays["location"], arrays["identity"], arrays.get("lateral"), **attrs)
    except DatasetError as exc:
        raise DatasetError(f"{path}: {exc}") from None


def _open_hdf5(path: pathlib.Path, mode: str, **kwargs):
    """``h5py.File(path, mode)`` with errors that say what is wrong (missing, permission, not HDF5)."""
    import h5py

    if not path.exists():
        raise FileNotFoundError(f"no such dataset file: {path}")
    if path.is_dir():
        raise DatasetError(f"{path} is a folder, not a dataset file")
    wanted = os.R_OK | (os.W_OK if mode != "r" else 0)
    if not os.access(path, wanted):
        doing = "reading" if mode == "r" else "writing"
        raise PermissionError(13, f"permission denied {doing} {str(path)!r}")
    try:
        return h5py.File(path, mode, **kwargs)
    except OSError as exc:
        text = str(exc).lower()
        cut = re.search(r"truncated file: eof = (\d+).*stored_eof = (\d+)", text)
        if cut and int(cut.group(2)) > int(cut.group(1)):
            if mode == "r":
                raise DatasetError(f"{path} was cut short by a failed write (disk full or a file size limit): "
                                   f"rerun the collection to repair it and resume") from None
            # A write that failed for lack of space left the file shorter than its header says: give it
            # back its length (zeros); the taps counted before the failure were on the disk already.
            try:
                os.truncate(path, int(cut.group(2)))
                return h5py.File(path, mode, **kwargs)
            except OSError as again:
                raise write_error(again, path) from None
        if "permission denied" in text or "errno = 13" in text:
            raise PermissionError(13, f"permission denied opening {str(path)!r}") from None
        if "unable to lock" in text or "resource temporarily unavailable" in text:
            raise DatasetError(f"{path} is open in another process (a collection still running into it?)") from None
        raise DatasetError(f"{path} is not an HDF5 file") from None


def _check_arrays(f, path) -> None:
    """Each array of the schema holds numbers (not bytes, strings or records) and has the right rank."""
    for name, rank in (("taps", 3), ("location", 1), ("identity", 1), ("lateral", 1)):
        if name not in f:
            continue
        node = f[name]
        if not hasattr(node, "dtype"):
            raise DatasetError(f"{path}: {name!r} is a group, not a dataset of numbers")
        if node.dtype.kind not in "fiu":
            raise DatasetError(f"{path}: dataset {name!r} holds {node.dtype} values, not numbers "
                               f"(required by {SCHEMA})")
        if node.ndim != rank:
            raise DatasetError(f"{path}: dataset {name!r} has {node.ndim} dimensions, not {rank}")


def _complete_count(f) -> int | None:
    """The complete-tap count attribute, or None for files written before it existed."""
    if COUNT_ATTRIBUTE not in f.attrs:
        return None
    value = f.attrs[COUNT_ATTRIBUTE]
    try:
        count = int(value)
    except (TypeError, ValueError):
        raise DatasetError(f"{f.filename}: attribute {COUNT_ATTRIBUTE} is {value!r}, not a count") from None
    if count < 0:
        raise DatasetError(f"{f.filename}: attribute {COUNT_ATTRIBUTE} is negative ({count})")
    return count


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


def _taps_chunks(samples: int, dims: int) -> tuple[int, int, int]:
    # About 256 kB per chunk, at least one tap.
    return (max(1, min(64, 65536 // max(1, samples * dims))), samples, dims)


def _write_attributes(f, front_end, location_unit, identity_unit, dim_names, sensor, identity_period=None,
                      identity_names=()) -> None:
    f.attrs["schema"] = SCHEMA
    f.attrs["front_end"] = front_end
    f.attrs["location_unit"] = location_unit
    f.attrs["identity_unit"] = identity_unit
    f.attrs["dim_names"] = list(dim_names)
    f.attrs["sensor"] = json.dumps(sensor, sort_keys=True)
    if identity_period is not None:
        f.attrs["identity_period"] = float(identity_period)
    if identity_names:
        f.attrs["identity_names"] = list(identity_names)


def _check_schema(f, path) -> None:
    schema = f.attrs.get("schema")
    if isinstance(schema, bytes):
        schema = schema.decode()
    if schema != SCHEMA:
        raise DatasetError(f"{path} is not a {SCHEMA} file (schema {schema!r})")


def _text(value) -> str:
    return value.decode() if isinstance(value, bytes) else str(value)


def _read_attributes(f, path) -> dict:
    text = _text

    try:
        sensor = json.loads(text(f.attrs["sensor"]))
    except ValueError:
        raise DatasetError(f"{path}: sensor attribute is not JSON") from None
    return {
        "front_end": text(f.attrs["front_end"]),
        "location_unit": text(f.attrs["location_unit"]),
        "identity_unit": text(f.attrs["identity_unit"]),
        "dim_names": tuple(text(n) for n in np.atleast_1d(f.attrs["dim_names"])),
        "sensor": sensor,
        "identity_period": float(f.attrs["identity_period"]) if "identity_period" in f.attrs else None,
        "identity_names": tuple(text(n) for n in np.atleast_1d(f.attrs["identity_names"]))
        if "identity_names" in f.attrs else (),
    }
