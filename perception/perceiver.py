"""The tap-by-tap active Bayesian classifier that a station drives.

Each `Perceiver.observe` takes one tap, updates the joint (location, identity) belief, and
returns a `Step`: the beliefs, the estimates, whether the decision is made, and the move the
policy asks for. The caller moves the sensor and reports the move it actually made with
`Perceiver.moved`, which shifts the beliefs by whole location classes. The perceiver records
nothing; it keeps the last prior and posterior for inspection.

Rules (papers 000, 001, 002, 003, 004):

- stop (``decision_rule="marginal"``, papers 002-004): the 'what' (identity) marginal crosses
  ``decision_threshold`` (theta_dec); for a model with a single identity (a location task) the
  'where' marginal does. ``decision_rule="joint"`` (paper 001 eq. 3): any joint (location,
  identity) class crosses it, and the decision is that joint MAP class;
- move: when the 'where' marginal crosses ``move_threshold`` (theta_est: 0 always moves,
  1 never moves, in between weakly active), the policy's move from the MAP location;
- deadline: after ``deadline`` taps without a decision, a null decision; the beliefs restart
  from the prior and the sensor relocates to a location drawn uniformly over the range
  (``Step.relocate_to``, absolute: paper 001 "the finger randomly moves to another position");
- ``max_taps``: the decision is forced (MAP, ``Step.forced``) when the taps reach it; the papers
  have no cap, so ``max_taps=None`` never forces;
- adaptive prior: with ``adaptive_prior=True``, `reset` starts from alpha x the last decision's
  posterior shifted by Delta identity classes + (1 - alpha) x flat (paper 004 eqs. 7, 12); Delta
  is ``prior_shift`` if given, else learned from decision to decision by predicted information
  gain (`perception.adaptive.ShiftLearner`, eqs. 8-11). ``identity_period`` makes the identity
  classes circular (angles over a full turn: the shift wraps round).

Example
-------
>>> perceiver = Perceiver(model, FixationPolicy(9), decision_threshold=0.9)   # doctest: +SKIP
>>> step = perceiver.observe(tap)                                            # doctest: +SKIP
>>> if not step.decided:                                                     # doctest: +SKIP
...     perceiver.moved(arm.move_depth(step.move))
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import bayes
from .errors import PerceptionError
from .likelihood import LikelihoodModel
from .histogram import HistogramModel
from .adaptive import ShiftLearner
from .policies import Policy, StationaryPolicy

__all__ = ["Step", "Perceiver", "clamp_move"]


@dataclass(frozen=True)
class Step:
    """What one tap changed.

    Attributes
    ----------
    posterior : (L, I) ndarray
        Joint belief P(x_l, w_i | z_1:t) after the tap (before any move).
    where_belief : (L,) ndarray
        Location marginal.
    what_belief : (I,) ndarray
        Identity marginal.
    location_class, identity_class : int
        MAP classes.
    location_estimate : float
        MAP location class centre, location units (e.g. depth in mm).
    identity_estimate : float
        MAP identity, identity units (e.g. gap width in mm).
    belief : float
        Largest belief of the decision marginal (identity; location for a location task).
    decided : bool
        The decision is made (threshold crossed, or forced at ``max_taps``).
    forced : bool
        Decided because ``max_taps`` was reached, below the threshold.
    null : bool
        The deadline passed without a decision: beliefs restarted; move the sensor to `relocate_to`.
    move : float
        Requested relative move, location units, snapped to whole classes and clamped to the range
        (0 after a null decision: the relocation is absolute).
    move_classes : int
        The same move in location classes.
    taps : int
        Taps since `Perceiver.reset` (including those before null decisions).
    relocate_to : float or None
        After a null decision: the location (location units, a class centre drawn uniformly over
        the model's range) to move the sensor to, in the frame of the training range; else None.
    """

    posterior: np.ndarray
    where_belief: np.ndarray
    what_belief: np.ndarray
    location_class: int
    identity_class: int
    location_estimate: float
    identity_estimate: float
    belief: float
    decided: bool
    forced: bool
    null: bool
    move: float
    move_classes: int
    taps: int
    relocate_to: float | None = None


def clamp_move(location_estimate, offset_classes, n_locations: int) -> np.ndarray:
    """Clamp moves so that the estimated location stays inside the class range.

    Parameters
    ----------
    location_estimate : (R,) int array
        Current MAP location classes.
    offset_classes : (R,) int array
        Requested moves in classes.
    n_locations : int

    Returns
    -------
    (R,) intp ndarray
    """
    estimate = np.asarray(location_estimate, dtype=np.intp)
    return np.clip(estimate + np.asarray(offset_classes, dtype=np.intp), 0, n_locations - 1) - estimate


class Perceiver:
    """Sequential active Bayesian perception over a model's (location, identity) classes.

    Parameters
    ----------
    model : HistogramModel
    policy : Policy, optional
        Control policy; default `StationaryPolicy` (passive).
    decision_threshold : float in [0, 1]
        theta_dec on the decision marginal.
    move_threshold : float in [0, 1]
        theta_est on the 'where' marginal (0: always move, 1: never).
    max_taps : int or None
        Taps at which the decision is forced; None never forces (the papers' rule).
    deadline : int, optional
        Taps per attempt before a null decision and random relocation (paper 001).
    shift_mode : {"edge", "uniform"}
        Belief shift boundary convention (see `perception.bayes.shift`).
    decision_rule : {"marginal", "joint"}
        Stop on the 'what' marginal (papers 002-004) or on the joint class (paper 001).
    adaptive_prior : bool
        Start each decision from the adaptive prior of paper 004 eq. 12.
    alpha : float
        Weight of the predicted distribution in the adaptive prior (paper 004: 0.5).
    prior_shift : int, optional
        Delta, identity classes; default: learned by predicted information gain.
    identity_period : float, optional
        Period of the identities, identity units (e.g. 360 deg): the identity classes are circular.
    rng : numpy.random.Generator or int, optional
        Randomness for random policies and relocations.
    """

    def __init__(self, model: HistogramModel, policy: Policy | None = None, *, decision_threshold: float = 0.9,
                 move_threshold: float = 0.0, max_taps: int | None = 20, deadline: int | None = None,
                 shift_mode: str = "edge", decision_rule: str = "marginal", adaptive_prior: bool = False,
                 alpha: float = 0.5, prior_shift: int | None = None, identity_period: float | None = None, rng=None):
        if not isinstance(model, LikelihoodModel):
            raise TypeError(f"model must be a LikelihoodModel, got {type(model).__name__}")
        for name, value in (("decision_threshold", decision_threshold), ("move_threshold", move_threshold),
                            ("alpha", alpha)):
            if not 0.0 <= value <= 1.0:
                raise ValueError(f"{name} must be in [0, 1], got {value}")
        if max_taps is not None and (int(max_taps) != max_taps or max_taps < 1):
            raise ValueError(f"max_taps must be an integer >= 1 or None, got {max_taps}")
        if decision_rule not in bayes.DECISION_RULES:
            raise ValueError(f"decision_rule must be one of {bayes.DECISION_RULES}, got {decision_rule!r}")
        if prior_shift is not None and int(prior_shift) != prior_shift:
            raise ValueError(f"prior_shift must be an integer number of identity classes or None, got {prior_shift}")
        if identity_period is not None and not (np.isfinite(identity_period) and identity_period > 0):
            raise ValueError(f"identity_period must be a finite number > 0 or None, got {identity_period}")
        if deadline is not None and (int(deadline) != deadline or deadline < 1):
            raise ValueError(f"deadline must be an integer >= 1 or None, got {deadline}")
        if shift_mode not in bayes.SHIFT_MODES:
            raise ValueError(f"shift_mode must be one of {bayes.SHIFT_MODES}, got {shift_mode!r}")
        self.model = model
        self.policy = policy if policy is not None else StationaryPolicy()
        self.decision_threshold = float(decision_threshold)
        self.move_threshold = float(move_threshold)
        self.max_taps = None if max_taps is None else int(max_taps)
        self.decision_rule = decision_rule
        self.prior_shift = None if prior_shift is None else int(prior_shift)
        self.identity_period = None if identity_period is None else float(identity_period)
        self.deadline = None if deadline is None else int(deadline)
        self.shift_mode = shift_mode
        self.adaptive_prior = bool(adaptive_prior)
        self.alpha = float(alpha)
        self.rng = np.random.default_rng(rng)
        self.shift_learner = ShiftLearner(model.n_identities, alpha=max(self.alpha, 1e-6),
                                          circular=self.identity_period is not None)
        self._last_decision = None
        self._last_evidence = None
        self.reset()

    def __repr__(self) -> str:
        return (f"Perceiver(policy={self.policy!r}, decision_threshold={self.decision_threshold}, "
                f"move_threshold={self.move_threshold}, max_taps={self.max_taps}, deadline={self.deadline}, "
                f"shift_mode={self.shift_mode!r}, decision_rule={self.decision_rule!r}, "
                f"adaptive_prior={self.adaptive_prior}, prior_shift={self.prior_shift})")

    @property
    def delta(self) -> int:
        """Delta, identity classes, that the adaptive prior shifts the last posterior by (paper 004 eq. 7)."""
        return self.prior_shift if self.prior_shift is not None else int(self.shift_learner.delta[0])

    @property
    def prior(self) -> np.ndarray:
        """(L, I) belief before the last update (after `reset`: the starting prior)."""
        return np.exp(self._log_prior)

    @property
    def posterior(self) -> np.ndarray:
        """(L, I) current belief (after the last update and any reported move)."""
        return np.exp(self._log_posterior)

    @property
    def taps(self) -> int:
        """Taps since the last `reset`."""
        return self._taps

    def reset(self, prior=None) -> None:
        """Start a new decision.

        Parameters
        ----------
        prior : (L, I) array of probabilities, optional
            Starting belief. Default: flat, or the adaptive prior after a decision when
            ``adaptive_prior`` is on.
        """
        shape = (self.model.n_locations, self.model.n_identities)
        if prior is not None:
            prior = np.asarray(prior, dtype=np.float64)
            if prior.shape != shape or (prior < 0).any() or not prior.sum() > 0:
                raise PerceptionError(f"prior must be non-negative of shape {shape} with a positive sum")
            with np.errstate(divide="ignore"):
                start = bayes.normalize(np.log(prior))
        elif self.adaptive_prior and self._last_decision is not None:
            start = bayes.adaptive_prior(self._last_decision, alpha=self.alpha, shift_classes=self.delta,
                                         circular=self.identity_period is not None)
        else:
            start = bayes.flat_prior(*shape)
        self._start = start
        self._log_prior = self._log_posterior = start
        self._log_evidence = bayes.flat_prior(*shape)
        self._taps = self._attempt_taps = 0
        self._decided = False
        self._pending_move = 0
        self._relocating = False

    def observe(self, tap) -> Step:
        """Update the beliefs with one tap and decide what to do next.

        Parameters
        ----------
        tap : (samples, dims) array

        Returns
        -------
        Step

        Raises
        ------
        ModelError
            The tap does not have the model's shape.
        PerceptionError
            The decision is already made (call `reset`), or the last requested move was not reported.
        """
        if self._decided:
            raise PerceptionError("the decision is made; call reset() before the next tap")
        if self._pending_move or self._relocating:
            raise PerceptionError("report the requested move with moved() before the next tap "
                                  "(moved(0.0) if the sensor did not move)")
        model = self.model
        log_likelihood = model.log_likelihood(tap)
        self._taps += 1
        self._attempt_taps += 1
        self._log_prior = self._log_posterior
        # the t-th tap of this attempt, tempered by the model's g_t (its taps repeat each other's evidence)
        self._log_posterior = bayes.tap_update(log_likelihood, self._log_prior, self._attempt_taps,
                                               model.tap_tempering)
        self._log_evidence = bayes.tap_update(log_likelihood, self._log_evidence, self._attempt_taps,
                                              model.tap_tempering)
        posterior = np.exp(self._log_posterior)
        where, what = posterior.sum(axis=1), posterior.sum(axis=0)
        belief, location_class, identity_class = (x.item() for x in bayes.decide(self._log_posterior,
                                                                                  rule=self.decision_rule))
        decided = belief > self.decision_threshold
        forced = not decided and self.max_taps is not None and self._taps >= self.max_taps
        null = not (decided or forced) and self.deadline is not None and self._attempt_taps >= self.deadline
        move = 0
        relocate_to = None
        if decided or forced:
            self._decided = True
            self._learn()
            self._last_decision = self._log_posterior
        elif null:
            # Null decision (paper 001): discard the evidence, move to a uniformly drawn place of the range.
            relocate_to = float(model.location_centres[self.rng.integers(model.n_locations)])
            self._log_posterior = self._start
            self._log_evidence = bayes.flat_prior(model.n_locations, model.n_identities)
            self._attempt_taps = 0
            self._relocating = True
        elif where.max() > self.move_threshold:
            # the move starts from the MAP 'where' class (papers 003 eq. 8, 004 eq. 5)
            move = self.policy.move(where[None], np.array([where.argmax()]), self.rng)[0]
        move = int(clamp_move([where.argmax()], [move], model.n_locations)[0])
        self._pending_move = move
        return Step(posterior=posterior, where_belief=where, what_belief=what, location_class=location_class,
                    identity_class=identity_class, location_estimate=float(model.location_centres[location_class]),
                    identity_estimate=float(model.identities[identity_class]), belief=belief,
                    decided=decided or forced, forced=forced, null=null, move=move * model.class_width,
                    move_classes=move, taps=self._taps, relocate_to=relocate_to)

    def _learn(self) -> None:
        """Update the learned Delta from what this decision's taps and the previous decision's taps say.

        The taps' own belief (from a flat prior), not the posterior: a posterior holds the prior
        that the current Delta made, which would teach Delta to keep itself.
        """
        evidence = np.exp(self._log_evidence).sum(axis=0)
        if self.adaptive_prior and self.prior_shift is None and self._last_evidence is not None:
            self.shift_learner.observe(self._last_evidence[None], evidence[None])
        self._last_evidence = evidence

    def moved(self, offset: float) -> None:
        """Report the move the sensor actually made; the beliefs shift by whole classes.

        After a decision (before `reset`), the move shifts the decision's posterior too, the one the
        adaptive prior starts the next decision from (paper 004 eq. 7 predicts the identity's change,
        not the sensor's move: that is known and shifts the location classes like any other move).

        Parameters
        ----------
        offset : float
            Relative move in location units (e.g. mm of depth), positive towards higher location.
            After a null decision, the move to ``Step.relocate_to``: the beliefs, restarted, do not shift.
        """
        if self._relocating:
            self._relocating = False
            return
        width = self.model.class_width
        classes = int(np.rint(offset / width)) if width > 0 else 0
        self._log_posterior = bayes.shift(self._log_posterior, classes, mode=self.shift_mode)
        self._log_evidence = bayes.shift(self._log_evidence, classes, mode=self.shift_mode)
        if self._decided:
            self._last_decision = self._log_posterior
        self._pending_move = 0
