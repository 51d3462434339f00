"""Tempering a likelihood on held-out taps, so that a one-tap posterior means what it says.

A model's log likelihood is multiplied by a tempering factor beta > 0,

    log P_beta(z | c) = beta log P(z | c),

and beta is the one that maximises the probability the flat-prior one-tap posterior gives the
true identity of held-out taps (the decision marginal: identity, or location for a model with a
single identity). That is temperature scaling (Guo et al. 2017) with T = 1 / beta; the held-out
log likelihoods come from cross-validation over the training collection (`cross_validation_folds`).

Example
-------
>>> import numpy as np
>>> rng = np.random.default_rng(0)
>>> truth = rng.integers(0, 4, 50000)
>>> z = 3.0 * np.eye(4)[truth] + rng.normal(size=(50000, 4))   # unit Gaussians: log P(z | c) = 3 z_c + const
>>> beta = fit_tempering(12.0 * z.reshape(50000, 1, 4), truth)  # a likelihood 4 times too confident
>>> round(beta, 2)
0.25
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize_scalar

from .bayes import logsumexp

__all__ = ["cross_validation_folds", "fit_tempering", "decision_log_loss", "check_tempering"]

#: Range searched for beta (log10): the paper's geometric mean (1) to a naive Bayes over 3200 values and beyond.
_LOG10_BETA = (-4.0, 4.0)


def cross_validation_folds(tap_class, folds: int, *, order=None) -> np.ndarray:
    """Fold of each tap, dealt in turn within each class so that every fold holds out part of every class.

    Parameters
    ----------
    tap_class : (N,) int array
        Joint class of each tap.
    folds : int
        Number of folds, >= 2.
    order : (N,) array, optional
        Order in which the taps of a class are dealt (e.g. their locations); default their index.

    Returns
    -------
    (N,) intp ndarray in [0, folds)
    """
    tap_class = np.asarray(tap_class, dtype=np.intp)
    if int(folds) != folds or folds < 2:
        raise ValueError(f"folds must be an integer >= 2, got {folds}")
    order = np.arange(len(tap_class)) if order is None else np.asarray(order)
    sort = np.lexsort((order, tap_class))
    cls = tap_class[sort]
    first = np.searchsorted(cls, cls, side="left")          # index of each class's first tap in sorted order
    rank = np.arange(len(cls)) - first
    offset = cls % folds                                      # classes of one tap do not all go to fold 0
    fold = np.empty(len(cls), np.intp)
    fold[sort] = (rank + offset) % folds
    return fold


def check_tempering(beta: float) -> None:
    """Raise DatasetError when beta sits at the bottom of its range: held-out taps were told apart no
    better than chance, so no tempering makes the beliefs useful (too few taps per class)."""
    from .errors import DatasetError

    if beta <= 1.01 * 10.0 ** _LOG10_BETA[0]:
        raise DatasetError("held-out training taps are told apart no better than chance, so the tempering cannot "
                           "be fitted: collect more taps per class, repeated at the same locations ([protocol] "
                           "repeats = 2), or train the papers' histogram model")


def decision_log_loss(log_likelihood, truth, beta: float = 1.0) -> float:
    """Mean negative log posterior of the true decision class after one tap from a flat prior.

    Parameters
    ----------
    log_likelihood : (N, L, I) array
        log P(z | x_l, w_i) of held-out taps.
    truth : (N,) int array
        True identity class (location class when I = 1) of each tap.
    beta : float
        Tempering factor.

    Returns
    -------
    float, nats
    """
    log_likelihood = np.asarray(log_likelihood, dtype=np.float64)
    axis = 1 if log_likelihood.shape[2] > 1 else 2           # sum out location, or (single identity) identity
    joint = beta * log_likelihood
    joint = joint - logsumexp(joint, axis=(1, 2), keepdims=True)
    marginal = logsumexp(joint, axis=axis)
    return float(-marginal[np.arange(len(marginal)), np.asarray(truth, dtype=np.intp)].mean())


def fit_tempering(log_likelihood, truth) -> float:
    """The tempering factor beta that calibrates one-tap posteriors (lowest `decision_log_loss`).

    Parameters
    ----------
    log_likelihood : (N, L, I) array
        Held-out log likelihoods (taps not used to fit the model that gave them).
    truth : (N,) int array
        True identity class (location class when I = 1).

    Returns
    -------
    float > 0
    """
    log_likelihood = np.asarray(log_likelihood, dtype=np.float64)
    if log_likelihood.ndim != 3 or len(log_likelihood) == 0:
        raise ValueError(f"log_likelihood must be a non-empty (N, L, I) array, got shape {log_likelihood.shape}")
    result = minimize_scalar(lambda e: decision_log_loss(log_likelihood, truth, 10.0 ** e), bounds=_LOG10_BETA,
                             method="bounded", options={"xatol": 1e-3})
    return float(10.0 ** result.x)

