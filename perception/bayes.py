"""Discrete Bayes over joint (location, identity) classes, in the log domain.

Pure functions in the shape of filterpy's discrete Bayes: `normalize`, `update`, `shift`
(filterpy's ``predict`` for a known move), plus the 'where'/'what' `marginals` and the priors.
A belief is an array of log probabilities whose last two axes are (location, identity);
leading axes are a batch (e.g. Monte Carlo runs), so every function works on ``(L, I)`` and
``(R, L, I)`` alike. The log domain keeps a long run of confident taps from underflowing.

Example
-------
>>> import numpy as np
>>> log_prior = flat_prior(3, 2)
>>> log_posterior = update(np.log([[1.0, 1.0], [2.0, 2.0], [1.0, 1.0]]), log_prior)
>>> where, what = marginals(log_posterior)
>>> where.round(2).tolist(), what.round(2).tolist()
([0.25, 0.5, 0.25], [0.5, 0.5])
"""

from __future__ import annotations

import numpy as np
from scipy.special import logsumexp

from .choices import DECISION_RULES, SHIFT_MODES

__all__ = ["SHIFT_MODES", "DECISION_RULES", "normalize", "update", "shift", "shift_identity", "marginals",
           "decide", "flat_prior", "adaptive_prior"]

_CLASSES = (-2, -1)


def normalize(log_belief) -> np.ndarray:
    """Rescale log beliefs so that the probabilities of each belief sum to one.

    Parameters
    ----------
    log_belief : (..., L, I) array of unnormalised log probabilities

    Returns
    -------
    (..., L, I) float64 ndarray
    """
    log_belief = np.asarray(log_belief, dtype=np.float64)
    return log_belief - logsumexp(log_belief, axis=_CLASSES, keepdims=True)


def update(log_likelihood, log_prior) -> np.ndarray:
    """Bayes' rule for one tap (paper 002 eqs. 4-5; 000 eqs. 4-5).

    Parameters
    ----------
    log_likelihood : (..., L, I) array
        log P(z_t | x_l, w_i) of the new tap.
    log_prior : (..., L, I) array
        log P(x_l, w_i | z_1:t-1), the previous posterior.

    Returns
    -------
    (..., L, I) float64 ndarray
        log P(x_l, w_i | z_1:t).
    """
    # P(c|z_1:t) = P(z_t|c) P(c|z_1:t-1) / P(z_t|z_1:t-1),  P(z_t|z_1:t-1) = sum_c P(z_t|c) P(c|z_1:t-1)
    return normalize(np.add(log_likelihood, log_prior))


def shift(log_belief, offset_classes, *, mode: str = "edge") -> np.ndarray:
    """Keep beliefs aligned with the sensor after it moved by a number of location classes.

    Parameters
    ----------
    log_belief : (..., L, I) array
    offset_classes : int or (...) int array
        Move in location classes (positive: towards higher location); one per belief of the batch.
    mode : {"edge", "uniform"}
        What fills the classes shifted in from outside the range: ``"edge"`` replicates the
        belief of the edge class then renormalises (paper 002); ``"uniform"`` spreads the belief
        shifted out of the range evenly over them, separately for each identity, so the
        beliefs still sum to one and the identity marginal is kept (paper 000 eq. 8).

    Returns
    -------
    (..., L, I) float64 ndarray
    """
    if mode not in SHIFT_MODES:
        raise ValueError(f"mode must be one of {SHIFT_MODES}, got {mode!r}")
    log_belief = np.asarray(log_belief, dtype=np.float64)
    n_loc = log_belief.shape[-2]
    offset = np.asarray(offset_classes, dtype=np.intp)[..., None]
    # P(x_l, w_i) <- P(x_l - offset, w_i)
    source = np.arange(n_loc) - offset
    inside = (source >= 0) & (source < n_loc)
    shifted = np.take_along_axis(log_belief, np.clip(source, 0, n_loc - 1)[..., None], axis=-2)
    if mode == "edge":
        # outside the range: P(x_l, w_i) <- P(x_1, w_i) or P(x_L, w_i), then renormalise
        return normalize(shifted)
    leaving = np.abs(np.arange(n_loc) + offset - (n_loc - 1) / 2) > (n_loc - 1) / 2
    with np.errstate(divide="ignore"):
        lost = logsumexp(np.where(leaving[..., None], log_belief, -np.inf), axis=-2)
        # outside the range: P(x_l, w_i) <- p0(w_i) = (belief of w_i shifted out) / (number of classes shifted in)
        fill = lost - np.log(np.maximum((~inside).sum(axis=-1), 1))[..., None]
    return normalize(np.where(inside[..., None], shifted, fill[..., None, :]))


