"""The registry of likelihood model kinds and the model file (schema ``tactip-model/1``).

Each kind lives in its own module and knows nothing of this one: ``histogram`` (the papers' model,
`perception.histogram`), ``calibrated-histogram`` (`perception.calibrated`), ``gaussian``
(`perception.gaussian`), ``torch`` (`perception.learned`). Here the kind's name (``tactip train
--model NAME``) maps to its class and fit function; `train_model` trains any kind, `save_model` and
`load_model` write and read any kind's file.

Example
-------
>>> model = train_model(train, kind="gaussian", n_locations=11)    # doctest: +SKIP
>>> save_model("model.h5", model, inputs=["train.h5"])               # doctest: +SKIP
>>> load_model("model.h5").KIND                                      # doctest: +SKIP
'gaussian'
"""

from __future__ import annotations

import json
import os
import pathlib

import numpy as np

from _shared import atomic_path, cut_short, hdf5_in_memory

from .calibrated import CalibratedHistogramModel, fit_calibrated_histogram
from .choices import MODEL_KINDS
from .dataset import Dataset, check_identity_labels
from .errors import DatasetError, ModelError
from .gaussian import GaussianModel, fit_gaussian
from .histogram import DEFAULT_EPSILON, HistogramModel, fit_model
from .learned import TorchModel, fit_torch
from .likelihood import LikelihoodModel

__all__ = ["MODEL_SCHEMA", "MODEL_KINDS", "train_model", "save_model", "load_model", "model_class"]

MODEL_SCHEMA = "tactip-model/1"
#: Each kind's class, fit function and the `train_model` knobs it takes beyond the class grid's.
_KINDS = {
    "histogram": (HistogramModel, fit_model, ("bins", "epsilon")),
    "calibrated-histogram": (CalibratedHistogramModel, fit_calibrated_histogram, ("bins", "epsilon")),
    "gaussian": (GaussianModel, fit_gaussian, ("components", "shrinkages")),
    "torch": (TorchModel, fit_torch, ("seed", "max_epochs", "inputs", "deviations")),
}


def train_model(dataset: Dataset, *, kind: str = "histogram", n_locations: int = 11, bins: int = 100,
                epsilon: float = DEFAULT_EPSILON, min_taps_per_class: int = 1, seed: int = 0, components=None,
                shrinkages=None, max_epochs: int | None = None, inputs: str | None = None,
                deviations: str | None = None) -> LikelihoodModel:
    """Train a likelihood model of any kind on a dataset.

    Parameters
    ----------
    dataset : Dataset
    kind : str
        One of `MODEL_KINDS`: ``histogram`` (the papers' model, `perception.histogram.fit_model`),
        ``calibrated-histogram`` (`perception.calibrated.fit_calibrated_histogram`), ``gaussian``
        (`perception.gaussian.fit_gaussian`), ``torch`` (`perception.learned.fit_torch`, needs torch).
    n_locations : int
        Equal location classes over the training locations.
    bins, epsilon : int, float
        Histogram bins and regularising count (histogram kinds).
    min_taps_per_class : int
    seed : int
        Seed of the torch model's initialisation and batches.
    components, shrinkages : int or sequence, optional
        The Gaussian's candidate principal components and covariance shrinkages (default: its own
        candidates, chosen among by cross-validation); one of each fixes them, e.g. to fit models
        of the same settings on parts of the taps (`calibration.fit_with_fixation`).
    max_epochs : int, optional
        Most epochs each of the torch model's networks trains (default: `perception.learned.fit_torch`'s).
    inputs, deviations : str, optional
        The torch model's input and augmentation (default: chosen on held-out taps); one of each fixes
        them, as ``components`` and ``shrinkages`` do the Gaussian's (`perception.learned.fit_torch`).

    Returns
    -------
    LikelihoodModel

    Raises
    ------
    ModelError
        An unknown kind (the message lists the kinds), before any work.
    """
    model_class(kind)
    _, fit, own = _KINDS[kind]
    given = dict(bins=bins, epsilon=epsilon, seed=seed, components=components, shrinkages=shrinkages,
                 max_epochs=max_epochs, inputs=inputs, deviations=deviations)
    return fit(dataset, n_locations=n_locations, min_taps_per_class=min_taps_per_class,
               **{name: given[name] for name in own if given[name] is not None})


def model_class(kind: str) -> type:
    """The class of a kind of likelihood model.

    Parameters
    ----------
    kind : str
        One of `MODEL_KINDS`.

    Raises
    ------
    ModelError
        An unknown kind (the message lists the kinds).
    """
    if not isinstance(kind, str) or kind not in _KINDS:
        raise ModelError(f"unknown model kind {kind!r}; choose from {', '.join(MODEL_KINDS)}")
    return _KINDS[kind][0]


