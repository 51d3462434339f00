"""The torch likelihood: numpy inference equals torch's, storage, calibration (torch is in the test extra)."""

import numpy as np
import pytest
import torch
from scipy.special import logsumexp

from perception import load_model, save_model, train_model
from tests.perception.synthetic import gap_dataset


GRID = dict(depths=3, widths=4, samples=6, dims=6, contact_floor=1.0, noise=0.1)


@pytest.fixture(scope="module")
def model():
    from perception.learned import fit_torch

    return fit_torch(gap_dataset(seed=1, taps_per_class=8, **GRID), n_locations=3, seed=0, max_epochs=40)


def test_train_model_makes_a_torch_model():
    # Its own knobs reach it (5 epochs: what is asserted does not need a trained network; 100 took 13 s).
    model = train_model(gap_dataset(seed=1, taps_per_class=2, **GRID), kind="torch", n_locations=3, max_epochs=5)
    assert model.KIND == "torch" and model.summary().endswith(f"tempering {model.tempering:.4g}")
    assert model.epochs <= 5 and "up to 5 epochs" in model.summary()


def test_numpy_scores_equal_the_torch_networks(model):
    # Each member rebuilt as a plain torch network: the model's numpy scores are their log softmax, averaged.
    taps = gap_dataset(seed=2, taps_per_class=2, **GRID).taps
    x = torch.as_tensor((taps.reshape(len(taps), -1) - model.mean) / model.scale, dtype=torch.float32)
    members = []
    for m in range(model.members):
        net = torch.nn.Sequential(torch.nn.Linear(model.mean.size, model.hidden_bias.shape[1]), torch.nn.ReLU(),
                                  torch.nn.Linear(model.hidden_bias.shape[1], model.n_classes))
        with torch.no_grad():
            net[0].weight.copy_(torch.as_tensor(model.hidden_weight[m].T))
            net[0].bias.copy_(torch.as_tensor(model.hidden_bias[m]))
            net[2].weight.copy_(torch.as_tensor(model.output_weight[m].T))
            net[2].bias.copy_(torch.as_tensor(model.output_bias[m]))
            members.append(torch.log_softmax(net(x), dim=1).numpy())
    expected = model.tempering * np.mean(members, axis=0)
    assert model.members == 5
    np.testing.assert_allclose(model.log_likelihood_batch(taps).reshape(len(taps), -1), expected, rtol=1e-4, atol=1e-4)


def test_the_network_tells_the_widths_apart_and_survives_a_round_trip(model, tmp_path):
    test = gap_dataset(seed=3, taps_per_class=10, **GRID)
    what = logsumexp(model.log_likelihood_batch(test.taps), axis=1)
    assert np.mean(what.argmax(axis=1) == model.identity_class(test.identity)) > 0.8
    save_model(tmp_path / "t.h5", model)
    loaded = load_model(tmp_path / "t.h5")
    assert loaded.KIND == "torch" and 1 <= loaded.epochs
    np.testing.assert_allclose(loaded.log_likelihood_batch(test.taps[:5]), model.log_likelihood_batch(test.taps[:5]))


@pytest.mark.parametrize("seed", [0, 1])
def test_a_network_trained_on_taps_missing_a_pin_tells_the_widths_apart_on_taps_missing_one(seed):
    from perception import Dataset
    from perception.learned import fit_torch

    grid = dict(GRID, dims=16)   # 8 pins: dx 0..7, dy 8..15

    def lose_a_pin(dataset, rng):
        taps = dataset.taps.copy()
        for tap in taps:
            k = rng.integers(8)
            tap[:, [k, k + 8]] = np.nan
        return Dataset(taps, dataset.location, dataset.identity, None, "tactip")

    rng = np.random.default_rng(seed)
    model = fit_torch(lose_a_pin(gap_dataset(seed=1, taps_per_class=8, **grid), rng), n_locations=3, seed=seed,
                      max_epochs=40)
    test = gap_dataset(seed=3, taps_per_class=10, **grid)
    accuracy = []
    for taps in (test.taps, lose_a_pin(test, rng).taps):
        what = logsumexp(model.log_likelihood_batch(taps), axis=1)
        accuracy.append(np.mean(what.argmax(axis=1) == model.identity_class(test.identity)))
    assert accuracy[0] > 0.8 and accuracy[0] - accuracy[1] < 0.05


