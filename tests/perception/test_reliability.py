"""Calibration measures: ECE against a plain computation, traces against the Monte Carlo, accuracy targets."""

import doctest

import numpy as np
import pytest

import perception.calibration_error
import perception.reliability
import perception.tempering
from perception import (FixationPolicy, RandomPolicy, VirtualEnvironment, calibration_error_floor,
                        expected_calibration_error, fit_model,
                        monte_carlo, reliability_bins, threshold_for_accuracy, trace_beliefs, train_model)
from perception.reliability import fixation_for_accuracy
from tests.perception.synthetic import gap_dataset

GRID = dict(depths=5, widths=4, samples=8, dims=6, legible_from=0.4, noise=0.1)


@pytest.fixture(scope="module")
def environment():
    model = fit_model(gap_dataset(seed=1, taps_per_class=4, **GRID), n_locations=5, bins=20)
    return VirtualEnvironment(model, gap_dataset(seed=2, taps_per_class=6, **GRID))


@pytest.mark.parametrize("module", [perception.calibration_error, perception.tempering])   # reliability: all SKIP
def test_docstring_examples(module):
    result = doctest.testmod(module)
    assert result.attempted > 0 and result.failed == 0


def test_ece_equals_a_plain_loop():
    rng = np.random.default_rng(0)
    confidence = rng.random(500)
    correct = rng.random(500) < confidence ** 2
    expected = 0.0
    for b in range(10):
        inside = [i for i in range(500) if min(int(confidence[i] * 10), 9) == b]
        if inside:
            expected += len(inside) / 500 * abs(np.mean(correct[inside]) - np.mean(confidence[inside]))
    assert expected_calibration_error(confidence, correct) == pytest.approx(expected, rel=1e-12)
    _, accuracy, counts = reliability_bins(confidence, correct)
    assert counts.sum() == 500 and np.nanmax(accuracy) <= 1


def test_a_calibrated_belief_has_a_small_ece():
    rng = np.random.default_rng(1)
    confidence = rng.uniform(0.2, 1.0, 50000)
    assert expected_calibration_error(confidence, rng.random(50000) < confidence) < 0.01
    assert expected_calibration_error(confidence, rng.random(50000) < confidence / 2) > 0.25


def test_the_ece_floor_is_what_calibrated_beliefs_measure():
    # Beliefs of 0.5 on N decisions: one bin, and E|right / N - 0.5| of a fair coin, exactly by the binomial sum.
    from scipy.stats import binom

    for n in (25, 100, 400):
        k = np.arange(n + 1)
        exact = float((binom.pmf(k, n, 0.5) * np.abs(k / n - 0.5)).sum())
        assert calibration_error_floor(np.full(n, 0.5), draws=20000, seed=1).mean() == pytest.approx(exact, rel=0.03)
    # Spread beliefs: each draw is the ECE of a plain loop over those beliefs with Bernoulli(belief) outcomes,
    # and the floor falls as 1 / sqrt(N).
    belief = np.random.default_rng(2).uniform(0.3, 0.9, 96)
    floor = calibration_error_floor(belief, draws=500, seed=3)
    right = np.random.default_rng(3).random((500, 96)) < belief
    assert floor == pytest.approx([expected_calibration_error(belief, r) for r in right], abs=1e-12)
    large = calibration_error_floor(np.tile(belief, 16), draws=500, seed=3)
    assert large.mean() == pytest.approx(floor.mean() / 4, rel=0.2)
    with pytest.raises(ValueError, match="draws"):
        calibration_error_floor(belief, draws=0)


@pytest.mark.parametrize("g1", [None, 0.4])
def test_one_tap_beliefs_are_each_taps_posterior_from_a_flat_prior(environment, g1):
    # Every test tap once: P(w | z) = sum_l exp(g1 * log P(z | l, w)) / sum_(l, w) exp(g1 * log P(z | l, w)).
    from scipy.special import softmax

    from perception import one_tap_beliefs

    model, test = environment.model, environment.test
    if g1 is not None:
        model = model.with_tap_tempering((g1, 1.0, 1.0, 1.0, 1.0))
    belief, right = one_tap_beliefs(model, test)
    log_likelihood = model.log_likelihood_batch(test.taps).reshape(len(test), -1) * (1.0 if g1 is None else g1)
    what = softmax(log_likelihood, axis=1).reshape(len(test), model.n_locations, model.n_identities).sum(axis=1)
    assert belief.shape == right.shape == (len(test),)
    assert np.allclose(belief, what.max(axis=1))
    assert np.array_equal(right, model.identities[what.argmax(axis=1)] == test.identity)


@pytest.mark.parametrize("policy", [FixationPolicy(4), RandomPolicy()])
def test_trace_decisions_are_the_monte_carlo_decisions(environment, policy):
    thresholds = (0.3, 0.6, 0.9, 0.99)
    result = monte_carlo(environment, policy, runs=700, seed=5, thresholds=thresholds, max_taps=12)
    trace = trace_beliefs(environment, policy, runs=700, seed=5, max_taps=12)
    for k, threshold in enumerate(thresholds):
        decisions = trace.decisions(threshold)
        assert decisions.taps.mean() == pytest.approx(result.mean_taps[k], abs=1e-12)
        assert decisions.error.mean() == pytest.approx(result.mean_identity_error[k], abs=1e-12)
        assert decisions.forced.mean() == pytest.approx(result.forced[k], abs=1e-12)


