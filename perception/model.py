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
from .dataset import Dataset
from .errors import DatasetError, ModelError

__all__ = ["MODEL_SCHEMA", "DEFAULT_EPSILON", "HistogramModel", "fit_model", "save_model", "load_model"]

MODEL_SCHEMA = "tactip-model/1"
#: Regularising count added to every histogram bin (paper 000: epsilon << 1).
DEFAULT_EPSILON = 1e-3
#: Recommended settings a model may carry (written by ``tactip validate --sweep-fixation``).
RECOMMENDED_KEYS = ("decision_threshold", "fixation_location", "policy")
_BATCH = 256  # taps per chunk in the batch likelihood (counts of 256 taps x 8000 bins: 8 MB)


@dataclass(frozen=True)
class HistogramModel:
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
        unknown = set(self.recommended) - set(RECOMMENDED_KEYS)
        if unknown:
            raise ModelError(f"unknown recommended settings {sorted(unknown)}; choose from {RECOMMENDED_KEYS}")
        if not (isinstance(self.epsilon, (int, float, np.floating)) and np.isfinite(self.epsilon) and self.epsilon > 0):
            raise ModelError(f"epsilon must be a finite number > 0, got {self.epsilon!r}")
        self._check_recommended()

    def _check_recommended(self) -> None:
        """Each recommended setting is a number in its range, as a station file's key would be."""
        lo, hi = float(self.location_edges[0]), float(self.location_edges[-1])
        checks = {
            "decision_threshold": (lambda v: 0.0 < v <= 1.0, "a number in (0, 1]"),
            "fixation_location": (lambda v: lo - 1e-9 <= v <= hi + 1e-9,
                                  f"a location inside the model's range {lo:g}..{hi:g} {self.location_unit}"),
        }
        for key, (inside, accepted) in checks.items():
            if key not in self.recommended:
                continue
            value = self.recommended[key]
            number = isinstance(value, (int, float)) and not isinstance(value, bool)
            if not (number and np.isfinite(value) and inside(float(value))):
                raise ModelError(f"recommended {key} must be {accepted}, got {value!r} (run 'tactip validate "
                                 f"--sweep-fixation' again)")
        policy = self.recommended.get("policy")
        if policy is not None and policy not in ("active", "stationary", "random"):
            raise ModelError(f"recommended policy must be one of active, stationary, random, got {policy!r}")

    def __repr__(self) -> str:
        return f"<HistogramModel {self.summary()}>"

    @property
    def dims(self) -> int:
        """Data dimensions per sample."""
        return self.log_probability.shape[0]

    @property
    def bins(self) -> int:
        """Value bins per dimension."""
        return self.log_probability.shape[1]

    @property
    def n_locations(self) -> int:
        """Number of location classes L."""
        return len(self.location_edges) - 1

    @property
    def n_identities(self) -> int:
        """Number of identity classes I."""
        return len(self.identities)

    @property
    def n_classes(self) -> int:
        """Number of joint classes L * I."""
        return self.n_locations * self.n_identities

    @property
    def location_centres(self) -> np.ndarray:
        """(L,) centre of each location class, in ``location_unit``."""
        return 0.5 * (self.location_edges[:-1] + self.location_edges[1:])

    @property
    def class_width(self) -> float:
        """Width of one location class, in ``location_unit`` (0 for a single-location model)."""
        return float(self.location_edges[1] - self.location_edges[0]) if self.n_locations > 1 else 0.0

    def summary(self) -> str:
        """One line: front end, class grid, tap shape, bins."""
        lo, hi = self.location_edges[0], self.location_edges[-1]
        return (f"{self.front_end} model: {self.n_classes} classes = {self.n_locations} locations "
                f"({lo:g}..{hi:g} {self.location_unit}) x {self.n_identities} identities "
                f"({self.identities.min():g}..{self.identities.max():g} {self.identity_unit}); "
                f"taps of {self.samples} samples x {self.dims} dims; {self.bins} bins")

    def with_recommended(self, **settings) -> HistogramModel:
        """A copy of the model with some recommended settings replaced.

        Parameters
        ----------
        **settings
            ``decision_threshold`` (float), ``fixation_location`` (float, location units), ``policy`` (str).
        """
        return dataclasses.replace(self, recommended={**self.recommended, **settings})

    # -- class grid -------------------------------------------------------------------------
    def location_class(self, location) -> np.ndarray:
        """Location class index of each location (values outside the range go to the edge classes).

        Parameters
        ----------
        location : float or (N,) array, location units

        Returns
        -------
        int ndarray of the same shape, in [0, n_locations)
        """
        return np.searchsorted(self.location_edges[1:-1], np.asarray(location, dtype=np.float64), side="right")

    def fixation_class(self, fixation: float | None = None) -> int:
        """Location class to fixate on: of `fixation` (location units) if given, else of the
        recommended ``fixation_location``, else the middle class of the range."""
        if fixation is None:
            fixation = self.recommended.get("fixation_location")
        if fixation is None:
            return self.n_locations // 2
        return int(self.location_class(float(fixation)))

    def identity_class(self, identity) -> np.ndarray:
        """Identity class index of each identity value.

        Parameters
        ----------
        identity : float or (N,) array, identity units

        Raises
        ------
        DatasetError
            A value matches none of the model's identities.
        """
        identity = np.asarray(identity, dtype=np.float64)
        scale = max(1.0, float(np.abs(self.identities).max()))
        distance = np.abs(identity[..., None] - self.identities)
        index = distance.argmin(axis=-1)
        unknown = distance.min(axis=-1) > 1e-9 * scale
        if unknown.any():
            raise DatasetError(f"identity {np.unique(identity[unknown])[:5].tolist()} {self.identity_unit} is not one "
                               f"of the model's identities {self.identities.tolist()}")
        return index

    # -- compatibility ----------------------------------------------------------------------
    def check_dataset(self, dataset: Dataset) -> None:
        """Raise ModelError if the dataset's taps are not the kind this model was trained on.

        Parameters
        ----------
        dataset : Dataset
        """
        if (dataset.front_end, dataset.dims, dataset.samples) != (self.front_end, self.dims, self.samples):
            raise ModelError(f"model trained for {self.front_end} ({self.dims} dims, {self.samples} samples), "
                             f"got {dataset.front_end} taps ({dataset.dims} dims, {dataset.samples} samples)")
        for name in ("location_unit", "identity_unit"):
            if getattr(dataset, name) != getattr(self, name):
                raise ModelError(f"model trained with {name} {getattr(self, name)!r}, got {getattr(dataset, name)!r}")

    def _check_taps(self, taps: np.ndarray, batch: bool) -> np.ndarray:
        taps = np.asarray(taps)
        shape = taps.shape[1:] if batch else taps.shape
        if taps.ndim != (3 if batch else 2) or shape != (self.samples, self.dims):
            expected = "(N, samples, dims)" if batch else "(samples, dims)"
            raise ModelError(f"model trained for {self.front_end} taps of {self.samples} samples x {self.dims} "
                             f"dims; expected {expected}, got shape {taps.shape}")
        return taps

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
    # h(b, k, c): sample counts per class, dimension and bin, in one bincount.
    counts = np.zeros((grid.n_classes, dims, bins))
    for start in range(0, len(dataset), 4096):  # bounded memory for large datasets
        b = grid.bin_index(dataset.taps[start:start + 4096])
        flat = (cls[start:start + 4096, None, None] * dims + np.arange(dims)) * bins + b
        counts += np.bincount(flat.ravel(), minlength=counts.size).reshape(counts.shape)
    # P_k(b|c) = (h(b,k,c) + eps) / sum_b (h(b,k,c) + eps)
    regularised = counts + epsilon
    log_p = np.log(regularised) - np.log(regularised.sum(axis=2, keepdims=True))
    return dataclasses.replace(grid, log_probability=np.ascontiguousarray(log_p.transpose(1, 2, 0), np.float32),
                               taps_per_class=taps_per_class.reshape(n_locations, len(identities)))