#: Fields every kind stores: arrays, then attributes.
_COMMON_ARRAYS = ("location_edges", "identities", "taps_per_class")
_COMMON_ATTRS = ("front_end", "location_unit", "identity_unit", "samples", "dim_names", "sensor", "recommended")


def save_model(path, model: LikelihoodModel, *, inputs=()) -> None:
    """Write a model to an HDF5 file of schema ``tactip-model/1`` atomically (temporary file, fsync, rename).

    The file holds the class grid, the tap description and the recommended settings, the model's
    ``kind`` and the kind's own parameters (a file without ``kind`` is read as a histogram model, so
    histogram files that do not name their kind still load).

    Parameters
    ----------
    path : str or os.PathLike
    model : LikelihoodModel
    inputs : iterable of path
        Files the caller read (e.g. the training dataset): ``path`` must not be one of them.

    Raises
    ------
    OSError
        Disk full or permission denied (named so); ``path`` keeps its old content.
    FileExistsError
        ``path`` is one of ``inputs``.
    """
    if not isinstance(model, LikelihoodModel):
        raise TypeError(f"model must be a LikelihoodModel, got {type(model).__name__}")
    arrays, attrs = model._stored()
    path = pathlib.Path(path)
    with atomic_path(path, inputs=inputs) as tmp:
        with hdf5_in_memory(tmp) as f:  # a full disk is an OSError, not a crash inside HDF5
            f.attrs["schema"] = MODEL_SCHEMA
            f.attrs["kind"] = model.KIND
            for name in _COMMON_ARRAYS:
                f.create_dataset(name, data=getattr(model, name))
            for name, value in arrays.items():
                f.create_dataset(name, data=value)
            for name in ("front_end", "location_unit", "identity_unit"):
                f.attrs[name] = getattr(model, name)
            f.attrs["samples"] = model.samples
            f.attrs["dim_names"] = list(model.dim_names)
            f.attrs["sensor"] = json.dumps(model.sensor, sort_keys=True)
            f.attrs["recommended"] = json.dumps(model.recommended, sort_keys=True)
            if model.identity_period is not None:
                f.attrs["identity_period"] = float(model.identity_period)
            if model.identity_names:
                f.attrs["identity_names"] = list(model.identity_names)
            if model.tap_tempering:  # optional: a file without it has no tap tempering (every g_t = 1)
                f.attrs["tap_tempering"] = np.asarray(model.tap_tempering, dtype=np.float64)
            for name, value in attrs.items():
                f.attrs[name] = value


