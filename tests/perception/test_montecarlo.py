"""Monte Carlo validation: accuracy on separable classes, active beats passive, agreement with Perceiver."""

import numpy as np
import pytest

from perception import (Dataset, DatasetError, FixationPolicy, ModelError, Perceiver, RandomPolicy, StationaryPolicy,
                        VirtualEnvironment, compare_policies, fit_model, monte_carlo)
from tests.perception.synthetic import gap_dataset

GRID = dict(depths=6, widths=4, samples=10, dims=8)


def environment(*, train_taps=4, test_taps=20, seed=0, **options):
    model = fit_model(gap_dataset(seed=seed + 1, taps_per_class=train_taps, **GRID, **options), n_locations=6)
    return VirtualEnvironment(model, gap_dataset(seed=seed + 2, taps_per_class=test_taps, **GRID, **options))


@pytest.fixture(scope="module")
def deep_only():
    """Width legible only in the deeper half of the depth range (paper 002: deep contacts inform)."""
    return environment(legible_from=0.5)


def test_separable_classes_are_all_classified_right():
    env = environment(contact_floor=1.0, noise=0.03)
    for policy in (FixationPolicy(3), StationaryPolicy(), RandomPolicy()):
        result = monte_carlo(env, policy, thresholds=[0.99, 0.999], runs=2000, seed=1)
        np.testing.assert_array_equal(result.accuracy, 1.0)
        np.testing.assert_array_equal(result.mean_identity_error, 0.0)
        assert (result.forced < 0.01).all()  # decided by the threshold, not by max_taps


def test_active_beats_passive_when_only_deep_taps_are_informative(deep_only):
    policies = [FixationPolicy(5), RandomPolicy(), StationaryPolicy()]
    results = compare_policies(deep_only, policies, thresholds=[0.9, 0.99], runs=3000, seed=2)
    active, random, stationary = (results[name].mean_identity_error for name in ("active", "random", "stationary"))
    assert (active < 0.05).all()
    assert (active < random / 4).all() and (random < stationary).all()  # the paper's ordering
    assert (stationary > 0.5).all()
    taps = results["active"].mean_taps
    assert (taps < results["stationary"].mean_taps).all()


def test_monte_carlo_agrees_with_the_perceiver_run_by_run():
    """One test tap per class makes the virtual environment deterministic for deterministic policies."""
    env = environment(test_taps=1, legible_from=0.4, noise=0.1)
    model = env.model
    start, identity = np.divmod(np.arange(model.n_classes), model.n_identities)
    for policy, shift_mode in ((FixationPolicy(4), "edge"), (FixationPolicy(1), "uniform"), (StationaryPolicy(), "edge")):
        thresholds = [0.6, 0.95]
        result = monte_carlo(env, policy, thresholds=thresholds, runs=len(start), seed=0, start_location=start,
                             true_identity=identity, max_taps=12, shift_mode=shift_mode)
        for k, threshold in enumerate(thresholds):
            for l, i in zip(start, identity):
                perceiver = Perceiver(model, policy, decision_threshold=threshold, max_taps=12, shift_mode=shift_mode)
                location = l
                while True:
                    step = perceiver.observe(env.test.taps[env.draw([location * model.n_identities + i], np.random.default_rng(0))[0]])
                    if step.decided:
                        break
                    perceiver.moved(step.move)
                    location = int(np.clip(location + step.move_classes, 0, model.n_locations - 1))
                assert result.taps_map[k, l, i] == step.taps
                assert result.identity_error_map[k, l, i] == abs(step.identity_estimate - model.identities[i])
                centres = model.location_centres
                assert result.location_error_map[k, l, i] == pytest.approx(abs(step.location_estimate
                                                                               - centres[location]))


def test_higher_thresholds_never_decide_sooner(deep_only):
    result = monte_carlo(deep_only, RandomPolicy(), thresholds=np.linspace(0, 0.999, 12), runs=500, seed=3)
    assert (np.diff(result.mean_taps) >= 0).all()
    assert result.mean_taps[0] == 1.0 and (result.forced[:-1] <= result.forced[1:]).all()


