"""Histogram measurement model over joint (location, identity) classes (paper 000 eqs. 2-3; 002 eqs. 2-3).

Sensor values of each dimension k are binned into ``bins`` equal intervals spanning the training
range of that dimension; the model holds, for every class c = (x_l, w_i), the regularised
sampling distribution of the bins

    P_k(b | c) = (n_kc(b) + epsilon) / sum_b (n_kc(b) + epsilon)

and the log likelihood of a tap z = {s_k(j)} is the mean log probability over its samples j and
dimensions k (a geometric-mean likelihood, paper 001):

    log P(z | c) = sum_k sum_j log P_k(b_k(j) | c) / (N_samples N_dims)

Location classes are ``n_locations`` equal bins of the training locations; identity classes are
the distinct training identities. Class c = l * n_identities + i, so a likelihood vector reshapes
to ``(n_locations, n_identities)``.

Example
-------
>>> model = fit_model(train, n_locations=11)           # doctest: +SKIP
>>> model.log_likelihood(tap).shape                    # doctest: +SKIP
(11, 20)
"""

from __future__ import annotations

import dataclasses
import json
import os
import pathlib
from dataclasses import dataclass, field

import numpy as np

from ._files import atomic_path, cut_short, hdf5_in_memory
from .choices import MODEL_KINDS
from .dataset import Dataset
from .errors import DatasetError, ModelError
from .likelihood import RECOMMENDED_KEYS, LikelihoodModel

__all__ = ["MODEL_SCHEMA", "DEFAULT_EPSILON", "MODEL_KINDS", "HistogramModel", "fit_model", "train_model",
           "save_model", "load_model", "model_class"]

MODEL_SCHEMA = "tactip-model/1"
#: Regularising count added to every histogram bin (paper 000: epsilon << 1).
DEFAULT_EPSILON = 1e-3
_BATCH = 256  # taps per chunk in the batch likelihood (counts of 256 taps x 8000 bins: 8 MB)


