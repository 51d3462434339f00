"""The Table II bar of paper 000 on the simulated iCub fingertip (12 taxels, 4 mm apart, 30 mm range).

Protocol of the paper: two independent collections of 3000 taps (0.01 mm steps over 30 mm), a
histogram model (100 bins) trained on one, Monte Carlo validation on the other, passive
(stationary) against active perception (fixation at the centre of the range, uniform belief fill),
both compared at a mean decision time of 2 taps, for every class count of Table II.
"""

import numpy as np
import pytest

from tactip.taxel import TaxelSimulator, simulate_taxel_dataset, sweep_locations
from tactip.reproduce.acuity import TABLE2_CLASSES, acuity_table

SEED = 0


@pytest.fixture(scope="module")
def collections():
    """Training and test sets of the paper's size, simulated once for the module."""
    simulator = TaxelSimulator("fingertip", seed=SEED)
    where = sweep_locations(simulator.sensor, 3000)           # 0.01 mm steps over 30 mm
    train = simulate_taxel_dataset(simulator, where, seed=(SEED, 2), collection="train")
    test = simulate_taxel_dataset(simulator, where, seed=(SEED, 3), collection="test")
    return train, test


@pytest.fixture(scope="module")
def table(collections):
    """Table II rows, keyed by class count (computed once: ~10 s)."""
    train, test = collections
    rows = acuity_table(train, test, class_counts=TABLE2_CLASSES, fixation_mm=15.0, tap_budget=2.0, runs=5000, seed=1)
    return {row.classes: row for row in rows}


def test_training_and_test_sets_are_independent_collections(collections):
    train, test = collections
    assert len(train) == len(test) == 3000
    np.testing.assert_array_equal(train.location, test.location)
    # same sensor and locations, independent noise: never the same tap
    assert not np.any(np.all(train.taps == test.taps, axis=(1, 2)))


def test_active_perception_reaches_hyperacuity_at_300_classes_in_about_2_taps(table):
    row = table[300]
    assert row.class_width_mm == pytest.approx(0.1, rel=1e-3)
    assert 1.5 <= row.active_taps <= 2.0
    assert row.active_error_mm <= 0.2                          # paper: 0.12 mm
    assert row.acuity_mm <= 0.2                                # 20x finer than the 4 mm taxel spacing


def test_passive_perception_is_at_least_ten_times_worse_at_300_classes(table):
    row = table[300]
    assert row.passive_error_mm >= 10 * row.active_error_mm    # paper: ~4.5 mm against 0.12 mm
    # not a matter of the tap budget: passive stays poor with up to 20 taps
    assert row.passive_best_error_mm >= 10 * row.active_error_mm


@pytest.mark.parametrize("classes", TABLE2_CLASSES)
def test_active_beats_passive_at_every_class_count(table, classes):
    row = table[classes]
    assert row.active_taps <= 2.0 and row.passive_taps <= 2.0
    assert row.active_error_mm < row.passive_error_mm