def test_maps_average_to_the_means(deep_only):
    result = monte_carlo(deep_only, FixationPolicy(5), thresholds=[0.5, 0.9], runs=3000, seed=4)
    rng = np.random.default_rng(4)  # the same starting classes as the run
    start, identity = rng.integers(0, 6, 3000), rng.integers(0, 4, 3000)
    runs = np.bincount(start * 4 + identity, minlength=24).reshape(6, 4)
    for means, maps in ((result.mean_identity_error, result.identity_error_map),
                        (result.mean_location_error, result.location_error_map), (result.mean_taps, result.taps_map)):
        np.testing.assert_allclose((maps * runs).sum(axis=(1, 2)) / 3000, means, rtol=1e-12)
    rows = result.rows()
    assert [r["threshold"] for r in rows] == [0.5, 0.9] and rows[0]["policy"] == "active"
    assert set(rows[0]) >= {"threshold", "mean_identity_error", "accuracy", "mean_location_error", "mean_taps"}


def test_deadline_counts_null_decisions(deep_only):
    result = monte_carlo(deep_only, StationaryPolicy(), thresholds=[1.0], runs=200, seed=5, deadline=3, max_taps=10)
    assert result.null_decisions.tolist() == [3.0] and result.mean_taps.tolist() == [10.0]
    assert result.forced.tolist() == [1.0]
    # Relocating after a deadline helps stationary perception (paper 001).
    options = dict(thresholds=[0.9], runs=2000, seed=6, max_taps=40)
    with_deadline = monte_carlo(deep_only, StationaryPolicy(), deadline=12, **options)
    without = monte_carlo(deep_only, StationaryPolicy(), **options)
    assert with_deadline.mean_identity_error[0] < 0.6 * without.mean_identity_error[0]
    assert with_deadline.null_decisions[0] > 0.5


def test_draw_picks_uniformly_within_the_class(deep_only):
    rng = np.random.default_rng(7)
    picks = deep_only.draw(np.full(20000, 9), rng)
    assert (deep_only.tap_class[picks] == 9).all()
    counts = np.bincount(picks)[np.bincount(picks) > 0]
    assert len(counts) == 20
    np.testing.assert_allclose(counts, 1000, atol=160)


def test_environment_refuses_incompatible_test_sets(deep_only):
    model = deep_only.model
    test = deep_only.test
    with pytest.raises(DatasetError, match="classes have no test taps"):
        VirtualEnvironment(model, test.subset(test.location != 2))
    with pytest.raises(DatasetError, match="is not one of the model's identities"):
        VirtualEnvironment(model, gap_dataset(**{**GRID, "widths": 5}))
    other = gap_dataset(**{**GRID, "dims": 12})
    with pytest.raises(ModelError, match=r"model trained for tactip \(8 dims, 10 samples\), got tactip taps \(12 dims"):
        VirtualEnvironment(model, other)


@pytest.mark.parametrize("option, value", [("thresholds", [1.5]), ("runs", 0), ("max_taps", 0), ("deadline", 0),
                                           ("move_threshold", 2.0), ("shift_mode", "wrap")])
def test_bad_options_name_the_parameter(deep_only, option, value):
    with pytest.raises(ValueError, match=option):
        monte_carlo(deep_only, StationaryPolicy(), **{option: value})


def test_null_decisions_relocate_uniformly_on_the_simulated_fingertip():
    """The pile-up of issue 10: 30 classes, deadline 5, every run starting in the end class 0.

    Contacts at the ends of the range give no response, so the estimate there is poor; a
    relocation drawn relative to it and clipped to the range put 59 % of the sensors back into
    class 0. Paper 001 moves the finger to a random place: each class gets 1/30 of them.
    """
    from tactip.taxel import TaxelSimulator, simulate_taxel_dataset, sweep_locations

    simulator = TaxelSimulator("fingertip", seed=0)
    where = sweep_locations(simulator.sensor, 900)
    train = simulate_taxel_dataset(simulator, where, seed=(0, 2), collection="train")
    test = simulate_taxel_dataset(simulator, where, seed=(0, 3), collection="test")
    env = VirtualEnvironment(fit_model(train, n_locations=30), test)
    runs = 6000
    # threshold 1 never decides: tap 6 is forced at the place the first null decision moved to
    result = monte_carlo(env, StationaryPolicy(), thresholds=[1.0], runs=runs, seed=1, deadline=5, max_taps=6,
                         start_location=np.zeros(runs, int), true_identity=np.zeros(runs, int))
    landed = np.bincount(result.final_location[0], minlength=30) / runs
    assert landed[0] < 0.05                                     # 59 % before the fix
    np.testing.assert_allclose(landed, 1 / 30, atol=0.012)
    assert result.null_fraction.tolist() == [0.5]              # one null, then one (forced) decision per run


