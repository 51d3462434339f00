"""Localisation acuity against the number of location classes: Tables II and III of paper 000.

For each class count the training set trains a histogram model (`perception.fit_model`, 100 bins),
the independent test set is the virtual environment, and Monte Carlo runs (`perception.monte_carlo`)
start at random locations with passive (stationary) and active (fixation at the centre of the
range) perception over a sweep of decision thresholds. As in the paper the policies are compared at
a fixed mean decision time ("results are for mean decision times of 2 taps"): for each policy we
take the lowest mean location error among the thresholds whose mean decision time is within
``tap_budget`` taps. Beliefs shift with the uniform fill of paper 000 eq. 8.

Acuity is ``max(class width, mean error)`` (paper 000 Sec. III-C).

Example
-------
>>> rows = acuity_table(train, test, class_counts=(10, 300))        # doctest: +SKIP
>>> rows[-1].active_error_mm, rows[-1].passive_error_mm              # doctest: +SKIP
(0.09, 4.1)
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from _shared import map_pieces
from perception import Dataset, FixationPolicy, StationaryPolicy, VirtualEnvironment, compare_policies, fit_model

__all__ = ["TABLE2_CLASSES", "TABLE3_CLASSES", "ACUITY_THRESHOLDS", "AcuityRow", "acuity_table"]

#: Location class counts of paper 000 Table II (fingertip, 30 mm) and Table III (skin, 50 mm).
TABLE2_CLASSES = (10, 15, 30, 60, 100, 150, 300)
TABLE3_CLASSES = (25, 50, 100, 200, 250, 500)
#: Decision thresholds: dense and logarithmic, because with hundreds of classes a belief that
#: decides within 2 taps is only a few times the flat prior 1 / N.
ACUITY_THRESHOLDS = tuple(np.concatenate([[0.0], np.geomspace(1e-3, 0.999, 120)]).round(6))


@dataclass(frozen=True)
class AcuityRow:
    """One column of Table II: a class count and both policies at the tap budget.

    Attributes
    ----------
    classes : int
    class_width_mm : float
    passive_error_mm, active_error_mm : float
        Mean absolute location error at the best threshold within the tap budget, mm.
    passive_taps, active_taps : float
        Mean decision taps at that threshold.
    passive_threshold, active_threshold : float
        That threshold.
    passive_best_error_mm : float
        Lowest passive error at any threshold (up to ``max_taps`` taps), mm.
    """

    classes: int
    class_width_mm: float
    passive_error_mm: float
    passive_taps: float
    passive_threshold: float
    active_error_mm: float
    active_taps: float
    active_threshold: float
    passive_best_error_mm: float

    @property
    def acuity_mm(self) -> float:
        """Active acuity ``max(class width, mean error)``, mm."""
        return max(self.class_width_mm, self.active_error_mm)


def acuity_table(train: Dataset, test: Dataset, *, class_counts=TABLE2_CLASSES, fixation_mm: float | None = None,
                 tap_budget: float = 2.0, runs: int = 5000, seed: int = 1, thresholds=ACUITY_THRESHOLDS,
                 max_taps: int = 20, progress=None, map_fn=None) -> list[AcuityRow]:
    """Passive and active localisation error for each number of location classes.

    Parameters
    ----------
    train, test : Dataset
        Independent collections over the same location range (e.g. `simulate_taxel_datasets`).
    class_counts : sequence of int
        Numbers of equal location classes over the range.
    fixation_mm : float, optional
        Fixation location of the active policy, mm (default: the centre of the range).
    tap_budget : float
        Mean decision taps within which each policy's error is taken (paper 000: 2).
    runs, seed, thresholds, max_taps
        Of `perception.monte_carlo` (both policies use the same starting classes).
    progress : callable, optional
        Wraps the iterable of class counts (e.g. ``tqdm``).
    map_fn : callable, optional
        Runs the class counts: ``map_fn(function, class_counts)``, results in order (e.g. on a Dask
        cluster, `tactip.cluster.cluster_map`); the same rows as run here (default).

    Returns
    -------
    list of AcuityRow, in the order of ``class_counts``
    """
    row = functools.partial(_acuity_row, train=train, test=test, fixation_mm=fixation_mm, tap_budget=tap_budget,
                            options=dict(seed=seed, runs=runs, thresholds=thresholds, max_taps=max_taps,
                                         shift_mode="uniform"))
    return map_pieces(row, list(class_counts), map_fn=map_fn, progress=progress)


def _acuity_row(n: int, *, train, test, fixation_mm, tap_budget, options) -> AcuityRow:
    """One row of `acuity_table`: ``n`` location classes (module level, so it travels to a worker)."""
    model = fit_model(train, n_locations=int(n))
    environment = VirtualEnvironment(model, test)
    centre = 0.5 * (model.location_edges[0] + model.location_edges[-1])
    fixation = int(model.location_class(centre if fixation_mm is None else fixation_mm))
    results = compare_policies(environment, [StationaryPolicy(), FixationPolicy(fixation)], **options)
    passive, active = results["stationary"], results["active"]
    p, a = passive.best_within(tap_budget), active.best_within(tap_budget)
    return AcuityRow(
        classes=int(n), class_width_mm=model.class_width,
        passive_error_mm=float(passive.mean_location_error[p]), passive_taps=float(passive.mean_taps[p]),
        passive_threshold=float(passive.thresholds[p]),
        active_error_mm=float(active.mean_location_error[a]), active_taps=float(active.mean_taps[a]),
        active_threshold=float(active.thresholds[a]),
        passive_best_error_mm=float(passive.mean_location_error.min()))
