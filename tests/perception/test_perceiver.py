"""The tap-by-tap Perceiver: beliefs, stop and move rules, deadline, forced decision, adaptive prior."""

import numpy as np
import pytest

from perception import (Dataset, FixationPolicy, ModelError, PerceptionError, Perceiver, RandomPolicy, fit_model,
                        shift)
from tests.perception.synthetic import gap_dataset


@pytest.fixture(scope="module")
def model():
    return fit_model(gap_dataset(depths=6, widths=3, taps_per_class=4, samples=10, dims=8, seed=1, noise=0.2),
                     n_locations=6)


@pytest.fixture(scope="module")
def taps():
    return gap_dataset(depths=6, widths=3, taps_per_class=4, samples=10, dims=8, seed=2, noise=0.2)


def test_beliefs_are_the_normalised_product_of_likelihoods(model, taps):
    perceiver = Perceiver(model, decision_threshold=1.0, max_taps=50)
    total = np.zeros((6, 3))
    for n, tap in enumerate(taps.taps[::7][:8], start=1):
        before = perceiver.posterior
        step = perceiver.observe(tap)
        total += model.log_likelihood(tap)
        expected = np.exp(total - total.max())
        np.testing.assert_allclose(step.posterior, expected / expected.sum(), atol=1e-12)
        np.testing.assert_allclose(perceiver.prior, before, atol=1e-15)
        np.testing.assert_allclose(step.where_belief, step.posterior.sum(axis=1))
        np.testing.assert_allclose(step.what_belief, step.posterior.sum(axis=0))
        assert step.taps == n and not step.decided and step.move == 0.0
        assert step.location_estimate == model.location_centres[step.posterior.sum(axis=1).argmax()]
        assert step.identity_estimate == model.identities[step.posterior.sum(axis=0).argmax()]


def test_stops_when_the_identity_belief_crosses_the_threshold(model, taps):
    clean = taps.subset((taps.location == 5) & (taps.identity == 2))
    perceiver = Perceiver(model, decision_threshold=0.95, max_taps=50)
    total = np.zeros((6, 3))
    for tap in np.concatenate([clean.taps] * 10):
        step = perceiver.observe(tap)
        total += model.log_likelihood(tap)
        what = np.exp(total - total.max()).sum(axis=0)
        assert step.decided == (what.max() / what.sum() > 0.95)
        assert step.belief == pytest.approx(what.max() / what.sum())
        if step.decided:
            break
    assert step.decided and not step.forced and step.identity_estimate == 2.0
    with pytest.raises(PerceptionError, match="call reset"):
        perceiver.observe(clean.taps[0])
    perceiver.reset()
    assert perceiver.taps == 0
    np.testing.assert_allclose(perceiver.posterior, 1 / 18)


def test_active_move_is_snapped_clamped_and_must_be_reported(model, taps):
    perceiver = Perceiver(model, FixationPolicy(5), decision_threshold=1.0)
    step = perceiver.observe(taps.subset(taps.location == 1).taps[0])
    assert step.move_classes == 5 - step.location_class
    assert step.move == pytest.approx(step.move_classes * model.class_width)
    with pytest.raises(PerceptionError, match="moved"):
        perceiver.observe(taps.taps[0])
    before = np.log(perceiver.posterior)
    perceiver.moved(step.move + 0.3 * model.class_width)  # the arm's real move, rounded to classes
    np.testing.assert_allclose(np.log(perceiver.posterior), shift(before, step.move_classes, mode="edge"),
                               atol=1e-12)
    perceiver.observe(taps.taps[0])


def test_moves_are_clamped_to_the_range(model, taps):
    class FarAway:
        name = "far"

        def move(self, where_belief, location_estimate, rng):
            return location_estimate * 0 + 100

    step = Perceiver(model, FarAway(), decision_threshold=1.0).observe(taps.taps[0])
    assert step.location_class + step.move_classes == 5