def save_model(path, model: HistogramModel, *, inputs=()) -> None:
    """Write a model to an HDF5 file of schema ``tactip-model/1`` atomically (temporary file, fsync, rename).

    Parameters
    ----------
    path : str or os.PathLike
    model : HistogramModel
    inputs : iterable of path
        Files the caller read (e.g. the training dataset): ``path`` must not be one of them.

    Raises
    ------
    OSError
        Disk full or permission denied (named so); ``path`` keeps its old content.
    FileExistsError
        ``path`` is one of ``inputs``.
    """
    path = pathlib.Path(path)
    with atomic_path(path, inputs=inputs) as tmp:
        with hdf5_in_memory(tmp) as f:  # a full disk is an OSError, not a crash inside HDF5
            f.attrs["schema"] = MODEL_SCHEMA
            for name in ("log_probability", "bin_lower", "bin_width", "location_edges", "identities",
                         "taps_per_class"):
                f.create_dataset(name, data=getattr(model, name))
            for name in ("front_end", "location_unit", "identity_unit"):
                f.attrs[name] = getattr(model, name)
            f.attrs["samples"] = model.samples
            f.attrs["epsilon"] = model.epsilon
            f.attrs["dim_names"] = list(model.dim_names)
            f.attrs["sensor"] = json.dumps(model.sensor, sort_keys=True)
            f.attrs["recommended"] = json.dumps(model.recommended, sort_keys=True)


