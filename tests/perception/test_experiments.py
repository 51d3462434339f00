"""Experiments: fixation sweep, lateral placement noise, policy comparison, and their plots."""

import numpy as np
import pytest

from perception import (DatasetError, FixationPolicy, StationaryPolicy, VirtualEnvironment, compare_policies,
                        fit_model, fixation_sweep, lateral_sweep)
from perception.plots import plot_fixation_sweep, plot_lateral_sweep, plot_speed_accuracy
from tests.perception.synthetic import gap_dataset

GRID = dict(depths=6, widths=4, samples=10, dims=8, legible_from=0.5)
OFFSETS = [-2.0, -1.0, -0.5, 0.0, 0.5, 1.0, 2.0]


@pytest.fixture(scope="module")
def model():
    return fit_model(gap_dataset(seed=1, taps_per_class=4, **GRID), n_locations=6)


@pytest.fixture(scope="module")
def env(model):
    return VirtualEnvironment(model, gap_dataset(seed=2, taps_per_class=20, **GRID))


@pytest.fixture(scope="module")
def lateral_env(model):
    return VirtualEnvironment(model, gap_dataset(seed=3, taps_per_class=6, lateral=OFFSETS, **GRID))


def test_fixation_sweep_finds_the_informative_depths(env):
    sweep = fixation_sweep(env, thresholds=[0.5, 0.9, 0.99], runs=1000, seed=1, tap_budget=12)
    np.testing.assert_allclose(sweep.fixations, env.model.location_centres)
    assert sweep.best_fixation >= 4.0  # the deep half, where the width is legible
    assert sweep.errors[sweep.best] == sweep.errors.min()
    assert sweep.errors[-1] < sweep.errors[0] / 4  # deep fixation far better than shallow
    assert sweep.taps[sweep.best] <= 12 and sweep.best_threshold in (0.5, 0.9, 0.99)
    assert len(sweep.results) == 6


def test_fixation_sweep_of_chosen_classes_and_bad_classes(env):
    sweep = fixation_sweep(env, fixation_classes=[1, 5], thresholds=[0.9], runs=300, seed=1)
    assert sweep.fixations.tolist() == [env.model.location_centres[1], env.model.location_centres[5]]
    assert sweep.best == 1
    with pytest.raises(ValueError, match="fixation_classes"):
        fixation_sweep(env, fixation_classes=[6])


def test_lateral_noise_degrades_gracefully(lateral_env):
    sweep = lateral_sweep(lateral_env, FixationPolicy(5), sigmas=[0, 0.5, 1, 2], thresholds=[0.5, 0.9, 0.99],
                          runs=1500, seed=2)
    assert sweep.ratio[0] == 1.0
    assert sweep.errors[-1] > sweep.errors[0]  # errors grow with the lateral noise
    assert sweep.ratio[-1] > sweep.ratio[1]


def test_lateral_sweep_needs_lateral_offsets(env, lateral_env):
    with pytest.raises(DatasetError, match="no lateral offsets"):
        lateral_sweep(env, FixationPolicy(5))
    with pytest.raises(DatasetError, match="lateral sigma 0.25 mm: .*no test taps"):
        lateral_sweep(lateral_env.restrict(lateral_env.lateral != 0), FixationPolicy(5), sigmas=[0.25])


def test_compare_policies_uses_the_same_runs(env):
    seen = []

    def progress(items):
        seen.extend(items)
        return items

    policies = [FixationPolicy(5), StationaryPolicy()]
    results = compare_policies(env, policies, thresholds=[0.0], runs=400, seed=3, progress=progress)
    assert list(results) == ["active", "stationary"] and seen == policies
    # At threshold 0 both decide on the first tap at the same starting classes with the same draws.
    assert results["active"].mean_identity_error == results["stationary"].mean_identity_error


def test_plots_write_images(tmp_path, env, lateral_env):
    results = compare_policies(env, [FixationPolicy(5), StationaryPolicy()], thresholds=[0.5, 0.9], runs=100)
    plot_speed_accuracy(results, tmp_path / "curves.png")
    plot_fixation_sweep(fixation_sweep(env, thresholds=[0.9], runs=100), tmp_path / "fixation.png")
    plot_lateral_sweep(lateral_sweep(lateral_env, FixationPolicy(5), sigmas=[0, 1], thresholds=[0.9], runs=100),
                       tmp_path / "lateral.png")
    for name in ("curves.png", "fixation.png", "lateral.png"):
        data = (tmp_path / name).read_bytes()
        assert data.startswith(b"\x89PNG") and len(data) > 5000


@pytest.mark.parametrize("budget", [0, 0.5, float("nan"), float("inf"), -3, True, "12"])
def test_sweeps_refuse_a_tap_budget_no_run_can_meet(env, lateral_env, budget):
    with pytest.raises(ValueError, match="tap_budget must be a finite number of mean taps >= 1"):
        fixation_sweep(env, runs=10, tap_budget=budget)
    with pytest.raises(ValueError, match="tap_budget"):
        lateral_sweep(lateral_env, StationaryPolicy(), sigmas=[0.0], runs=10, tap_budget=budget)


def assert_same(a, b, where="result"):
    """Every field of two results equal (arrays exactly, NaN where NaN), recursing into tuples and dataclasses."""
    import dataclasses

    if dataclasses.is_dataclass(a):
        assert type(a) is type(b), where
        for field in dataclasses.fields(a):
            assert_same(getattr(a, field.name), getattr(b, field.name), f"{where}.{field.name}")
    elif isinstance(a, (tuple, list)):
        assert len(a) == len(b), where
        for k, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{where}[{k}]")
    elif isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        assert np.array_equal(a, b, equal_nan=True), where
    else:
        assert a == b or (a != a and b != b), where


class ElsewhereMap:
    """A map_fn as a cluster runs it: each piece pickled (another process), run in reverse order, results in order."""

    def __init__(self):
        self.calls = []

    def __call__(self, function, items):
        import pickle

        self.calls.append(list(items))
        function = pickle.loads(pickle.dumps(function))
        return [pickle.loads(pickle.dumps(function(item))) for item in reversed(items)][::-1]


def test_sweeps_through_a_map_fn_equal_the_sweeps_run_here(env, lateral_env):
    mapped = ElsewhereMap()
    options = dict(thresholds=[0.5, 0.9, 0.99], runs=300, seed=4)
    assert_same(fixation_sweep(env, map_fn=mapped, **options), fixation_sweep(env, **options))
    assert_same(lateral_sweep(lateral_env, FixationPolicy(5), sigmas=[0, 1, 2], map_fn=mapped, **options),
                lateral_sweep(lateral_env, FixationPolicy(5), sigmas=[0, 1, 2], **options))
    assert mapped.calls == [list(range(6)), [0.0, 1.0, 2.0]]
    # A piece's error comes through the map as it would here.
    with pytest.raises(DatasetError, match="lateral sigma 0.25 mm"):
        lateral_sweep(lateral_env.restrict(lateral_env.lateral != 0), FixationPolicy(5), sigmas=[0.25], map_fn=mapped)
