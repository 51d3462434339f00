"""Missing tap values (NaN: a pin unseen for a whole tap) are marginalised by every likelihood model."""

import dataclasses

import h5py
import numpy as np
import pytest
from scipy.special import logsumexp

from perception import (Dataset, FixationPolicy, ModelError, Perceiver, VirtualEnvironment, fit_model,
                        load_model, monte_carlo, save_model, train_model)
from perception.gaussian import GaussianModel
from perception.learned import TorchModel
from perception.marginal import LowRankGaussian, fit_low_rank_gaussian, missing_patterns
from tests.perception.synthetic import gap_dataset

GRID = dict(depths=4, widths=3, samples=6, dims=10, contact_floor=1.0, noise=0.1)


def lose_pins(dataset, seed, lost):
    """The dataset with `lost` random pins of each tap unseen: both their columns (dx k, dy k + P) NaN."""
    rng = np.random.default_rng(seed)
    pins = dataset.dims // 2
    taps = dataset.taps.copy()
    for tap in taps:
        k = rng.choice(pins, lost, replace=False)
        tap[:, np.concatenate([k, k + pins])] = np.nan
    return Dataset(taps, dataset.location, dataset.identity, None, dataset.front_end, dim_names=dataset.dim_names)


def per_tap_centred(log_likelihood):
    """Log likelihoods less their mean over the classes of each tap (a constant shared by the classes cancels)."""
    flat = np.asarray(log_likelihood).reshape(len(log_likelihood), -1)
    return flat - flat.mean(axis=1, keepdims=True)


@pytest.fixture(scope="module")
def train():
    return gap_dataset(seed=1, taps_per_class=6, **GRID)


