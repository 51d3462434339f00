"""Simple baselines on the same tap features as a likelihood model: does the Bayesian model earn its keep?

A user with labelled recordings wants to know at once whether the project's model is worth its
machinery. The well-kept standard answer is scikit-learn's simple learners, fitted on the same
training taps and scored on the same test taps:

- ``knn``: k-nearest neighbours voting among the label classes, k chosen by cross-validation on
  the training taps (the lowest label error);
- ``logistic``: (multinomial) logistic regression over the label classes, its inverse
  regularisation C chosen by cross-validation the same way;
- ``ridge``: ridge regression of a numeric label (of ``(cos, sin)`` of a circular label, the
  angle then taken back with ``atan2``), its alpha chosen by leave-one-out, its estimate snapped to
  the nearest label class; none for a named label.

Every baseline thus decides one of the label classes, as the model does: the errors compare like
with like (snapping also makes ridge the stronger baseline when its estimates scatter by less than
a class spacing, the usual case).

Features: every tap flattened to one row of ``samples x dims`` values, NaN (a pin unseen during
the tap) imputed with the training mean of that column (`sklearn.impute.SimpleImputer`; a column
never observed in the training taps is dropped), then standardised.

The label is what the model decides: the identity, or the location (class centres) of a model
with a single identity. Errors are in the label's unit, circular for a label with a period (315
and 0 deg are 45 deg apart), and 0 or 1 (wrong) for a named label, so that its mean error is the
fraction wrong. Means weigh each true class equally (as the Monte Carlo validation draws its classes).

The model's own 1-tap figures (`one_tap`) are exact: its decision on every test tap from the flat
prior (the first tap of any policy), on the same taps as the baselines. `keep_verdict` then says
whether the model is worse than the best baseline at 1 tap (by more than 5 %) and whether its
decisions at a threshold (0.9) are well below the best baseline's 1-tap error (at most 0.75x).

Example
-------
>>> report = compare_baselines(model, train, test, seed=0)             # doctest: +SKIP
>>> [(b.name, round(b.error, 3)) for b in report.baselines]              # doctest: +SKIP
[('knn', 0.412), ('logistic', 0.388), ('ridge', 0.301)]
"""

from __future__ import annotations

import contextlib
import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy.special import logsumexp

from .dataset import Dataset
from .errors import DatasetError
from .likelihood import LikelihoodModel

__all__ = ["BASELINES", "BaselineResult", "BaselineReport", "KeepVerdict", "tap_features", "task_labels",
           "label_error", "one_tap", "fit_baselines", "compare_baselines", "keep_verdict"]

#: The baselines, in the order they are reported.
BASELINES = ("knn", "logistic", "ridge")
#: Candidate k of the nearest-neighbour baseline (those below the size of a cross-validation training fold).
KNN_NEIGHBOURS = (1, 3, 5, 9, 15, 25)
#: Candidate inverse regularisation strengths C of the logistic baseline.
LOGISTIC_C = (1e-4, 1e-3, 0.01, 0.1, 1.0)
#: Candidate alphas of the ridge baseline (leave-one-out picks one).
RIDGE_ALPHAS = tuple(np.logspace(-4, 4, 17))
#: Cross-validation folds (fewer when a class has fewer training taps).
FOLDS = 5
#: The project's 1-tap error may exceed the best baseline's by this fraction before it is called worse.
ONE_TAP_TOLERANCE = 0.05
#: Decisions at the threshold should make at most this fraction of the best baseline's 1-tap error.
THRESHOLD_RATIO = 0.75


@dataclass(frozen=True)
class BaselineResult:
    """The 1-tap figures of one baseline on the test taps.

    Attributes
    ----------
    name : str
        ``"knn"``, ``"logistic"`` or ``"ridge"``.
    error : float
        Mean label error (label units; the fraction wrong for a named label), classes weighed equally.
    accuracy : float
        Fraction of test taps whose class is right, classes weighed equally.
    settings : dict
        What cross-validation chose (``{"k": 5}``, ``{"C": 0.1}``, ``{"alpha": 10.0}``).
    predicted : (T,) ndarray
        Label value (one of the classes') decided for each test tap.
    """

    name: str
    error: float
    accuracy: float
    settings: dict = field(default_factory=dict)
    predicted: np.ndarray = field(default=None, repr=False)