def test_brier_score_after_one_tap_and_over_the_first_taps(environment):
    trace = trace_beliefs(environment, FixationPolicy(2), runs=300, seed=3, max_taps=4)
    right = trace.estimate == trace.truth
    per_tap = [float(((trace.belief[:, t] - right[:, t]) ** 2).mean()) for t in range(4)]   # a plain loop
    assert [trace.brier_score_at(t + 1) for t in range(4)] == pytest.approx(per_tap, abs=1e-15)
    assert trace.brier_score(3) == pytest.approx(np.mean(per_tap[:3]), abs=1e-15)
    assert len(set(np.round(per_tap, 6))) > 1                        # the taps differ: the tap index matters
    with pytest.raises(ValueError, match="1..4"):
        trace.brier_score_at(5)


def test_threshold_for_accuracy_reaches_the_target_in_the_fewest_taps(environment):
    trace = trace_beliefs(environment, FixationPolicy(4), runs=1000, seed=2, max_taps=15)
    decisions, best = threshold_for_accuracy(trace, 0.8, tolerance=1.0)
    assert decisions is not None and decisions.within(1.0).mean() >= 0.8
    for threshold in np.arange(0.5, decisions.threshold, 0.005):  # every cheaper threshold misses the target
        cheaper = trace.decisions(threshold)
        if cheaper.taps.mean() < decisions.taps.mean():
            assert cheaper.within(1.0).mean() < 0.8
    none, best = threshold_for_accuracy(trace, 1.0, tolerance=0.0)
    assert (none is None) == (best < 1.0)


def test_fixation_for_accuracy_prefers_the_legible_end(environment):
    sweep = fixation_for_accuracy(environment, target=0.8, tolerance=1.0, runs=600, max_taps=15, seed=0)
    assert sweep.best is not None and sweep.fixations[sweep.best] >= 2.5  # widths are legible deep only
    assert np.nanmin(sweep.taps) == sweep.taps[sweep.best]


def test_the_chosen_threshold_is_confirmed_on_runs_that_did_not_choose_it(environment):
    options = dict(target=0.8, tolerance=1.0, max_taps=15, seed=0)
    sweep = fixation_for_accuracy(environment, runs=300, confirm_runs=2000, **options)
    unconfirmed = fixation_for_accuracy(environment, runs=300, confirm_runs=0, **options)
    assert sweep.best == unconfirmed.best and np.array_equal(np.delete(sweep.thresholds, sweep.best),
                                                             np.delete(unconfirmed.thresholds, sweep.best), equal_nan=True)
    # The best fixation's threshold and figures are those of 2000 runs drawn from another seed.
    other = np.random.SeedSequence(0).spawn(1)[0]
    trace = trace_beliefs(environment, FixationPolicy(sweep.best), runs=2000, max_taps=15, seed=other)
    decisions, _ = threshold_for_accuracy(trace, 0.8, tolerance=1.0)
    assert sweep.thresholds[sweep.best] == decisions.threshold
    assert sweep.taps[sweep.best] == pytest.approx(decisions.taps.mean())


def test_calibrated_models_have_smaller_multi_tap_ece_than_the_papers_model():
    grid = dict(depths=3, widths=4, samples=8, dims=6, contact_floor=1.0, noise=0.2)
    train, test = gap_dataset(seed=1, taps_per_class=6, **grid), gap_dataset(seed=2, taps_per_class=20, **grid)
    ece = {}
    for kind in ("histogram", "gaussian"):
        model = train_model(train, kind=kind, n_locations=3, bins=20)
        trace = trace_beliefs(VirtualEnvironment(model, test), FixationPolicy(2), runs=2000, seed=0, max_taps=5)
        ece[kind] = [trace.calibration_error(t) for t in (1, 3, 5)]
    # The papers' mean log likelihood is timid: far from calibrated until many taps have piled up.
    assert max(ece["gaussian"]) < 0.1 < 0.2 < ece["histogram"][0]
    assert np.mean(ece["gaussian"]) < np.mean(ece["histogram"]) / 3


def test_tap_tempering_calibrates_an_overconfident_model_whatever_its_tempering():
    grid = dict(depths=4, widths=5, samples=8, dims=6, contact_floor=1.0, noise=0.4)
    model = train_model(gap_dataset(seed=1, taps_per_class=6, **grid), kind="gaussian", n_locations=4)
    environment = VirtualEnvironment(model, gap_dataset(seed=2, taps_per_class=30, **grid))
    overconfident = environment.tempered(4.0)
    assert overconfident.model.tempering == pytest.approx(4.0 * model.tempering)
    policy = FixationPolicy(3)
    schedule = perception.reliability.fit_tap_tempering(overconfident, policy, runs=2000, seed=0)
    # about the same calibrated first tap from either starting point (the Brier score is noisy in g)
    plain = perception.reliability.fit_tap_tempering(environment, policy, runs=2000, seed=0, taps=1)
    assert 4.0 * schedule[0] == pytest.approx(plain[0], rel=0.2)
    before = trace_beliefs(overconfident, policy, runs=4000, seed=1, max_taps=5)
    after = trace_beliefs(overconfident.with_tap_tempering(schedule), policy, runs=4000, seed=1, max_taps=5)
    for taps in (3, 5):
        assert before.calibration_error(taps) > 0.2 and after.calibration_error(taps) < 0.07
    assert after.calibration_error(1) < before.calibration_error(1) / 2
    with pytest.raises(perception.ModelError, match="no tempering"):
        fit_model(gap_dataset(seed=1, taps_per_class=2, **grid), n_locations=4, bins=10).tempered(2.0)


def test_fixation_for_accuracy_through_a_map_fn_equals_a_run_here(environment):
    from tests.perception.test_experiments import ElsewhereMap, assert_same

    mapped = ElsewhereMap()
    options = dict(target=0.8, tolerance=1.0, runs=300, max_taps=15, seed=2, confirm_runs=500)
    assert_same(fixation_for_accuracy(environment, map_fn=mapped, **options),
                fixation_for_accuracy(environment, **options))
    assert mapped.calls == [list(range(5))]
