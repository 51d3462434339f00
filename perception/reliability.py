"""Do beliefs mean what they say? Calibration of the identity belief over Monte Carlo runs.

`trace_beliefs` runs the virtual environment like `perception.monte_carlo` (same rules: update, the
policy's move from the MAP location, clamped, the belief shifted), but never stops before
``max_taps`` and keeps every tap's decision belief. Without a deadline a run's trajectory does not
depend on the decision threshold, so one trace gives:

- the calibration after t taps: the expected calibration error (ECE) of the decision belief, i.e.
  the mean over equal confidence bins of |accuracy - mean belief| weighted by the bin's share of
  runs, and the reliability diagram (`reliability_bins`);
- the decision at any threshold (`BeliefTrace.decisions`): taps, decided identity, error, and the
  fraction of decisions within a tolerance;
- the threshold that reaches a target accuracy in the fewest taps (`threshold_for_accuracy`);
- the tap tempering schedule that calibrates the beliefs of a policy's runs after each of taps 1 to 5
  (`fit_tap_tempering`): a model's tempering is fitted on single held-out taps, but the taps of one
  run are not independent evidence (the same depth of the same gap gives nearly the same tap), so
  their product is overconfident after a few taps unless the t-th tap is tempered by its own g_t.

Example
-------
>>> trace = trace_beliefs(env, FixationPolicy(9), runs=5000, seed=0)       # doctest: +SKIP
>>> [round(trace.calibration_error(t), 3) for t in (1, 3, 5)]             # doctest: +SKIP
[0.021, 0.034, 0.029]
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from _shared.mapping import map_pieces

from . import bayes
from .calibration_error import expected_calibration_error, reliability_bins
from .montecarlo import VirtualEnvironment
from .perceiver import clamp_move
from .policies import Policy

__all__ = ["BeliefTrace", "Decisions", "AccuracySweep", "trace_beliefs", "expected_calibration_error", "reliability_bins",
           "threshold_for_accuracy", "fixation_for_accuracy", "fit_tap_tempering", "CALIBRATION_TAPS"]

#: Taps after which the calibration of the identity belief is reported: one tap (the likelihood alone), a few,
#: and the last tap whose belief `fit_tap_tempering` calibrates by default.
CALIBRATION_TAPS = (1, 3, 5)

#: Thresholds `threshold_for_accuracy` chooses from: 0.3..0.99 in 0.005 steps and the 0.999x tail. With
#: calibrated beliefs a decision within a tolerance of one class needs no majority belief in the exact class
#: (a belief of 0.45 in 4.25 mm may be within 0.25 mm 95 % of the time); below 0.3 one tap decides too often.
DECISION_THRESHOLDS = np.concatenate([np.round(np.arange(0.3, 0.99, 0.005), 3),
                                      [0.99, 0.995, 0.998, 0.999, 0.9995, 0.9999]])


@dataclass(frozen=True)
class Decisions:
    """The decisions of a trace at one threshold (arrays over runs).

    Attributes
    ----------
    threshold : float
    taps : (R,) int ndarray
        Taps to the decision (``max_taps`` when forced).
    identity : (R,) int ndarray
        Decided identity class.
    belief : (R,) float ndarray
        Belief in it at the decision.
    forced : (R,) bool ndarray
        The belief never crossed the threshold.
    error : (R,) float ndarray
        |decided - true identity|, identity units.
    """

    threshold: float
    taps: np.ndarray
    identity: np.ndarray
    belief: np.ndarray
    forced: np.ndarray
    error: np.ndarray

    def within(self, tolerance: float) -> np.ndarray:
        """(R,) bool: the decided identity lies within ``tolerance`` (identity units) of the truth."""
        return self.error <= tolerance + 1e-9


@dataclass(frozen=True)
class BeliefTrace:
    """Every tap's decision belief in a set of Monte Carlo runs (arrays over R runs and T taps).

    Attributes
    ----------
    policy : str
    belief : (R, T) float64 ndarray
        Largest belief of the decision marginal (identity; location for a single-identity model).
    estimate : (R, T) int ndarray
        MAP class of the decision marginal.
    truth : (R, T) int ndarray
        True class of the decision marginal at that tap (identity, or the current location class).
    values : (n,) float64 ndarray
        Value of each decision class (identities, or location class centres), for errors.
    period : float or None
        Period of circular values (e.g. 360 deg): errors wrap. None: not circular.
    """

    policy: str
    belief: np.ndarray
    estimate: np.ndarray
    truth: np.ndarray
    values: np.ndarray
    period: float | None = None

    @property
    def runs(self) -> int:
        """Number of runs R."""
        return self.belief.shape[0]

    @property
    def max_taps(self) -> int:
        """Taps per run T."""
        return self.belief.shape[1]

    def _column(self, taps: int) -> int:
        if int(taps) != taps or not 1 <= taps <= self.max_taps:
            raise ValueError(f"taps must be an integer in 1..{self.max_taps}, got {taps}")
        return int(taps) - 1

    def calibration_error(self, taps: int, *, bins: int = 10) -> float:
        """ECE of the decision belief after ``taps`` taps (every run, none stopped)."""
        t = self._column(taps)
        return expected_calibration_error(self.belief[:, t], self.estimate[:, t] == self.truth[:, t], bins=bins)

    def reliability(self, taps: int, *, bins: int = 10):
        """`reliability_bins` of the decision belief after ``taps`` taps."""
        t = self._column(taps)
        return reliability_bins(self.belief[:, t], self.estimate[:, t] == self.truth[:, t], bins=bins)

    def brier_score(self, taps: int) -> float:
        """Mean (belief in the decided class - 1 if it is right else 0)^2 over the first ``taps`` taps of
        every run: the Brier score of the decision's confidence, what a reliability diagram shows."""
        return float(self._squared_errors(slice(0, self._column(taps) + 1)).mean())

    def brier_score_at(self, tap: int) -> float:
        """The Brier score of the decision's confidence after tap ``tap`` alone (every run's belief then)."""
        return float(self._squared_errors(self._column(tap)).mean())

    def _squared_errors(self, columns) -> np.ndarray:
        """(belief in the decided class - 1 if it is right else 0)^2 at the tap ``columns`` index."""
        right = self.estimate[:, columns] == self.truth[:, columns]
        return (self.belief[:, columns] - right) ** 2

    def decisions(self, threshold: float) -> Decisions:
        """Each run's decision at ``threshold``: the first tap whose belief exceeds it, else the last tap."""
        if not 0.0 <= threshold <= 1.0:
            raise ValueError(f"threshold must be in [0, 1], got {threshold}")
        crossed = self.belief > threshold
        forced = ~crossed.any(axis=1)
        column = np.where(forced, self.max_taps - 1, crossed.argmax(axis=1))
        rows = np.arange(self.runs)
        identity = self.estimate[rows, column]
        error = np.abs(self.values[identity] - self.values[self.truth[rows, column]])
        if self.period is not None:
            error = np.minimum(error % self.period, self.period - error % self.period)
        return Decisions(float(threshold), column + 1, identity, self.belief[rows, column], forced, error)


