"""The tap dataset's HDF5 file (schema ``tactip-dataset/1``, `perception.dataset`): written whole
and atomically (`save_dataset`), read back (`load_dataset`), and the helpers that open the file with
errors that say what is wrong and write and read its attributes (shared with
`perception._dataset_writer`).
"""

from __future__ import annotations

import json
import os
import pathlib
import re

import numpy as np

from _shared import atomic_path, hdf5_in_memory, write_error

from ._dataset_checks import (_ARRAYS, COUNT_ATTRIBUTE, SCHEMA, _check_arrays, _check_schema,
                              _complete_count)
from ._dataset_container import Dataset
from .errors import DatasetError

__all__ = ["save_dataset", "load_dataset"]


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
