"""Monte Carlo validation in a virtual environment made of test taps (paper 000 III-C; 002 III-B.5).

Each run draws a true identity class and a random starting location class, then taps: every tap
is drawn at random from the test taps of the run's current (location, identity) class, the
beliefs update, the policy moves the sensor (moves clamped to the range) and the beliefs shift,
until the decision. All runs step together: the log likelihood of every test tap against every
class is computed once (a test taps x classes matrix), so a step is gathers and adds.

Without a deadline, the decision threshold does not change a run's trajectory (moves depend on
the 'where' belief only), so one set of runs serves every threshold: each threshold records
its decision the first time the belief crosses it (common random numbers across thresholds).

Example
-------
>>> env = VirtualEnvironment(model, load_dataset("test.h5"))              # doctest: +SKIP
>>> result = monte_carlo(env, FixationPolicy(9), runs=5000, seed=1)      # doctest: +SKIP
>>> result.rows()[0]                                                     # doctest: +SKIP
{'policy': 'active', 'threshold': 0.0, 'mean_identity_error': 1.2, ...}
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import bayes
from .dataset import Dataset
from .errors import DatasetError
from .histogram import HistogramModel
from .perceiver import clamp_move
from .policies import Policy

__all__ = ["DEFAULT_THRESHOLDS", "VirtualEnvironment", "MonteCarloResult", "monte_carlo"]

#: Taps after which a run without a cap (``max_taps=None``) is stopped all the same and counted as forced.
SAFETY_TAPS = 2000

#: Decision thresholds of a speed-accuracy curve (20 values over 0-0.9999).
DEFAULT_THRESHOLDS = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.85, 0.9, 0.925, 0.95, 0.97, 0.98, 0.99,
                      0.995, 0.998, 0.999, 0.9999)


class VirtualEnvironment:
    """Test taps arranged by class, with their log likelihoods against a model computed once.

    Parameters
    ----------
    model : HistogramModel
    test : Dataset
        Test taps, independent of the training taps; every (location, identity) class of the
        model needs at least one.

    Raises
    ------
    ModelError
        The test taps are not of the model's front end, dims or samples.
    DatasetError
        A test identity is not one of the model's, or a class has no test taps.

    Attributes
    ----------
    log_likelihood : (T, L * I) float64 ndarray
        log P(z | c) of each test tap against each class.
    tap_class : (T,) int ndarray
        Class (l * I + i) each test tap was collected in.
    lateral : (T,) ndarray or None
        Lateral offset of each test tap, mm.
    """

    def __init__(self, model: HistogramModel, test: Dataset, *, _log_likelihood=None):
        model.check_dataset(test)
        self.model = model
        self.test = test
        self.tap_class = model.location_class(test.location) * model.n_identities + model.identity_class(test.identity)
        self.lateral = test.lateral
        if _log_likelihood is None:
            _log_likelihood = model.log_likelihood_batch(test.taps).reshape(len(test), model.n_classes)
        self.log_likelihood = _log_likelihood
        counts = np.bincount(self.tap_class, minlength=model.n_classes)
        empty = np.flatnonzero(counts == 0)
        if empty.size:
            l, i = divmod(int(empty[0]), model.n_identities)
            raise DatasetError(f"{empty.size} of {model.n_classes} classes have no test taps, e.g. location "
                               f"{model.location_centres[l]:g} {model.location_unit}, identity "
                               f"{model.identities[i]:g} {model.identity_unit}")
        # Per-class table: the test taps of class c are _order[_start[c]:_start[c] + _count[c]].
        self._order = np.argsort(self.tap_class, kind="stable")
        self._count = counts
        self._start = np.concatenate([[0], np.cumsum(counts)[:-1]])

    def __repr__(self) -> str:
        return f"<VirtualEnvironment {len(self.test)} test taps, {self.model.n_classes} classes>"

    @property
    def decided_class(self) -> np.ndarray:
        """(T,) int ndarray: what a decision on each test tap is judged against: its identity class, or its
        location class for a model of one identity (as `perception.bayes.decide` decides)."""
        n_id = self.model.n_identities
        return self.tap_class % n_id if n_id > 1 else self.tap_class

    def restrict(self, keep) -> VirtualEnvironment:
        """The environment with only some test taps (e.g. a band of lateral offsets).

        Parameters
        ----------
        keep : (T,) bool array
        """
        keep = np.asarray(keep, dtype=bool)
        return VirtualEnvironment(self.model, self.test.subset(keep), _log_likelihood=self.log_likelihood[keep])

    def tempered(self, factor: float) -> VirtualEnvironment:
        """The environment of ``model.tempered(factor)``: the same test taps, log likelihoods times ``factor``.

        Parameters
        ----------
        factor : float > 0
        """
        return VirtualEnvironment(self.model.tempered(factor), self.test, _log_likelihood=factor * self.log_likelihood)

    def with_tap_tempering(self, schedule) -> VirtualEnvironment:
        """The environment of ``model.with_tap_tempering(schedule)``: the same test taps and log likelihoods,
        the t-th tap of a run tempered by g_t in the belief update.

        Parameters
        ----------
        schedule : sequence of float > 0
        """
        return VirtualEnvironment(self.model.with_tap_tempering(schedule), self.test,
                                  _log_likelihood=self.log_likelihood)

    def draw(self, tap_class, rng: np.random.Generator) -> np.ndarray:
        """Indices of test taps drawn uniformly within each requested class.

        Parameters
        ----------
        tap_class : (R,) int array of class indices l * I + i
        rng : numpy.random.Generator

        Returns
        -------
        (R,) int ndarray of test tap indices
        """
        tap_class = np.asarray(tap_class)
        pick = (rng.random(tap_class.shape) * self._count[tap_class]).astype(np.intp)
        return self._order[self._start[tap_class] + pick]


@dataclass(frozen=True)
class MonteCarloResult:
    """Speed-accuracy figures of one policy over decision thresholds (arrays over K thresholds).

    Errors are mean absolute differences between the true and decided class values (identity
    units; location class centres in location units), averaged over runs. ``accuracy`` is the
    fraction of runs whose decided identity class is exactly right (location class, for a model
    with a single identity). The maps hold the same means per starting (location, identity)
    class (NaN for classes no run started in). ``identity_error_runs`` and ``taps_runs`` keep each
    run's identity error and decision taps, for figures of their distributions (paper 001 Fig. 7A,
    003 Fig. 7, 000 Fig. 8B).
    """

    policy: str
    thresholds: np.ndarray            # (K,)
    mean_identity_error: np.ndarray   # (K,)
    accuracy: np.ndarray              # (K,)
    mean_location_error: np.ndarray   # (K,)
    mean_taps: np.ndarray             # (K,)
    forced: np.ndarray                # (K,) fraction of runs that reached max_taps below the threshold
    null_decisions: np.ndarray        # (K,) mean null decisions per run (deadline)
    null_fraction: np.ndarray         # (K,) null decisions / attempts (paper 001 Fig. 6: a proportion)
    decided_identity_error: np.ndarray  # (K,) mean identity error over runs decided by the threshold (NaN: none)
    decided_location_error: np.ndarray  # (K,) the same for the location
    identity_error_map: np.ndarray    # (K, L, I)
    location_error_map: np.ndarray    # (K, L, I)
    taps_map: np.ndarray              # (K, L, I)
    runs: int
    final_location: np.ndarray | None = None  # (K, runs) true location class of each run at its decision
    identity_error_runs: np.ndarray | None = None  # (K, runs) each run's identity error (figures: histograms)
    taps_runs: np.ndarray | None = None            # (K, runs) each run's decision taps (figures: histograms)

    def rows(self) -> list[dict]:
        """One JSON-ready dict per threshold: policy, threshold, errors, accuracy, mean taps, forced and null."""
        return [{"policy": self.policy, "threshold": float(t), "mean_identity_error": float(e),
                 "accuracy": float(a), "mean_location_error": float(le), "mean_taps": float(n),
                 "forced": float(f), "null_decisions": float(z), "null_fraction": float(zf)}
                for t, e, a, le, n, f, z, zf in zip(self.thresholds, self.mean_identity_error, self.accuracy,
                                                    self.mean_location_error, self.mean_taps, self.forced,
                                                    self.null_decisions, self.null_fraction)]

    def best_within(self, tap_budget: float) -> int:
        """Index of the threshold with the lowest identity error among those with mean taps <= budget.

        Ties go to fewer taps; if no threshold fits the budget, the one with the fewest taps.
        Location errors decide for a model with a single identity.
        """
        error = self.mean_identity_error if self.identity_error_map.shape[-1] > 1 else self.mean_location_error
        fits = self.mean_taps <= tap_budget
        if not fits.any():
            return int(np.argmin(self.mean_taps))
        order = np.lexsort((self.mean_taps, np.where(fits, error, np.inf)))
        return int(order[0])


def monte_carlo(environment: VirtualEnvironment, policy: Policy, *, thresholds=DEFAULT_THRESHOLDS,
                runs: int = 5000, seed=None, move_threshold: float = 0.0, max_taps: int | None = 20,
                deadline: int | None = None, shift_mode: str = "edge", decision_rule: str = "marginal",
                identity_period: float | None = None, start_location=None, true_identity=None) -> MonteCarloResult:
    """Run the Monte Carlo validation of one policy over decision thresholds.

    Parameters
    ----------
    environment : VirtualEnvironment
    policy : Policy
    thresholds : sequence of float in [0, 1]
        Decision thresholds theta_dec.
    runs : int
        Monte Carlo runs (paper 002: 5000; 000: 10000).
    seed : int or numpy.random.Generator, optional
    move_threshold : float
        theta_est on the 'where' belief (0: always move).
    max_taps : int or None
        Taps at which a decision is forced (reported in ``forced``, apart from the threshold
        decisions in ``decided_*_error``); None: no cap, as in the papers (a run still undecided
        after `SAFETY_TAPS` taps is stopped and counted as forced).
    deadline : int, optional
        Taps per attempt before a null decision (paper 001): the beliefs restart from the flat
        prior and the sensor moves to a location class drawn uniformly over the range. Runs then
        depend on the threshold, so each threshold gets its own runs.
    shift_mode : {"edge", "uniform"}
    decision_rule : {"marginal", "joint"}
        Stop on the 'what' marginal (papers 002-004) or the joint class (paper 001 eq. 3).
    identity_period : float, optional
        Period of circular identities (e.g. 360 deg for edge angles): identity errors go the
        shorter way round. Default: the model's own (``model.identity_period``, from its training
        dataset); a named identity's error is 0 or 1 (wrong).
    start_location, true_identity : (runs,) int arrays, optional
        Starting location class and true identity class of each run (default: uniform random).

    Returns
    -------
    MonteCarloResult
    """
    model = environment.model
    thresholds = np.atleast_1d(np.asarray(thresholds, dtype=np.float64))
    if thresholds.ndim != 1 or thresholds.size == 0 or ((thresholds < 0) | (thresholds > 1)).any():
        raise ValueError(f"thresholds must be values in [0, 1], got {thresholds}")
    if int(runs) != runs or runs < 1:
        raise ValueError(f"runs must be an integer >= 1, got {runs}")
    if max_taps is not None and (int(max_taps) != max_taps or max_taps < 1):
        raise ValueError(f"max_taps must be an integer >= 1 or None, got {max_taps}")
    if decision_rule not in bayes.DECISION_RULES:
        raise ValueError(f"decision_rule must be one of {bayes.DECISION_RULES}, got {decision_rule!r}")
    if deadline is not None and (int(deadline) != deadline or deadline < 1):
        raise ValueError(f"deadline must be an integer >= 1 or None, got {deadline}")
    if identity_period is not None and not (np.isfinite(identity_period) and identity_period > 0):
        raise ValueError(f"identity_period must be a finite number > 0 or None, got {identity_period}")
    if not 0.0 <= move_threshold <= 1.0:
        raise ValueError(f"move_threshold must be in [0, 1], got {move_threshold}")
    if shift_mode not in bayes.SHIFT_MODES:
        raise ValueError(f"shift_mode must be one of {bayes.SHIFT_MODES}, got {shift_mode!r}")
    rng = np.random.default_rng(seed)
    runs = int(runs)
    start = rng.integers(0, model.n_locations, runs) if start_location is None else np.asarray(start_location)
    identity = rng.integers(0, model.n_identities, runs) if true_identity is None else np.asarray(true_identity)
    if start.shape != (runs,) or identity.shape != (runs,):
        raise ValueError(f"start_location and true_identity must have shape ({runs},)")
    settings = dict(move_threshold=move_threshold, max_taps=SAFETY_TAPS if max_taps is None else int(max_taps),
                    deadline=deadline, shift_mode=shift_mode, decision_rule=decision_rule)
    if deadline is None:
        outcome = _simulate(environment, policy, thresholds, start, identity, rng, **settings)
    else:
        parts = [_simulate(environment, policy, thresholds[k:k + 1], start, identity, rng, **settings)
                 for k in range(len(thresholds))]
        outcome = {name: np.concatenate([p[name] for p in parts]) for name in parts[0]}
    return _summarise(model, policy.name, thresholds, start, identity, outcome, identity_period)


def _simulate(env, policy, thresholds, start, identity, rng, *, move_threshold, max_taps, deadline, shift_mode,
              decision_rule="marginal"):
    """All runs step together; returns per-(threshold, run) decisions."""
    model = env.model
    n_loc, n_id = model.n_locations, model.n_identities
    runs, k = len(start), len(thresholds)
    location = start.astype(np.intp).copy()
    flat = bayes.flat_prior(n_loc, n_id)
    log_belief = np.broadcast_to(flat, (runs, n_loc, n_id)).copy()
    done = np.zeros((k, runs), bool)
    out = {"identity_class": np.zeros((k, runs), np.intp), "location_class": np.zeros((k, runs), np.intp),
           "true_location": np.zeros((k, runs), np.intp), "taps": np.zeros((k, runs), np.intp),
           "forced": np.zeros((k, runs), bool), "nulls": np.zeros((k, runs), np.intp)}
    nulls = np.zeros(runs, np.intp)
    attempt = np.zeros(runs, np.intp)
    table = env.log_likelihood.reshape(-1, n_loc, n_id)
    for tap in range(1, max_taps + 1):
        attempt += 1
        log_belief = bayes.tap_update(table[env.draw(location * n_id + identity, rng)], log_belief, attempt,
                                      model.tap_tempering)
        where, what = bayes.marginals(log_belief)
        estimate = where.argmax(axis=1)
        if decision_rule == "joint":
            belief, decided_location, decided_identity = bayes.decide(log_belief, rule="joint")
        else:   # the marginal rule from the marginals already at hand (one exp per step)
            belief, decided_location, decided_identity = (what if n_id > 1 else where).max(axis=1), estimate, \
                what.argmax(axis=1)
        crossed = belief > thresholds[:, None]
        new = ~done & (crossed | (tap == max_taps))
        for name, value in (("identity_class", decided_identity), ("location_class", decided_location),
                            ("true_location", location), ("nulls", nulls)):
            out[name] = np.where(new, value, out[name])
        out["taps"][new] = tap
        out["forced"] |= new & ~crossed
        done |= new
        if done.all():
            break
        offset = np.where(where.max(axis=1) > move_threshold, policy.move(where, estimate, rng), 0)
        offset = clamp_move(estimate, offset, n_loc)
        location = np.clip(location + offset, 0, n_loc - 1)
        log_belief = bayes.shift(log_belief, offset, mode=shift_mode)
        if deadline is not None:
            # Null decision (paper 001): restart from the prior, move to a place drawn uniformly over the range.
            null = ~done[0] & (attempt >= deadline)
            location = np.where(null, rng.integers(0, n_loc, runs), location)
            log_belief[null] = flat
            attempt[null] = 0
            nulls += null
    return out


def _summarise(model, name, thresholds, start, identity, out, period=None) -> MonteCarloResult:
    """Errors, accuracy, taps, per starting-class maps."""
    n_loc, n_id = model.n_locations, model.n_identities
    identity_error = model.identity_error(model.identities[out["identity_class"]], model.identities[identity])
    if period is not None:  # a period given to this run, over the model's own
        identity_error = np.abs(model.identities[out["identity_class"]] - model.identities[identity])
        identity_error = np.minimum(identity_error % period, period - identity_error % period)
    centres = model.location_centres
    location_error = np.abs(centres[out["location_class"]] - centres[out["true_location"]])
    right = out["identity_class"] == identity if n_id > 1 else out["location_class"] == out["true_location"]
    k = len(thresholds)
    decided = ~out["forced"]
    with np.errstate(invalid="ignore"):
        decided_identity = np.where(decided, identity_error, 0).sum(axis=1) / decided.sum(axis=1)
        decided_location = np.where(decided, location_error, 0).sum(axis=1) / decided.sum(axis=1)
    # attempts: every null decision plus the run's final decision (forced ones included)
    null_fraction = out["nulls"].sum(axis=1) / (out["nulls"].sum(axis=1) + len(start))
    start_class = start * n_id + identity
    runs_per_class = np.bincount(start_class, minlength=n_loc * n_id)

    def per_class(values):
        index = (np.arange(k)[:, None] * (n_loc * n_id) + start_class).ravel()
        sums = np.bincount(index, weights=values.ravel().astype(np.float64), minlength=k * n_loc * n_id)
        with np.errstate(invalid="ignore", divide="ignore"):
            return (sums.reshape(k, n_loc * n_id) / runs_per_class).reshape(k, n_loc, n_id)

    return MonteCarloResult(
        policy=name, thresholds=thresholds, mean_identity_error=identity_error.mean(axis=1),
        accuracy=right.mean(axis=1), mean_location_error=location_error.mean(axis=1),
        mean_taps=out["taps"].mean(axis=1), forced=out["forced"].mean(axis=1),
        null_decisions=out["nulls"].mean(axis=1), null_fraction=null_fraction,
        decided_identity_error=decided_identity, decided_location_error=decided_location,
        identity_error_map=per_class(identity_error),
        location_error_map=per_class(location_error), taps_map=per_class(out["taps"]), runs=len(start),
        final_location=out["true_location"], identity_error_runs=identity_error, taps_runs=out["taps"])
