"""Histogram measurement model over joint (location, identity) classes (paper 000 eqs. 2-3; 002 eqs. 2-3).

Sensor values of each dimension k are binned into ``bins`` equal intervals spanning the training
range of that dimension; the model holds, for every class c = (x_l, w_i), the regularised
sampling distribution of the bins

    P_k(b | c) = (n_kc(b) + epsilon) / sum_b (n_kc(b) + epsilon)

and the log likelihood of a tap z = {s_k(j)} is the mean log probability over its samples j and
dimensions k (a geometric-mean likelihood, paper 001):

    log P(z | c) = sum_k sum_j log P_k(b_k(j) | c) / (N_samples N_dims)

A missing value s_k(j) (NaN) is marginalised: the dimensions are independent given the class, so
integrating the value out leaves sum_b P_k(b | c) = 1, a term log 1 = 0. The sum runs over the
observed values only and keeps its divisor N_samples N_dims (the model's fixed tempering), so a tap
missing some values is weaker evidence, never stronger; every class is scored on the same observed
values. Training counts the observed values of each dimension; a class without any observed value
of a dimension takes that dimension's counts pooled over all the classes (and a warning,
`perception.likelihood.fit_class_grid`).

Location classes are ``n_locations`` equal bins of the training locations; identity classes are
the distinct training identities (`perception.likelihood.fit_class_grid`). Class c = l * n_identities + i, so a likelihood vector reshapes
to ``(n_locations, n_identities)``.

Example
-------
>>> model = fit_model(train, n_locations=11)           # doctest: +SKIP
>>> model.log_likelihood(tap).shape                    # doctest: +SKIP
(11, 20)
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from .dataset import Dataset
from .errors import DatasetError, ModelError
from .likelihood import LikelihoodModel, fit_class_grid

__all__ = ["DEFAULT_EPSILON", "HistogramModel", "fit_model", "histogram_log_probability"]

#: Regularising count added to every histogram bin (paper 000: epsilon << 1).
DEFAULT_EPSILON = 1e-3
#: Largest regularising count: a million taps' worth in every bin, beyond any collection's counts.
MAX_EPSILON = 1e6
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
    identity_period: float | None = None   # circular identity (e.g. 360 deg), from the training dataset
    identity_names: tuple[str, ...] = ()   # class names of a named identity, from the training dataset
    tap_tempering: tuple[float, ...] = ()  # g_1..g_K on the t-th tap's log likelihood (`perception.bayes.tap_factor`)

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
        self._check_tap_tempering()

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

    def _kind_summary(self) -> str:
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
            NaN where missing.

        Returns
        -------
        (..., dims) intp ndarray in [0, bins)
            Bin 0 for a missing value (mask it with ``~np.isnan(taps)``).
        """
        b = np.floor((np.asarray(taps, dtype=np.float64) - self.bin_lower) / self.bin_width)
        return np.clip(np.nan_to_num(b, nan=0.0), 0, self.bins - 1).astype(np.intp)

    def log_likelihood(self, tap) -> np.ndarray:
        """Mean log likelihood log P(z | x_l, w_i) of one tap against every class (eq. 3).

        Parameters
        ----------
        tap : (samples, dims) array
            NaN where missing: those values' terms are dropped (marginalised).

        Returns
        -------
        (n_locations, n_identities) float64 ndarray
        """
        tap = self._check_taps(tap, batch=False)
        flat = (self.bin_index(tap) + np.arange(self.dims) * self.bins).ravel()
        # One gather of the occupied (dim, bin) rows, weighted by how many observed samples fell in each.
        counts = np.bincount(flat[~np.isnan(tap).ravel()], minlength=self.dims * self.bins)
        rows = np.flatnonzero(counts)
        table = self.log_probability.reshape(self.dims * self.bins, self.n_classes)
        total = counts[rows].astype(np.float32) @ np.take(table, rows, axis=0)
        return (total.astype(np.float64) / flat.size).reshape(self.n_locations, self.n_identities)

    def log_likelihood_batch(self, taps) -> np.ndarray:
        """`log_likelihood` of many taps at once (Monte Carlo precomputation).

        Parameters
        ----------
        taps : (N, samples, dims) array
            NaN where missing: those values' terms are dropped (marginalised).

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
            missing = np.isnan(chunk).ravel()
            if missing.any():  # log P_k(b | c) of a missing value is marginalised to log 1 = 0: no count
                flat = flat[~missing]
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
        Regularising count added to every bin, in (0, `MAX_EPSILON`]: more would drown any count of taps
        (and beyond about 1e300 the probabilities overflow).
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
    if not (np.isfinite(epsilon) and 0 < epsilon <= MAX_EPSILON):
        raise ValueError(f"epsilon must be a number in (0, {MAX_EPSILON:g}], got {epsilon}")
    grid = fit_class_grid(dataset, n_locations=n_locations, min_taps_per_class=min_taps_per_class)
    dims, bins = dataset.dims, int(bins)
    values = dataset.taps.reshape(-1, dims).astype(np.float64)
    # Over the observed values of each dimension (one never observed: any bins, it has no counts).
    low = np.where(np.isnan(values), np.inf, values).min(axis=0)
    high = np.where(np.isnan(values), -np.inf, values).max(axis=0)
    bin_lower = np.where(np.isfinite(low), low, 0.0)
    span = np.where(np.isfinite(high), high - bin_lower, 0.0)
    bin_width = np.where(span > 0, span / bins, 1.0)
    empty = HistogramModel(np.zeros((dims, bins, grid.n_classes), np.float32), bin_lower, bin_width,
                           grid.location_edges, grid.identities, grid.front_end, grid.samples, grid.dim_names,
                           grid.sensor, grid.location_unit, grid.identity_unit, float(epsilon), grid.taps_per_class,
                           identity_period=grid.identity_period, identity_names=grid.identity_names)
    return dataclasses.replace(empty, log_probability=histogram_log_probability(empty, dataset.taps,
                                                                                grid.tap_class(dataset)))


def histogram_log_probability(grid: HistogramModel, taps, tap_class) -> np.ndarray:
    """The regularised histograms log P_k(b | c) of taps on a model's bins and classes (paper 002 eq. 3).

    Parameters
    ----------
    grid : HistogramModel
        Gives the value bins, the classes and epsilon.
    taps : (N, samples, dims) array
        NaN where missing: only observed values are counted.
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
        chunk = taps[start:start + 4096]
        flat = ((tap_class[start:start + 4096, None, None] * dims + np.arange(dims)) * bins
                + grid.bin_index(chunk)).ravel()
        counts += np.bincount(flat[~np.isnan(chunk).ravel()], minlength=counts.size).reshape(counts.shape)
    # A class with taps but no observed value of a dimension: that dimension's counts over all the classes.
    empty = (counts.sum(axis=2) == 0) & (np.bincount(tap_class, minlength=n_classes) > 0)[:, None]
    if empty.any():
        counts = np.where(empty[:, :, None], counts.sum(axis=0, keepdims=True), counts)
    # P_k(b|c) = (h(b,k,c) + eps) / sum_b (h(b,k,c) + eps)
    regularised = counts + grid.epsilon
    log_p = np.log(regularised) - np.log(regularised.sum(axis=2, keepdims=True))
    return np.ascontiguousarray(log_p.transpose(1, 2, 0), np.float32)