@dataclass(frozen=True)
class BaselineReport:
    """Baselines and the model's own 1-tap figures on the same test taps.

    Attributes
    ----------
    baselines : tuple of BaselineResult
    model_error, model_accuracy : float
        The model's exact 1-tap label error and accuracy (see `one_tap`).
    label_unit : str
        Unit of the errors (``"none"`` for a named label, whose error is the fraction wrong).
    period : float or None
        Period of a circular label.
    named : bool
        Whether the label is named (its errors are 0 or 1).
    """

    baselines: tuple
    model_error: float
    model_accuracy: float
    label_unit: str
    period: float | None
    named: bool

    @property
    def best(self) -> BaselineResult:
        """The baseline with the lowest 1-tap error (ties: the higher accuracy)."""
        return min(self.baselines, key=lambda b: (b.error, -b.accuracy))


@dataclass(frozen=True)
class KeepVerdict:
    """Whether a model earns its keep against the best baseline.

    Attributes
    ----------
    one_tap_ratio : float
        Model's 1-tap error / best baseline's 1-tap error (inf when the baseline is exact and the model is not,
        1 when both are).
    worse_at_one_tap : bool
        The ratio exceeds ``1 + ONE_TAP_TOLERANCE``.
    threshold_ratio : float or None
        Error of the decisions at the threshold / best baseline's 1-tap error (None: not measured).
    well_below_at_threshold : bool or None
        That ratio is at most ``THRESHOLD_RATIO`` (None: not measured).
    """

    one_tap_ratio: float
    worse_at_one_tap: bool
    threshold_ratio: float | None
    well_below_at_threshold: bool | None


def tap_features(taps) -> np.ndarray:
    """Every tap flattened to one feature row (NaN kept: the baselines impute it).

    Parameters
    ----------
    taps : (N, samples, dims) array

    Returns
    -------
    (N, samples * dims) float64 ndarray
    """
    taps = np.asarray(taps, dtype=np.float64)
    if taps.ndim != 3:
        raise ValueError(f"taps must have shape (N, samples, dims), got {taps.shape}")
    return taps.reshape(len(taps), -1)


def task_labels(model: LikelihoodModel, dataset: Dataset) -> tuple[np.ndarray, np.ndarray]:
    """The label the model decides, for every tap of a dataset: its value and its class.

    Parameters
    ----------
    model : LikelihoodModel
    dataset : Dataset
        Taps of the model's classes (`LikelihoodModel.check_dataset`).

    Returns
    -------
    values : (N,) float64 ndarray
        Identity of each tap, or the centre of its location class for a model with one identity.
    classes : (N,) intp ndarray
        Index of that value among the model's identities (location classes).
    """
    model.check_dataset(dataset)
    if model.n_identities > 1:
        classes = model.identity_class(dataset.identity)
        return model.identities[classes], classes
    classes = model.location_class(dataset.location)
    return model.location_centres[classes], classes


def _label_values(model: LikelihoodModel) -> np.ndarray:
    """(K,) the values of the label classes the model decides among."""
    return model.identities if model.n_identities > 1 else model.location_centres


def _label_kind(model: LikelihoodModel) -> tuple[str, float | None, bool]:
    """(unit, period, named) of the label the model decides."""
    if model.n_identities > 1:
        return model.identity_unit, model.identity_period, bool(model.identity_names)
    return model.location_unit, None, False


def label_error(decided, true, *, period: float | None = None, named: bool = False) -> np.ndarray:
    """|decided - true| between label values: wrapped for a circular label, 0 or 1 for a named one.

    Parameters
    ----------
    decided, true : arrays of label values (broadcast together)
    period : float, optional
        Period of a circular label (e.g. 360 deg): the error goes the shorter way round.
    named : bool
        A named label: the error is 1 where the classes differ, else 0.

    Returns
    -------
    float64 ndarray, label units

    Examples
    --------
    >>> label_error([315.0, 10.0], [0.0, 350.0], period=360).tolist()
    [45.0, 20.0]
    """
    decided, true = np.asarray(decided, np.float64), np.asarray(true, np.float64)
    if named:
        return (decided != true).astype(np.float64)
    error = np.abs(decided - true)
    if period is not None:
        error = error % period
        error = np.minimum(error, period - error)
    return error


def _class_weights(classes: np.ndarray) -> np.ndarray:
    """(N,) weights that make each class's taps count as much as any other class's, summing to 1."""
    _, inverse, counts = np.unique(classes, return_inverse=True, return_counts=True)
    return 1.0 / (counts[inverse] * len(counts))


