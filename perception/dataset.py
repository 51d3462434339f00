"""The tap dataset: the contract between front ends, calibration and perception.

A dataset is a set of taps, each a ``(samples, dims)`` time series of sensor values, labelled
with the location (e.g. depth in mm) and identity (e.g. gap width in mm) it was collected at.
On disk it is one HDF5 file of schema ``tactip-dataset/1``:

==============  ==========================  ============================================
name            kind                        content
==============  ==========================  ============================================
``taps``        float32 (N, samples, dims)  sensor values of each tap
``location``    float64 (N,)                location of each tap (``location_unit``)
``identity``    float64 (N,)                identity of each tap (``identity_unit``)
``lateral``     float64 (N,), optional      lateral placement offset of each tap, mm
``schema``      attribute                   ``"tactip-dataset/1"``
``front_end``   attribute                   ``"tactip"`` (pin displacements) or ``"taxel"``
``location_unit``, ``identity_unit``        attributes, e.g. ``"mm"`` (``"none"`` for a constant)
``dim_names``   attribute, list of str      one name per dimension (``"pin03_x"``, ``"taxel07"``)
``sensor``      attribute, JSON string      sensor description (kind, pins or taxels, preset, ...)
==============  ==========================  ============================================

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

import json
import os
import pathlib
from dataclasses import dataclass, field

import numpy as np

from .errors import DatasetError

__all__ = ["SCHEMA", "FRONT_ENDS", "Dataset", "save_dataset", "load_dataset", "DatasetWriter"]

SCHEMA = "tactip-dataset/1"
FRONT_ENDS = ("tactip", "taxel")
_ARRAYS = ("taps", "location", "identity")


@dataclass(frozen=True)
class Dataset:
    """Labelled taps of one front end, validated on construction.

    Parameters
    ----------
    taps : (N, samples, dims) array, converted to float32
        Sensor values of each tap (pin displacements in px, or taxel readings).
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

    Raises
    ------
    DatasetError
        Naming the field: wrong shapes, NaN or infinite values, unknown front end,
        wrong number of dim names, a sensor description that is not JSON.
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
            bad = ~np.isfinite(value)
            if bad.any():
                first = int(np.argwhere(bad)[0][0])
                raise DatasetError(f"{name} holds NaN or infinite values (first in tap {first})")
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
                       self.location_unit, self.identity_unit, self.dim_names, self.sensor)

    def describe(self) -> str:
        """One line: front end, taps, samples x dims, location and identity ranges."""
        def span(values, unit):
            if len(values) == 0:
                return "-"
            return f"{values.min():g}..{values.max():g} {unit} ({len(np.unique(values))} values)"
        return (f"{self.front_end} dataset: {len(self)} taps of {self.samples} samples x {self.dims} dims; "
                f"location {span(self.location, self.location_unit)}; identity {span(self.identity, self.identity_unit)}")