@pytest.mark.parametrize("move_threshold", [1.0, 0.999])
def test_move_threshold_gates_the_policy(model, taps, move_threshold):
    perceiver = Perceiver(model, FixationPolicy(5), decision_threshold=1.0, move_threshold=move_threshold,
                          max_taps=50)
    for tap in taps.subset(taps.location == 0).taps:
        step = perceiver.observe(tap)
        assert (step.move_classes != 0) == (step.where_belief.max() > move_threshold and step.location_class != 5)
        perceiver.moved(step.move)


def test_deadline_gives_null_decisions_and_relocates(model, taps):
    perceiver = Perceiver(model, decision_threshold=1.0, deadline=3, max_taps=10, rng=0)
    steps = []
    for n in range(10):
        step = perceiver.observe(taps.taps[5 * n])
        steps.append(step)
        if step.null:
            np.testing.assert_allclose(perceiver.posterior, 1 / 18)  # the evidence is discarded
            assert step.move_classes == 0 and step.relocate_to in model.location_centres
            with pytest.raises(PerceptionError, match="moved"):
                perceiver.observe(taps.taps[0])   # the relocation must be reported first
        else:
            assert step.relocate_to is None
        perceiver.moved(step.move)
    assert [s.null for s in steps] == [False, False, True] * 3 + [False]
    assert [s.taps for s in steps] == list(range(1, 11))
    assert steps[-1].decided and steps[-1].forced


def test_max_taps_forces_the_decision(model, taps):
    perceiver = Perceiver(model, decision_threshold=1.0, max_taps=4)
    steps = [perceiver.observe(tap) for tap in taps.taps[:4]]
    assert [s.decided for s in steps] == [False, False, False, True]
    assert steps[-1].forced and steps[-1].belief <= 1.0


def test_adaptive_prior_mixes_the_last_decision_with_a_flat_prior(model, taps):
    perceiver = Perceiver(model, decision_threshold=0.0, adaptive_prior=True)
    step = perceiver.observe(taps.taps[30])
    assert step.decided
    perceiver.reset()
    np.testing.assert_allclose(perceiver.posterior, 0.5 * step.posterior + 0.5 / 18, atol=1e-12)
    np.testing.assert_allclose(perceiver.prior, perceiver.posterior)
    explicit = np.arange(18.0).reshape(6, 3)
    perceiver.reset(prior=explicit)
    np.testing.assert_allclose(perceiver.posterior, explicit / explicit.sum(), atol=1e-15)
    plain = Perceiver(model, decision_threshold=0.0)
    plain.observe(taps.taps[30])
    plain.reset()
    np.testing.assert_allclose(plain.posterior, 1 / 18)


def test_location_task_stops_on_the_location_belief():
    rng = np.random.default_rng(0)
    location = np.repeat(np.arange(5.0), 6)
    taps = location[:, None, None] + 0.05 * rng.normal(size=(30, 8, 3))
    model = fit_model(Dataset(taps, location, np.zeros(30), None, "taxel", identity_unit="none"), n_locations=5)
    perceiver = Perceiver(model, decision_threshold=0.99)
    step = perceiver.observe(3.0 + 0.05 * rng.normal(size=(8, 3)))
    assert step.decided and step.belief == step.where_belief.max() > 0.99
    assert step.location_class == 3 and step.location_estimate == pytest.approx(2.8)  # class 2.4-3.2 mm


def test_bad_taps_and_knobs(model):
    perceiver = Perceiver(model)
    with pytest.raises(ModelError, match="10 samples x 8 dims"):
        perceiver.observe(np.zeros((10, 12)))
    for knob, value in [("decision_threshold", 1.5), ("move_threshold", -0.1), ("max_taps", 0), ("deadline", 0),
                        ("shift_mode", "wrap"), ("alpha", 2.0)]:
        with pytest.raises(ValueError, match=knob):
            Perceiver(model, **{knob: value})
    with pytest.raises(PerceptionError, match="prior"):
        perceiver.reset(prior=np.ones((2, 2)))
    assert "RandomPolicy" in repr(Perceiver(model, RandomPolicy()))