@dataclass(frozen=True)
class HistogramModel(LikelihoodModel):
    """A trained histogram likelihood model (build it with `fit_model`, or `load_model`).

    Attributes
    ----------
    log_probability : (dims, bins, classes) float32 ndarray
        log P_k(b | c), classes ordered c = l * n_identities + i.
    bin_lower, bin_width : (dims,) float64 ndarray
        Lower edge and width of the value bins of each dimension (sensor units).
    location_edges : (n_locations + 1,) float64 ndarray
        Edges of the equal location classes, in ``location_unit``.
    identities : (n_identities,) float64 ndarray
        Identity of each identity class, in ``identity_unit``.
    front_end : str
        ``"tactip"`` or ``"taxel"``.
    samples : int
        Time samples per tap.
    dim_names : tuple of str
    sensor : dict
        Sensor description copied from the training dataset.
    location_unit, identity_unit : str
    epsilon : float
        The regularising count.
    taps_per_class : (n_locations, n_identities) int ndarray
        Training taps in each class.
    recommended : dict
        Recommended settings: ``decision_threshold``, ``fixation_location`` (location units), ``policy``.
    """

    log_probability: np.ndarray
    bin_lower: np.ndarray
    bin_width: np.ndarray
    location_edges: np.ndarray
    identities: np.ndarray
    front_end: str
    samples: int
    dim_names: tuple[str, ...]
    sensor: dict
    location_unit: str
    identity_unit: str
    epsilon: float
    taps_per_class: np.ndarray
    recommended: dict = field(default_factory=dict)

    def __post_init__(self):
        dims, _, classes = self.log_probability.shape
        if classes != self.n_locations * self.n_identities:
            raise ModelError(f"log_probability has {classes} classes, expected {self.n_locations} locations x "
                             f"{self.n_identities} identities")
        if self.bin_lower.shape != (dims,) or self.bin_width.shape != (dims,) or len(self.dim_names) != dims:
            raise ModelError(f"bin_lower, bin_width and dim_names must have {dims} entries")
        if not (isinstance(self.epsilon, (int, float, np.floating)) and np.isfinite(self.epsilon) and self.epsilon > 0):
            raise ModelError(f"epsilon must be a finite number > 0, got {self.epsilon!r}")
        self._check_recommended()

    KIND = "histogram"

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.summary()}>"

    @property
    def dims(self) -> int:
        """Data dimensions per sample."""
        return self.log_probability.shape[0]

    @property
    def bins(self) -> int:
        """Value bins per dimension."""
        return self.log_probability.shape[1]

    def summary(self) -> str:
        """One line: front end, class grid, tap shape, bins."""
        return f"{self._grid_summary()}; {self.bins} bins"

    # -- storage ----------------------------------------------------------------------------
    _ARRAYS = ("log_probability", "bin_lower", "bin_width")
    _ATTRS = ("epsilon",)

    def _stored(self) -> tuple[dict, dict]:
        return {name: getattr(self, name) for name in self._ARRAYS}, {"epsilon": self.epsilon}

    @classmethod
    def _from_stored(cls, common: dict, arrays: dict, attrs: dict):
        try:
            epsilon = float(attrs["epsilon"])
        except (TypeError, ValueError):
            raise ModelError(f"unreadable epsilon {attrs['epsilon']!r}") from None
        return cls(**arrays, **common, epsilon=epsilon)

    # -- likelihood -------------------------------------------------------------------------
    def bin_index(self, taps) -> np.ndarray:
        """Value bin b_k(j) of every sample (values outside the training range go to the edge bins).

        Parameters
        ----------
        taps : (..., dims) array

        Returns
        -------
        (..., dims) intp ndarray in [0, bins)
        """
        b = np.floor((np.asarray(taps, dtype=np.float64) - self.bin_lower) / self.bin_width)
        return np.clip(b, 0, self.bins - 1).astype(np.intp)

    def log_likelihood(self, tap) -> np.ndarray:
        """Mean log likelihood log P(z | x_l, w_i) of one tap against every class (eq. 3).

        Parameters
        ----------
        tap : (samples, dims) array

        Returns
        -------
        (n_locations, n_identities) float64 ndarray
        """
        tap = self._check_taps(tap, batch=False)
        flat = (self.bin_index(tap) + np.arange(self.dims) * self.bins).ravel()
        # One gather of the occupied (dim, bin) rows, weighted by how many samples fell in each.
        counts = np.bincount(flat, minlength=self.dims * self.bins)
        rows = np.flatnonzero(counts)
        table = self.log_probability.reshape(self.dims * self.bins, self.n_classes)
        total = counts[rows].astype(np.float32) @ np.take(table, rows, axis=0)
        return (total.astype(np.float64) / flat.size).reshape(self.n_locations, self.n_identities)

    def log_likelihood_batch(self, taps) -> np.ndarray:
        """`log_likelihood` of many taps at once (Monte Carlo precomputation).

        Parameters
        ----------
        taps : (N, samples, dims) array

        Returns
        -------
        (N, n_locations, n_identities) float64 ndarray
        """
        taps = self._check_taps(taps, batch=True)
        table = self.log_probability.reshape(self.dims * self.bins, self.n_classes)
        out = np.empty((len(taps), self.n_classes))
        offsets = np.arange(self.dims) * self.bins
        for start in range(0, len(taps), _BATCH):
            chunk = taps[start:start + _BATCH]
            n = len(chunk)
            flat = (self.bin_index(chunk) + offsets + (np.arange(n) * self.dims * self.bins)[:, None, None]).ravel()
            counts = np.bincount(flat, minlength=n * self.dims * self.bins).astype(np.float32)
            out[start:start + n] = counts.reshape(n, -1) @ table
        out /= self.samples * self.dims
        return out.reshape(len(taps), self.n_locations, self.n_identities)


