"""The adaptive prior with a learned shift (paper 004): the PIG learner."""

import numpy as np
import pytest

from perception.adaptive import ShiftLearner, kl_divergence


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