def one_tap(model: LikelihoodModel, test: Dataset, *, log_likelihood=None) -> tuple[np.ndarray, float, float]:
    """The model's decision on every test tap alone, from the flat prior (the first tap of any policy).

    Parameters
    ----------
    model : LikelihoodModel
    test : Dataset
    log_likelihood : (T, L * I) array, optional
        The test taps' log likelihoods, if already computed (`VirtualEnvironment.log_likelihood`).

    Returns
    -------
    decided : (T,) ndarray
        The decided label value of each test tap (the most likely marginal class).
    error : float
        Mean label error, classes weighed equally.
    accuracy : float
        Fraction decided right, classes weighed equally.
    """
    true, classes = task_labels(model, test)
    if log_likelihood is None:
        log_likelihood = model.log_likelihood_batch(test.taps)
    table = np.asarray(log_likelihood, np.float64).reshape(len(test), model.n_locations, model.n_identities)
    # From the flat prior the posterior after one tap is the normalised likelihood; the marginal sums the other.
    if model.n_identities > 1:
        decided_class = logsumexp(table, axis=1).argmax(axis=1)
    else:
        decided_class = logsumexp(table, axis=2).argmax(axis=1)
    decided = _label_values(model)[decided_class]
    _, period, named = _label_kind(model)
    weights = _class_weights(classes)
    error = float(weights @ label_error(decided, true, period=period, named=named))
    return decided, error, float(weights @ (decided_class == classes))


def _folds(classes: np.ndarray, seed: int):
    """Stratified folds when every class has 2 or more training taps, else plain shuffled folds."""
    from sklearn.model_selection import KFold, StratifiedKFold

    counts = np.bincount(classes)
    counts = counts[counts > 0]
    if counts.min() >= 2:
        return StratifiedKFold(n_splits=int(min(FOLDS, counts.min())), shuffle=True, random_state=seed)
    return KFold(n_splits=int(min(FOLDS, len(classes))), shuffle=True, random_state=seed)


def _preprocess():
    """Impute NaN with the training column mean, then standardise (the first two steps of every baseline)."""
    from sklearn.impute import SimpleImputer
    from sklearn.preprocessing import StandardScaler

    return [("impute", SimpleImputer(strategy="mean")), ("scale", StandardScaler())]


def fit_baselines(features, classes, values, *, period: float | None = None, named: bool = False,
                  seed: int = 0) -> dict:
    """Fit every baseline of the label on training features, their settings chosen by cross-validation.

    Parameters
    ----------
    features : (N, F) array
        Training taps, one row each (`tap_features`); NaN where unseen.
    classes : (N,) int array
        Label class of each training tap (index into `values`).
    values : (K,) array
        Label value of each class.
    period : float, optional
        Period of a circular label.
    named : bool
        A named label (no ridge regression).
    seed : int
        Seed of the cross-validation folds.

    Returns
    -------
    dict
        Name -> ``(predict, settings)``: ``predict(features)`` gives the label value (one of
        `values`) decided for each test row; ``settings`` what cross-validation chose.

    Raises
    ------
    DatasetError
        Fewer than two label classes, or fewer than two training taps.
    """
    features = np.asarray(features, np.float64)
    classes = np.asarray(classes, np.intp)
    values = np.asarray(values, np.float64)
    if len(np.unique(classes)) < 2 or len(classes) < 2:
        raise DatasetError(f"baselines need training taps of two or more label classes, got {len(classes)} taps of "
                           f"{len(np.unique(classes))} class(es)")
    with _quiet_imputer():
        return _fit(features, classes, values, period=period, named=named, folds=_folds(classes, seed))


