"""Control policies: where to tap next, from the 'where' belief (paper 002 III-B.4; 000 eq. 9).

A policy is any object with a ``name`` and a vectorised ``move`` method (the `Policy` protocol),
so a user can add one. Moves are in location classes; the caller clamps them to the range.

Example
-------
>>> import numpy as np
>>> policy = FixationPolicy(8)
>>> policy.move(np.full((2, 11), 1 / 11), np.array([3, 10]), np.random.default_rng(0)).tolist()
[5, -2]
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from .choices import POLICIES

__all__ = ["POLICIES", "Policy", "FixationPolicy", "StationaryPolicy", "RandomPolicy", "make_policy"]


@runtime_checkable
class Policy(Protocol):
    """What a control policy provides.

    Attributes
    ----------
    name : str
        Short name used in tables and plots.
    """

    name: str

    def move(self, where_belief: np.ndarray, location_estimate: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Relative move of each sensor, in location classes.

        Parameters
        ----------
        where_belief : (R, L) ndarray
            Marginal location beliefs P(x_l | z_1:t) of R runs (R = 1 for one perceiver).
        location_estimate : (R,) int ndarray
            MAP location class x_est of each run.
        rng : numpy.random.Generator
            Source of randomness for stochastic policies.

        Returns
        -------
        (R,) int ndarray
            Move in location classes (positive: towards higher location), before clamping.
        """
        ...


@dataclass(frozen=True)
class FixationPolicy:
    """Active 'fixation point' control: move to a fixed location on the object (paper 002 eq. 10).

    Parameters
    ----------
    fixation_class : int
        Location class x_fix to move the sensor to.
    """

    fixation_class: int
    name: str = "active"

    def move(self, where_belief, location_estimate, rng):
        """pi(x_est) = x_fix - x_est, in classes (see `Policy.move`)."""
        return self.fixation_class - np.asarray(location_estimate, dtype=np.intp)


@dataclass(frozen=True)
class StationaryPolicy:
    """Passive stationary perception: never move (pi = 0)."""

    name: str = "stationary"

    def move(self, where_belief, location_estimate, rng):
        """No move for any run (see `Policy.move`)."""
        return np.zeros(np.shape(location_estimate), dtype=np.intp)


@dataclass(frozen=True)
class RandomPolicy:
    """Passive random perception: move to a location drawn uniformly over the range (paper 002).

    The target class is uniform over the L classes, relative to the current estimate.
    """

    name: str = "random"

    def move(self, where_belief, location_estimate, rng):
        """A uniform target class minus the estimate (see `Policy.move`)."""
        estimate = np.asarray(location_estimate, dtype=np.intp)
        return rng.integers(0, np.shape(where_belief)[-1], size=estimate.shape) - estimate


def make_policy(name: str, *, fixation_class: int | None = None) -> Policy:
    """A policy by name.

    Parameters
    ----------
    name : {"active", "stationary", "random"}
    fixation_class : int, optional
        Location class to fixate on; required for ``"active"``.

    Raises
    ------
    ValueError
        Unknown name, or ``"active"`` without a fixation class.
    """
    if name == "active":
        if fixation_class is None:
            raise ValueError("the active policy needs a fixation_class")
        return FixationPolicy(int(fixation_class))
    if name == "stationary":
        return StationaryPolicy()
    if name == "random":
        return RandomPolicy()
    raise ValueError(f"unknown policy {name!r}; choose from {', '.join(POLICIES)}")