@pytest.fixture(scope="module")
def test():
    return lose_pins(gap_dataset(seed=2, taps_per_class=3, **GRID), seed=3, lost=2)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_histogram_marginal_equals_a_plain_loop_over_the_observed_values(train, seed):
    model = fit_model(train, n_locations=4, bins=12)
    rng = np.random.default_rng(seed)
    taps = gap_dataset(seed=10 + seed, taps_per_class=1, **GRID).taps.astype(np.float64)
    taps[rng.random(taps.shape) < 0.3] = np.nan            # any values, not only whole dimensions
    expected = np.zeros((len(taps), model.n_classes))
    for n, tap in enumerate(taps):
        for j in range(model.samples):
            for k in range(model.dims):
                if np.isnan(tap[j, k]):
                    continue                                 # marginalised: sum_b P_k(b | c) = 1, log 1 = 0
                b = int(np.clip(np.floor((tap[j, k] - model.bin_lower[k]) / model.bin_width[k]), 0, model.bins - 1))
                expected[n] += model.log_probability[k, b]
    expected /= model.samples * model.dims                  # eq. 2's divisor: the model's fixed tempering
    batch = model.log_likelihood_batch(taps).reshape(len(taps), -1)
    np.testing.assert_allclose(batch, expected, rtol=1e-5, atol=1e-6)
    for n, tap in enumerate(taps):
        np.testing.assert_allclose(model.log_likelihood(tap).ravel(), batch[n], rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("kind", ["histogram", "calibrated-histogram"])
def test_histogram_on_a_tap_missing_dims_equals_the_model_trained_without_them(train, kind):
    missing = np.array([1, 6, 7])
    kept = np.setdiff1d(np.arange(train.dims), missing)
    model = train_model(train, kind=kind, n_locations=4, bins=12)
    without = fit_model(Dataset(train.taps[:, :, kept], train.location, train.identity, None, "tactip"),
                        n_locations=4, bins=12)
    taps = gap_dataset(seed=5, taps_per_class=1, **GRID).taps.copy()
    taps[:, :, missing] = np.nan
    tempering = getattr(model, "tempering", 1.0)
    # The same sum over the observed values; only eq. 2's divisor (N_samples x dims) differs.
    np.testing.assert_allclose(model.log_likelihood_batch(taps) * train.dims / tempering,
                               without.log_likelihood_batch(taps[:, :, kept]) * len(kept), rtol=1e-5, atol=1e-5)


def test_gaussian_marginal_is_the_exact_gaussian_marginal_of_the_observed_values(train, test):
    model = train_model(train, kind="gaussian", n_locations=4)
    assert np.isfinite(model.residual_variance) and model.residual_variance > 0
    gaussian = LowRankGaussian.from_whitening(model.mean, model.transform, model.residual_variance)
    x = test.taps.reshape(len(test), -1).astype(np.float64)
    x[0, :3] = np.nan                                         # and a pattern of single values
    expected = np.empty((len(x), model.n_classes))
    for c in range(model.n_classes):
        # Class c: mean mu + Q lambda^1/2 m_c, the shared covariance; its marginal over the observed values.
        shifted = dataclasses.replace(gaussian, mean=model.mean + gaussian.basis @ (np.sqrt(gaussian.variances)
                                                                                       * model.class_means[c]))
        expected[:, c] = model.tempering * shifted.log_density(x)
    got = model.log_likelihood_batch(x.reshape(test.taps.shape))
    np.testing.assert_allclose(per_tap_centred(got), per_tap_centred(expected), atol=1e-7 * np.abs(expected).max())
    # One tap at a time (its own pattern group) equals the batch.
    for n in (0, 5, 17):
        np.testing.assert_allclose(model.log_likelihood(x[n].reshape(test.taps.shape[1:])).ravel(),
                                   got.reshape(len(x), -1)[n], rtol=1e-9, atol=1e-9)


def test_gaussian_of_a_complete_tap_is_the_whitened_distance_and_the_dense_gaussian(train):
    model = train_model(train, kind="gaussian", n_locations=4)
    taps = gap_dataset(seed=7, taps_per_class=1, **GRID).taps.astype(np.float64)
    z = (taps.reshape(len(taps), -1) - model.mean) @ model.transform
    formula = -0.5 * model.tempering * ((z[:, None] - model.class_means[None]) ** 2).sum(axis=2)
    np.testing.assert_allclose(model.log_likelihood_batch(taps).reshape(len(taps), -1), formula, rtol=1e-9, atol=1e-9)
    # The same model read as the full-space Gaussian the marginal uses: equal up to a constant per tap.
    gaussian = LowRankGaussian.from_whitening(model.mean, model.transform, model.residual_variance)
    dense = np.stack([model.tempering * dataclasses.replace(
        gaussian, mean=model.mean + gaussian.basis @ (np.sqrt(gaussian.variances) * m)).log_density(
        taps.reshape(len(taps), -1)) for m in model.class_means], axis=1)
    np.testing.assert_allclose(per_tap_centred(formula), per_tap_centred(dense), atol=1e-7 * np.abs(dense).max())


@pytest.mark.parametrize("seed", [0, 1])
def test_conditional_mean_equals_the_dense_gaussian_formula(seed):
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(60, 12)) @ rng.normal(size=(12, 12)) + rng.normal(size=12)
    gaussian = fit_low_rank_gaussian(x, 4)
    covariance = gaussian.residual_variance * np.eye(12) + \
        (gaussian.basis * (gaussian.variances - gaussian.residual_variance)) @ gaussian.basis.T
    rows = x[:5].copy()
    rows[rng.random(rows.shape) < 0.4] = np.nan
    filled = gaussian.conditional_mean(rows)
    for row, got in zip(rows, filled):
        m = np.isnan(row)
        # E[x_M | x_O] = mu_M + Sigma_MO Sigma_OO^-1 (x_O - mu_O)
        expected = gaussian.mean[m] + covariance[np.ix_(m, ~m)] @ np.linalg.solve(
            covariance[np.ix_(~m, ~m)], row[~m] - gaussian.mean[~m])
        np.testing.assert_allclose(got[m], expected, rtol=1e-8, atol=1e-8)
        np.testing.assert_array_equal(got[~m], row[~m])


