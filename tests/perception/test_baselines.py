"""Baselines on the model's own features: exact where the data are separable, right across the wrap, NaN-proof."""

import numpy as np
import pytest

from perception import Dataset, VirtualEnvironment, make_policy, monte_carlo, train_model
from perception.baselines import compare_baselines, keep_verdict, label_error, one_tap, task_labels
from tests.perception.labelled import DIRECTIONS, labelled_taps


def test_label_error_wraps_for_a_period_and_counts_wrong_names():
    assert label_error([315.0, 0.0, 90.0, 10.0], [0.0, 315.0, 270.0, 350.0], period=360).tolist() == [45, 45, 180, 20]
    assert label_error([315.0], [0.0]).tolist() == [315.0]
    assert label_error([0, 1, 2], [0, 2, 2], named=True).tolist() == [0.0, 1.0, 0.0]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_baselines_are_exact_on_separable_names(seed):
    train = labelled_taps("named", seed=seed, structure_seed=seed, separation=20.0, noise=0.1, per_class=12)
    test = labelled_taps("named", seed=seed + 10, structure_seed=seed, separation=20.0, noise=0.1, per_class=12)
    model = train_model(train, kind="gaussian", n_locations=1)
    report = compare_baselines(model, train, test, seed=seed)
    assert [b.name for b in report.baselines] == ["knn", "logistic"]          # no regression of a name
    for baseline in report.baselines:
        assert (baseline.error, baseline.accuracy) == (0.0, pytest.approx(1.0))
        np.testing.assert_array_equal(baseline.predicted, test.identity)
    assert (report.model_error, report.model_accuracy) == (0.0, pytest.approx(1.0))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_ridge_reads_a_label_carried_linearly_by_one_feature(seed):
    kwargs = dict(label="numeric", classes=6, per_class=25, separation=6.0, noise=1.0, structure_seed=seed)
    train, test = labelled_taps(seed=seed, **kwargs), labelled_taps(seed=seed + 10, **kwargs)
    report = compare_baselines(train_model(train, kind="gaussian", n_locations=1), train, test, seed=seed)
    ridge = {b.name: b for b in report.baselines}["ridge"]
    chance = np.abs(np.arange(1, 7)[:, None] - np.arange(1, 7)).mean()     # guessing a depth: 1.94 mm
    assert ridge.error < 0.2 * chance, ridge
    assert report.label_unit == "mm" and ridge.settings["alpha"] > 0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_circular_baselines_are_right_across_the_wrap(seed):
    # Ridge regresses (cos, sin): 0 and 315 deg are neighbours to it, not the two ends of a line.
    kwargs = dict(label="circular", per_class=25, separation=3.0, noise=1.0, structure_seed=seed)
    train, test = labelled_taps(seed=seed, **kwargs), labelled_taps(seed=seed + 10, **kwargs)
    report = compare_baselines(train_model(train, kind="gaussian", n_locations=1), train, test, seed=seed)
    for baseline in report.baselines:
        error = label_error(baseline.predicted, test.identity, period=360)
        per_direction = np.array([error[test.identity == d].mean() for d in DIRECTIONS])
        assert per_direction.max() < 30, (baseline.name, per_direction)
        assert per_direction[[0, 7]].mean() < 2 * per_direction[1:7].mean() + 5, (baseline.name, per_direction)
        assert baseline.error == pytest.approx(error.mean())               # balanced classes: the plain mean
    ridge = {b.name: b for b in report.baselines}["ridge"].predicted
    assert ((ridge >= 0) & (ridge < 360)).all()


def test_unseen_pins_are_imputed_and_a_pin_never_seen_in_training_is_dropped():
    kwargs = dict(label="named", classes=4, per_class=20, separation=4.0, noise=1.0, unseen=0.3)
    train, test = labelled_taps(seed=0, **kwargs), labelled_taps(seed=1, **kwargs)
    taps = train.taps.copy()
    taps[:, :, :2] = np.nan                                                  # pin 0: never seen in training
    taps[np.isnan(taps).all(axis=(1, 2)), 0, 2] = 0.0
    train = Dataset(taps, train.location, train.identity, None, "tactip", "none", "none",
                    identity_names=train.identity_names)
    with pytest.warns(UserWarning, match="no observed value"):                # the model notices pin 0 too
        model = train_model(train, kind="gaussian", n_locations=1)
    report = compare_baselines(model, train, test, seed=0)
    assert np.isnan(test.taps).any()
    for baseline in report.baselines:
        assert baseline.accuracy > 0.9, baseline


def test_one_tap_is_the_first_decision_of_every_policy():
    kwargs = dict(label="circular", per_class=20, separation=0.6, noise=1.0)
    train, test = labelled_taps(seed=3, **kwargs), labelled_taps(seed=4, **kwargs)
    model = train_model(train, kind="gaussian", n_locations=1)
    decided, error, accuracy = one_tap(model, test)
    loop = np.array([model.identities[model.log_likelihood(tap)[0].argmax()] for tap in test.taps])
    np.testing.assert_array_equal(decided, loop)
    assert error == pytest.approx(label_error(loop, test.identity, period=360).mean())
    assert 0.05 < 1 - accuracy < 0.6                                        # neither trivial nor hopeless
    result = monte_carlo(VirtualEnvironment(model, test), make_policy("stationary", fixation_class=0),
                         thresholds=[0.0], runs=20000, seed=0)
    assert result.mean_taps[0] == 1.0
    assert result.mean_identity_error[0] == pytest.approx(error, rel=0.1)
    assert result.accuracy[0] == pytest.approx(accuracy, abs=0.02)


def test_the_label_of_a_model_with_one_identity_is_its_location():
    rng = np.random.default_rng(0)
    depth = np.repeat(np.arange(5.0), 20)
    taps = depth[:, None, None] * np.ones((1, 3, 4)) + 0.3 * rng.standard_normal((100, 3, 4))
    data = Dataset(taps, depth, np.ones(100), None, "tactip")
    model = train_model(data, kind="gaussian", n_locations=5)
    values, classes = task_labels(model, data)
    np.testing.assert_allclose(values, model.location_centres[classes])
    report = compare_baselines(model, data.subset(np.arange(0, 100, 2)), data.subset(np.arange(1, 100, 2)))
    assert report.label_unit == "mm" and report.model_accuracy > 0.9
    assert {b.name for b in report.baselines} == {"knn", "logistic", "ridge"}


def test_keep_verdict_marks_worse_beyond_five_percent_and_the_threshold_bar():
    assert not keep_verdict(1.05, 1.0).worse_at_one_tap
    assert keep_verdict(1.06, 1.0).worse_at_one_tap
    assert keep_verdict(0.75, 1.0, 0.75).well_below_at_threshold
    assert not keep_verdict(0.5, 1.0, 0.76).well_below_at_threshold
    exact = keep_verdict(0.01, 0.0, 0.0)                                     # an exact baseline
    assert exact.worse_at_one_tap and exact.one_tap_ratio == float("inf") and exact.well_below_at_threshold
    both = keep_verdict(0.0, 0.0, 0.0)                                       # both exact: level, not worse
    assert both.one_tap_ratio == 1.0 and not both.worse_at_one_tap and both.well_below_at_threshold