def trace_beliefs(environment: VirtualEnvironment, policy: Policy, *, runs: int = 5000, max_taps: int = 20,
                  seed=None, move_threshold: float = 0.0, shift_mode: str = "edge") -> BeliefTrace:
    """Monte Carlo runs of ``max_taps`` taps each, keeping every tap's decision belief.

    The runs follow `perception.monte_carlo` without a deadline: the same seed draws the same true
    classes and starting locations.

    Parameters
    ----------
    environment : VirtualEnvironment
    policy : Policy
    runs : int
    max_taps : int
    seed : int or numpy.random.Generator, optional
    move_threshold : float
        theta_est on the 'where' belief (0: always move).
    shift_mode : {"edge", "uniform"}

    Returns
    -------
    BeliefTrace
    """
    if int(runs) != runs or runs < 1:
        raise ValueError(f"runs must be an integer >= 1, got {runs}")
    if int(max_taps) != max_taps or max_taps < 1:
        raise ValueError(f"max_taps must be an integer >= 1, got {max_taps}")
    model = environment.model
    n_loc, n_id = model.n_locations, model.n_identities
    rng = np.random.default_rng(seed)
    runs, max_taps = int(runs), int(max_taps)
    location = rng.integers(0, n_loc, runs)
    identity = rng.integers(0, n_id, runs)
    log_belief = np.broadcast_to(bayes.flat_prior(n_loc, n_id), (runs, n_loc, n_id)).copy()
    table = environment.log_likelihood.reshape(-1, n_loc, n_id)
    belief = np.empty((runs, max_taps))
    estimate = np.empty((runs, max_taps), np.intp)
    truth = np.empty((runs, max_taps), np.intp)
    for tap in range(max_taps):
        log_belief = bayes.tap_update(table[environment.draw(location * n_id + identity, rng)], log_belief, tap + 1,
                                      model.tap_tempering)
        where, what = bayes.marginals(log_belief)
        decision = what if n_id > 1 else where
        belief[:, tap] = decision.max(axis=1)
        estimate[:, tap] = decision.argmax(axis=1)
        truth[:, tap] = identity if n_id > 1 else location
        where_estimate = where.argmax(axis=1)
        offset = np.where(where.max(axis=1) > move_threshold, policy.move(where, where_estimate, rng), 0)
        offset = clamp_move(where_estimate, offset, n_loc)
        location = np.clip(location + offset, 0, n_loc - 1)
        log_belief = bayes.shift(log_belief, offset, mode=shift_mode)
    values = model.identities if n_id > 1 else model.location_centres
    return BeliefTrace(policy.name, belief, estimate, truth, np.asarray(values, dtype=np.float64),
                       model.identity_period if n_id > 1 else None)