def shift_identity(log_belief, offset_classes, *, circular: bool = False) -> np.ndarray:
    """Shift beliefs along the identity axis: P(x_l, w_i) <- P(x_l, w_(i - offset)) (paper 004 eq. 7).

    Parameters
    ----------
    log_belief : (..., L, I) array
    offset_classes : int or (...) int array
        Shift in identity classes; one per belief of the batch.
    circular : bool
        The identity classes cover a full turn (e.g. edge angles over 360 deg): classes shifted
        out at one end come back at the other. Otherwise the belief shifted out is spread evenly
        over the classes shifted in, separately for each location (uniform fill, as `shift`).

    Returns
    -------
    (..., L, I) float64 ndarray
    """
    log_belief = np.asarray(log_belief, dtype=np.float64)
    n_id = log_belief.shape[-1]
    offset = np.asarray(offset_classes, dtype=np.intp)[..., None, None]
    source = np.arange(n_id) - offset                                       # (..., 1, I)
    if circular:
        index = np.broadcast_to(source % n_id, log_belief.shape)
        return normalize(np.take_along_axis(log_belief, index, axis=-1))
    swapped = np.swapaxes(log_belief, -1, -2)
    return np.swapaxes(shift(swapped, offset_classes, mode="uniform"), -1, -2)


def decide(log_belief, *, rule: str = "marginal") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The decision belief and the MAP classes under a stop rule.

    Parameters
    ----------
    log_belief : (..., L, I) array of normalised log probabilities
    rule : {"marginal", "joint"}
        ``"marginal"``: the largest 'what' marginal P(w_i | z) (the 'where' marginal for a single
        identity; papers 002-004), with the MAP of each marginal. ``"joint"``: the largest joint
        belief P(x_l, w_i | z) and its class (paper 001 eq. 3: "if any P(c_n | z_t) > theta then
        c = argmax P(c_n | z_t)").

    Returns
    -------
    belief : (...) float64 ndarray
        Compared with the decision threshold.
    location_class, identity_class : (...) intp ndarrays
        MAP classes under the rule.
    """
    if rule not in DECISION_RULES:
        raise ValueError(f"rule must be one of {DECISION_RULES}, got {rule!r}")
    belief = np.exp(np.asarray(log_belief, dtype=np.float64))
    n_loc, n_id = belief.shape[-2:]
    if rule == "joint":
        flat = belief.reshape(belief.shape[:-2] + (n_loc * n_id,))
        best = flat.argmax(axis=-1)
        return np.take_along_axis(flat, best[..., None], axis=-1)[..., 0], best // n_id, best % n_id
    where, what = belief.sum(axis=-1), belief.sum(axis=-2)
    decision = what if n_id > 1 else where
    return decision.max(axis=-1), where.argmax(axis=-1), what.argmax(axis=-1)


def marginals(log_belief) -> tuple[np.ndarray, np.ndarray]:
    """The 'where' and 'what' marginal beliefs (paper 003 eqs. 5-6; 002 eqs. 6, 9).

    Parameters
    ----------
    log_belief : (..., L, I) array of normalised log probabilities

    Returns
    -------
    where : (..., L) float64 ndarray
        P(x_l | z_1:t) = sum_i P(x_l, w_i | z_1:t)
    what : (..., I) float64 ndarray
        P(w_i | z_1:t) = sum_l P(x_l, w_i | z_1:t)
    """
    belief = np.exp(log_belief)
    return belief.sum(axis=-1), belief.sum(axis=-2)


def flat_prior(n_locations: int, n_identities: int) -> np.ndarray:
    """The uniform prior log P(x_l, w_i | z_0) = -log(L I), shape (L, I)."""
    return np.full((n_locations, n_identities), -np.log(n_locations * n_identities))


def adaptive_prior(log_posterior, *, alpha: float = 0.5, shift_classes=0, circular: bool = False) -> np.ndarray:
    """Prior for the next decision mixing the predicted distribution with a flat prior (paper 004 eqs. 7, 12).

    Parameters
    ----------
    log_posterior : (..., L, I) array
        The posterior at the previous decision.
    alpha : float in [0, 1]
        Weight of the predicted distribution (paper 004: 0.5); 0 gives the flat prior.
    shift_classes : int or (...) int array
        Delta: the predicted distribution is the posterior shifted by Delta identity classes,
        P_predicted(x_l, w_i) = P(x_l, w_(i - Delta) | z) (eq. 7; see `shift_identity`).
    circular : bool
        The identity classes are angles over a full turn.

    Returns
    -------
    (..., L, I) float64 ndarray
    """
    if not 0.0 <= alpha <= 1.0:
        raise ValueError(f"alpha must be in [0, 1], got {alpha}")
    log_posterior = shift_identity(log_posterior, shift_classes, circular=circular)
    log_flat = -np.log(log_posterior.shape[-2] * log_posterior.shape[-1])
    # P(c|z_0) = alpha P_predicted(c) + (1 - alpha) P_flat(c)
    with np.errstate(divide="ignore"):
        return np.logaddexp(np.log(alpha) + log_posterior, np.log1p(-alpha) + log_flat)
