"""Tap tempering: the t-th tap of a decision has its log likelihood multiplied by g_t.

The schedule is checked, g = 1 is plain Bayes, the perceiver, the Monte Carlo and the belief trace
apply it the same way, every kind stores it (and files without it load with none), and a schedule
fitted on runs whose taps repeat each other's evidence calibrates the beliefs after 1, 3 and 5 taps.
"""

import dataclasses

import h5py
import numpy as np
import pytest

from perception import (FixationPolicy, ModelError, Perceiver, StationaryPolicy, VirtualEnvironment, bayes,
                        fit_model, fit_tap_tempering, load_model, monte_carlo, save_model, trace_beliefs, train_model)
from perception.likelihood import fit_class_grid
from perception.reliability import fixation_for_accuracy
from tests.perception.synthetic import gap_dataset

GRID = dict(depths=4, widths=5, samples=8, dims=6, contact_floor=1.0, noise=0.4)


@pytest.fixture(scope="module")
def gaussian():
    return train_model(gap_dataset(seed=1, taps_per_class=6, **GRID), kind="gaussian", n_locations=4)


@pytest.mark.parametrize("bad", [[0.5, 0.0], [-1.0], [np.nan], [np.inf, 1.0], [[1.0, 0.5]], ["a"]])
def test_a_schedule_of_anything_but_finite_numbers_above_zero_is_refused(bad, gaussian):
    with pytest.raises(ValueError, match="tap_tempering"):
        bayes.check_tap_tempering(bad)
    with pytest.raises(ModelError, match="tap_tempering"):
        gaussian.with_tap_tempering(bad)


def test_the_last_factor_serves_every_later_tap_and_none_is_one():
    assert bayes.check_tap_tempering((1, 0.5)) == (1.0, 0.5) and bayes.check_tap_tempering(()) == ()
    assert bayes.tap_factor(np.arange(1, 8), (0.9, 0.5, 0.3)).tolist() == [0.9, 0.5, 0.3, 0.3, 0.3, 0.3, 0.3]
    assert bayes.tap_factor([[1, 4], [2, 9]], ()).tolist() == [[1.0, 1.0], [1.0, 1.0]]
    with pytest.raises(ValueError, match="taps must be >= 1"):
        bayes.tap_factor(0, (0.5,))


def test_a_schedule_of_ones_is_plain_bayes_and_a_factor_scales_the_log_likelihood():
    rng = np.random.default_rng(0)
    log_likelihood, log_prior = rng.normal(size=(2, 7, 3, 4)) * 3
    log_prior = bayes.normalize(log_prior)
    taps = np.array([1, 2, 3, 4, 5, 6, 9])
    plain = bayes.update(log_likelihood, log_prior)
    assert np.array_equal(bayes.tap_update(log_likelihood, log_prior, taps, ()), plain)
    np.testing.assert_allclose(bayes.tap_update(log_likelihood, log_prior, taps, (1.0, 1.0)),
                               bayes.update(log_likelihood, log_prior), atol=1e-12)
    schedule = (0.8, 0.5, 0.25)
    batch = bayes.tap_update(log_likelihood, log_prior, taps, schedule)
    for r, t in enumerate(taps):   # a plain loop: P(c | z_1:t) proportional to P(z_t | c)^g_t P(c | z_1:t-1)
        g = schedule[min(t, 3) - 1]
        posterior = np.exp(g * log_likelihood[r]) * np.exp(log_prior[r])
        np.testing.assert_allclose(np.exp(batch[r]), posterior / posterior.sum(), atol=1e-12)


def test_the_perceiver_tempers_each_tap_of_a_decision_by_its_own_factor(gaussian):
    taps = gap_dataset(seed=3, taps_per_class=1, **GRID).taps[:4]
    schedule = (0.9, 0.6, 0.4)
    perceiver = Perceiver(gaussian.with_tap_tempering(schedule), StationaryPolicy(), decision_threshold=1.0)
    log_belief = bayes.flat_prior(gaussian.n_locations, gaussian.n_identities)
    for t, tap in enumerate(taps, start=1):
        step = perceiver.observe(tap)
        perceiver.moved(0.0)
        log_belief = bayes.update(schedule[min(t, 3) - 1] * gaussian.log_likelihood(tap), log_belief)
        np.testing.assert_allclose(step.posterior, np.exp(log_belief), atol=1e-12)
    perceiver.reset()   # a new decision starts again at g_1
    np.testing.assert_allclose(perceiver.observe(taps[0]).posterior,
                               np.exp(bayes.update(0.9 * gaussian.log_likelihood(taps[0]), bayes.flat_prior(4, 5))),
                               atol=1e-12)


def test_the_monte_carlo_and_the_trace_temper_as_a_model_tempered_throughout(gaussian):
    # A schedule of one factor g is the model's tempering times g on every tap.
    environment = VirtualEnvironment(gaussian, gap_dataset(seed=2, taps_per_class=5, **GRID))
    scheduled, tempered = environment.with_tap_tempering((0.3,)), environment.tempered(0.3)
    policy = FixationPolicy(2)
    a = trace_beliefs(scheduled, policy, runs=300, max_taps=6, seed=4)
    b = trace_beliefs(tempered, policy, runs=300, max_taps=6, seed=4)
    np.testing.assert_allclose(a.belief, b.belief, atol=1e-12)
    plain = trace_beliefs(environment, policy, runs=300, max_taps=6, seed=4)
    assert np.abs(plain.belief - a.belief).max() > 0.1   # the factor does change the beliefs
    runs = dict(runs=300, seed=4, thresholds=(0.5, 0.9), max_taps=8, deadline=3)
    c, d = monte_carlo(scheduled, policy, **runs), monte_carlo(tempered, policy, **runs)
    assert np.array_equal(c.mean_taps, d.mean_taps) and np.array_equal(c.accuracy, d.accuracy)