#: Ranges (log10) `fit_tap_tempering` searches for g_1 and for g_2, g_3, ...
_LOG10_FIRST_TAP, _LOG10_LATER_TAPS = (-2.0, 2.0), (-2.0, 0.0)


def fit_tap_tempering(environment: VirtualEnvironment, policy: Policy, *, taps: int = CALIBRATION_TAPS[-1],
                      runs: int = 2000, seed=0, **options) -> tuple[float, ...]:
    """The tap tempering schedule (g_1, ..., g_taps) that calibrates the beliefs of this policy's runs tap by tap.

    Temperature scaling (Guo et al. 2017) of each tap of a decision in turn: the t-th tap's log
    likelihood is multiplied by g_t (`perception.bayes.tap_update`), and g_1, then g_2 given g_1, ...
    minimise the Brier score of the decision's confidence after tap t (belief in the decided class
    against 1 if it is right, else 0) over Monte Carlo runs of ``environment`` (`trace_beliefs`, the
    same seed for every candidate). g_t < 1 where a run's t-th tap repeats the evidence of the taps
    before it (the same depth of the same gap gives nearly the same tap). Taps beyond the last take
    g_taps. (The log loss is ruled by the few runs confidently wrong, and its factors leave the common
    beliefs underconfident.) Any schedule the environment's model has is replaced, not built on.

    g_1 is searched over 0.01..100 (it also corrects the one-tap tempering, fitted by log loss on
    single taps, for the Brier score and the policy's first tap); g_2, g_3, ... over 0.01..1: a later
    tap is worth at most an independent one. Without that bound, when every held-out run is right
    after tap t the Brier score falls as g_t grows and the fit runs to the end of its range (g = 100 on
    the simulated station's 52 held-out taps), which makes one later mistake a certainty.

    Parameters
    ----------
    environment : VirtualEnvironment
        Taps independent of those the model was fitted on (e.g. out-of-fold training taps), not the
        test collection whose figures are reported.
    policy : Policy
    taps : int
        Taps fitted, >= 1: the length of the schedule.
    runs : int
    seed : int
    **options
        ``move_threshold``, ``shift_mode`` for `trace_beliefs`.

    Returns
    -------
    tuple of float > 0; ``environment.model.with_tap_tempering(schedule)`` is the calibrated model
    """
    from scipy.optimize import minimize_scalar

    if int(taps) != taps or taps < 1:
        raise ValueError(f"taps must be an integer >= 1, got {taps}")
    schedule: list[float] = []

    def brier(log10_factor: float, t: int) -> float:
        trace = trace_beliefs(environment.with_tap_tempering((*schedule, 10.0 ** log10_factor)), policy, runs=runs,
                              max_taps=t, seed=seed, **options)
        return trace.brier_score_at(t)

    for t in range(1, int(taps) + 1):
        bounds = _LOG10_FIRST_TAP if t == 1 else _LOG10_LATER_TAPS
        result = minimize_scalar(brier, bounds=bounds, args=(t,), method="bounded", options={"xatol": 2e-3})
        factor = 10.0 ** result.x
        if t > 1 and brier(0.0, t) <= result.fun:   # the bounded search never evaluates its end: g_t = 1 itself
            factor = 1.0
        schedule.append(float(factor))
    return tuple(schedule)