def test_null_fraction_is_a_proportion_and_forced_runs_are_apart(deep_only):
    options = dict(thresholds=[0.5, 0.8], runs=1500, seed=7, max_taps=300)
    short = monte_carlo(deep_only, StationaryPolicy(), deadline=6, **options)
    long = monte_carlo(deep_only, StationaryPolicy(), deadline=8, **options)
    for result in (short, long):
        assert ((0 < result.null_fraction) & (result.null_fraction < 1)).all()
        assert (np.diff(result.null_fraction) > 0).all()        # paper 001 Fig. 6: rises with theta
        assert (result.forced == 0).all()                       # every run decides by the threshold
        np.testing.assert_allclose(result.decided_identity_error, result.mean_identity_error)
    assert (short.null_fraction > long.null_fraction).all()     # ... and with shorter deadlines
    capped = monte_carlo(deep_only, StationaryPolicy(), thresholds=[0.9], runs=1500, seed=7, max_taps=8)
    assert 0 < capped.forced[0] < 1
    # the threshold decisions alone are better than the mix with the forced ones
    assert capped.decided_identity_error[0] < capped.mean_identity_error[0]
    assert capped.rows()[0]["null_fraction"] == 0.0


def test_joint_rule_agrees_with_the_perceiver_and_is_never_sooner(deep_only):
    env = environment(test_taps=1, legible_from=0.4, noise=0.1)
    model = env.model
    start, identity = np.divmod(np.arange(model.n_classes), model.n_identities)
    result = monte_carlo(env, FixationPolicy(4), thresholds=[0.6], runs=len(start), seed=0, start_location=start,
                         true_identity=identity, max_taps=12, decision_rule="joint")
    for l, i in zip(start, identity):
        perceiver = Perceiver(model, FixationPolicy(4), decision_threshold=0.6, max_taps=12, decision_rule="joint")
        location = l
        while True:
            step = perceiver.observe(env.test.taps[env.draw([location * model.n_identities + i],
                                                            np.random.default_rng(0))[0]])
            if step.decided:
                break
            perceiver.moved(step.move)
            location = int(np.clip(location + step.move_classes, 0, model.n_locations - 1))
        assert result.taps_map[0, l, i] == step.taps
        assert result.identity_error_map[0, l, i] == abs(step.identity_estimate - model.identities[i])
    marginal = monte_carlo(deep_only, StationaryPolicy(), thresholds=[0.3, 0.9], runs=1000, seed=8)
    joint = monte_carlo(deep_only, StationaryPolicy(), thresholds=[0.3, 0.9], runs=1000, seed=8, decision_rule="joint")
    assert (joint.mean_taps >= marginal.mean_taps).all() and joint.mean_taps[0] > marginal.mean_taps[0]


def test_circular_identities_count_errors_the_shorter_way_round():
    """Edge angles (paper 004): deciding 355 deg for 0 deg is a 5 deg error, not 355."""
    rng = np.random.default_rng(0)
    angles = np.arange(0.0, 360.0, 45.0)
    # taps that tell nothing: every decision is a guess, spread over all angles
    taps = rng.normal(size=(8 * 2 * 6, 5, 3))
    location, identity = np.repeat([0.0, 1.0], 8 * 6), np.tile(np.repeat(angles, 6), 2)
    data = Dataset(taps, location, identity, None, "taxel", identity_unit="deg")
    test = Dataset(rng.normal(size=taps.shape), location, identity, None, "taxel", identity_unit="deg")
    env = VirtualEnvironment(fit_model(data, n_locations=2), test)
    plain = monte_carlo(env, StationaryPolicy(), thresholds=[0.0], runs=4000, seed=1)
    circular = monte_carlo(env, StationaryPolicy(), thresholds=[0.0], runs=4000, seed=1, identity_period=360.0)
    assert circular.accuracy[0] == plain.accuracy[0]
    assert circular.mean_identity_error[0] < plain.mean_identity_error[0]
    assert circular.mean_identity_error[0] <= 180.0 and plain.mean_identity_error[0] > 100.0
    with pytest.raises(ValueError, match="identity_period"):
        monte_carlo(env, StationaryPolicy(), identity_period=0.0)
