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

    KIND = "gaussian"
    _ARRAYS = ("mean", "transform", "class_means")
    _ATTRS = ("tempering", "shrinkage", "folds")

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

    @property
    def n_components(self) -> int:
        """Principal components K."""
        return self.transform.shape[1]

    def summary(self) -> str:
        """One line: front end, class grid, tap shape, components, tempering."""
        return (f"{self._grid_summary()}; gaussian on {self.n_components} whitened components "
                f"(shrinkage {self.shrinkage:g}), tempering {self.tempering:.4g}")

    def log_likelihood_batch(self, taps) -> np.ndarray:
        """Tempered Gaussian log likelihood of many taps against every class (up to a shared constant).

        Parameters
        ----------
        taps : (N, samples, dims) array

        Returns
        -------
        (N, n_locations, n_identities) float64 ndarray
        """
        taps = self._check_taps(taps, batch=True)
        out = np.empty((len(taps), self.n_classes))
        m2 = (self.class_means ** 2).sum(axis=1)
        for start in range(0, len(taps), _BATCH):
            x = taps[start:start + _BATCH].reshape(-1, self.mean.size).astype(np.float64)
            z = (x - self.mean) @ self.transform
            # -beta/2 ||z - m_c||^2 = -beta/2 (|z|^2 - 2 z.m_c + |m_c|^2)
            out[start:start + len(x)] = -0.5 * self.tempering * (
                (z ** 2).sum(axis=1)[:, None] - 2.0 * z @ self.class_means.T + m2)
        return out.reshape(len(taps), self.n_locations, self.n_identities)

    def _stored(self) -> tuple[dict, dict]:
        return ({name: getattr(self, name) for name in self._ARRAYS},
                {"tempering": self.tempering, "shrinkage": self.shrinkage, "folds": self.folds})

    @classmethod
    def _from_stored(cls, common: dict, arrays: dict, attrs: dict):
        try:
            settings = dict(tempering=float(attrs["tempering"]), shrinkage=float(attrs["shrinkage"]),
                            folds=int(attrs["folds"]))
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
    z = (x - mean) @ transform
    return (z ** 2).sum(axis=1)[:, None] - 2.0 * z @ class_means.T + (class_means ** 2).sum(axis=1)


def fit_gaussian(dataset: Dataset, *, n_locations: int = 11, min_taps_per_class: int = 1, folds: int = 2,
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
        so taps repeated at one location land in different folds.
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
    cls = grid.tap_class(dataset)
    truth = grid.identity_class(dataset.identity) if grid.n_identities > 1 else grid.location_class(dataset.location)
    fold = cross_validation_folds(cls, folds, order=dataset.location)
    shape = (grid.n_locations, grid.n_identities)
    # Held-out squared distances of every candidate (components, shrinkage): one SVD per fold.
    held = {(k, s): np.full((len(x), grid.n_classes), -np.inf) for k in components for s in shrinkages}
    kept = np.zeros(len(x), bool)
    for f in range(folds):
        train = fold != f
        mean, directions = _principal_components(x[train], max(components))
        y_train, y_held = (x[train] - mean) @ directions, (x[fold == f] - mean) @ directions
        for k in components:
            for shrinkage in shrinkages:
                whiten, class_means, seen = _whitened(y_train[:, :k], cls[train], grid.n_classes, shrinkage)
                use = seen[cls[fold == f]]  # a class without training taps in this fold cannot be scored
                rows = np.flatnonzero(fold == f)[use]
                d = _distances(np.zeros(min(k, y_held.shape[1])), whiten, class_means, y_held[use, :k])
                d[:, ~seen] = np.inf
                held[k, shrinkage][rows] = -0.5 * d
                kept[rows] = True
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
    mean, directions = _principal_components(x, k)
    whiten, class_means, _ = _whitened((x - mean) @ directions, cls, grid.n_classes, shrinkage)
    transform = directions @ whiten
    return GaussianModel(mean, transform, class_means, float(beta), float(shrinkage), int(folds), grid.location_edges,
                         grid.identities, grid.front_end, grid.samples, grid.dim_names, grid.sensor, grid.location_unit,
                         grid.identity_unit, grid.taps_per_class)