@contextlib.contextmanager
def _quiet_imputer():
    """Silence the imputer's notice that it drops a column never observed (in the training taps or a fold of them)."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Skipping features without any observed values")
        yield


def _fit(features, classes, values, *, period, named, folds) -> dict:
    """`fit_baselines` on checked arrays."""
    from sklearn.linear_model import LogisticRegression, RidgeCV
    from sklearn.model_selection import GridSearchCV
    from sklearn.neighbors import KNeighborsClassifier
    from sklearn.pipeline import Pipeline

    def score(estimator, x, y):  # higher is better: minus the label error of the decided classes
        return -label_error(values[estimator.predict(x)], values[y], period=period, named=named).mean()

    fitted = {}
    fold_size = len(classes) - -(-len(classes) // folds.get_n_splits())   # smallest training fold
    ks = [k for k in KNN_NEIGHBOURS if k <= fold_size] or [1]
    for name, step, grid in (("knn", KNeighborsClassifier(), {"n_neighbors": ks}),
                             ("logistic", LogisticRegression(max_iter=2000), {"C": list(LOGISTIC_C)})):
        search = GridSearchCV(Pipeline([*_preprocess(), (name, step)]),
                              {f"{name}__{key}": choices for key, choices in grid.items()}, scoring=score, cv=folds)
        search.fit(features, classes)
        settings = {("k" if key == "n_neighbors" else key): value for key, value in
                    ((k.split("__")[1], v) for k, v in search.best_params_.items())}
        fitted[name] = (lambda x, e=search.best_estimator_: values[e.predict(np.asarray(x, np.float64))], settings)
    if not named:
        target = values[classes]
        if period is not None:   # regress the point on the circle, not the angle that jumps at the wrap
            angle = 2 * np.pi * target / period
            target = np.stack([np.cos(angle), np.sin(angle)], axis=1)
        ridge = Pipeline([*_preprocess(), ("ridge", RidgeCV(alphas=RIDGE_ALPHAS))]).fit(features, target)

        def predict(x, ridge=ridge):
            estimate = ridge.predict(np.asarray(x, np.float64))
            if period is not None:
                estimate = (np.arctan2(estimate[:, 1], estimate[:, 0]) * period / (2 * np.pi)) % period
            return values[label_error(estimate[:, None], values, period=period).argmin(axis=1)]   # nearest class

        fitted["ridge"] = (predict, {"alpha": float(ridge[-1].alpha_)})
    return fitted


def compare_baselines(model: LikelihoodModel, train: Dataset, test: Dataset, *, seed: int = 0,
                      log_likelihood=None) -> BaselineReport:
    """Fit the baselines on the training taps and score them, and the model's first tap, on the test taps.

    Parameters
    ----------
    model : LikelihoodModel
        The model whose label (identity, or location for a single identity) the baselines predict.
    train, test : Dataset
        The model's training taps and the independent test taps (both checked against the model).
    seed : int
        Seed of the cross-validation folds.
    log_likelihood : (T, L * I) array, optional
        The test taps' log likelihoods under the model, if already computed.

    Returns
    -------
    BaselineReport
    """
    values = _label_values(model)
    _, train_classes = task_labels(model, train)
    true, test_classes = task_labels(model, test)
    unit, period, named = _label_kind(model)
    from threadpoolctl import threadpool_limits

    # One BLAS and OpenMP thread: these are small problems (hundreds to thousands of taps), on which threads
    # only spin; on a busy machine they made the fits 10-30x slower.
    with threadpool_limits(limits=1), _quiet_imputer():
        fitted = fit_baselines(tap_features(train.taps), train_classes, values, period=period, named=named, seed=seed)
        features = tap_features(test.taps)
        predictions = {name: predict(features) for name, (predict, _) in fitted.items()}
    weights = _class_weights(test_classes)
    results = []
    for name in BASELINES:
        if name not in fitted:
            continue
        predicted = predictions[name]
        settings = fitted[name][1]
        error = label_error(predicted, true, period=period, named=named)
        results.append(BaselineResult(name, float(weights @ error), float(weights @ (predicted == true)), settings,
                                      predicted))
    _, error, accuracy = one_tap(model, test, log_likelihood=log_likelihood)
    return BaselineReport(tuple(results), error, accuracy, unit, period, named)


def keep_verdict(model_error: float, best_error: float, threshold_error: float | None = None, *,
                 tolerance: float = ONE_TAP_TOLERANCE, ratio: float = THRESHOLD_RATIO) -> KeepVerdict:
    """Compare a model's errors with the best baseline's 1-tap error.

    Parameters
    ----------
    model_error : float
        The model's 1-tap label error.
    best_error : float
        The best baseline's 1-tap label error.
    threshold_error : float, optional
        The error of the model's decisions at a decision threshold (e.g. 0.9).
    tolerance : float
        The model is worse at 1 tap when its error exceeds ``(1 + tolerance) x best_error``.
    ratio : float
        Its decisions are well below when ``threshold_error <= ratio x best_error``.

    Returns
    -------
    KeepVerdict

    Examples
    --------
    >>> keep_verdict(0.42, 0.40, 0.20)
    KeepVerdict(one_tap_ratio=1.05, worse_at_one_tap=False, threshold_ratio=0.5, well_below_at_threshold=True)
    """
    def divide(a, b):
        return float(a / b) if b > 0 else (1.0 if a <= 0 else float("inf"))   # both exact: level

    one = divide(model_error, best_error)
    worse = bool(model_error > (1 + tolerance) * best_error + 1e-12)
    if threshold_error is None:
        return KeepVerdict(round(one, 12), worse, None, None)
    below = bool(threshold_error <= ratio * best_error + 1e-12)
    return KeepVerdict(round(one, 12), worse, round(divide(threshold_error, best_error), 12), below)
