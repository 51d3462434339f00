"""Discrete Bayes over joint (location, identity) classes, in the log domain.

Pure functions in the shape of filterpy's discrete Bayes: `normalize`, `update`, `shift`
(filterpy's ``predict`` for a known move), plus the 'where'/'what' `marginals` and the priors.
`tap_update` is `update` with the t-th tap's log likelihood tempered by a per-tap-count factor g_t
(a model's ``tap_tempering`` schedule): the taps of one decision repeat each other's evidence, so
treating them as independent makes the beliefs after a few taps overconfident.
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

from .choices import DECISION_RULES, SHIFT_MODES

__all__ = ["SHIFT_MODES", "DECISION_RULES", "normalize", "update", "tap_update", "tap_factor",
           "check_tap_tempering", "shift", "shift_identity", "marginals",
           "decide", "flat_prior", "adaptive_prior"]

_CLASSES = (-2, -1)


def logsumexp(values, axis, keepdims: bool = False) -> np.ndarray:
    """log(sum(exp(values))) over ``axis``, shifted by the largest value for range (as scipy's, for reals).

    scipy.special.logsumexp costs ~0.2 ms of argument handling a call, ten times this on one belief, and
    the Bayes update normalises once a tap of every Monte Carlo run. Where every value is -inf the result
    is -inf; results agree with scipy's to ~1e-15.
    """
    values = np.asarray(values, dtype=np.float64)
    peak = values.max(axis=axis, keepdims=True)
    peak = np.where(np.isfinite(peak), peak, 0.0)
    with np.errstate(divide="ignore"):
        total = np.log(np.exp(values - peak).sum(axis=axis, keepdims=True)) + peak
    return total if keepdims else np.squeeze(total, axis=axis)


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


def check_tap_tempering(schedule) -> tuple[float, ...]:
    """A tap tempering schedule (g_1, ..., g_K) checked and as a tuple of floats.

    Parameters
    ----------
    schedule : sequence of float
        g_t > 0 and finite multiplies the log likelihood of the t-th tap of a decision; the last one is
        used for every tap beyond the K-th. Empty: no tempering (every g_t = 1).

    Returns
    -------
    tuple of float

    Raises
    ------
    ValueError
        Not a flat sequence of finite numbers > 0 (the message names ``tap_tempering``).

    Examples
    --------
    >>> check_tap_tempering([1, 0.5, 0.25])
    (1.0, 0.5, 0.25)
    """
    try:
        values = np.asarray(schedule if schedule is not None else (), dtype=np.float64)
    except (TypeError, ValueError):
        values = np.full((1, 1), np.nan)
    if values.ndim != 1 or not (np.isfinite(values) & (values > 0)).all():
        raise ValueError(f"tap_tempering must be a sequence of finite numbers > 0, got {schedule!r}")
    return tuple(float(v) for v in values)


def tap_factor(taps, schedule) -> np.ndarray:
    """g_t: the factor on the log likelihood of the ``taps``-th tap of a decision.

    Parameters
    ----------
    taps : int or (...) int array, >= 1
        Count of the tap in its decision (1 for the first tap after a flat or restarted prior).
    schedule : sequence of float
        (g_1, ..., g_K), checked by `check_tap_tempering`; taps beyond K take g_K; empty: 1.

    Returns
    -------
    float64 ndarray of the shape of ``taps``

    Examples
    --------
    >>> tap_factor([1, 2, 3, 7], (1.0, 0.5, 0.25)).tolist()
    [1.0, 0.5, 0.25, 0.25]
    """
    taps = np.asarray(taps)
    if taps.size and taps.min() < 1:
        raise ValueError(f"taps must be >= 1, got {taps.min()}")
    if len(schedule) == 0:
        return np.ones(taps.shape)
    return np.asarray(schedule, dtype=np.float64)[np.minimum(taps, len(schedule)) - 1]


def tap_update(log_likelihood, log_prior, taps, schedule=()) -> np.ndarray:
    """Bayes' rule for the ``taps``-th tap of a decision, its log likelihood tempered by g_t.

    Parameters
    ----------
    log_likelihood : (..., L, I) array
        log P(z_t | x_l, w_i) of the new tap.
    log_prior : (..., L, I) array
        log P(x_l, w_i | z_1:t-1).
    taps : int or (...) int array, >= 1
        t, the count of this tap in its decision (one per belief of a batch).
    schedule : sequence of float
        (g_1, ..., g_K) (see `tap_factor`); empty: `update` itself.

    Returns
    -------
    (..., L, I) float64 ndarray
        log P(x_l, w_i | z_1:t).
    """
    if len(schedule) == 0:
        return update(log_likelihood, log_prior)
    factor = tap_factor(taps, schedule)[..., None, None]
    # P(c|z_1:t) proportional to P(z_t|c)^g_t P(c|z_1:t-1)
    return normalize(np.add(factor * np.asarray(log_likelihood, dtype=np.float64), log_prior))


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
