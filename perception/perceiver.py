"""The tap-by-tap active Bayesian classifier that a station drives.

Each `Perceiver.observe` takes one tap, updates the joint (location, identity) belief, and
returns a `Step`: the beliefs, the estimates, whether the decision is made, and the move the
policy asks for. The caller moves the sensor and reports the move it actually made with
`Perceiver.moved`, which shifts the beliefs by whole location classes. The perceiver records
nothing; it keeps the last prior and posterior for inspection.

Rules (papers 000, 001, 002, 003, 004):

- stop: the 'what' (identity) marginal crosses ``decision_threshold`` (theta_dec); for a model
  with a single identity (a location task) the 'where' marginal does;
- move: when the 'where' marginal crosses ``move_threshold`` (theta_est: 0 always moves,
  1 never moves, in between weakly active), the policy's move from the MAP location;
- deadline: after ``deadline`` taps without a decision, a null decision; the beliefs restart
  from the prior and the sensor relocates to a random location (paper 001);
- ``max_taps``: the decision is forced (MAP, ``Step.forced``) when the taps reach it;
- adaptive prior: with ``adaptive_prior=True``, `reset` starts from alpha x the last decision's
  posterior + (1 - alpha) x flat (paper 004 eq. 12).

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
from .model import HistogramModel
from .policies import Policy, RandomPolicy, StationaryPolicy

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
        The deadline passed without a decision: beliefs restarted, `move` relocates randomly.
    move : float
        Requested relative move, location units, snapped to whole classes and clamped to the range.
    move_classes : int
        The same move in location classes.
    taps : int
        Taps since `Perceiver.reset` (including those before null decisions).
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
    max_taps : int
        Taps at which the decision is forced.
    deadline : int, optional
        Taps per attempt before a null decision and random relocation (paper 001).
    shift_mode : {"edge", "uniform"}
        Belief shift boundary convention (see `perception.bayes.shift`).
    adaptive_prior : bool
        Start each decision from the adaptive prior of paper 004 eq. 12.
    alpha : float
        Weight of the previous posterior in the adaptive prior (paper 004: 0.5).
    rng : numpy.random.Generator or int, optional
        Randomness for random policies and relocations.
    """

    def __init__(self, model: HistogramModel, policy: Policy | None = None, *, decision_threshold: float = 0.9,
                 move_threshold: float = 0.0, max_taps: int = 20, deadline: int | None = None,
                 shift_mode: str = "edge", adaptive_prior: bool = False, alpha: float = 0.5, rng=None):
        if not isinstance(model, LikelihoodModel):
            raise TypeError(f"model must be a LikelihoodModel, got {type(model).__name__}")
        for name, value in (("decision_threshold", decision_threshold), ("move_threshold", move_threshold),
                            ("alpha", alpha)):
            if not 0.0 <= value <= 1.0:
                raise ValueError(f"{name} must be in [0, 1], got {value}")
        if int(max_taps) != max_taps or max_taps < 1:
            raise ValueError(f"max_taps must be an integer >= 1, got {max_taps}")
        if deadline is not None and (int(deadline) != deadline or deadline < 1):
            raise ValueError(f"deadline must be an integer >= 1 or None, got {deadline}")
        if shift_mode not in bayes.SHIFT_MODES:
            raise ValueError(f"shift_mode must be one of {bayes.SHIFT_MODES}, got {shift_mode!r}")
        self.model = model
        self.policy = policy if policy is not None else StationaryPolicy()
        self.decision_threshold = float(decision_threshold)
        self.move_threshold = float(move_threshold)
        self.max_taps = int(max_taps)
        self.deadline = None if deadline is None else int(deadline)
        self.shift_mode = shift_mode
        self.adaptive_prior = bool(adaptive_prior)
        self.alpha = float(alpha)
        self.rng = np.random.default_rng(rng)
        self._last_decision = None
        self.reset()

    def __repr__(self) -> str:
        return (f"Perceiver(policy={self.policy!r}, decision_threshold={self.decision_threshold}, "
                f"move_threshold={self.move_threshold}, max_taps={self.max_taps}, deadline={self.deadline}, "
                f"shift_mode={self.shift_mode!r}, adaptive_prior={self.adaptive_prior})")

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
            start = bayes.adaptive_prior(self._last_decision, alpha=self.alpha)
        else:
            start = bayes.flat_prior(*shape)
        self._start = start
        self._log_prior = self._log_posterior = start
        self._taps = self._attempt_taps = 0
        self._decided = False
        self._pending_move = 0

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
        if self._pending_move:
            raise PerceptionError("report the requested move with moved() before the next tap "
                                  "(moved(0.0) if the sensor did not move)")
        model = self.model
        log_likelihood = model.log_likelihood(tap)
        self._log_prior = self._log_posterior
        self._log_posterior = bayes.update(log_likelihood, self._log_prior)
        self._taps += 1
        self._attempt_taps += 1
        posterior = np.exp(self._log_posterior)
        where, what = posterior.sum(axis=1), posterior.sum(axis=0)
        location_class, identity_class = int(where.argmax()), int(what.argmax())
        belief = float((what if model.n_identities > 1 else where).max())
        decided = belief > self.decision_threshold
        forced = not decided and self._taps >= self.max_taps
        null = not (decided or forced) and self.deadline is not None and self._attempt_taps >= self.deadline
        move = 0
        if decided or forced:
            self._decided = True
            self._last_decision = self._log_posterior
        elif null:
            # Null decision (paper 001): discard the evidence, relocate randomly.
            move = RandomPolicy().move(where[None], np.array([location_class]), self.rng)[0]
            self._log_posterior = self._start
            self._attempt_taps = 0
        elif where.max() > self.move_threshold:
            move = self.policy.move(where[None], np.array([location_class]), self.rng)[0]
        move = int(clamp_move([location_class], [move], model.n_locations)[0])
        self._pending_move = move
        return Step(posterior=posterior, where_belief=where, what_belief=what, location_class=location_class,
                    identity_class=identity_class, location_estimate=float(model.location_centres[location_class]),
                    identity_estimate=float(model.identities[identity_class]), belief=belief,
                    decided=decided or forced, forced=forced, null=null, move=move * model.class_width,
                    move_classes=move, taps=self._taps)

    def moved(self, offset: float) -> None:
        """Report the move the sensor actually made; the beliefs shift by whole classes.

        Parameters
        ----------
        offset : float
            Relative move in location units (e.g. mm of depth), positive towards higher location.
        """
        width = self.model.class_width
        classes = int(np.rint(offset / width)) if width > 0 else 0
        self._log_posterior = bayes.shift(self._log_posterior, classes, mode=self.shift_mode)
        self._pending_move = 0
