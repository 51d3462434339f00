"""The adaptive prior with a learned shift (paper 004): the PIG learner and decision sequences."""

import numpy as np
import pytest

from perception import StationaryPolicy, VirtualEnvironment, fit_model
from perception.adaptive import ShiftLearner, kl_divergence
from perception.sequence import identity_distance, monte_carlo_sequence
from tests.perception.synthetic import gap_dataset

GRID = dict(depths=4, widths=8, samples=10, dims=8, contact_floor=1.0, noise=0.15)


def test_kl_divergence_by_hand():
    assert kl_divergence([0.5, 0.5], [0.5, 0.5]) == 0.0
    assert kl_divergence([1.0, 0.0], [0.25, 0.75]) == pytest.approx(np.log(4))


@pytest.mark.parametrize("circular", [True, False])
def test_learner_finds_the_shift_of_noisy_beliefs(circular):
    """Each decision's belief peaks one class further on, with confusions; Delta converges to 1."""
    rng = np.random.default_rng(0)
    n, runs = 24, 50   # true classes stay inside the range: 0-5 plus 15 turns
    learner = ShiftLearner(n, circular=circular, runs=runs)
    true = rng.integers(0, 6, runs)
    previous = None
    for _ in range(15):
        seen = np.clip(true + rng.integers(-1, 2, runs) * (rng.random(runs) < 0.3), 0, n - 1)
        belief = np.full((runs, n), 0.05 / (n - 1))
        belief[np.arange(runs), seen] = 0.95
        if previous is not None:
            learner.observe(previous, belief)
        previous, true = belief, (true + 1) % n if circular else true + 1
    assert (learner.delta == 1).mean() > 0.9
    assert np.allclose(learner.gamma.sum(axis=1), 1) and (learner.tau == 14).all()


def test_learner_keeps_the_runs_that_did_not_decide():
    learner = ShiftLearner(5, runs=2)
    learner.observe(np.eye(5)[[0, 0]], np.eye(5)[[2, 2]], active=[True, False])
    assert learner.delta.tolist() == [2, 0] and learner.tau.tolist() == [1, 0]
    np.testing.assert_allclose(learner.gamma[1], 1 / 5)
    with pytest.raises(ValueError, match="max_shift"):
        ShiftLearner(5, max_shift=5)


@pytest.fixture(scope="module")
def turning():
    """Identities on a circle of 8 classes (like edge angles over 360 deg)."""
    model = fit_model(gap_dataset(seed=1, taps_per_class=10, **GRID), n_locations=4)
    return VirtualEnvironment(model, gap_dataset(seed=2, taps_per_class=20, **GRID))


def test_adaptive_prior_with_the_learned_shift_beats_the_flat_prior(turning):
    """The true identity turns one class per decision (paper 004's contour following)."""
    options = dict(threshold=0.3, decisions=20, identity_step=1, runs=300, seed=3, identity_period=8.0)
    flat = monte_carlo_sequence(turning, StationaryPolicy(), **options)
    learned = monte_carlo_sequence(turning, StationaryPolicy(), adaptive=True, **options)
    unshifted = monte_carlo_sequence(turning, StationaryPolicy(), adaptive=True, prior_shift=0, **options)
    late = slice(5, None)
    # the bar: >= 20 % lower error at no more taps
    assert learned.identity_error[late].mean() <= 0.8 * flat.identity_error[late].mean()
    assert learned.taps[late].mean() <= flat.taps[late].mean()
    # the learned shift converges on the true turn ...
    assert learned.delta_error()[-1] < 0.1 < 0.5 < learned.delta_error()[1]
    assert (flat.delta == 0).all() and (learned.delta[0] == 0).all()
    # ... and the prior without a shift is no gain (paper 004 eq. 12 without eq. 7's Delta)
    assert unshifted.identity_error[late].mean() >= flat.identity_error[late].mean()


def test_identity_distance_is_circular_with_a_period():
    assert identity_distance([1.0, 8.0], [8.0, 1.0]).tolist() == [7.0, 7.0]
    assert identity_distance([1.0, 8.0], [8.0, 1.0], period=8.0).tolist() == [1.0, 1.0]