def threshold_for_accuracy(trace: BeliefTrace, target: float, *, tolerance: float = 0.0, thresholds=None):
    """The threshold whose decisions reach ``target`` accuracy within ``tolerance`` in the fewest mean taps.

    Parameters
    ----------
    trace : BeliefTrace
    target : float in (0, 1]
        Fraction of decisions that must lie within ``tolerance`` of the truth.
    tolerance : float
        Identity units (0: the exact class).
    thresholds : sequence of float, optional
        Candidates; default `DECISION_THRESHOLDS` (0.3..0.9999).

    Returns
    -------
    (Decisions, float) or (None, float)
        The decisions at the chosen threshold, and the best accuracy any candidate reached (None if
        none reaches the target).
    """
    if not 0.0 < target <= 1.0:
        raise ValueError(f"target must be in (0, 1], got {target}")
    if not (np.isfinite(tolerance) and tolerance >= 0):
        raise ValueError(f"tolerance must be a number >= 0, got {tolerance}")
    if thresholds is None:
        thresholds = DECISION_THRESHOLDS
    best, best_accuracy = None, 0.0
    for threshold in thresholds:
        decisions = trace.decisions(float(threshold))
        accuracy = float(decisions.within(tolerance).mean())
        best_accuracy = max(best_accuracy, accuracy)
        if accuracy >= target and (best is None or decisions.taps.mean() < best.taps.mean()):
            best = decisions
    return best, best_accuracy


@dataclass(frozen=True)
class AccuracySweep:
    """Active perception at each fixation location, with the threshold reaching a target accuracy.

    Attributes
    ----------
    fixations : (F,) ndarray
        Fixation locations, location units (class centres).
    thresholds : (F,) ndarray
        Decision threshold reaching the target in the fewest taps (NaN where none does).
    taps : (F,) ndarray
        Mean decision taps there (NaN where none does).
    accuracy : (F,) ndarray
        Fraction of decisions within the tolerance there (else the best any threshold reached).
    target, tolerance : float
    best : int or None
        Index of the fixation reaching the target in the fewest mean taps (None: no fixation does).
    tap_tempering : tuple of float
        The tap tempering schedule g_1..g_5 fitted at the best fixation, whose threshold, taps and
        accuracy are those of the model with it (`fit_tap_tempering`; empty: not fitted).
    """

    fixations: np.ndarray
    thresholds: np.ndarray
    taps: np.ndarray
    accuracy: np.ndarray
    target: float
    tolerance: float
    best: int | None
    tap_tempering: tuple[float, ...] = ()


def _other_seed(seed):
    """A seed whose runs are independent of ``seed``'s (None: fresh entropy; a Generator: itself, drawn on)."""
    if isinstance(seed, (int, np.integer)):
        return np.random.SeedSequence(int(seed)).spawn(1)[0]
    return seed