def load_model(path) -> LikelihoodModel:
    """Read a ``tactip-model/1`` file; the model is of the class its ``kind`` names (histogram if none).

    Parameters
    ----------
    path : str or os.PathLike

    Raises
    ------
    ModelError
        Not HDF5, another schema, an unknown kind, or a missing field.
    FileNotFoundError
        No such file.
    """
    import h5py

    path = pathlib.Path(path)
    if not path.exists():
        raise FileNotFoundError(f"no such model file: {path}")
    if path.is_dir():
        raise ModelError(f"{path} is a folder, not a model file")
    if not os.access(path, os.R_OK):
        raise PermissionError(13, f"permission denied reading {str(path)!r}")
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        if "permission denied" in str(exc).lower():
            raise PermissionError(13, f"permission denied reading {str(path)!r}") from None
        cut = cut_short(exc)
        if cut:
            raise ModelError(f"{path} is cut short ({cut[0]} of its {cut[1]} bytes: a copy or a write that did not "
                             f"finish); copy it again or train it again") from None
        raise ModelError(f"{path} is not an HDF5 file") from None
    with f:
        schema = f.attrs.get("schema")
        schema = schema.decode() if isinstance(schema, bytes) else schema
        if schema != MODEL_SCHEMA:
            raise ModelError(f"{path} is not a {MODEL_SCHEMA} file (schema {schema!r})")
        kind = str(f.attrs.get("kind", "histogram"))
        try:
            cls = model_class(kind)
        except ModelError as exc:
            raise ModelError(f"{path}: {exc}") from None
        optional = getattr(cls, "_OPTIONAL", {})  # fields a file of an older version may lack: their defaults
        names = _COMMON_ARRAYS + tuple(n for n in cls._ARRAYS if n in f or n not in optional)
        attr_names = _COMMON_ATTRS + cls._ATTRS
        missing = [n for n in names if n not in f] + [n for n in attr_names if n not in f.attrs and n not in optional]
        if missing:
            raise ModelError(f"{path} misses {', '.join(missing)} (required by {MODEL_SCHEMA} {kind})")
        for name in names:
            if not hasattr(f[name], "dtype") or f[name].dtype.kind not in "fiu":
                raise ModelError(f"{path}: {name!r} does not hold numbers")
        arrays = {name: f[name][()] for name in names}
        common = {name: str(f.attrs[name]) for name in ("front_end", "location_unit", "identity_unit")}
        try:
            common.update(samples=int(f.attrs["samples"]), sensor=json.loads(f.attrs["sensor"]),
                          recommended=json.loads(f.attrs["recommended"]))
            own = {name: f.attrs[name] if name in f.attrs else optional[name] for name in cls._ATTRS}
        except (TypeError, ValueError) as exc:
            raise ModelError(f"{path}: unreadable settings ({exc})") from None
        common["dim_names"] = tuple(str(n) for n in np.atleast_1d(f.attrs["dim_names"]))
        if "tap_tempering" in f.attrs:  # optional (older files: no tap tempering); checked by the model
            value = np.atleast_1d(f.attrs["tap_tempering"])
            if value.dtype.kind not in "fiu":
                raise ModelError(f"{path}: tap_tempering does not hold numbers")
            common["tap_tempering"] = tuple(float(g) for g in value)
        try:  # optional: the label's period and class names (absent: a plain number)
            common["identity_period"], common["identity_names"] = check_identity_labels(
                f.attrs["identity_period"] if "identity_period" in f.attrs else None,
                [str(n) for n in np.atleast_1d(f.attrs["identity_names"])] if "identity_names" in f.attrs else ())
        except DatasetError as exc:
            raise ModelError(f"{path}: {exc}") from None
    _check_model_arrays(path, arrays)
    if not isinstance(common["recommended"], dict):
        raise ModelError(f"{path}: recommended settings are not a table")
    common.update({name: arrays.pop(name) for name in _COMMON_ARRAYS})
    try:
        return cls._from_stored(common, arrays, own)
    except ModelError as exc:
        raise ModelError(f"{path}: {exc}") from None


def _check_model_arrays(path, arrays: dict) -> None:
    """Refuse a model whose numbers cannot be right (NaN or infinite likelihoods, empty or reversed grids)."""
    if "log_probability" not in arrays:
        for name, value in arrays.items():
            if np.asarray(value).dtype.kind == "f" and not np.isfinite(value).all():
                raise ModelError(f"{path}: {name} holds NaN or infinite numbers; train the model again")
        _check_grid(path, arrays)
        return
    log_p = arrays["log_probability"]
    if log_p.ndim != 3 or 0 in log_p.shape:
        raise ModelError(f"{path}: log_probability must be a non-empty (dims, bins, classes) array, got {log_p.shape}")
    bad = ~np.isfinite(log_p)
    if bad.any():
        raise ModelError(f"{path}: log_probability holds {int(bad.sum())} NaN or infinite likelihoods of "
                         f"{log_p.size} (a model trained with a non-finite epsilon?); train it again")
    if (log_p > 1e-4).any():
        raise ModelError(f"{path}: log_probability holds probabilities above 1; train it again")
    for name in ("bin_lower", "bin_width", "location_edges", "identities"):
        value = np.asarray(arrays[name], dtype=np.float64)
        if value.ndim != 1 or not np.isfinite(value).all():
            raise ModelError(f"{path}: {name} must be a 1-d array of finite numbers")
    if not (arrays["bin_width"] > 0).all():
        raise ModelError(f"{path}: bin_width must be > 0")
    _check_grid(path, arrays)


def _check_grid(path, arrays: dict) -> None:
    """Refuse empty or reversed location classes, and training tap counts that are not counts of them."""
    edges = arrays["location_edges"]
    if len(edges) < 2 or (len(edges) > 2 and not (np.diff(edges) > 0).all()):
        raise ModelError(f"{path}: location_edges must increase (at least 2 edges)")
    counts = np.asarray(arrays["taps_per_class"])
    shape = (len(edges) - 1, len(np.atleast_1d(arrays["identities"])))
    if counts.shape != shape or not np.isfinite(counts).all() or (counts < 0).any() or (counts != np.round(counts)).any():
        raise ModelError(f"{path}: taps_per_class must hold a whole number >= 0 for each of the {shape[0]} x "
                         f"{shape[1]} classes; train the model again")