@pytest.mark.parametrize("kind", ["histogram", "calibrated-histogram", "gaussian"])
def test_every_kind_saves_and_loads_its_schedule_and_an_old_file_has_none(kind, tmp_path):
    model = train_model(gap_dataset(seed=1, taps_per_class=4, **GRID), kind=kind, n_locations=4, bins=10)
    assert model.tap_tempering == ()
    save_model(tmp_path / "plain.h5", model)
    with h5py.File(tmp_path / "plain.h5", "r") as f:
        assert "tap_tempering" not in f.attrs   # a file without a schedule is the file of before
    assert load_model(tmp_path / "plain.h5").tap_tempering == ()
    scheduled = model.with_tap_tempering([0.9, 0.5, 0.4])
    save_model(tmp_path / "scheduled.h5", scheduled)
    loaded = load_model(tmp_path / "scheduled.h5")
    assert loaded.tap_tempering == (0.9, 0.5, 0.4) and loaded.KIND == kind
    assert "tap tempering 0.9, 0.5, 0.4" in loaded.summary()
    with h5py.File(tmp_path / "scheduled.h5", "r+") as f:
        f.attrs["tap_tempering"] = np.array([0.9, -0.5])
    with pytest.raises(ModelError, match="tap_tempering"):
        load_model(tmp_path / "scheduled.h5")


def test_a_class_grid_carries_a_schedule_too():
    grid = fit_class_grid(gap_dataset(seed=1, taps_per_class=2, **GRID), n_locations=4)
    assert grid.tap_tempering == () and grid.with_tap_tempering((0.5,)).tap_tempering == (0.5,)
    with pytest.raises(ModelError, match="tap_tempering"):
        dataclasses.replace(grid, tap_tempering=(0.0,))


def _repeating_environment(model, seed):
    """Test taps whose class shares a deviation the model never saw: a run's taps repeat each other's evidence."""
    test = gap_dataset(seed=seed, taps_per_class=8, **GRID)
    classes = model.tap_class(test)
    shared = np.random.default_rng(seed + 100).normal(scale=0.15, size=(model.n_classes, 1, test.dims))
    return VirtualEnvironment(model, dataclasses.replace(test, taps=test.taps + shared[classes]))


def test_a_fitted_schedule_calibrates_the_beliefs_after_1_3_and_5_taps(gaussian):
    # Over three environments (a class's 8 test taps and its shared deviation bound how calibrated any
    # belief can be measured to be: about 0.04 after 1 tap here), each judged on other runs than those the
    # schedule was fitted on.
    policy = FixationPolicy(3)
    before, after = [], []
    for seed in (10, 11, 12):
        environment = _repeating_environment(gaussian, seed)
        schedule = fit_tap_tempering(environment, policy, runs=1000, seed=0)
        assert len(schedule) == 5
        # The taps of a run repeat each other's evidence: later taps are worth less than the first.
        assert max(schedule[2:]) < schedule[0], schedule
        for out, env in ((before, environment), (after, environment.with_tap_tempering(schedule))):
            trace = trace_beliefs(env, policy, runs=4000, max_taps=5, seed=1)
            out.append([trace.calibration_error(t) for t in (1, 3, 5)])
    before, after = np.array(before), np.array(after)
    assert after.max() < 0.12 and after[:, 1:].mean() < 0.5 * before[:, 1:].mean(), (before, after)
    assert before[:, 2].min() > 0.15   # without it, the beliefs after 5 taps are overconfident


def test_the_accuracy_sweep_fits_the_schedule_at_its_best_fixation(gaussian):
    environment = _repeating_environment(gaussian, 10)
    sweep = fixation_for_accuracy(environment, target=0.8, tolerance=1.0, runs=400, seed=0, temper=True,
                                  confirm_runs=0)
    assert sweep.best is not None
    policy = FixationPolicy(int(np.argmin(np.abs(gaussian.location_centres - sweep.fixations[sweep.best]))))
    assert sweep.tap_tempering == fit_tap_tempering(environment, policy, runs=400, seed=0)
    assert fixation_for_accuracy(environment, target=0.8, tolerance=1.0, runs=400, seed=0,
                                 confirm_runs=0).tap_tempering == ()


def test_the_papers_histogram_model_runs_as_before_without_a_schedule():
    model = fit_model(gap_dataset(seed=1, taps_per_class=4, **GRID), n_locations=4, bins=10)
    assert model.tap_tempering == () and "tap tempering" not in model.summary()


def test_a_later_tap_is_worth_at_most_an_independent_one():
    # Taps easy to tell apart: every run is right after its second tap, so the Brier score keeps falling as
    # g_t grows; the fit stops at 1 (a later tap worth one independent tap) instead of running away.
    easy = dict(GRID, noise=0.05)
    model = train_model(gap_dataset(seed=1, taps_per_class=6, **easy), kind="gaussian", n_locations=4)
    environment = VirtualEnvironment(model, gap_dataset(seed=2, taps_per_class=6, **easy))
    trace = trace_beliefs(environment, FixationPolicy(3), runs=500, max_taps=5, seed=0)
    assert (trace.estimate[:, 1:] == trace.truth[:, 1:]).all()
    schedule = fit_tap_tempering(environment, FixationPolicy(3), runs=500, seed=0)
    assert schedule[1:] == (1.0, 1.0, 1.0, 1.0), schedule