def _accuracy_row(fixation_class, *, environment, runs, seed, max_taps, target, tolerance, options):
    """(threshold, mean taps, accuracy) at one fixation: a piece of `fixation_for_accuracy` (module level, so
    that it travels to a worker); NaN, NaN, the best accuracy reached when the target is not."""
    from .policies import FixationPolicy

    trace = trace_beliefs(environment, FixationPolicy(int(fixation_class)), runs=runs, max_taps=max_taps, seed=seed,
                          **options)
    decisions, best_accuracy = threshold_for_accuracy(trace, target, tolerance=tolerance)
    if decisions is None:
        return np.nan, np.nan, best_accuracy
    return decisions.threshold, float(decisions.taps.mean()), float(decisions.within(tolerance).mean())


def fixation_for_accuracy(environment: VirtualEnvironment, *, target: float, tolerance: float = 0.0,
                          fixation_classes=None, runs: int = 2000, max_taps: int = 20, seed=0,
                          progress=None, temper: bool = False, confirm_runs: int | None = None,
                          map_fn=None, **options) -> AccuracySweep:
    """For each fixation location, the threshold whose decisions reach ``target`` accuracy in the fewest taps.

    Parameters
    ----------
    environment : VirtualEnvironment
    target : float in (0, 1]
        Fraction of decisions within ``tolerance`` of the true identity.
    tolerance : float
        Identity units (0: the exact class).
    fixation_classes : sequence of int, optional
        Location classes to try; default all.
    runs, max_taps, seed
        As `trace_beliefs` (the same seed for every fixation).
    progress : callable, optional
        Wraps the iterable of fixations (e.g. ``tqdm``).
    temper : bool
        Fit the tap tempering schedule at the best fixation (`fit_tap_tempering`: beliefs after each of
        taps 1 to 5) and choose its threshold again on the calibrated beliefs. (Tempering
        relabels the beliefs rather than reorders the runs' decisions, so the fixation is chosen before.)
    confirm_runs : int, optional
        The best fixation's threshold is chosen again on this many fresh runs (another seed): the
        sweep's own runs chose the fixation, and the lowest threshold that happened to reach the
        target on them reaches it less often on others (with 2000 runs on the simulated station: 80-95 %
        of live decisions within tolerance for a target of 95 %). Default ``max(runs, 10000)``; 0 keeps
        the sweep's choice.
    map_fn : callable, optional
        Runs the fixations: ``map_fn(function, fixation_classes)``, results in order (e.g.
        `tactip.cluster.cluster_map` on a Dask cluster); the same results as run here (default).
    **options
        ``move_threshold``, ``shift_mode`` for `trace_beliefs`.

    Returns
    -------
    AccuracySweep
    """
    from .policies import FixationPolicy

    model = environment.model
    classes = np.arange(model.n_locations) if fixation_classes is None else np.asarray(fixation_classes, np.intp)

    row = functools.partial(_accuracy_row, runs=runs, seed=seed, max_taps=max_taps, target=target,
                            tolerance=tolerance, options=options)
    rows = map_pieces(functools.partial(row, environment=environment), classes.tolist(), map_fn=map_fn,
                      progress=progress)
    thresholds, taps, accuracy = (np.array(column, dtype=np.float64) for column in zip(*rows))
    reached = np.isfinite(taps)
    best = int(np.nanargmin(taps)) if reached.any() else None
    schedule = ()
    if temper and best is not None:
        fitted = fit_tap_tempering(environment, FixationPolicy(int(classes[best])), runs=runs, seed=seed, **options)
        tempered = row(classes[best], environment=environment.with_tap_tempering(fitted))
        if np.isfinite(tempered[1]):  # the target is still reached (else keep the model as it was)
            schedule = fitted
            thresholds[best], taps[best], accuracy[best] = tempered
    confirm_runs = max(runs, 10000) if confirm_runs is None else int(confirm_runs)
    if confirm_runs > 0 and best is not None:
        # The threshold again at the chosen fixation, on runs that did not choose it (another seed).
        chosen = environment.with_tap_tempering(schedule) if schedule else environment
        confirmed = row(classes[best], environment=chosen, runs=confirm_runs, seed=_other_seed(seed))
        if np.isfinite(confirmed[1]):
            thresholds[best], taps[best], accuracy[best] = confirmed
    return AccuracySweep(model.location_centres[classes], thresholds, taps, accuracy, float(target), float(tolerance),
                         best, schedule)
