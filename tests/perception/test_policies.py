"""Control policies: fixation, stationary, random, and a user-defined one."""

import numpy as np
import pytest

from perception import FixationPolicy, Policy, RandomPolicy, StationaryPolicy, make_policy

FLAT = np.full((4, 11), 1 / 11)


def test_fixation_moves_from_the_estimate_to_the_fixation_point():
    move = FixationPolicy(7).move(FLAT, np.array([0, 7, 10, 3]), np.random.default_rng(0))
    assert move.tolist() == [7, 0, -3, 4]


def test_stationary_never_moves():
    assert StationaryPolicy().move(FLAT, np.array([0, 5, 10, 3]), None).tolist() == [0, 0, 0, 0]


def test_random_targets_are_uniform_over_the_range():
    rng = np.random.default_rng(0)
    estimate = rng.integers(0, 11, 22000)
    move = RandomPolicy().move(np.full((22000, 11), 1 / 11), estimate, rng)
    counts = np.bincount(estimate + move, minlength=11)
    assert counts.size == 11  # every target inside the range
    # 2000 expected per class; 5 standard deviations is about 220
    np.testing.assert_allclose(counts, 2000, atol=220)


def test_make_policy_by_name():
    assert make_policy("active", fixation_class=3) == FixationPolicy(3)
    assert make_policy("stationary").name == "stationary"
    assert make_policy("random").name == "random"
    with pytest.raises(ValueError, match="needs a fixation_class"):
        make_policy("active")
    with pytest.raises(ValueError, match="unknown policy 'greedy'; choose from active, stationary, random"):
        make_policy("greedy")


def test_a_user_policy_satisfies_the_protocol():
    class Deepest:
        name = "deepest"

        def move(self, where_belief, location_estimate, rng):
            return where_belief.shape[-1] - 1 - location_estimate

    assert isinstance(Deepest(), Policy)
    assert isinstance(FixationPolicy(1), Policy) and isinstance(RandomPolicy(), Policy)
    assert Deepest().move(FLAT, np.array([0, 10]), None).tolist() == [10, 0]
