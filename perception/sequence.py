"""Monte Carlo of decision sequences with the adaptive prior (paper 004, e.g. contour following).

`monte_carlo` validates single decisions from a flat prior. In an exploration the sensor makes
decision after decision while the perceived identity changes between them (following a circle,
the edge angle turns by the same step at every decision). Here every run makes ``decisions``
decisions in a row in the virtual environment; after each one the true identity moves by
``identity_step`` classes (wrapping round for circular identities) and the sensor stays where it
is. With ``adaptive=True`` each decision after the first starts from the adaptive prior of paper
004 (eq. 12): alpha x the last posterior shifted by Delta + (1 - alpha) x flat, Delta fixed
(``prior_shift``) or learned by predicted information gain (`perception.adaptive.ShiftLearner`).

Example
-------
>>> result = monte_carlo_sequence(env, FixationPolicy(9), threshold=0.6, decisions=20,   # doctest: +SKIP
...                               identity_step=1, adaptive=True, identity_period=360.0)
>>> result.identity_error[5:].mean(), result.delta[-1]                                    # doctest: +SKIP
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import bayes
from .adaptive import ShiftLearner
from .montecarlo import VirtualEnvironment
from .perceiver import clamp_move
from .policies import Policy

__all__ = ["SequenceResult", "monte_carlo_sequence", "identity_distance"]


def identity_distance(a, b, *, period: float | None = None) -> np.ndarray:
    """Absolute difference of identities, identity units; the shorter way round for circular ones.

    Parameters
    ----------
    a, b : array_like
    period : float, optional
        Period of circular identities (e.g. 360 deg).

    Examples
    --------
    >>> identity_distance([350.0, 10.0], [10.0, 30.0], period=360.0).tolist()
    [20.0, 20.0]
    """
    d = np.abs(np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64))
    return d if period is None else np.minimum(d % period, period - d % period)


@dataclass(frozen=True)
class SequenceResult:
    """Per-decision figures of a decision sequence (arrays over D decisions, means over runs).

    Attributes
    ----------
    identity_error : (D,) ndarray
        Mean absolute identity error of each decision, identity units (circular if a period is given).
    location_error : (D,) ndarray
        Mean absolute location error, location units (class centres).
    taps : (D,) ndarray
        Mean taps of each decision.
    forced : (D,) ndarray
        Fraction of runs whose decision was forced at ``max_taps``.
    delta : (D, runs) int ndarray
        Delta (identity classes) of the prior each decision started from (0 for the first).
    identity_step : int
        The true change of identity between decisions, classes.
    """

    identity_error: np.ndarray
    location_error: np.ndarray
    taps: np.ndarray
    forced: np.ndarray
    delta: np.ndarray
    identity_step: int

    def delta_error(self) -> np.ndarray:
        """(D,) mean |Delta - identity_step| over runs, identity classes (Fig. 8 of paper 004)."""
        return np.abs(self.delta - self.identity_step).mean(axis=1)


def monte_carlo_sequence(environment: VirtualEnvironment, policy: Policy, *, threshold: float, decisions: int,
                         identity_step: int = 0, runs: int = 1000, seed=None, adaptive: bool = False,
                         alpha: float = 0.5, prior_shift: int | None = None, identity_period: float | None = None,
                         move_threshold: float = 0.0, max_taps: int = 50, shift_mode: str = "uniform",
                         decision_rule: str = "marginal") -> SequenceResult:
    """Decision sequences in the virtual environment, with or without the adaptive prior.

    Parameters
    ----------
    environment : VirtualEnvironment
    policy : Policy
    threshold : float in [0, 1]
        Decision threshold.
    decisions : int
        Decisions per run.
    identity_step : int
        True change of identity between decisions, classes.
    runs : int
    seed : int, optional
    adaptive : bool
        Start each decision after the first from the adaptive prior (paper 004 eq. 12).
    alpha : float in [0, 1]
    prior_shift : int, optional
        Delta, fixed; default: learned by predicted information gain.
    identity_period : float, optional
        Period of circular identities, identity units (e.g. 360 deg).
    move_threshold, max_taps, shift_mode, decision_rule
        As `monte_carlo`.

    Returns
    -------
    SequenceResult
    """
    model = environment.model
    n_loc, n_id = model.n_locations, model.n_identities
    for name, value in (("threshold", threshold), ("alpha", alpha), ("move_threshold", move_threshold)):
        if not 0.0 <= value <= 1.0:
            raise ValueError(f"{name} must be in [0, 1], got {value}")
    for name, value in (("decisions", decisions), ("runs", runs), ("max_taps", max_taps)):
        if int(value) != value or value < 1:
            raise ValueError(f"{name} must be an integer >= 1, got {value}")
    circular = identity_period is not None
    rng = np.random.default_rng(seed)
    runs = int(runs)
    location = rng.integers(0, n_loc, runs)
    identity = rng.integers(0, n_id, runs)
    learner = ShiftLearner(n_id, alpha=max(alpha, 1e-6), circular=circular, runs=runs)
    table = environment.log_likelihood.reshape(-1, n_loc, n_id)
    flat = np.broadcast_to(bayes.flat_prior(n_loc, n_id), (runs, n_loc, n_id))
    figures = {name: np.zeros(decisions) for name in ("identity_error", "location_error", "taps", "forced")}
    deltas = np.zeros((decisions, runs), np.intp)
    last = last_evidence = None
    for d in range(int(decisions)):
        delta = np.full(runs, 0 if prior_shift is None else int(prior_shift), np.intp)
        if prior_shift is None:
            delta = learner.delta
        deltas[d] = delta if (adaptive and last is not None) else 0
        log_belief = (bayes.adaptive_prior(last, alpha=alpha, shift_classes=delta, circular=circular)
                      if adaptive and last is not None else flat.copy())
        decided, location, posterior, evidence, taps, forced = _decide(table, environment, policy, log_belief, location,
                                                             identity, rng, threshold, move_threshold,
                                                             int(max_taps), shift_mode, decision_rule)
        figures["identity_error"][d] = identity_distance(model.identities[decided[1]], model.identities[identity],
                                                         period=identity_period).mean()
        centres = model.location_centres
        figures["location_error"][d] = np.abs(centres[decided[0]] - centres[location]).mean()
        figures["taps"][d] = taps.mean()
        figures["forced"][d] = forced.mean()
        if adaptive and prior_shift is None and last is not None:
            # what this decision's taps alone say, against the last decision's taps shifted by each a
            # (the taps, not the posteriors: a posterior holds the prior that the current Delta made)
            learner.observe(np.exp(last_evidence).sum(axis=1), np.exp(evidence).sum(axis=1))
        last, last_evidence = posterior, evidence
        identity = (identity + int(identity_step)) % n_id if circular else np.clip(identity + int(identity_step),
                                                                                    0, n_id - 1)
    return SequenceResult(delta=deltas, identity_step=int(identity_step), **figures)


def _decide(table, env, policy, log_belief, location, identity, rng, threshold, move_threshold, max_taps,
            shift_mode, decision_rule):
    """One decision of every run from its prior; returns decided (location, identity), true location at
    the decision, posterior, evidence (the posterior of the same taps from a flat prior), taps and forced flags."""
    runs, n_loc, n_id = log_belief.shape
    done = np.zeros(runs, bool)
    decided_location = np.zeros(runs, np.intp)
    decided_identity = np.zeros(runs, np.intp)
    final_location = location.copy()
    posterior = log_belief.copy()
    log_evidence = np.broadcast_to(bayes.flat_prior(n_loc, n_id), log_belief.shape).copy()
    evidence = log_evidence.copy()
    taps = np.zeros(runs, np.intp)
    forced = np.zeros(runs, bool)
    for tap in range(1, max_taps + 1):
        log_likelihood = table[env.draw(location * n_id + identity, rng)]
        log_belief = bayes.update(log_likelihood, log_belief)
        log_evidence = bayes.update(log_likelihood, log_evidence)
        belief, map_location, map_identity = bayes.decide(log_belief, rule=decision_rule)
        crossed = belief > threshold
        new = ~done & (crossed | (tap == max_taps))
        decided_location[new], decided_identity[new] = map_location[new], map_identity[new]
        final_location[new] = location[new]
        posterior[new] = log_belief[new]
        evidence[new] = log_evidence[new]
        taps[new] = tap
        forced |= new & ~crossed
        done |= new
        if done.all():
            break
        where = np.exp(log_belief).sum(axis=2)
        estimate = where.argmax(axis=1)
        offset = np.where(~done & (where.max(axis=1) > move_threshold), policy.move(where, estimate, rng), 0)
        offset = clamp_move(estimate, offset, n_loc)
        location = np.clip(location + offset, 0, n_loc - 1)
        log_belief = bayes.shift(log_belief, offset, mode=shift_mode)
        log_evidence = bayes.shift(log_evidence, offset, mode=shift_mode)
    return (decided_location, decided_identity), final_location, posterior, evidence, taps, forced
