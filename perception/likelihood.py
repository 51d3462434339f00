"""The likelihood interface every measurement model implements, and the class grid they share.

A measurement model gives, for a tap z (samples x dims sensor values), the log likelihood
log P(z | x_l, w_i) of every joint class c = (location l, identity i), c = l * n_identities + i
(papers 000 and 002 eqs. 2-3). The perceiver, the Monte Carlo, the station and replay call only:

- ``log_likelihood(tap)`` -> (n_locations, n_identities) and ``log_likelihood_batch(taps)``;
  a tap may miss values (NaN: the dimensions of a pin unseen during the tap), and every kind then
  gives the likelihood of the values observed, the missing ones marginalised out (integrated over),
  never the tap discarded: all classes are scored on the same observed values, so the posterior
  stays a comparison of like with like;
- the class grid: ``n_locations``, ``n_identities``, ``n_classes``, ``location_edges``,
  ``location_centres``, ``class_width``, ``identities``, ``location_class``, ``identity_class``,
  ``fixation_class``;
- what the taps must be: ``front_end``, ``samples``, ``dims``, ``dim_names``, ``sensor``, units,
  ``check_dataset``;
- the recommended station settings: ``recommended``, ``with_recommended``; and ``summary``;
- the tap tempering schedule ``tap_tempering`` (g_1..g_K, empty: none) that the belief update applies
  to the t-th tap of a decision (`perception.bayes.tap_update`), ``with_tap_tempering``.

`LikelihoodModel` implements everything but the likelihood itself once, for frozen dataclasses
holding the fields ``location_edges, identities, front_end, samples, dim_names, sensor,
location_unit, identity_unit, taps_per_class, recommended`` (and ``tap_tempering``, default empty).
Each kind of model (``KIND``) adds its parameters and how they are stored (`perception.model.save_model` / `load_model`).
`fit_class_grid` derives the classes from a training dataset; every kind is fitted on it.

Kinds: ``histogram`` (the papers' model, `perception.histogram`), ``calibrated-histogram``
(`perception.calibrated`), ``gaussian`` (`perception.gaussian`), ``torch`` (`perception.learned`);
`perception.model` is the registry of kinds and the model file.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from .bayes import check_tap_tempering
from .choices import POLICIES
from .dataset import Dataset
from .errors import DatasetError, ModelError

__all__ = ["LikelihoodModel", "RECOMMENDED_KEYS", "ClassGrid", "fit_class_grid"]

#: Recommended settings a model may carry (written by ``tactip validate --sweep-fixation``).
RECOMMENDED_KEYS = ("decision_threshold", "fixation_location", "policy")


class LikelihoodModel:
    """Base of every measurement model: the class grid, tap checks and recommended settings.

    Subclasses are frozen dataclasses; they implement `log_likelihood_batch` and set ``KIND``.
    """

    #: Name of the kind of model, stored in the model file (``tactip train --model NAME``).
    KIND = ""

    # -- the likelihood (subclasses) -------------------------------------------------------
    def log_likelihood_batch(self, taps) -> np.ndarray:
        """log P(z | x_l, w_i) of many taps against every class.

        Parameters
        ----------
        taps : (N, samples, dims) array
            NaN where a value is missing (marginalised out).

        Returns
        -------
        (N, n_locations, n_identities) float64 ndarray
        """
        raise NotImplementedError

    def log_likelihood(self, tap) -> np.ndarray:
        """log P(z | x_l, w_i) of one tap against every class.

        Parameters
        ----------
        tap : (samples, dims) array
            NaN where a value is missing (marginalised out).

        Returns
        -------
        (n_locations, n_identities) float64 ndarray
        """
        tap = self._check_taps(tap, batch=False)
        return self.log_likelihood_batch(tap[None])[0]

    # -- description -----------------------------------------------------------------------
    @property
    def dims(self) -> int:
        """Data dimensions per sample."""
        return len(self.dim_names)

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

    @property
    def shift_mode(self) -> str:
        """The belief-shift convention of the model's front end (see `perception.bayes.shift`).

        ``"uniform"`` for the taxel front end (paper 000 eq. 8: the classes shifted in from outside
        the range are filled uniformly), ``"edge"`` for the TacTip (paper 002: the edge class is
        replicated).
        """
        return "uniform" if self.front_end == "taxel" else "edge"

    def identity_label(self, index) -> str:
        """How identity class ``index`` is shown: its name, or its value and unit (``"45 deg"``)."""
        if self.identity_names:
            return self.identity_names[int(self.identities[index])]
        return f"{self.identities[index]:g} {self.identity_unit}"

    def identity_error(self, decided, true) -> np.ndarray:
        """|decided - true| between identity values, identity units: wrapped for a circular identity
        (``identity_period``), 0 or 1 (wrong) for a named one.

        Parameters
        ----------
        decided, true : arrays of identity values (not class indices)
        """
        decided, true = np.asarray(decided, np.float64), np.asarray(true, np.float64)
        if self.identity_names:
            return (decided != true).astype(np.float64)
        error = np.abs(decided - true)
        if self.identity_period is not None:
            error = error % self.identity_period
            error = np.minimum(error, self.identity_period - error)
        return error

    def _grid_summary(self) -> str:
        lo, hi = self.location_edges[0], self.location_edges[-1]
        if self.identity_names:
            shown = ", ".join(self.identity_names[:6]) + (", ..." if len(self.identity_names) > 6 else "")
            identities = f"({shown})"
        else:
            period = f", period {self.identity_period:g}" if self.identity_period is not None else ""
            identities = f"({self.identities.min():g}..{self.identities.max():g} {self.identity_unit}{period})"
        return (f"{self.front_end} model: {self.n_classes} classes = {self.n_locations} locations "
                f"({lo:g}..{hi:g} {self.location_unit}) x {self.n_identities} identities "
                f"{identities}; taps of {self.samples} samples x {self.dims} dims")

    def _kind_summary(self) -> str:
        """What `summary` says of the kind (each kind its own)."""
        return f"{self._grid_summary()}; {self.KIND} likelihood"

    def summary(self) -> str:
        """One line: kind, front end, class grid, tap shape, and the tap tempering schedule if any."""
        schedule = ""
        if self.tap_tempering:
            schedule = "; tap tempering " + ", ".join(f"{g:.3g}" for g in self.tap_tempering) + " (taps 1, 2, ...)"
        return self._kind_summary() + schedule

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.summary()}>"

    @property
    def temperable(self) -> bool:
        """Whether the kind has a fitted tempering beta (every kind but the papers' histogram model)."""
        return any(f.name == "tempering" for f in dataclasses.fields(self))

    def tempered(self, factor: float):
        """A copy whose log likelihood is ``factor`` times this one's (its tempering beta times ``factor``).

        Parameters
        ----------
        factor : float > 0

        Raises
        ------
        ModelError
            The kind has no tempering (the papers' histogram model is kept as it is).
        """
        if not self.temperable:
            raise ModelError(f"a {self.KIND} model has no tempering to refit; train a calibrated kind "
                             f"(tactip train --model gaussian)")
        if not (np.isfinite(factor) and factor > 0):
            raise ValueError(f"factor must be a finite number > 0, got {factor!r}")
        return dataclasses.replace(self, tempering=float(self.tempering * factor))

    def with_tap_tempering(self, schedule):
        """A copy whose t-th tap of a decision has its log likelihood multiplied by g_t.

        Parameters
        ----------
        schedule : sequence of float
            (g_1, ..., g_K), each finite and > 0; taps beyond K take g_K; empty: no tap tempering.
            (`perception.reliability.fit_tap_tempering` fits one.)
        """
        return dataclasses.replace(self, tap_tempering=tuple(schedule))

    def _check_tap_tempering(self) -> None:
        """The tap tempering schedule is finite numbers > 0, stored as a tuple of floats."""
        try:
            object.__setattr__(self, "tap_tempering", check_tap_tempering(self.tap_tempering))
        except ValueError as exc:
            raise ModelError(str(exc)) from None

    def with_recommended(self, **settings):
        """A copy of the model with some recommended settings replaced.

        Parameters
        ----------
        **settings
            ``decision_threshold`` (float), ``fixation_location`` (float, location units), ``policy`` (str).
        """
        return dataclasses.replace(self, recommended={**self.recommended, **settings})

    def _check_recommended(self) -> None:
        """Each recommended setting is a number in its range, as a station file's key would be."""
        unknown = set(self.recommended) - set(RECOMMENDED_KEYS)
        if unknown:
            raise ModelError(f"unknown recommended settings {sorted(unknown)}; choose from {RECOMMENDED_KEYS}")
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
        if policy is not None and policy not in POLICIES:
            raise ModelError(f"recommended policy must be one of {', '.join(POLICIES)}, got {policy!r}")

    # -- class grid ------------------------------------------------------------------------
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

    def tap_class(self, dataset: Dataset) -> np.ndarray:
        """Joint class l * n_identities + i of every tap of a dataset.

        Parameters
        ----------
        dataset : Dataset

        Returns
        -------
        (N,) intp ndarray
        """
        return self.location_class(dataset.location) * self.n_identities + self.identity_class(dataset.identity)

    # -- compatibility ---------------------------------------------------------------------
    def check_dataset(self, dataset: Dataset) -> None:
        """Raise ModelError if the dataset's taps are not the kind this model was trained on.

        Parameters
        ----------
        dataset : Dataset
        """
        if (dataset.front_end, dataset.dims, dataset.samples) != (self.front_end, self.dims, self.samples):
            raise ModelError(f"model trained for {self.front_end} ({self.dims} dims, {self.samples} samples), "
                             f"got {dataset.front_end} taps ({dataset.dims} dims, {dataset.samples} samples)")
        for name in ("location_unit", "identity_unit", "identity_period", "identity_names"):
            if getattr(dataset, name) != getattr(self, name):
                raise ModelError(f"model trained with {name} {getattr(self, name)!r}, got {getattr(dataset, name)!r}")

    def _check_taps(self, taps, batch: bool) -> np.ndarray:
        taps = np.asarray(taps)
        shape = taps.shape[1:] if batch else taps.shape
        if taps.ndim != (3 if batch else 2) or shape != (self.samples, self.dims):
            expected = "(N, samples, dims)" if batch else "(samples, dims)"
            raise ModelError(f"model trained for {self.front_end} taps of {self.samples} samples x {self.dims} "
                             f"dims; expected {expected}, got shape {taps.shape}")
        return taps

    # -- storage (subclasses) --------------------------------------------------------------
    def _stored(self) -> tuple[dict, dict]:
        """(arrays, attributes) of the kind's own parameters, for the model file."""
        return {}, {}

    @classmethod
    def _from_stored(cls, common: dict, arrays: dict, attrs: dict):
        """The model from the common grid fields and the kind's stored parameters."""
        raise NotImplementedError


@dataclass(frozen=True, repr=False)
class ClassGrid(LikelihoodModel):
    """The classes of a training dataset and the taps they hold, without a likelihood (build with `fit_class_grid`).

    Every kind of model is fitted on one: it gives the (location, identity) classes, the tap
    description and the training taps per class, which the kind's constructor copies.

    Attributes
    ----------
    location_edges : (n_locations + 1,) float64 ndarray
        Edges of the equal location classes, in ``location_unit``.
    identities : (n_identities,) float64 ndarray
        Identity of each identity class, in ``identity_unit``.
    front_end, samples, dim_names, sensor, location_unit, identity_unit
        The training dataset's.
    taps_per_class : (n_locations, n_identities) int ndarray
        Training taps in each class.
    recommended : dict
        Empty: a grid has no settings to recommend.
    """

    location_edges: np.ndarray
    identities: np.ndarray
    front_end: str
    samples: int
    dim_names: tuple[str, ...]
    sensor: dict
    location_unit: str
    identity_unit: str
    taps_per_class: np.ndarray
    recommended: dict = field(default_factory=dict)
    identity_period: float | None = None   # circular identity (e.g. 360 deg), from the training dataset
    identity_names: tuple[str, ...] = ()   # class names of a named identity, from the training dataset
    tap_tempering: tuple[float, ...] = ()  # g_1..g_K on the t-th tap's log likelihood (`perception.bayes.tap_factor`)

    def __post_init__(self):
        self._check_tap_tempering()

    def _kind_summary(self) -> str:
        """Front end, class grid, tap shape."""
        return self._grid_summary()


def fit_class_grid(dataset: Dataset, *, n_locations: int = 11, min_taps_per_class: int = 1) -> ClassGrid:
    """The (location, identity) classes of a training dataset, every class checked to hold enough taps.

    Location classes are ``n_locations`` equal bins spanning the training locations (one class when
    the dataset has a single location); identity classes are the distinct training identities.

    Parameters
    ----------
    dataset : Dataset
        Training taps.
    n_locations : int
        Number of equal location classes (paper 002: 11).
    min_taps_per_class : int
        Fewest training taps a (location, identity) class may have.

    Returns
    -------
    ClassGrid

    Raises
    ------
    DatasetError
        Not a dataset, no taps, or a class has fewer than `min_taps_per_class` taps (the message names it).
    ValueError
        A knob is out of range (the message names it).
    """
    if not isinstance(dataset, Dataset):
        raise DatasetError(f"dataset must be a Dataset, got {type(dataset).__name__}")
    for name, value in (("n_locations", n_locations), ("min_taps_per_class", min_taps_per_class)):
        if int(value) != value or value < 1:
            raise ValueError(f"{name} must be an integer >= 1, got {value}")
    if len(dataset) == 0:
        raise DatasetError("dataset has no taps")
    lo, hi = float(dataset.location.min()), float(dataset.location.max())
    n_locations = int(n_locations) if hi > lo else 1
    identities = np.unique(dataset.identity)
    grid = ClassGrid(np.linspace(lo, hi, n_locations + 1), identities, dataset.front_end, dataset.samples,
                     dataset.dim_names, dataset.sensor, dataset.location_unit, dataset.identity_unit,
                     np.zeros((n_locations, len(identities)), np.int64), identity_period=dataset.identity_period,
                     identity_names=dataset.identity_names)
    taps_per_class = np.bincount(grid.tap_class(dataset), minlength=grid.n_classes)
    few = np.flatnonzero(taps_per_class < min_taps_per_class)
    if few.size:
        l, i = divmod(int(few[0]), len(identities))
        raise DatasetError(f"{few.size} of {grid.n_classes} classes have fewer than {min_taps_per_class} training "
                           f"taps, e.g. location {grid.location_centres[l]:g} {dataset.location_unit}, identity "
                           f"{identities[i]:g} {dataset.identity_unit} has {taps_per_class[few[0]]}; "
                           f"use fewer location classes")
    _warn_unobserved(grid, dataset)
    return dataclasses.replace(grid, taps_per_class=taps_per_class.reshape(n_locations, len(identities)))


def _warn_unobserved(grid: ClassGrid, dataset: Dataset) -> None:
    """Warn when a dimension has no observed value among the training taps of some class.

    Such a class has nothing to learn that dimension's distribution from; every kind then uses what
    all the classes' taps say of it (the histogram counts pooled over the classes, the Gaussian's
    overall mean, the network's imputation), so a tap's value there neither favours nor rules out
    that class much. Taps of that class where the pin is seen are the cure.
    """
    if dataset.complete:
        return
    observed = (~np.isnan(dataset.taps)).any(axis=1).astype(np.int64)          # (N, dims)
    per_class = np.zeros((grid.n_classes, dataset.dims), np.int64)
    np.add.at(per_class, grid.tap_class(dataset), observed)
    never = np.argwhere(per_class == 0)
    if not never.size:
        return
    import warnings

    c, k = never[0]
    l, i = divmod(int(c), grid.n_identities)
    warnings.warn(f"{len(never)} class and dimension pair(s) have no observed value in the training taps (e.g. "
                  f"{dataset.dim_names[k]} at location {grid.location_centres[l]:g} {dataset.location_unit}, identity "
                  f"{grid.identities[i]:g} {dataset.identity_unit}); those classes use the dimension's distribution "
                  f"over all classes: collect taps of them in which the pin is seen", stacklevel=3)