def test_a_circular_label_of_one_location_is_decided_and_its_errors_wrap(tmp_path):
    # Slide directions every 45 deg (period 360) at one location, as `tactip dataset build --period 360` makes them.
    from dataclasses import replace

    from perception.learned import fit_torch

    def directions(dataset):
        return replace(dataset, location=np.zeros(len(dataset)), location_unit="none",
                       identity=(dataset.identity - 1) * 45.0, identity_unit="deg", identity_period=360.0)

    grid = dict(GRID, depths=1, widths=8, noise=0.02)
    model = fit_torch(directions(gap_dataset(seed=1, taps_per_class=12, **grid)), n_locations=1, seed=0)
    test = directions(gap_dataset(seed=3, taps_per_class=10, **grid))
    decided = model.identities[model.log_likelihood_batch(test.taps)[:, 0].argmax(axis=1)]
    assert model.identity_period == 360.0 and model.n_locations == 1
    # Measured 0.83-0.85 right (the Gaussian: 1.0; chance 0.125), a mean wrapped error of 7-8 deg (chance 90).
    assert np.mean(decided == test.identity) > 0.75
    assert model.identity_error(decided, test.identity).mean() < 15.0
    assert model.identity_error(np.array([315.0]), np.array([0.0]))[0] == 45.0   # across the wrap, not 315
    save_model(tmp_path / "d.h5", model)
    assert load_model(tmp_path / "d.h5").identity_period == 360.0


def test_training_uses_every_core_and_gives_the_callers_threads_back(monkeypatch):
    import os

    import perception._ensemble_training as training
    from perception.learned import fit_torch

    seen = []
    real = training.train_ensemble
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)      # no cap (the suite's xdist workers set one)
    monkeypatch.setattr(training, "MIN_SHARED_WORK", 0)       # this small network as if it were a large one
    monkeypatch.setattr(training, "train_ensemble",
                        lambda *a, **k: seen.append(torch.get_num_threads()) or real(*a, **k))
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        fit_torch(gap_dataset(seed=1, taps_per_class=4, **GRID), n_locations=3, max_epochs=3)
        # Early stopping with pooled and with own-class deviations (on every value and, maybe, on the leading
        # directions), then the final fit.
        assert len(seen) in (3, 5) and set(seen) == {os.cpu_count()} and torch.get_num_threads() == 1
    finally:
        torch.set_num_threads(before)


def test_omp_num_threads_caps_the_training_threads(monkeypatch):
    # Where processes of one job share the cores (the suite's pytest-xdist workers), OMP_NUM_THREADS caps them.
    import perception._ensemble_training as training

    monkeypatch.setattr(training.os, "cpu_count", lambda: 8)
    before = torch.get_num_threads()
    for value, expected in (("2", 2), ("16", 8), ("many", 8), (None, 8)):
        if value is None:
            monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
        else:
            monkeypatch.setenv("OMP_NUM_THREADS", value)
        with training.all_cores(torch, work=training.MIN_SHARED_WORK):
            assert torch.get_num_threads() == expected, value
        assert torch.get_num_threads() == before


@pytest.mark.parametrize("threads", [1, 2, 4])
def test_training_is_reproducible_whatever_the_cores(monkeypatch, threads):
    # Seeded initialisations and batch orders: the same taps and seed give the same weights, bit for bit,
    # trained on 1, 2 or 4 threads (the station's settings are chosen on these models, and a rerun must choose
    # the same). Measured on the small station too: 15 members, 3200 values, 1 / 2 / 4 threads, two processes.
    import perception._ensemble_training as training
    from perception.learned import fit_torch

    train = gap_dataset(seed=1, taps_per_class=4, **GRID)
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)      # no cap (the suite's xdist workers set one)
    monkeypatch.setattr(training, "MIN_SHARED_WORK", 0)
    monkeypatch.setattr(training.os, "cpu_count", lambda: 1)
    one = fit_torch(train, n_locations=3, max_epochs=5, seed=3)
    monkeypatch.setattr(training.os, "cpu_count", lambda: threads)
    again = fit_torch(train, n_locations=3, max_epochs=5, seed=3)
    for name in ("hidden_weight", "hidden_bias", "output_weight", "output_bias"):
        assert np.array_equal(getattr(one, name), getattr(again, name)), name
    assert one.tempering == again.tempering
    other = fit_torch(train, n_locations=3, max_epochs=5, seed=4)
    assert not np.array_equal(one.hidden_weight, other.hidden_weight)   # the seed is what sets them


