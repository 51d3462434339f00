"""Discrete Bayes: update against a direct product, shifts against hand-computed cases, priors."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from perception import adaptive_prior, flat_prior, marginals, normalize, shift, update
from perception.bayes import decide, shift_identity

# A 3-location x 2-identity belief whose shifts are easy to compute by hand.
P = np.array([[0.1, 0.2],
              [0.3, 0.1],
              [0.2, 0.1]])


def test_sequential_updates_equal_one_batch_product():
    rng = np.random.default_rng(0)
    log_likelihoods = rng.normal(scale=3.0, size=(25, 4, 5))
    log_belief = flat_prior(4, 5)
    for log_likelihood in log_likelihoods:
        log_belief = update(log_likelihood, log_belief)
    # P(c | z_1:T) = prod_t P(z_t | c) P(c) / sum_c' prod_t P(z_t | c') P(c')
    product = np.exp(log_likelihoods.sum(axis=0) - log_likelihoods.sum(axis=0).max())
    np.testing.assert_allclose(np.exp(log_belief), product / product.sum(), rtol=0, atol=1e-12)


def test_update_is_bayes_rule_with_a_non_flat_prior():
    likelihood = np.array([[0.5, 0.1], [0.2, 0.9], [0.3, 0.3]])
    posterior = np.exp(update(np.log(likelihood), np.log(P)))
    expected = likelihood * P / (likelihood * P).sum()
    np.testing.assert_allclose(posterior, expected, atol=1e-15)


def test_update_stays_finite_after_many_confident_taps():
    log_belief = flat_prior(3, 2)
    for _ in range(2000):  # evidence far beyond what probabilities could hold
        log_belief = update(np.array([[0.0, -50.0], [-50.0, -50.0], [-50.0, -50.0]]), log_belief)
    assert np.isfinite(log_belief).all()
    assert np.exp(log_belief)[0, 0] == 1.0 and log_belief[1, 1] == pytest.approx(-100000.0)


@pytest.mark.parametrize("offset, expected", [
    (0, P),
    (1, [[0.1, 0.2], [0.1, 0.2], [0.3, 0.1]]),            # P(x_l) <- P(x_l - 1), x_1 replicated
    (-1, [[0.3, 0.1], [0.2, 0.1], [0.2, 0.1]]),           # x_3 replicated
    (2, np.array([[0.1, 0.2]] * 3) / 0.9),                # renormalised
    (-7, np.array([[0.2, 0.1]] * 3) / 0.9),
])
def test_edge_shift_by_hand(offset, expected):
    np.testing.assert_allclose(np.exp(shift(np.log(P), offset, mode="edge")), expected, atol=1e-15)


@pytest.mark.parametrize("offset, expected", [
    (0, P),
    (1, [[0.2, 0.1], [0.1, 0.2], [0.3, 0.1]]),            # x_3 shifted out: its belief fills x_1
    (-1, [[0.3, 0.1], [0.2, 0.1], [0.1, 0.2]]),           # x_1 shifted out: fills x_3
    (2, [[0.25, 0.1], [0.25, 0.1], [0.1, 0.2]]),          # x_2, x_3 out: (0.3+0.2)/2, (0.1+0.1)/2
    (5, [[0.2, 0.4 / 3]] * 3),                            # everything out: uniform per identity
])
def test_uniform_shift_by_hand(offset, expected):
    np.testing.assert_allclose(np.exp(shift(np.log(P), offset, mode="uniform")), expected, atol=1e-15)


@pytest.mark.parametrize("mode", ["edge", "uniform"])
def test_batch_shift_with_one_offset_per_run_equals_single_shifts(mode):
    rng = np.random.default_rng(1)
    beliefs = normalize(rng.normal(size=(6, 5, 3)))
    offsets = np.array([-6, -2, 0, 1, 3, 5])
    batch = shift(beliefs, offsets, mode=mode)
    for belief, offset, shifted in zip(beliefs, offsets, batch):
        np.testing.assert_allclose(shifted, shift(belief, offset, mode=mode), atol=1e-14)


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 6), st.integers(1, 4), st.integers(-8, 8), st.integers(0, 2**32 - 1))
def test_uniform_shift_keeps_unit_sum_and_the_identity_marginal(n_loc, n_id, offset, seed):
    belief = normalize(np.random.default_rng(seed).normal(scale=2, size=(n_loc, n_id)))
    shifted = shift(belief, offset, mode="uniform")
    np.testing.assert_allclose(np.exp(shifted).sum(), 1.0, atol=1e-12)
    np.testing.assert_allclose(marginals(shifted)[1], marginals(belief)[1], atol=1e-12)
    # and shifting there and back restores the classes that never left the range
    kept = slice(max(0, -offset), n_loc - max(0, offset)) if abs(offset) < n_loc else slice(0, 0)
    back = shift(shifted, -offset, mode="uniform")
    np.testing.assert_allclose(np.exp(back[kept]), np.exp(belief[kept]), atol=1e-12)


def test_shift_refuses_an_unknown_mode():
    with pytest.raises(ValueError, match="mode must be one of"):
        shift(np.log(P), 1, mode="wrap")


def test_marginals_sum_over_the_other_axis():
    where, what = marginals(np.log(P))
    np.testing.assert_allclose(where, [0.3, 0.4, 0.3])
    np.testing.assert_allclose(what, [0.6, 0.4])
    where, what = marginals(np.log(np.stack([P, P[::-1]])))
    np.testing.assert_allclose(where, [[0.3, 0.4, 0.3], [0.3, 0.4, 0.3]])


def test_adaptive_prior_mixes_posterior_and_flat():
    # P(c|z_0) = alpha P_predicted(c) + (1 - alpha) / N (paper 004 eq. 12)
    np.testing.assert_allclose(np.exp(adaptive_prior(np.log(P))), 0.5 * P + 0.5 / 6, atol=1e-15)
    np.testing.assert_allclose(np.exp(adaptive_prior(np.log(P), alpha=0.0)), np.full((3, 2), 1 / 6), atol=1e-15)
    np.testing.assert_allclose(np.exp(adaptive_prior(np.log(P), alpha=1.0)), P, atol=1e-15)
    with pytest.raises(ValueError, match="alpha"):
        adaptive_prior(np.log(P), alpha=1.5)


def test_flat_prior():
    np.testing.assert_allclose(np.exp(flat_prior(4, 5)), np.full((4, 5), 0.05))


def test_shift_identity_by_hand():
    belief = np.log(np.array([[0.1, 0.2, 0.3], [0.1, 0.2, 0.1]]))
    # circular (angles over a full turn): what leaves at one end comes back at the other
    np.testing.assert_allclose(np.exp(shift_identity(belief, 1, circular=True)),
                               [[0.3, 0.1, 0.2], [0.1, 0.1, 0.2]], atol=1e-15)
    np.testing.assert_allclose(np.exp(shift_identity(belief, -4, circular=True)),
                               np.exp(shift_identity(belief, -1, circular=True)), atol=1e-15)
    # not circular: the belief shifted out is spread over the classes shifted in, per location
    np.testing.assert_allclose(np.exp(shift_identity(belief, 1)), [[0.3, 0.1, 0.2], [0.1, 0.1, 0.2]], atol=1e-15)
    np.testing.assert_allclose(np.exp(shift_identity(belief, 2)), [[0.25, 0.25, 0.1], [0.15, 0.15, 0.1]],
                               atol=1e-15)
    batch = shift_identity(np.stack([belief, belief]), np.array([1, 2]), circular=True)
    np.testing.assert_allclose(batch[1], shift_identity(belief, 2, circular=True))


def test_adaptive_prior_shifts_the_posterior_by_delta():
    # P(c|z_0) = alpha P(x_l, w_(i - Delta)) + (1 - alpha) / N (paper 004 eqs. 7, 12)
    expected = 0.5 * np.roll(P, 1, axis=1) + 0.5 / 6
    np.testing.assert_allclose(np.exp(adaptive_prior(np.log(P), shift_classes=1, circular=True)), expected, atol=1e-15)


def test_decision_rules():
    belief = np.array([[0.30, 0.05], [0.05, 0.30], [0.25, 0.05]])
    # marginal: 'what' = [0.6, 0.4]; MAP location from the 'where' marginal [0.35, 0.35, 0.3]
    value, location, identity = decide(np.log(belief))
    assert value == pytest.approx(0.6) and (location, identity) == (0, 0)
    # joint (paper 001 eq. 3): the largest joint class, 0.30 at (0, 0) (ties: the first)
    value, location, identity = decide(np.log(belief), rule="joint")
    assert value == pytest.approx(0.30) and (location, identity) == (0, 0)
    value, location, identity = decide(np.log(np.stack([belief, belief[::-1]])), rule="joint")
    assert location.tolist() == [0, 1] and identity.tolist() == [0, 1] and value.tolist() == pytest.approx([0.3, 0.3])
    with pytest.raises(ValueError, match="rule"):
        decide(np.log(belief), rule="any")
