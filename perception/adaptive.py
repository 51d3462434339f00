"""Learning the forward model's shift Delta by predicted information gain (paper 004 eqs. 7-11).

Between two decisions of an exploration (e.g. following a contour), the perceived identity (an
edge angle) changes. Paper 004 predicts the next decision's belief by shifting the last posterior
by Delta identity classes (eq. 7) and starts the next decision from that prediction mixed with a
flat prior (eq. 12, `perception.bayes.adaptive_prior`). Delta is learned online:

- at decision tau, for every candidate shift a ("what would have happened had the prediction
  used a"), the information lost by predicting the new 'what' posterior p_tau with the previous
  one shifted by a is D_KL(p_tau || q_a), q_a = alpha shift(p_(tau-1), a) + (1 - alpha) flat
  (the prior that a would have given; the flat part keeps the divergence finite);
- PIG(a) = gamma exp(-D_KL(p_tau || q_a)): a reward in [0, 1], gamma normalising it over the
  candidates (eq. 8; our reading: the paper's "amount of information that would have been lost"
  turned into a reward that is largest for the shift that would have lost least);
- Gamma_tau = eta ((tau - 1) / tau Gamma_(tau-1) + PIG / tau): the running mean of PIG over the
  decisions (eq. 10 as printed reads "... + 1 / tau) PIG", which with 73 candidates would add
  almost the same 1 / tau to every entry and forget the past; we read the PIG as the term the
  1 / tau weighs, which makes eq. 10 the incremental mean that eq. 9 describes);
- Delta = argmax Gamma_tau (eq. 11).

`ShiftLearner` keeps Gamma for a batch of runs, so one learner serves a Monte Carlo.

Example
-------
>>> import numpy as np
>>> learner = ShiftLearner(8, circular=True)
>>> before = np.eye(8)[[2]]          # the 'what' posterior at one decision: class 2
>>> after = np.eye(8)[[3]]           # at the next: class 3
>>> learner.observe(before, after).tolist()
[1]
"""

from __future__ import annotations

import numpy as np

__all__ = ["ShiftLearner", "kl_divergence"]


def kl_divergence(p, q) -> np.ndarray:
    """D_KL(p || q) over the last axis, nats (0 log 0 = 0).

    Parameters
    ----------
    p, q : (..., N) arrays of probabilities, q > 0 where p > 0

    Returns
    -------
    (...) float64 ndarray
    """
    p = np.asarray(p, dtype=np.float64)
    q = np.asarray(q, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        terms = np.where(p > 0, p * (np.log(p) - np.log(q)), 0.0)
    return terms.sum(axis=-1)


class ShiftLearner:
    """Online estimate of Delta for a batch of runs (paper 004 eqs. 8-11; see the module docstring).

    Parameters
    ----------
    n_identities : int
        Identity classes I (e.g. 72 angle classes of 5 deg).
    max_shift : int, optional
        Candidate shifts are -max_shift..max_shift classes; default every shift (I // 2 each way).
    alpha : float in (0, 1]
        Weight of the predicted distribution in the prior (eq. 12; paper 004: 0.5).
    circular : bool
        The identity classes cover a full turn.
    runs : int
        Independent learners kept side by side (Monte Carlo runs).
    """

    def __init__(self, n_identities: int, *, max_shift: int | None = None, alpha: float = 0.5,
                 circular: bool = False, runs: int = 1):
        if int(n_identities) != n_identities or n_identities < 1:
            raise ValueError(f"n_identities must be an integer >= 1, got {n_identities}")
        max_shift = int(n_identities) // 2 if max_shift is None else max_shift
        if int(max_shift) != max_shift or not 0 <= max_shift < n_identities:
            raise ValueError(f"max_shift must be an integer in [0, {n_identities}), got {max_shift}")
        if not 0.0 < alpha <= 1.0:
            raise ValueError(f"alpha must be in (0, 1], got {alpha}")
        self.n_identities = int(n_identities)
        self.candidates = np.arange(-int(max_shift), int(max_shift) + 1)
        self.alpha = float(alpha)
        self.circular = bool(circular)
        self.runs = int(runs)
        self.reset()

    def __repr__(self) -> str:
        return (f"ShiftLearner(n_identities={self.n_identities}, max_shift={self.candidates[-1]}, "
                f"alpha={self.alpha}, circular={self.circular}, runs={self.runs})")

    def reset(self) -> None:
        """Forget what was learned: Gamma flat, tau = 0 (decisions learned from, per run), Delta = 0."""
        self.gamma = np.full((self.runs, len(self.candidates)), 1.0 / len(self.candidates))
        self.tau = np.zeros(self.runs, np.intp)
        self._delta = np.zeros(self.runs, np.intp)

    @property
    def delta(self) -> np.ndarray:
        """(runs,) int ndarray: the current Delta of each run, identity classes (eq. 11)."""
        return self._delta.copy()

    def _shifted(self, what: np.ndarray) -> np.ndarray:
        """(R, A, I): each run's 'what' belief shifted by every candidate a, P(w_(i - a))."""
        n = self.n_identities
        source = np.arange(n)[None, :] - self.candidates[:, None]          # (A, I)
        if self.circular:
            return what[:, source % n]
        inside = (source >= 0) & (source < n)
        shifted = np.where(inside, what[:, np.clip(source, 0, n - 1)], 0.0)
        lost = 1.0 - shifted.sum(axis=-1, keepdims=True)
        return shifted + np.where(inside, 0.0, lost / np.maximum((~inside).sum(axis=-1), 1)[:, None])

    def observe(self, previous_what, current_what, *, active=None) -> np.ndarray:
        """Learn from one decision: the 'what' posteriors at decisions tau - 1 and tau.

        Parameters
        ----------
        previous_what, current_what : (runs, I) arrays of probabilities
        active : (runs,) bool array, optional
            Runs that made a decision this time (others keep their Gamma).

        Returns
        -------
        (runs,) int ndarray
            Delta after the update.
        """
        previous = np.asarray(previous_what, dtype=np.float64).reshape(self.runs, self.n_identities)
        current = np.asarray(current_what, dtype=np.float64).reshape(self.runs, self.n_identities)
        active = np.ones(self.runs, bool) if active is None else np.asarray(active, bool)
        predicted = self.alpha * self._shifted(previous) + (1.0 - self.alpha) / self.n_identities
        # PIG(a) = gamma exp(-D_KL(p_tau || q_a))   (eq. 8, gamma normalises over a)
        loss = kl_divergence(current[:, None, :], predicted)                 # (R, A)
        pig = np.exp(-(loss - loss.min(axis=1, keepdims=True)))
        pig /= pig.sum(axis=1, keepdims=True)
        self.tau = self.tau + active
        tau = np.maximum(self.tau, 1)[:, None]
        # Gamma_tau = eta ((tau - 1) / tau Gamma_(tau-1) + PIG / tau)   (eq. 10, see the module docstring)
        gamma = (tau - 1) / tau * self.gamma + pig / tau
        gamma /= gamma.sum(axis=1, keepdims=True)
        self.gamma = np.where(active[:, None], gamma, self.gamma)
        # Delta = argmax Gamma_tau   (eq. 11); ties go to the smallest |a|
        order = np.argsort(np.abs(self.candidates), kind="stable")
        best = order[np.argmax(self.gamma[:, order], axis=1)]
        self._delta = self.candidates[best].astype(np.intp)
        return self.delta