def fit_model(dataset: Dataset, *, n_locations: int = 11, bins: int = 100, epsilon: float = DEFAULT_EPSILON,
              min_taps_per_class: int = 1) -> HistogramModel:
    """Train the histogram model on a dataset (paper 002 eq. 3).

    Parameters
    ----------
    dataset : Dataset
        Training taps. A dataset with a single location value trains one location class
        (pure identity classification) whatever `n_locations`.
    n_locations : int
        Number of equal location classes spanning the training locations (paper 002: 11).
    bins : int
        Value bins per dimension, spanning its training range (paper: 100).
    epsilon : float
        Regularising count added to every bin (> 0).
    min_taps_per_class : int
        Fewest training taps a (location, identity) class may have.

    Returns
    -------
    HistogramModel

    Raises
    ------
    DatasetError
        A class has fewer than `min_taps_per_class` taps (the message names it).
    ValueError
        A knob is out of range (the message names it).
    """
    if not isinstance(dataset, Dataset):
        raise DatasetError(f"dataset must be a Dataset, got {type(dataset).__name__}")
    for name, value, low in (("n_locations", n_locations, 1), ("bins", bins, 2),
                             ("min_taps_per_class", min_taps_per_class, 1)):
        if int(value) != value or value < low:
            raise ValueError(f"{name} must be an integer >= {low}, got {value}")
    if not (np.isfinite(epsilon) and epsilon > 0):
        raise ValueError(f"epsilon must be a finite number > 0, got {epsilon}")
    if len(dataset) == 0:
        raise DatasetError("dataset has no taps")
    lo, hi = float(dataset.location.min()), float(dataset.location.max())
    n_locations = int(n_locations) if hi > lo else 1
    edges = np.linspace(lo, hi, n_locations + 1)
    identities = np.unique(dataset.identity)
    dims, bins = dataset.dims, int(bins)
    values = dataset.taps.reshape(-1, dims)
    bin_lower = values.min(axis=0).astype(np.float64)
    span = values.max(axis=0) - bin_lower
    bin_width = np.where(span > 0, span / bins, 1.0)
    grid = HistogramModel(np.zeros((dims, bins, n_locations * len(identities)), np.float32), bin_lower, bin_width,
                          edges, identities, dataset.front_end, dataset.samples, dataset.dim_names, dataset.sensor,
                          dataset.location_unit, dataset.identity_unit, float(epsilon),
                          np.zeros((n_locations, len(identities)), np.int64))
    cls = grid.location_class(dataset.location) * len(identities) + grid.identity_class(dataset.identity)
    taps_per_class = np.bincount(cls, minlength=grid.n_classes)
    few = np.flatnonzero(taps_per_class < min_taps_per_class)
    if few.size:
        l, i = divmod(int(few[0]), len(identities))
        raise DatasetError(f"{few.size} of {grid.n_classes} classes have fewer than {min_taps_per_class} training "
                           f"taps, e.g. location {grid.location_centres[l]:g} {dataset.location_unit}, identity "
                           f"{identities[i]:g} {dataset.identity_unit} has {taps_per_class[few[0]]}; "
                           f"use fewer location classes")
    return dataclasses.replace(grid, log_probability=histogram_log_probability(grid, dataset.taps, cls),
                               taps_per_class=taps_per_class.reshape(n_locations, len(identities)))


def histogram_log_probability(grid: HistogramModel, taps, tap_class) -> np.ndarray:
    """The regularised histograms log P_k(b | c) of taps on a model's bins and classes (paper 002 eq. 3).

    Parameters
    ----------
    grid : HistogramModel
        Gives the value bins, the classes and epsilon.
    taps : (N, samples, dims) array
    tap_class : (N,) int array
        Joint class l * n_identities + i of each tap.

    Returns
    -------
    (dims, bins, classes) float32 ndarray
    """
    dims, bins, n_classes = grid.dims, grid.bins, grid.n_classes
    tap_class = np.asarray(tap_class, dtype=np.intp)
    # h(b, k, c): sample counts per class, dimension and bin, in one bincount.
    counts = np.zeros((n_classes, dims, bins))
    for start in range(0, len(taps), 4096):  # bounded memory for large datasets
        b = grid.bin_index(taps[start:start + 4096])
        flat = (tap_class[start:start + 4096, None, None] * dims + np.arange(dims)) * bins + b
        counts += np.bincount(flat.ravel(), minlength=counts.size).reshape(counts.shape)
    # P_k(b|c) = (h(b,k,c) + eps) / sum_b (h(b,k,c) + eps)
    regularised = counts + grid.epsilon
    log_p = np.log(regularised) - np.log(regularised.sum(axis=2, keepdims=True))
    return np.ascontiguousarray(log_p.transpose(1, 2, 0), np.float32)


