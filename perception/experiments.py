"""Experiments on the virtual environment: policy comparison, fixation sweep, lateral noise.

- `compare_policies`: speed-accuracy curves of several policies on the same runs (paper 002 Fig. 9);
- `fixation_sweep`: active perception for every fixation location, the best one within a tap
  budget (paper 002 Fig. 10: lowest error after 12 taps);
- `lateral_sweep`: active perception on test taps whose lateral placement lies within
  [-sigma, sigma], relative to the noise-free case (paper 002 Fig. 11).

Every experiment takes ``progress``, an optional wrapper of an iterable (e.g. ``tqdm``), and
passes other options (``runs``, ``thresholds``, ``max_taps``, ...) to `monte_carlo`.

Example
-------
>>> sweep = fixation_sweep(env, runs=2000, seed=1)                   # doctest: +SKIP
>>> sweep.best_fixation, sweep.best_threshold                        # doctest: +SKIP
(4.75, 0.99)
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from _shared.mapping import map_pieces

from .errors import DatasetError
from .montecarlo import MonteCarloResult, VirtualEnvironment, monte_carlo
from .policies import FixationPolicy, Policy

__all__ = ["compare_policies", "FixationSweep", "fixation_sweep", "LateralSweep", "lateral_sweep"]

#: Mean decision taps within which the best accuracy is taken (paper 002: after 12 taps).
TAP_BUDGET = 12


def _identity(iterable):
    return iterable


def compare_policies(environment: VirtualEnvironment, policies, *, seed=0, progress=None,
                     **options) -> dict[str, MonteCarloResult]:
    """Monte Carlo of several policies with the same starting classes.

    Parameters
    ----------
    environment : VirtualEnvironment
    policies : sequence of Policy
    seed : int
        Seed of every policy's runs (same true classes and starting locations).
    progress : callable, optional
        Wraps the iterable of policies (e.g. ``tqdm``).
    **options
        Passed to `monte_carlo`.

    Returns
    -------
    dict
        Policy name -> MonteCarloResult, in the given order.
    """
    results = {}
    for policy in (progress or _identity)(list(policies)):
        results[policy.name] = monte_carlo(environment, policy, seed=seed, **options)
    return results


@dataclass(frozen=True)
class FixationSweep:
    """Active perception at each fixation location.

    Attributes
    ----------
    fixations : (F,) ndarray
        Fixation locations, location units (class centres).
    results : tuple of MonteCarloResult
        One speed-accuracy curve per fixation.
    tap_budget : float
    errors : (F,) ndarray
        Best mean error with mean taps within the budget (identity; location for a location task).
    taps : (F,) ndarray
        Mean taps at that threshold.
    thresholds : (F,) ndarray
        Decision threshold giving it.
    best : int
        Index of the fixation with the lowest error (ties: fewer taps).
    """

    fixations: np.ndarray
    results: tuple[MonteCarloResult, ...]
    tap_budget: float
    errors: np.ndarray
    taps: np.ndarray
    thresholds: np.ndarray
    best: int

    @property
    def best_fixation(self) -> float:
        """The fixation location with the lowest error, location units."""
        return float(self.fixations[self.best])

    @property
    def best_threshold(self) -> float:
        """The decision threshold reaching that error within the tap budget."""
        return float(self.thresholds[self.best])


def _check_budget(tap_budget) -> None:
    """A mean-taps budget is a finite number >= 1 (every run takes at least one tap)."""
    if isinstance(tap_budget, bool) or not isinstance(tap_budget, (int, float, np.number)) or \
            not (math.isfinite(tap_budget) and tap_budget >= 1):
        raise ValueError(f"tap_budget must be a finite number of mean taps >= 1, got {tap_budget!r}")


def _budget_figures(results, tap_budget):
    picks = [r.best_within(tap_budget) for r in results]
    single = results[0].identity_error_map.shape[-1] == 1
    errors = np.array([(r.mean_location_error if single else r.mean_identity_error)[k] for r, k in zip(results, picks)])
    taps = np.array([r.mean_taps[k] for r, k in zip(results, picks)])
    thresholds = np.array([r.thresholds[k] for r, k in zip(results, picks)])
    return errors, taps, thresholds


def _fixation_run(fixation_class: int, *, environment: VirtualEnvironment, seed, options: dict) -> MonteCarloResult:
    """The runs of one fixation (a piece of `fixation_sweep`; module level, so it travels to a worker)."""
    return monte_carlo(environment, FixationPolicy(int(fixation_class)), seed=seed, **options)


def fixation_sweep(environment: VirtualEnvironment, *, fixation_classes=None, tap_budget: float = TAP_BUDGET,
                   seed=0, progress=None, map_fn=None, **options) -> FixationSweep:
    """Active ('fixation point') perception for each fixation location (paper 002 Fig. 10).

    Parameters
    ----------
    environment : VirtualEnvironment
    fixation_classes : sequence of int, optional
        Location classes to try; default every class.
    tap_budget : float
        The best error of each fixation is taken among thresholds with mean taps <= budget.
    seed : int
        Seed of every fixation's runs (same true classes and starting locations).
    progress : callable, optional
        Wraps the iterable of fixations (e.g. ``tqdm``).
    map_fn : callable, optional
        Runs the fixations: ``map_fn(function, fixation_classes)``, results in order (e.g.
        `tactip.cluster.cluster_map` on a Dask cluster); the results are the same as run here
        (default), since every fixation's runs use the same seed.
    **options
        Passed to `monte_carlo`.

    Returns
    -------
    FixationSweep
    """
    _check_budget(tap_budget)
    model = environment.model
    classes = np.arange(model.n_locations) if fixation_classes is None else np.asarray(fixation_classes, np.intp)
    if classes.ndim != 1 or classes.size == 0 or ((classes < 0) | (classes >= model.n_locations)).any():
        raise ValueError(f"fixation_classes must be location classes in [0, {model.n_locations}), got {classes}")
    run = functools.partial(_fixation_run, environment=environment, seed=seed, options=options)
    results = tuple(map_pieces(run, classes.tolist(), map_fn=map_fn, progress=progress))
    errors, taps, thresholds = _budget_figures(results, tap_budget)
    best = int(np.lexsort((taps, errors))[0])
    return FixationSweep(model.location_centres[classes], results, float(tap_budget), errors, taps, thresholds, best)


@dataclass(frozen=True)
class LateralSweep:
    """Perception with test taps of lateral placement within [-sigma, sigma].

    Attributes
    ----------
    sigmas : (S,) ndarray, mm
    results : tuple of MonteCarloResult
    errors : (S,) ndarray
        Best mean error within the tap budget.
    ratio : (S,) ndarray
        errors / error at the smallest sigma (paper 002 Fig. 11: e(sigma) / e(0)).
    """

    sigmas: np.ndarray
    results: tuple[MonteCarloResult, ...]
    errors: np.ndarray
    ratio: np.ndarray


def _lateral_run(sigma: float, *, environment: VirtualEnvironment, policy: Policy, seed, options: dict):
    """The runs with test taps within [-sigma, sigma] mm (a piece of `lateral_sweep`)."""
    try:
        restricted = environment.restrict(np.abs(environment.lateral) <= sigma + 1e-9)
    except DatasetError as exc:
        raise DatasetError(f"lateral sigma {sigma:g} mm: {exc}") from None
    return monte_carlo(restricted, policy, seed=seed, **options)


def lateral_sweep(environment: VirtualEnvironment, policy: Policy, *, sigmas=(0.0, 0.25, 0.5, 1.0, 2.0),
                  tap_budget: float = TAP_BUDGET, seed=0, progress=None, map_fn=None, **options) -> LateralSweep:
    """Robustness to lateral placement noise (paper 002 Fig. 11).

    For each sigma the runs draw test taps only among those with |lateral| <= sigma, i.e. with
    lateral placement uniform over [-sigma, sigma] when the test set samples it evenly.

    Parameters
    ----------
    environment : VirtualEnvironment
        Its test set must have ``lateral`` offsets.
    policy : Policy
    sigmas : sequence of float, mm
    tap_budget : float
    seed : int
    progress : callable, optional
    map_fn : callable, optional
        Runs the sigmas: ``map_fn(function, sigmas)``, results in order (e.g. `tactip.cluster.cluster_map`);
        the same results as run here (default).
    **options
        Passed to `monte_carlo`.

    Raises
    ------
    DatasetError
        The test set has no lateral offsets, or some class has no taps within a sigma.
    """
    _check_budget(tap_budget)
    if environment.lateral is None:
        raise DatasetError("the test set has no lateral offsets; collect it with lateral placement noise")
    sigmas = np.sort(np.asarray(sigmas, dtype=np.float64))
    if sigmas.ndim != 1 or sigmas.size == 0 or (sigmas < 0).any():
        raise ValueError(f"sigmas must be values >= 0, got {sigmas}")
    run = functools.partial(_lateral_run, environment=environment, policy=policy, seed=seed, options=options)
    results = map_pieces(run, sigmas.tolist(), map_fn=map_fn, progress=progress)
    errors, _, _ = _budget_figures(results, tap_budget)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = errors / errors[0]
    return LateralSweep(sigmas, tuple(results), errors, ratio)