def test_missing_patterns_group_every_row_once():
    missing = np.array([[0, 1], [0, 0], [0, 1], [1, 1], [0, 0]], bool)
    groups = {tuple(p.tolist()): r.tolist() for p, r in missing_patterns(missing)}
    assert groups == {(False, True): [0, 2], (False, False): [1, 4], (True, True): [3]}


def test_a_class_that_never_observed_a_dimension_takes_its_distribution_over_all_classes(train, test):
    taps = train.taps.copy()
    lonely = (train.location == 0) & (train.identity == 2)
    taps[lonely, :, 3] = np.nan
    lossy = Dataset(taps, train.location, train.identity, None, "tactip")
    with pytest.warns(UserWarning, match=r"1 class and dimension pair\(s\) have no observed value .*\(e\.g\. dim03 at "
                                         r"location .* identity 2 mm"):
        model = fit_model(lossy, n_locations=4, bins=12)
    c = int(model.tap_class(lossy)[np.flatnonzero(lonely)[0]])
    values = taps[:, :, 3][~np.isnan(taps[:, :, 3])]
    b = np.clip(np.floor((values - model.bin_lower[3]) / model.bin_width[3]), 0, model.bins - 1).astype(int)
    pooled = np.bincount(b, minlength=model.bins) + model.epsilon
    np.testing.assert_allclose(model.log_probability[3, :, c], np.log(pooled / pooled.sum()), rtol=1e-5)
    others = np.setdiff1d(np.arange(model.n_classes), [c])
    np.testing.assert_array_equal(model.log_probability[:, :, others],
                                  fit_model(train, n_locations=4, bins=12).log_probability[:, :, others])
    for kind in ("gaussian", "calibrated-histogram"):
        with pytest.warns(UserWarning):
            assert np.isfinite(train_model(lossy, kind=kind, n_locations=4).log_likelihood_batch(test.taps)).all()


@pytest.mark.parametrize("kind", ["histogram", "calibrated-histogram", "gaussian"])
def test_models_trained_and_run_on_taps_missing_pins(kind, train, test):
    lossy_train = lose_pins(train, seed=4, lost=1)
    model = train_model(lossy_train, kind=kind, n_locations=4, **({} if kind == "gaussian" else {"bins": 12}))
    log_likelihood = model.log_likelihood_batch(test.taps)
    assert np.isfinite(log_likelihood).all()
    env = VirtualEnvironment(model, test)
    result = monte_carlo(env, FixationPolicy(model.n_locations - 1), thresholds=[0.9], runs=300, seed=0)
    assert result.accuracy[0] > 1.5 / model.n_identities   # far above chance
    perceiver = Perceiver(model, FixationPolicy(model.n_locations - 1), decision_threshold=0.999)
    step = perceiver.observe(test.taps[0])
    assert np.isfinite(step.posterior).all()


def test_gaussian_file_keeps_the_residual_variance_and_an_old_file_scores_complete_taps_only(train, test, tmp_path):
    model = train_model(train, kind="gaussian", n_locations=4)
    save_model(tmp_path / "g.h5", model)
    again = load_model(tmp_path / "g.h5")
    assert again.residual_variance == model.residual_variance
    np.testing.assert_array_equal(again.log_likelihood_batch(test.taps), model.log_likelihood_batch(test.taps))
    with h5py.File(tmp_path / "g.h5", "r+") as f:
        del f.attrs["residual_variance"]                     # a file written before marginalisation
    old = load_model(tmp_path / "g.h5")
    complete = gap_dataset(seed=2, taps_per_class=1, **GRID).taps
    np.testing.assert_array_equal(old.log_likelihood_batch(complete), model.log_likelihood_batch(complete))
    with pytest.raises(ModelError, match="train it again"):
        old.log_likelihood_batch(test.taps)