def train_model(dataset: Dataset, *, kind: str = "histogram", n_locations: int = 11, bins: int = 100,
                epsilon: float = DEFAULT_EPSILON, min_taps_per_class: int = 1, seed: int = 0) -> LikelihoodModel:
    """Train a likelihood model of any kind on a dataset.

    Parameters
    ----------
    dataset : Dataset
    kind : str
        One of `MODEL_KINDS`: ``histogram`` (the papers' model, `fit_model`), ``calibrated-histogram``
        (`perception.calibrated.fit_calibrated_histogram`), ``gaussian``
        (`perception.gaussian.fit_gaussian`), ``torch`` (`perception.learned.fit_torch`, needs torch).
    n_locations : int
        Equal location classes over the training locations.
    bins, epsilon : int, float
        Histogram bins and regularising count (histogram kinds).
    min_taps_per_class : int
    seed : int
        Seed of the torch model's initialisation and batches.

    Returns
    -------
    LikelihoodModel
    """
    model_class(kind)  # an unknown kind fails before any work
    common = dict(n_locations=n_locations, min_taps_per_class=min_taps_per_class)
    if kind == "histogram":
        return fit_model(dataset, bins=bins, epsilon=epsilon, **common)
    if kind == "calibrated-histogram":
        from .calibrated import fit_calibrated_histogram

        return fit_calibrated_histogram(dataset, bins=bins, epsilon=epsilon, **common)
    if kind == "gaussian":
        from .gaussian import fit_gaussian

        return fit_gaussian(dataset, **common)
    from .learned import fit_torch

    return fit_torch(dataset, seed=seed, **common)


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
    if kind == "histogram":
        return HistogramModel
    if kind == "calibrated-histogram":
        from .calibrated import CalibratedHistogramModel

        return CalibratedHistogramModel
    if kind == "gaussian":
        from .gaussian import GaussianModel

        return GaussianModel
    if kind == "torch":
        from .learned import TorchModel

        return TorchModel
    raise ModelError(f"unknown model kind {kind!r}; choose from {', '.join(MODEL_KINDS)}")


#: Fields every kind stores: arrays, then attributes.
_COMMON_ARRAYS = ("location_edges", "identities", "taps_per_class")
_COMMON_ATTRS = ("front_end", "location_unit", "identity_unit", "samples", "dim_names", "sensor", "recommended")


def save_model(path, model: LikelihoodModel, *, inputs=()) -> None:
    """Write a model to an HDF5 file of schema ``tactip-model/1`` atomically (temporary file, fsync, rename).

    The file holds the class grid, the tap description and the recommended settings, the model's
    ``kind`` and the kind's own parameters (a histogram model's file is the one earlier versions wrote,
    plus ``kind``).

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
        names = _COMMON_ARRAYS + cls._ARRAYS
        attr_names = _COMMON_ATTRS + cls._ATTRS
        missing = [n for n in names if n not in f] + [n for n in attr_names if n not in f.attrs]
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
            own = {name: f.attrs[name] for name in cls._ATTRS}
        except (TypeError, ValueError) as exc:
            raise ModelError(f"{path}: unreadable settings ({exc})") from None
        common["dim_names"] = tuple(str(n) for n in np.atleast_1d(f.attrs["dim_names"]))
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
    """Refuse empty or reversed location classes."""
    edges = arrays["location_edges"]
    if len(edges) < 2 or (len(edges) > 2 and not (np.diff(edges) > 0).all()):
        raise ModelError(f"{path}: location_edges must increase (at least 2 edges)")