def test_null_decisions_relocate_uniformly_over_the_range_whatever_the_estimate(model, taps):
    """Paper 001: the finger moves to another position at random, not relative to a poor estimate."""
    perceiver = Perceiver(model, decision_threshold=1.0, deadline=1, max_taps=None, rng=1)
    end_tap = taps.taps[(taps.location == 0) & (taps.identity == 1)][0]
    places = []
    for _ in range(3000):
        step = perceiver.observe(end_tap)
        assert step.null and not step.decided
        places.append(step.relocate_to)
        perceiver.moved(step.relocate_to - step.location_estimate)   # beliefs restarted: no shift
        np.testing.assert_allclose(perceiver.posterior, 1 / 18)
    counts = np.array([places.count(c) for c in model.location_centres])
    np.testing.assert_allclose(counts / 3000, 1 / 6, atol=0.03)


def test_joint_rule_stops_when_a_joint_class_crosses(model, taps):
    for rule in ("joint", "marginal"):
        perceiver = Perceiver(model, decision_threshold=0.7, max_taps=None, decision_rule=rule)
        for tap in taps.taps[::5]:
            step = perceiver.observe(tap)
            joint = step.posterior.max()
            marginal = step.what_belief.max()
            assert step.belief == pytest.approx(joint if rule == "joint" else marginal)
            assert step.decided == (step.belief > 0.7) and not step.forced
            if rule == "joint":
                assert step.posterior[step.location_class, step.identity_class] == joint
            if step.decided:
                break
            perceiver.moved(step.move)
        assert step.decided
    with pytest.raises(ValueError, match="decision_rule"):
        Perceiver(model, decision_rule="any")


def test_a_move_after_the_decision_shifts_the_adaptive_prior(model, taps):
    """The sensor moves between decisions: the next decision's prior is the last posterior moved with it."""
    perceiver = Perceiver(model, decision_threshold=0.0, adaptive_prior=True, prior_shift=0, shift_mode="uniform")
    step = perceiver.observe(taps.taps[30])
    assert step.decided
    perceiver.moved(2 * model.class_width)                  # two location classes up, after the decision
    moved = np.exp(shift(np.log(step.posterior), 2, mode="uniform"))
    assert not np.allclose(moved, step.posterior, atol=1e-3)  # the move changes the belief
    np.testing.assert_allclose(perceiver.posterior, moved, atol=1e-12)
    perceiver.reset()
    np.testing.assert_allclose(perceiver.posterior, 0.5 * moved + 0.5 / 18, atol=1e-12)


def test_adaptive_prior_learns_the_shift_between_decisions():
    """Identities move by one class between decisions; the perceiver learns Delta = 1 (paper 004)."""
    data = gap_dataset(depths=2, widths=6, taps_per_class=6, samples=10, dims=8, seed=1, noise=0.1, contact_floor=1.0)
    model = fit_model(data, n_locations=2)
    test = gap_dataset(depths=2, widths=6, taps_per_class=6, samples=10, dims=8, seed=2, noise=0.1, contact_floor=1.0)
    perceiver = Perceiver(model, decision_threshold=0.95, adaptive_prior=True, identity_period=6.0, rng=0)
    fixed = Perceiver(model, decision_threshold=0.95, adaptive_prior=True, prior_shift=2, identity_period=6.0)
    assert fixed.delta == 2
    rng = np.random.default_rng(0)
    width = 0
    for decision in range(12):
        pool = test.taps[(test.identity == width + 1) & (test.location == 1)]
        perceiver.reset()
        if decision >= 1:   # the prior is the last posterior turned by Delta, mixed half and half with flat
            expected = 0.5 * np.roll(last, perceiver.delta, axis=1) + 0.5 / 12
            np.testing.assert_allclose(perceiver.posterior, expected, atol=1e-12)
        while True:
            step = perceiver.observe(pool[rng.integers(len(pool))])
            if step.decided:
                break
            perceiver.moved(0.0)
        last = step.posterior
        width = (width + 1) % 6
    assert perceiver.delta == 1