def hand_made_torch_model(train, seed):
    """A TorchModel with random weights and the imputation Gaussian of the training taps (no torch needed)."""
    rng = np.random.default_rng(seed)
    x = train.taps.reshape(len(train), -1).astype(np.float64)
    mean, scale = x.mean(axis=0), x.std(axis=0)
    imputation = fit_low_rank_gaussian((x - mean) / scale, 8)
    grid = train_model(train, kind="histogram", n_locations=4, bins=4)
    hidden, values = 16, x.shape[1]
    return TorchModel(mean, scale, rng.normal(size=(values, hidden)).astype(np.float32),
                      rng.normal(size=hidden).astype(np.float32),
                      rng.normal(size=(hidden, grid.n_classes)).astype(np.float32),
                      rng.normal(size=grid.n_classes).astype(np.float32), 0.7, 5, grid.location_edges,
                      grid.identities, "tactip", train.samples, train.dim_names, {}, "mm", "mm", grid.taps_per_class,
                      imputation_basis=imputation.basis, imputation_variances=imputation.variances,
                      imputation_residual=imputation.residual_variance)


@pytest.mark.parametrize("seed", [0, 1])
def test_torch_scores_a_tap_missing_values_on_its_conditional_mean(train, test, seed, tmp_path):
    model = hand_made_torch_model(train, seed)
    standardised = (test.taps.reshape(len(test), -1) - model.mean) / model.scale
    gaussian = LowRankGaussian(np.zeros(standardised.shape[1]), model.imputation_basis, model.imputation_variances,
                               model.imputation_residual)
    imputed = gaussian.conditional_mean(standardised) * model.scale + model.mean   # back in sensor units
    np.testing.assert_allclose(model.log_likelihood_batch(test.taps),
                               model.log_likelihood_batch(imputed.reshape(test.taps.shape)), rtol=1e-6, atol=1e-6)
    save_model(tmp_path / "t.h5", model)
    # The same model to the last bits that matter (torch's summation order may differ with the arrays'
    # alignment after loading: 3e-14 seen).
    np.testing.assert_allclose(load_model(tmp_path / "t.h5").log_likelihood_batch(test.taps),
                               model.log_likelihood_batch(test.taps), rtol=1e-12, atol=1e-12)
    old = dataclasses.replace(model, imputation_basis=None, imputation_variances=None, imputation_residual=np.nan)
    save_model(tmp_path / "old.h5", old)
    with pytest.raises(ModelError, match="train it again"):
        load_model(tmp_path / "old.h5").log_likelihood_batch(test.taps)


def test_an_unseen_value_is_better_imputed_than_by_the_mean(train):
    # Neighbouring dimensions move together in a tap: the observed ones predict a missing one.
    model = hand_made_torch_model(train, 0)
    taps = gap_dataset(seed=9, taps_per_class=2, **GRID).taps.astype(np.float64)
    lossy = taps.copy()
    lossy[:, :, [2, 7]] = np.nan
    imputed = model.imputed(lossy).reshape(taps.shape) * model.scale.reshape(taps.shape[1:]) + \
        model.mean.reshape(taps.shape[1:])
    error = np.abs(imputed - taps)[:, :, [2, 7]].mean()
    baseline = np.abs(model.mean.reshape(taps.shape[1:]) - taps)[:, :, [2, 7]].mean()
    noise_floor = GRID["noise"] * np.sqrt(2 / np.pi)       # mean |noise|: what no imputation can predict
    assert error < 1.25 * noise_floor and error < 0.7 * baseline


def test_log_likelihoods_are_normalisable_with_missing_values(train, test):
    for kind in ("histogram", "gaussian"):
        model = train_model(train, kind=kind, n_locations=4)
        log_likelihood = model.log_likelihood_batch(test.taps)
        assert np.isfinite(logsumexp(log_likelihood, axis=(1, 2))).all()