def save_dataset(path, dataset: Dataset) -> None:
    """Write a dataset to an HDF5 file atomically (temporary file, then rename).

    Parameters
    ----------
    path : str or os.PathLike
        Destination file; replaced if it exists.
    dataset : Dataset
        The taps and their labels.
    """
    import h5py

    if not isinstance(dataset, Dataset):
        raise DatasetError(f"dataset must be a Dataset, got {type(dataset).__name__}")
    path = pathlib.Path(path)
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        with h5py.File(tmp, "w") as f:
            _write_attributes(f, dataset.front_end, dataset.location_unit, dataset.identity_unit,
                              dataset.dim_names, dataset.sensor)
            f.create_dataset("taps", data=dataset.taps, chunks=_taps_chunks(dataset.samples, dataset.dims),
                             maxshape=(None, dataset.samples, dataset.dims))
            for name in ("location", "identity", "lateral"):
                value = getattr(dataset, name)
                if value is not None:
                    f.create_dataset(name, data=value, chunks=(1024,), maxshape=(None,))
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


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
    """
    import h5py

    path = pathlib.Path(path)
    if not path.exists():
        raise FileNotFoundError(f"no such dataset file: {path}")
    try:
        f = h5py.File(path, "r")
    except OSError:
        raise DatasetError(f"{path} is not an HDF5 file") from None
    with f:
        _check_schema(f, path)
        missing = [name for name in _ARRAYS if name not in f]
        missing += [name for name in ("front_end", "location_unit", "identity_unit", "dim_names", "sensor")
                    if name not in f.attrs]
        if missing:
            raise DatasetError(f"{path} misses {', '.join(missing)} (required by {SCHEMA})")
        lengths = {name: f[name].shape[0] for name in (*_ARRAYS, "lateral") if name in f}
        if len(set(lengths.values())) > 1:
            raise DatasetError(f"{path} has mismatched lengths: " + ", ".join(f"{k} {v}" for k, v in lengths.items()))
        arrays = {name: f[name][()] for name in (*_ARRAYS, "lateral") if name in f}
        attrs = _read_attributes(f, path)
    try:
        return Dataset(arrays["taps"], arrays["location"], arrays["identity"], arrays.get("lateral"), **attrs)
    except DatasetError as exc:
        raise DatasetError(f"{path}: {exc}") from None


class DatasetWriter:
    """Append taps one at a time to a dataset file, resuming it if it exists.

    Each `append` resizes the chunked datasets and flushes the file, so a crash loses at most
    the tap in progress. Opening an existing file checks that its schema, tap shape, front end,
    units, dim names and sensor description match; taps stored by an interrupted append
    (some arrays one longer than the others) are dropped.

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

    Raises
    ------
    DatasetError
        The existing file does not match (the message names the field).

    Examples
    --------
    >>> with DatasetWriter("train.h5", samples=40, dims=80, front_end="tactip") as writer:  # doctest: +SKIP
    ...     writer.append(tap, location=1.5, identity=0.25)
    """

    def __init__(self, path, *, samples: int, dims: int, front_end: str, location_unit: str = "mm",
                 identity_unit: str = "mm", dim_names=(), sensor: dict | None = None):
        import h5py

        # Validate every knob through the Dataset contract (an empty dataset of this shape).
        template = Dataset(np.zeros((0, int(samples), int(dims)), np.float32), np.zeros(0), np.zeros(0), None,
                           front_end, location_unit, identity_unit, tuple(dim_names), sensor or {})
        self.path = pathlib.Path(path)
        self._shape = (template.samples, template.dims)
        if self.path.exists():
            try:
                self._file = h5py.File(self.path, "r+")
            except OSError:
                raise DatasetError(f"{self.path} is not an HDF5 file (or is open elsewhere)") from None
            try:
                self._check_resume(template)
            except BaseException:
                self._file.close()
                raise
        else:
            # Made under a temporary name and renamed: a crash here leaves no half-made file to refuse.
            tmp = self.path.with_name(f".{self.path.name}.tmp-{os.getpid()}")
            try:
                with h5py.File(tmp, "w") as f:
                    _write_attributes(f, template.front_end, template.location_unit, template.identity_unit,
                                      template.dim_names, template.sensor)
                    f.create_dataset("taps", shape=(0, *self._shape), dtype=np.float32,
                                     chunks=_taps_chunks(*self._shape), maxshape=(None, *self._shape))
                    for name in ("location", "identity"):
                        f.create_dataset(name, shape=(0,), dtype=np.float64, chunks=(1024,), maxshape=(None,))
                os.replace(tmp, self.path)
            finally:
                tmp.unlink(missing_ok=True)
            self._file = h5py.File(self.path, "r+")

    def _check_resume(self, template: Dataset) -> None:
        f = self._file
        _check_schema(f, self.path)
        missing = [name for name in _ARRAYS if name not in f]
        if missing:
            raise DatasetError(f"{self.path} misses {', '.join(missing)} (required by {SCHEMA})")
        stored = _read_attributes(f, self.path)
        shape = f["taps"].shape[1:]
        if shape != self._shape:
            raise DatasetError(f"{self.path} holds taps of (samples, dims) {shape}, not {self._shape}")
        for name, value in stored.items():
            if value != getattr(template, name):
                raise DatasetError(f"{self.path} has {name} {value!r}, not {getattr(template, name)!r}")
        # An interrupted append may have grown some arrays and not others: keep the complete taps.
        names = [name for name in (*_ARRAYS, "lateral") if name in f]
        count = min(f[name].shape[0] for name in names)
        for name in names:
            f[name].resize(count, axis=0)

    @property
    def count(self) -> int:
        """Number of taps already stored."""
        return self._file["taps"].shape[0]

    def append(self, tap, location: float, identity: float, lateral: float | None = None) -> None:
        """Store one tap with its labels and flush it to disk.

        Parameters
        ----------
        tap : (samples, dims) array
            Sensor values of the tap.
        location, identity : float
            Labels in the dataset's units.
        lateral : float or None
            Lateral offset in mm; give it for every tap of a file or for none.

        Raises
        ------
        DatasetError
            Wrong tap shape, NaN or infinite values, or `lateral` given for some taps only.
        """
        tap = np.asarray(tap, dtype=np.float32)
        if tap.shape != self._shape:
            raise DatasetError(f"tap must have shape (samples, dims) {self._shape}, got {tap.shape}")
        if not np.isfinite(tap).all():
            raise DatasetError("tap holds NaN or infinite values")
        labels = {"location": location, "identity": identity}
        if lateral is not None:
            labels["lateral"] = lateral
        for name, value in labels.items():
            if not np.isfinite(value):
                raise DatasetError(f"{name} must be finite, got {value}")
        f = self._file
        n = self.count
        if lateral is not None and "lateral" not in f:
            if n:
                raise DatasetError(f"lateral given for tap {n} but not for the {n} taps before it")
            f.create_dataset("lateral", shape=(0,), dtype=np.float64, chunks=(1024,), maxshape=(None,))
        elif lateral is None and "lateral" in f:
            raise DatasetError(f"lateral missing for tap {n}; the file has lateral for every tap")
        f["taps"].resize(n + 1, axis=0)
        f["taps"][n] = tap
        for name, value in labels.items():
            f[name].resize(n + 1, axis=0)
            f[name][n] = float(value)
        f.flush()

    def close(self) -> None:
        """Flush and close the file (idempotent)."""
        if self._file.id.valid:
            self._file.close()

    def __enter__(self) -> DatasetWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        count = self.count if self._file.id.valid else "closed"
        return f"DatasetWriter({str(self.path)!r}, samples={self._shape[0]}, dims={self._shape[1]}, count={count})"


def _taps_chunks(samples: int, dims: int) -> tuple[int, int, int]:
    # About 256 kB per chunk, at least one tap.
    return (max(1, min(64, 65536 // max(1, samples * dims))), samples, dims)


def _write_attributes(f, front_end, location_unit, identity_unit, dim_names, sensor) -> None:
    f.attrs["schema"] = SCHEMA
    f.attrs["front_end"] = front_end
    f.attrs["location_unit"] = location_unit
    f.attrs["identity_unit"] = identity_unit
    f.attrs["dim_names"] = list(dim_names)
    f.attrs["sensor"] = json.dumps(sensor, sort_keys=True)


def _check_schema(f, path) -> None:
    schema = f.attrs.get("schema")
    if isinstance(schema, bytes):
        schema = schema.decode()
    if schema != SCHEMA:
        raise DatasetError(f"{path} is not a {SCHEMA} file (schema {schema!r})")


def _read_attributes(f, path) -> dict:
    def text(value):
        return value.decode() if isinstance(value, bytes) else str(value)

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
    }