def test_within_class_residuals_are_each_taps_unbiased_deviation_from_its_class_mean():
    from perception.learned import within_class_residuals

    rng = np.random.default_rng(0)
    tap_class = np.array([0, 0, 0, 1, 2, 2, 3, 3, 3, 3])   # class 1 has a single tap: no deviation to give
    x = rng.normal(size=(len(tap_class), 5)) + 10.0 * tap_class[:, None]
    expected = []
    for i, c in enumerate(tap_class):   # the plain loop
        members = x[tap_class == c]
        if len(members) > 1:
            expected.append((x[i] - members.mean(axis=0)) * np.sqrt(len(members) / (len(members) - 1)))
    residuals = within_class_residuals(x, tap_class)
    np.testing.assert_allclose(residuals, np.array(expected), atol=1e-12)
    # Scaled so that their mean square is the classes' unbiased variance, free of the class offsets (10 apart).
    assert abs(residuals.std() - 1.0) < 0.5 and np.abs(residuals).max() < 5.0


def test_training_draws_deviations_only_when_augmenting(monkeypatch):
    from perception import _ensemble_training
    from perception.learned import fit_torch

    given, own = [], []
    real = _ensemble_training.train_ensemble

    def spy(*a, residuals=None, residual_class=None, **k):
        given.append(residuals)
        own.append(residual_class)
        return real(*a, residuals=residuals, residual_class=residual_class, **k)

    monkeypatch.setattr(_ensemble_training, "train_ensemble", spy)
    data = gap_dataset(seed=1, taps_per_class=4, **GRID)
    fit_torch(data, n_locations=3, max_epochs=3, augment=False)
    assert set(map(id, given)) == {id(None)} and set(map(id, own)) == {id(None)} and len(given) in (2, 3)
    given.clear(), own.clear()
    fit_torch(data, n_locations=3, max_epochs=3)
    # Early stopping with pooled deviations and with each tap's own class's (on every value and, maybe, the
    # leading directions), each on the deviations of the taps it trains on (fewer than all); the final fit: every
    # tap's.
    assert len(given) in (3, 5) and all(0 < len(g) < len(given[-1]) == len(data) for g in given[:-1])
    assert [o is None for o in own[:-1]] == [True, False] * (len(given) // 2)
    assert all(len(o) == len(g) for o, g in zip(own, given) if o is not None)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_network_learns_classes_told_apart_only_jointly(seed):
    # Xor: every pin moves along x = y in one class and x = -y in the other, so that both classes have the same
    # per-value distribution and mean; deviations pooled over the classes would turn one class into the other
    # (the held-out loss must choose each class's own), and kNN decides 98-99.5 % of such taps right.
    from perception import Dataset
    from perception.learned import fit_torch

    def xor(seed, per_class):
        rng = np.random.default_rng(seed)
        label = np.repeat([0.0, 1.0], per_class)
        x = rng.standard_normal((2 * per_class, 1, 6)) * np.ones((1, 4, 1))
        taps = np.stack([x, np.where(label[:, None, None] == 0, x, -x)], axis=-1).reshape(2 * per_class, 4, -1)
        return Dataset(taps + 0.1 * rng.standard_normal(taps.shape), np.zeros(len(label)), label, None, "tactip",
                       "none", "none", identity_names=("same", "mirror"))

    model = fit_torch(xor(seed, 40), n_locations=1, seed=seed)
    test = xor(seed + 100, 100)
    decided = model.log_likelihood_batch(test.taps)[:, 0].argmax(axis=1)
    assert np.mean(decided == model.identity_class(test.identity)) >= 0.99   # 0.96-0.97 with pooled deviations


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_imputation_rank_follows_the_structure_of_the_taps(seed):
    # Values that move together along 3 directions are imputed from the others (the rank keeps them: error near
    # the noise); values of plain noise are not predictable, and a rank fitted to their noise would do worse than
    # their mean: few directions are kept.
    from perception.learned import _fit_imputation

    rng = np.random.default_rng(seed)
    n, samples, dims = 150, 6, 24
    shared = rng.standard_normal((n, 3)) @ rng.standard_normal((3, samples * dims)) + 0.1 * rng.standard_normal(
        (n, samples * dims))
    noise = rng.standard_normal((n, samples * dims))
    held = np.arange(n) % 2 == 0
    structured = _fit_imputation(shared, ~held, held, samples)
    assert 3 <= len(structured.variances) <= 8
    assert len(_fit_imputation(noise, ~held, held, samples).variances) <= 2
    x = shared.copy()
    x[:10, :samples] = np.nan
    guess = structured.conditional_mean(x)[:10, :samples]
    assert np.sqrt(np.mean((guess - shared[:10, :samples]) ** 2)) < 0.3


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_depths_along_one_code_among_many_noisy_values_are_decided(seed):
    # Six depths whose mean taps lie along one code of 144 values, each with noise of 1: networks on every value
    # followed the noise (accuracy about 0.5); on the leading directions (the held-out loss chooses) 0.9 or more.
    from perception.learned import fit_torch
    from tests.perception.labelled import labelled_taps

    options = dict(label="numeric", classes=6, separation=5.0, noise=1.0, unseen=0.1, structure_seed=seed)
    model = fit_torch(labelled_taps(seed=seed, per_class=30, **options), n_locations=1, seed=seed)
    test = labelled_taps(seed=seed + 100, per_class=50, **options)
    decided = model.log_likelihood_batch(test.taps)[:, 0].argmax(axis=1)
    assert np.mean(decided == model.identity_class(test.identity)) >= 0.85


def test_given_its_input_and_deviations_a_network_trains_only_those(monkeypatch):
    # The choices made on held-out taps are the model's (`TorchModel.choices`); given back, early stopping runs
    # once, on them, not once per candidate (the station's fold models take the refit's: fit_with_fixation).
    from perception import _ensemble_training
    from perception.learned import DEVIATIONS, INPUTS, fit_torch

    calls = []
    real = _ensemble_training.train_ensemble

    def spy(torch, x, *a, **k):   # inputs trained on, and whether deviations come from each tap's own class
        calls.append((x.shape[1], k.get("residual_class") is not None))
        return real(torch, x, *a, **k)

    monkeypatch.setattr(_ensemble_training, "train_ensemble", spy)
    data = gap_dataset(seed=1, taps_per_class=4, **GRID)
    chosen = fit_torch(data, n_locations=3, max_epochs=3)
    assert chosen.choices["inputs"] in INPUTS and chosen.choices["deviations"] in DEVIATIONS
    assert len(calls) in (3, 5)
    values = data.taps[0].size
    for inputs in INPUTS:
        for deviations in DEVIATIONS:
            calls.clear()
            model = fit_torch(data, n_locations=3, max_epochs=3, inputs=inputs, deviations=deviations)
            assert model.choices == {"inputs": inputs, "deviations": deviations}
            assert len(calls) == 2 and calls[0] == calls[1]                  # early stopping, then the final fit
            assert (calls[0][0] == values) == (inputs == "values") and calls[0][1] == (deviations == "own class")
    # Given what it chose itself, the same model, bit for bit.
    again = fit_torch(data, n_locations=3, max_epochs=3, **chosen.choices)
    assert np.array_equal(again.hidden_weight, chosen.hidden_weight) and again.tempering == chosen.tempering
    assert fit_torch(data, n_locations=3, max_epochs=3, augment=False).choices["deviations"] is None
    with pytest.raises(ValueError, match="inputs must be one of 'values', 'directions'"):
        fit_torch(data, n_locations=3, inputs="pixels")


def test_the_stations_fold_models_take_the_refits_input_and_deviations(monkeypatch):
    # fit_with_fixation: the model kept (every tap) chooses its input and deviations on held-out taps; the fold
    # models the settings are chosen with are of its making (as the Gaussian's take its components and
    # shrinkage), each one early stopping and one final fit.
    import perception.learned as learned
    from calibration import fit_with_fixation
    from perception.model import _KINDS

    fits = []
    real = learned.fit_torch
    monkeypatch.setitem(_KINDS, "torch", (_KINDS["torch"][0], lambda *a, **k: fits.append(k) or real(*a, **k),
                                          _KINDS["torch"][2]))
    data = gap_dataset(seed=1, taps_per_class=4, **GRID)
    model = fit_with_fixation(data, kind="torch", n_locations=3, max_epochs=3, target_accuracy=0.8, tolerance=0.5,
                              runs=100, log=lambda line: None)
    assert len(fits) == 1 + 4 and "inputs" not in fits[0]
    assert all({k: f[k] for k in ("inputs", "deviations")} == model.choices for f in fits[1:])
