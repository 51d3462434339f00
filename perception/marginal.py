"""Missing values under a low-rank Gaussian: the marginal of the observed values, and the conditional mean.

A tap flattened to D values x is modelled as Gaussian with a low-rank-plus-isotropic covariance
(probabilistic PCA, Tipping & Bishop 1999):

    x ~ N(mu, Sigma),   Sigma = Q diag(lambda) Q^T + sigma^2 (I - Q Q^T) = sigma^2 I + Q A Q^T,

with Q (D, K) orthonormal directions, lambda (K,) the variances along them, sigma^2 the variance
per value of what they leave out, and A = diag(lambda) - sigma^2 I. When some values are missing
(NaN), the observed ones x_O are Gaussian with the sub-mean and the sub-covariance (the marginal):
x_O ~ N(mu_O, Sigma_OO). Everything the models need from Sigma_OO^{-1} lives in the K-dim space of
the directions; with C = Q_O^T Q_O and N = sigma^2 I + C A (both K x K, one per missing pattern),

    Q_O^T Sigma_OO^{-1} Q_O = N^{-1} C,    Q_O^T Sigma_OO^{-1} (x_O - mu_O) = N^{-1} Q_O^T (x_O - mu_O),

(Woodbury's identity, pushed through so that no difference of large terms is formed), and the
conditional mean of the missing values is E[x_M | x_O] = mu_M + Q_M A N^{-1} Q_O^T (x_O - mu_O).
With nothing missing, C = I and N = diag(lambda). Taps sharing a missing pattern share C and N, so
`missing_patterns` groups them and each group is one batch of matrix products.

`perception.gaussian` scores classes by the marginal; `perception.learned` imputes the network's
input by the conditional mean.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse.linalg import eigsh

__all__ = ["LowRankGaussian", "missing_patterns", "fit_low_rank_gaussian", "RESIDUAL_FLOOR"]

#: Values from which `fit_low_rank_gaussian` finds only the leading directions (Lanczos) instead of all.
_LANCZOS_MIN_VALUES = 512
#: Smallest sigma^2 as a fraction of the smallest variance along the directions (conditioning).
RESIDUAL_FLOOR = 1e-3


def missing_patterns(missing: np.ndarray):
    """Group rows by their missing pattern.

    Parameters
    ----------
    missing : (N, D) bool array

    Yields
    ------
    pattern : (D,) bool ndarray
        The values missing in every row of the group.
    rows : (n,) intp ndarray
        The rows with that pattern.
    """
    missing = np.asarray(missing, dtype=bool)
    if len(missing) == 0:
        return
    # One byte string per row (its bits packed), so that the rows are told apart by one 1-D unique.
    packed = np.ascontiguousarray(np.packbits(missing, axis=1))
    keys = packed.view(np.dtype((np.void, packed.shape[1]))).ravel()
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    order = np.argsort(inverse, kind="stable")
    bounds = np.searchsorted(inverse[order], np.arange(len(first) + 1))
    for k, row in enumerate(first):
        yield missing[row], order[bounds[k]:bounds[k + 1]]


@dataclass(frozen=True)
class LowRankGaussian:
    """N(mean, sigma^2 I + Q (diag(variances) - sigma^2 I) Q^T) over D values (see the module docstring).

    Attributes
    ----------
    mean : (D,) float64 ndarray
    basis : (D, K) float64 ndarray
        Orthonormal directions Q.
    variances : (K,) float64 ndarray
        Variance lambda along each direction, > 0.
    residual_variance : float
        sigma^2 > 0, the variance per value outside the directions.
    """

    mean: np.ndarray
    basis: np.ndarray
    variances: np.ndarray
    residual_variance: float

    @classmethod
    def from_whitening(cls, mean, transform, residual_variance: float) -> LowRankGaussian:
        """The Gaussian whose whitening is ``z = transform^T (x - mean)`` (columns of transform orthogonal).

        Parameters
        ----------
        mean : (D,) array
        transform : (D, K) array
            Orthogonal columns of norm 1 / sqrt(lambda_k) (directions divided by their spread).
        residual_variance : float
            sigma^2 of the values outside the columns' span; floored at `RESIDUAL_FLOOR` times the
            smallest lambda, which keeps the small solves well conditioned (with as many directions as
            values sigma^2 changes nothing, and a spread that small is a fit's rounding, not the data).
        """
        transform = np.asarray(transform, dtype=np.float64)
        variances = 1.0 / (transform ** 2).sum(axis=0)
        return cls(np.asarray(mean, dtype=np.float64), transform * np.sqrt(variances), variances,
                   max(float(residual_variance), RESIDUAL_FLOOR * float(variances.min())))

    def _pattern(self, missing: np.ndarray):
        """C = Q_O^T Q_O and N = sigma^2 I + C A of one missing pattern."""
        lost = self.basis[missing]
        c = np.eye(len(self.variances)) - lost.T @ lost
        n = self.residual_variance * np.eye(len(self.variances)) + c * (self.variances - self.residual_variance)
        return c, n

    def observed_terms(self, x) -> tuple[np.ndarray, list]:
        """What the observed values of each row say along the directions.

        Parameters
        ----------
        x : (N, D) array
            NaN where missing.

        Returns
        -------
        evidence : (N, K) float64 ndarray
            Q_O^T Sigma_OO^{-1} (x_O - mu_O) of each row.
        precisions : list of ((K, K) ndarray, (n,) intp ndarray)
            Q_O^T Sigma_OO^{-1} Q_O of each missing pattern, with the rows that have it.
        """
        x = np.asarray(x, dtype=np.float64)
        missing = np.isnan(x)
        projected = np.where(missing, 0.0, x - self.mean) @ self.basis       # Q_O^T (x_O - mu_O)
        evidence = np.empty_like(projected)
        precisions = []
        for pattern, rows in missing_patterns(missing):
            c, n = self._pattern(pattern)
            evidence[rows] = np.linalg.solve(n, projected[rows].T).T
            precision = np.linalg.solve(n, c)
            precisions.append((0.5 * (precision + precision.T), rows))
        return evidence, precisions

    def conditional_mean(self, x) -> np.ndarray:
        """x with each missing value replaced by its mean given the row's observed values.

        Parameters
        ----------
        x : (N, D) array
            NaN where missing.

        Returns
        -------
        (N, D) float64 ndarray
            E[x_M | x_O] in the missing places, x elsewhere; a row with nothing observed gets the mean.
        """
        x = np.asarray(x, dtype=np.float64)
        missing = np.isnan(x)
        if not missing.any():
            return x.copy()
        evidence, _ = self.observed_terms(x)
        # E[x_M | x_O] = mu_M + Q_M A N^{-1} Q_O^T (x_O - mu_O)
        guess = self.mean + (evidence * (self.variances - self.residual_variance)) @ self.basis.T
        return np.where(missing, guess, x)

    def log_density(self, x) -> np.ndarray:
        """log N(x_O; mu_O, Sigma_OO) of each row's observed values, by dense algebra (for tests, small D).

        Parameters
        ----------
        x : (N, D) array
            NaN where missing.

        Returns
        -------
        (N,) float64 ndarray
        """
        x = np.asarray(x, dtype=np.float64)
        covariance = self.residual_variance * np.eye(len(self.mean)) + \
            (self.basis * (self.variances - self.residual_variance)) @ self.basis.T
        out = np.empty(len(x))
        for k, row in enumerate(x):
            seen = ~np.isnan(row)
            sub = covariance[np.ix_(seen, seen)]
            d = row[seen] - self.mean[seen]
            _, logdet = np.linalg.slogdet(sub)
            out[k] = -0.5 * (d @ np.linalg.solve(sub, d) + logdet + seen.sum() * np.log(2 * np.pi))
        return out


def fit_low_rank_gaussian(x, n_components: int) -> LowRankGaussian:
    """Probabilistic PCA of rows that may miss values: mean and covariance of the observed values per
    pair, the leading directions, and sigma^2 the mean variance left out.

    Parameters
    ----------
    x : (N, D) array
        NaN where missing; every value observed in at least two rows.
    n_components : int
        Directions K kept (capped at D - 1 and at the rank of the data).

    Returns
    -------
    LowRankGaussian
    """
    x = np.asarray(x, dtype=np.float64)
    observed = ~np.isnan(x)
    mean = np.nanmean(x, axis=0)
    centred = np.where(observed, x - mean, 0.0)
    seen = observed.astype(np.float64)
    # Pairwise covariance over the rows observing both values (every row when nothing is missing).
    pairs = np.maximum(seen.T @ seen - 1.0, 1.0)
    covariance = (centred.T @ centred) / pairs
    d = len(mean)
    if d >= _LANCZOS_MIN_VALUES and d > 8 * n_components:
        # Only the leading directions (Lanczos, a few seconds where a full eigh of 3200 values takes a
        # minute); what they leave out is the trace less their variances.
        start = np.random.default_rng(0).standard_normal(d)   # ARPACK's own start is random: same data, same fit
        variances, vectors = eigsh(covariance, k=int(n_components), which="LA", v0=start)
        left_total = float(np.trace(covariance) - variances[variances > 0].sum())
    else:
        variances, vectors = np.linalg.eigh(covariance)
        left_total = None
    order = np.argsort(variances)[::-1]
    variances, vectors = variances[order], vectors[:, order]
    floor = 1e-9 * max(float(variances[0]), 1e-300)
    k = int(min(n_components, d - 1, (variances > floor).sum()))
    k = max(k, 1)
    if left_total is not None:
        left_total += float(np.clip(variances[k:], 0.0, None).sum())   # directions found but not kept
        residual = max(left_total, 0.0) / (d - k)
    else:
        left = variances[k:]
        residual = float(np.clip(left, 0.0, None).mean()) if left.size else 0.0
    residual = max(residual, RESIDUAL_FLOOR * float(variances[:k].min()), 1e-300)
    return LowRankGaussian(mean, vectors[:, :k], np.maximum(variances[:k], residual * (1 + 1e-9)), residual)
