"""tactip.reproduce.p001.deadline_runs: runs with a deadline composed from attempts equal the direct Monte Carlo."""

import numpy as np
import pytest

from perception import StationaryPolicy, monte_carlo
from tactip.reproduce.p001 import deadline_runs
from tactip.reproduce.report import environment
from tactip.reproduce.stimuli import make_stimulus


@pytest.fixture(scope="module")
def env():
    return environment(make_stimulus("rods"), seed=0, taps_per_identity=320, n_locations=16)


@pytest.mark.parametrize("deadline", [5, 10])
def test_attempts_give_the_direct_monte_carlo_with_a_deadline(env, deadline):
    # thresholds where every run decides quickly, so the direct Monte Carlo (no cap) ends
    thresholds = [0.3, 0.5]
    direct = monte_carlo(env, StationaryPolicy(), thresholds=thresholds, runs=3000, seed=7, deadline=deadline,
                         max_taps=None, decision_rule="joint", shift_mode="uniform")
    assert direct.forced.max() == 0
    composed = deadline_runs(env, deadline, thresholds=thresholds, attempts=6000, seed=8)
    assert composed.forced_fraction.max() == 0
    np.testing.assert_allclose(composed.shape_error_mm, direct.decided_identity_error, atol=0.15)
    np.testing.assert_allclose(composed.position_error_mm, direct.decided_location_error, atol=0.05)
    np.testing.assert_allclose(composed.reaction_taps, direct.mean_taps, rtol=0.08)
    np.testing.assert_allclose(composed.null_fraction, direct.null_fraction, atol=0.03)
    assert composed.null_fraction[1] > 0.05                       # the deadline is at work


def test_a_threshold_no_attempt_reaches_leaves_runs_that_never_decide(env):
    runs = deadline_runs(env, 5, thresholds=[0.5, 1.0], attempts=200, seed=1)
    assert runs.forced_fraction.tolist() == [0.0, 1.0]
    assert np.isfinite(runs.shape_error_mm[0]) and np.isnan(runs.shape_error_mm[1])
    assert np.isnan(runs.decided_position_error_mm[1]) and runs.reaction_taps[1] == np.inf
    assert runs.null_fraction[1] == 1.0 and (runs.decide_chance[1] == 0).all()