def load_model(path) -> HistogramModel:
    """Read a ``tactip-model/1`` file.

    Parameters
    ----------
    path : str or os.PathLike

    Raises
    ------
    ModelError
        Not HDF5, another schema, or a missing field.
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
        names = ("log_probability", "bin_lower", "bin_width", "location_edges", "identities", "taps_per_class")
        attr_names = ("front_end", "location_unit", "identity_unit", "samples", "epsilon", "dim_names", "sensor",
                      "recommended")
        missing = [n for n in names if n not in f] + [n for n in attr_names if n not in f.attrs]
        if missing:
            raise ModelError(f"{path} misses {', '.join(missing)} (required by {MODEL_SCHEMA})")
        for name in names:
            if not hasattr(f[name], "dtype") or f[name].dtype.kind not in "fiu":
                raise ModelError(f"{path}: {name!r} does not hold numbers")
        arrays = {name: f[name][()] for name in names}
        attrs = {name: str(f.attrs[name]) for name in ("front_end", "location_unit", "identity_unit")}
        try:
            settings = dict(samples=int(f.attrs["samples"]), epsilon=float(f.attrs["epsilon"]),
                            sensor=json.loads(f.attrs["sensor"]), recommended=json.loads(f.attrs["recommended"]))
        except (TypeError, ValueError) as exc:
            raise ModelError(f"{path}: unreadable settings ({exc})") from None
        dim_names = tuple(str(n) for n in np.atleast_1d(f.attrs["dim_names"]))
    _check_model_arrays(path, arrays)
    if not isinstance(settings["recommended"], dict):
        raise ModelError(f"{path}: recommended settings are not a table")
    try:
        return HistogramModel(**arrays, **attrs, dim_names=dim_names, **settings)
    except ModelError as exc:
        raise ModelError(f"{path}: {exc}") from None


def _check_model_arrays(path, arrays: dict) -> None:
    """Refuse a model whose numbers cannot be right (NaN or infinite likelihoods, empty or reversed grids)."""
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
    edges = arrays["location_edges"]
    if len(edges) < 2 or (len(edges) > 2 and not (np.diff(edges) > 0).all()):
        raise ModelError(f"{path}: location_edges must increase (at least 2 edges)")
