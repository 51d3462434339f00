"""Class-conditional Gaussians on whitened principal components (kind ``gaussian``): linear discriminants.

The histogram model treats every sample of every pin as independent given the class; the taps'
values are strongly correlated (neighbouring pins move together, samples of one tap follow one
profile). This model captures that correlation:

1. a tap z (samples x dims) is flattened to x (samples * dims values) and projected on the
   ``n_components`` leading principal components of the training taps;
2. every class c has a mean m_c there, and all classes share one covariance S, estimated from the
   within-class residuals and shrunk towards its average variance (weight ``shrinkage``);
3. the components are whitened by S, so the log likelihood is a tempered squared distance

       log P(z | c) = -beta / 2 || W (x - mu) - m_c ||^2   (+ a constant shared by all classes),

   with beta fitted on held-out taps like the calibrated histogram's (`perception.tempering`).

The number of components and the shrinkage are chosen by the same cross-validation (lowest held-out
log loss of the one-tap decision posterior) among a few candidates.

Missing values (NaN: the dimensions of a pin unseen during the tap) are marginalised. A projection on
the components mixes every value of the tap, so the missing ones cannot just be dropped; instead the
model is read as a Gaussian over the tap's values in the original space: class mean
mu + Q diag(lambda)^(1/2) m_c (Q the whitened components' directions, lambda their within-class
variances) and shared covariance Q diag(lambda) Q^T + sigma^2 (I - Q Q^T), sigma^2 the within-class
variance per value left outside the components (``residual_variance``). The likelihood of a tap
missing values is that of its observed values x_O under the marginal N(mu_c,O, Sigma_OO):

    log P(z | c) = -beta / 2 (m_c - z_O)^T G_O (m_c - z_O)   (+ a constant shared by all classes),

G_O = lambda^(1/2) Q_O^T Sigma_OO^{-1} Q_O lambda^(1/2) and z_O = G_O^{-1} lambda^(1/2) Q_O^T
Sigma_OO^{-1} (x_O - mu_O), computed in the components' space, one small solve per missing pattern
(`perception.marginal`). With nothing missing G_O = I and z_O is the whitened tap: the formula above.
Training imputes a missing value by the mean of that value over its class's observed taps (the
components and covariance are fitted on the filled taps); held-out taps keep their NaN and are
scored by the marginal. A value a class never observed is filled by its mean over all the classes'
taps (one never observed at all by 0: constant, it has no weight on the components).

Example
-------
>>> model = fit_gaussian(train, n_locations=11)     # doctest: +SKIP
>>> model.log_likelihood(tap).shape                 # doctest: +SKIP
(11, 20)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .dataset import Dataset
from .errors import DatasetError, ModelError
from .likelihood import LikelihoodModel, fit_class_grid
from .marginal import LowRankGaussian
from .tempering import check_tempering, cross_validation_folds, decision_log_loss, fit_tempering

__all__ = ["GaussianModel", "fit_gaussian", "COMPONENT_CHOICES", "SHRINKAGE_CHOICES"]

#: Candidate numbers of principal components and covariance shrinkages tried by cross-validation.
COMPONENT_CHOICES = (8, 16, 32, 64)
SHRINKAGE_CHOICES = (0.1, 0.3, 0.7)
_BATCH = 1024  # taps per chunk in the batch likelihood


@dataclass(frozen=True, repr=False)
class GaussianModel(LikelihoodModel):
    """Shared-covariance Gaussians over whitened principal components of the tap (build with `fit_gaussian`).

    Attributes
    ----------
    mean : (samples * dims,) float64 ndarray
        Mean training tap, flattened (sensor units).
    transform : (samples * dims, K) float64 ndarray
        Projection on the principal components followed by whitening by the shared covariance.
    class_means : (classes, K) float64 ndarray
        Whitened mean of each class, c = l * n_identities + i.
    tempering : float
        beta > 0 applied to the Gaussian log likelihood.
    shrinkage : float
        Weight of the average variance in the shared covariance, [0, 1].
    folds : int
        Cross-validation folds of the fit.
    residual_variance : float
        sigma^2 > 0, within-class variance per value outside the components (sensor units squared),
        used to marginalise missing values; NaN in a model file written before it was stored (such
        a model scores complete taps only).
    location_edges, identities, front_end, samples, dim_names, sensor, location_unit, identity_unit,
    taps_per_class, recommended
        As for `perception.HistogramModel`.
    """

    mean: np.ndarray
    transform: np.ndarray
    class_means: np.ndarray
    tempering: float
    shrinkage: float
    folds: int
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
    residual_variance: float = float("nan")

    KIND = "gaussian"
    _ARRAYS = ("mean", "transform", "class_means")
    _ATTRS = ("tempering", "shrinkage", "folds", "residual_variance")
    _OPTIONAL = {"residual_variance": float("nan")}  # absent from files written before marginalisation

    def __post_init__(self):
        values = self.samples * len(self.dim_names)
        k = self.transform.shape[1] if self.transform.ndim == 2 else -1
        if self.mean.shape != (values,) or self.transform.shape != (values, k) or k < 1:
            raise ModelError(f"mean and transform must be ({values},) and ({values}, K) for taps of {self.samples} "
                             f"samples x {len(self.dim_names)} dims, got {self.mean.shape} and {self.transform.shape}")
        if self.class_means.shape != (self.n_classes, k):
            raise ModelError(f"class_means must be ({self.n_classes}, {k}), got {self.class_means.shape}")
        if not (np.isfinite(self.tempering) and self.tempering > 0):
            raise ModelError(f"tempering must be a finite number > 0, got {self.tempering!r}")
        self._check_recommended()
        self._check_tap_tempering()

    @property
    def n_components(self) -> int:
        """Principal components K."""
        return self.transform.shape[1]

    def _kind_summary(self) -> str:
        """One line: front end, class grid, tap shape, components, tempering."""
        return (f"{self._grid_summary()}; gaussian on {self.n_components} whitened components "
                f"(shrinkage {self.shrinkage:g}), tempering {self.tempering:.4g}")

    def log_likelihood_batch(self, taps) -> np.ndarray:
        """Tempered Gaussian log likelihood of many taps against every class (up to a shared constant).

        Parameters
        ----------
        taps : (N, samples, dims) array
            NaN where missing: marginalised (the likelihood of the observed values).

        Returns
        -------
        (N, n_locations, n_identities) float64 ndarray

        Raises
        ------
        ModelError
            A tap misses values and the model has no ``residual_variance`` (a file from before it was stored).
        """
        taps = self._check_taps(taps, batch=True)
        out = np.empty((len(taps), self.n_classes))
        for start in range(0, len(taps), _BATCH):
            x = taps[start:start + _BATCH].reshape(-1, self.mean.size).astype(np.float64)
            out[start:start + len(x)] = -0.5 * self.tempering * _squared_distances(
                self.mean, self.transform, self.class_means, self.residual_variance, x)
        return out.reshape(len(taps), self.n_locations, self.n_identities)

    def _stored(self) -> tuple[dict, dict]:
        return ({name: getattr(self, name) for name in self._ARRAYS},
                {"tempering": self.tempering, "shrinkage": self.shrinkage, "folds": self.folds,
                 "residual_variance": self.residual_variance})

    @classmethod
    def _from_stored(cls, common: dict, arrays: dict, attrs: dict):
        try:
            settings = dict(tempering=float(attrs["tempering"]), shrinkage=float(attrs["shrinkage"]),
                            folds=int(attrs["folds"]), residual_variance=float(attrs["residual_variance"]))
        except (TypeError, ValueError):
            raise ModelError(f"unreadable gaussian settings {dict(attrs)!r}") from None
        return cls(**{k: np.asarray(v, dtype=np.float64) for k, v in arrays.items()}, **common, **settings)


def _principal_components(x, n_components: int):
    """Mean (values,) and the leading principal directions (values, K) of the rows of x.

    From the eigenvectors u of the taps' Gram matrix (N x N, fewer taps than values): a direction is
    x_c^T u / sqrt(lambda), the same as the SVD's right singular vector, at a fraction of its cost.
    """
    mean = x.mean(axis=0)
    centred = x - mean
    eigenvalues, eigenvectors = np.linalg.eigh(centred @ centred.T)
    order = np.argsort(eigenvalues)[::-1]
    keep = order[eigenvalues[order] > 1e-9 * max(eigenvalues.max(), 1e-300)][:n_components]
    return mean, (centred.T @ eigenvectors[:, keep]) / np.sqrt(eigenvalues[keep])


def _whitened(y, tap_class, n_classes: int, shrinkage: float):
    """Whitening (K, K) by the shrunk shared within-class covariance, class means (classes, K) in the
    whitened space, and which classes had taps."""
    k = y.shape[1]
    counts = np.bincount(tap_class, minlength=n_classes)
    means = np.zeros((n_classes, k))
    np.add.at(means, tap_class, y)
    seen = counts > 0
    means[seen] /= counts[seen, None]
    residual = y - means[tap_class]
    dof = len(y) - int(seen.sum())
    within = residual.T @ residual / max(dof, 1)
    if dof < 1 or np.trace(within) <= 0:  # one tap per class: no within-class spread, use the total
        within = np.cov(y, rowvar=False).reshape(k, k)
    # S = (1 - shrinkage) S_within + shrinkage (tr S_within / K) I
    covariance = (1.0 - shrinkage) * within + shrinkage * max(float(np.trace(within)) / k, 1e-12) * np.eye(k)
    eigenvalues, eigenvectors = np.linalg.eigh(covariance)
    whiten = eigenvectors / np.sqrt(np.maximum(eigenvalues, 1e-12 * eigenvalues.max()))
    return whiten, means @ whiten, seen


def _distances(mean, transform, class_means, x):
    # ||z - m_c||^2 = |z|^2 - 2 z.m_c + |m_c|^2
    z = (x - mean) @ transform
    return (z ** 2).sum(axis=1)[:, None] - 2.0 * z @ class_means.T + (class_means ** 2).sum(axis=1)


def _squared_distances(mean, transform, class_means, residual_variance, x):
    """(N, classes) squared whitened distances of flattened taps x to the class means, the rows
    missing values (NaN) by the marginal of their observed values (module docstring)."""
    incomplete = np.isnan(x).any(axis=1)
    if not incomplete.any():
        return _distances(mean, transform, class_means, x)
    out = np.empty((len(x), len(class_means)))
    out[~incomplete] = _distances(mean, transform, class_means, x[~incomplete])
    out[incomplete] = _marginal_distances(mean, transform, class_means, residual_variance, x[incomplete])
    return out


def _marginal_distances(mean, transform, class_means, residual_variance, x):
    """(m_c - z_O)^T G_O (m_c - z_O) of each row of x (NaN where missing) and class c, up to a
    constant shared by the classes of a row: m_c^T G_O m_c - 2 m_c . h_O + h_O^T G_O^+ h_O."""
    if not (np.isfinite(residual_variance) and residual_variance > 0):
        raise ModelError("this gaussian model was trained before missing values could be marginalised (its file "
                         "has no residual_variance); train it again to score taps with unseen pins")
    gaussian = LowRankGaussian.from_whitening(mean, transform, residual_variance)
    evidence, precisions = gaussian.observed_terms(x)
    root = np.sqrt(gaussian.variances)
    h = evidence * root                                                   # lambda^1/2 Q_O^T Sigma_OO^-1 x_O
    out = np.empty((len(x), len(class_means)))
    for precision, rows in precisions:
        g = root[:, None] * precision * root                            # G_O
        try:
            z = np.linalg.solve(g, h[rows].T)
        except np.linalg.LinAlgError:  # fewer observed values than components: any solution, the term is shared
            z = np.linalg.lstsq(g, h[rows].T, rcond=None)[0]
        shared = (h[rows] * z.T).sum(axis=1)
        out[rows] = ((class_means @ g) * class_means).sum(axis=1) - 2.0 * h[rows] @ class_means.T + shared[:, None]
    return out


def _class_filled(x, tap_class, n_classes: int):
    """x with each missing value (NaN) replaced by the mean of that value over its class's taps that
    observe it (over all taps when none of its class does)."""
    missing = np.isnan(x)
    if not missing.any():
        return x
    observed = (~missing).astype(np.float64)
    sums, counts = np.zeros((n_classes, x.shape[1])), np.zeros((n_classes, x.shape[1]))
    np.add.at(sums, tap_class, np.where(missing, 0.0, x))
    np.add.at(counts, tap_class, observed)
    overall = sums.sum(axis=0) / np.maximum(counts.sum(axis=0), 1.0)
    means = np.where(counts > 0, sums / np.maximum(counts, 1.0), overall)
    return np.where(missing, means[tap_class], x)


def _residual_variances(x, tap_class, n_classes: int, directions):
    """sigma^2 for 0..K components: within-class variance per value left outside the first k directions."""
    counts = np.bincount(tap_class, minlength=n_classes)
    means = np.zeros((n_classes, x.shape[1]))
    np.add.at(means, tap_class, x)
    means[counts > 0] /= counts[counts > 0, None]
    residual = x - means[tap_class]
    dof = len(x) - int((counts > 0).sum())
    if dof < 1:  # one tap per class: no within-class spread, use the total
        residual, dof = x - x.mean(axis=0), max(len(x) - 1, 1)
    total = float((residual ** 2).sum())
    inside = np.concatenate([[0.0], np.cumsum(((residual @ directions) ** 2).sum(axis=0))])
    left = np.maximum(x.shape[1] - np.arange(len(inside)), 1)
    floor = max(1e-12 * total / (dof * x.shape[1]), 1e-300)
    return np.maximum((total - inside) / (dof * left), floor)


def fit_gaussian(dataset: Dataset, *, n_locations: int = 11, min_taps_per_class: int = 1, folds: int = 4,
                 components=COMPONENT_CHOICES, shrinkages=SHRINKAGE_CHOICES) -> GaussianModel:
    """Train the whitened-component Gaussian model; components, shrinkage and tempering by cross-validation.

    Parameters
    ----------
    dataset : Dataset
        Training taps.
    n_locations : int
        Equal location classes over the training locations (`perception.likelihood.fit_class_grid`).
    min_taps_per_class : int
        Fewest training taps a class may have.
    folds : int
        Cross-validation folds, >= 2; the taps of each class are dealt to the folds in location order,
        so taps repeated at one location land in different folds. Four, not two: with two taps per
        class (a station's 2 repeats, one depth per class) two folds split every class one-one, so no
        fold's fit had within-class residuals and whitened by the total covariance, which the final
        fit (two taps a class) does not: its tempering came out 100x too large (one-tap ECE 0.27 on
        the small station). With four, each fold's fit keeps both taps of about half the classes.
    components : sequence of int
        Candidate numbers of principal components (each >= 1; capped at the taps available).
    shrinkages : sequence of float in [0, 1]
        Candidate shrinkages of the shared covariance.

    Returns
    -------
    GaussianModel

    Raises
    ------
    DatasetError
        A class has too few taps, or no class has taps in two folds.
    ValueError
        A knob is out of range (the message names it).
    """
    components = [int(c) for c in np.atleast_1d(components)]
    shrinkages = [float(s) for s in np.atleast_1d(shrinkages)]
    if not components or min(components) < 1:
        raise ValueError(f"components must be integers >= 1, got {components}")
    if not shrinkages or not all(0.0 <= s <= 1.0 for s in shrinkages):
        raise ValueError(f"shrinkages must be numbers in [0, 1], got {shrinkages}")
    grid = fit_class_grid(dataset, n_locations=n_locations, min_taps_per_class=min_taps_per_class)
    x = dataset.taps.reshape(len(dataset), -1).astype(np.float64)
    incomplete = np.isnan(x).any(axis=1)
    cls = grid.tap_class(dataset)
    truth = grid.identity_class(dataset.identity) if grid.n_identities > 1 else grid.location_class(dataset.location)
    fold = cross_validation_folds(cls, folds, order=dataset.location)
    shape = (grid.n_locations, grid.n_identities)
    # Held-out squared distances of every candidate (components, shrinkage): one SVD per fold.
    held = {(k, s): np.full((len(x), grid.n_classes), -np.inf) for k in components for s in shrinkages}
    kept = np.zeros(len(x), bool)
    for f in range(folds):
        train, rows = fold != f, np.flatnonzero(fold == f)
        filled = _class_filled(x[train], cls[train], grid.n_classes)
        mean, directions = _principal_components(filled, max(components))
        y_train = (filled - mean) @ directions
        residual = _residual_variances(filled, cls[train], grid.n_classes, directions)
        complete = ~incomplete[rows]
        y_held = (x[rows[complete]] - mean) @ directions
        for k in components:
            for shrinkage in shrinkages:
                whiten, class_means, seen = _whitened(y_train[:, :k], cls[train], grid.n_classes, shrinkage)
                d = np.empty((len(rows), grid.n_classes))
                d[complete] = _distances(np.zeros(min(k, y_held.shape[1])), whiten, class_means, y_held[:, :k])
                if not complete.all():  # held-out taps missing values: scored by their marginal
                    d[~complete] = _marginal_distances(mean, directions[:, :k] @ whiten, class_means,
                                                       residual[min(k, directions.shape[1])], x[rows[~complete]])
                use = seen[cls[rows]]  # a class without training taps in this fold cannot be scored
                d = d[use]
                d[:, ~seen] = np.inf
                held[k, shrinkage][rows[use]] = -0.5 * d
                kept[rows[use]] = True
    if not kept.any():
        raise DatasetError("no class has training taps in two folds: collect at least two taps per class")
    best = None
    for (k, shrinkage), log_likelihood in held.items():
        log_likelihood = np.maximum(log_likelihood[kept], -1e300).reshape(-1, *shape)
        beta = fit_tempering(log_likelihood, truth[kept])
        loss = decision_log_loss(log_likelihood, truth[kept], beta)
        if best is None or loss < best[0]:
            best = (loss, k, shrinkage, beta)
    _, k, shrinkage, beta = best
    check_tempering(beta)
    filled = _class_filled(x, cls, grid.n_classes)
    mean, directions = _principal_components(filled, k)
    whiten, class_means, _ = _whitened((filled - mean) @ directions, cls, grid.n_classes, shrinkage)
    transform = directions @ whiten
    residual = _residual_variances(filled, cls, grid.n_classes, directions)[directions.shape[1]]
    return GaussianModel(mean, transform, class_means, float(beta), float(shrinkage), int(folds), grid.location_edges,
                         grid.identities, grid.front_end, grid.samples, grid.dim_names, grid.sensor, grid.location_unit,
                         grid.identity_unit, grid.taps_per_class, residual_variance=float(residual),
                         identity_period=grid.identity_period, identity_names=grid.identity_names)
