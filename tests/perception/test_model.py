"""Histogram likelihood model: against a plain loop, class grid, errors, save/load."""

import h5py
import numpy as np
import pytest

from perception import Dataset, DatasetError, ModelError, fit_model, load_model, save_model
from tests.perception.synthetic import gap_dataset


def reference_log_likelihood(dataset, tap, *, n_locations, bins, epsilon):
    """Paper 002 eqs. 2-3 written out with loops: histogram per class and dimension, mean log."""
    dims = dataset.dims
    lo_loc, hi_loc = dataset.location.min(), dataset.location.max()
    width_loc = (hi_loc - lo_loc) / n_locations
    identities = sorted(set(dataset.identity.tolist()))
    out = np.zeros((n_locations, len(identities)))
    for l in range(n_locations):
        for i, w in enumerate(identities):
            total = 0.0
            for k in range(dims):
                lo, hi = dataset.taps[:, :, k].min(), dataset.taps[:, :, k].max()
                width = (hi - lo) / bins
                counts = np.zeros(bins)
                for n in range(len(dataset)):
                    cls = min(int((dataset.location[n] - lo_loc) / width_loc), n_locations - 1)
                    if cls == l and dataset.identity[n] == w:
                        for s in dataset.taps[n, :, k]:
                            counts[min(int((s - lo) / width), bins - 1)] += 1
                p = (counts + epsilon) / (counts + epsilon).sum()
                for s in tap[:, k]:
                    b = min(max(int(np.floor((s - lo) / width)), 0), bins - 1)
                    total += np.log(p[b])
            out[l, i] = total / (tap.shape[0] * dims)
    return out


@pytest.fixture(scope="module")
def small():
    return gap_dataset(depths=4, widths=3, taps_per_class=3, samples=6, dims=4, seed=1)


def test_likelihood_equals_the_plain_loop(small):
    model = fit_model(small, n_locations=4, bins=7, epsilon=0.01)
    test = gap_dataset(depths=4, widths=3, taps_per_class=1, samples=6, dims=4, seed=2, noise=0.3)
    for tap in test.taps[:5]:
        expected = reference_log_likelihood(small, tap, n_locations=4, bins=7, epsilon=0.01)
        np.testing.assert_allclose(model.log_likelihood(tap), expected, rtol=1e-5)


def test_batch_likelihood_equals_one_at_a_time(small):
    model = fit_model(small, n_locations=2, bins=10)
    test = gap_dataset(depths=4, widths=3, taps_per_class=30, samples=6, dims=4, seed=3, noise=0.5)
    batch = model.log_likelihood_batch(test.taps)  # > one chunk of 256 taps
    assert batch.shape == (len(test), 2, 3)
    one = np.array([model.log_likelihood(tap) for tap in test.taps])
    np.testing.assert_allclose(batch, one, rtol=1e-5)


def test_histograms_are_normalised_and_regularised(small):
    model = fit_model(small, n_locations=4, bins=20, epsilon=1e-3)
    p = np.exp(model.log_probability.astype(np.float64))
    np.testing.assert_allclose(p.sum(axis=1), 1.0, rtol=1e-5)
    # An empty bin holds eps / (samples per class + bins * eps); 3 taps x 6 samples per class.
    assert p.min() == pytest.approx(1e-3 / (18 + 20 * 1e-3), rel=1e-5)
    assert model.taps_per_class.tolist() == [[3, 3, 3]] * 4


def test_map_class_of_clean_taps_is_their_class():
    train = gap_dataset(depths=5, widths=4, taps_per_class=5, samples=10, dims=6, seed=1, noise=0.01,
                        contact_floor=1.0)
    test = gap_dataset(depths=5, widths=4, taps_per_class=2, samples=10, dims=6, seed=2, noise=0.01,
                       contact_floor=1.0)
    model = fit_model(train, n_locations=5)
    best = model.log_likelihood_batch(test.taps).reshape(len(test), -1).argmax(axis=1)
    truth = model.location_class(test.location) * 4 + model.identity_class(test.identity)
    np.testing.assert_array_equal(best, truth)


def test_location_classes_split_the_range_equally():
    # Paper 002: 110 taps over 5.45 mm at 0.05 mm steps, 11 classes of 10 taps.
    location = np.arange(110) * 0.05
    ds = Dataset(np.random.default_rng(0).normal(size=(110, 3, 2)), location, np.full(110, 0.5), None, "tactip")
    model = fit_model(ds, n_locations=11)
    assert model.taps_per_class.ravel().tolist() == [10] * 11
    np.testing.assert_allclose(model.location_edges, np.linspace(0, 5.45, 12))
    assert model.class_width == pytest.approx(5.45 / 11)
    np.testing.assert_array_equal(model.location_class([-1.0, 0.0, 0.5, 5.45, 9.0]), [0, 0, 1, 10, 10])


def test_fixation_class_given_recommended_or_middle(small):
    model = fit_model(small, n_locations=4)  # classes of 0.75 mm over 0-3 mm
    assert model.fixation_class() == 2
    assert model.fixation_class(0.8) == 1
    assert model.with_recommended(fixation_location=2.9).fixation_class() == 3
    assert model.with_recommended(fixation_location=2.9).fixation_class(0.1) == 0


def test_single_location_dataset_is_pure_identity_classification():
    ds = Dataset(np.random.default_rng(0).normal(size=(6, 3, 2)), np.full(6, 2.0), [1, 2, 3, 1, 2, 3], None, "taxel")
    model = fit_model(ds, n_locations=11)
    assert (model.n_locations, model.n_identities, model.class_width) == (1, 3, 0.0)
    assert model.log_likelihood(ds.taps[0]).shape == (1, 3)


def test_values_outside_the_training_range_go_to_edge_bins(small):
    model = fit_model(small, n_locations=2)
    tap = np.full((6, 4), 1e6)
    assert (model.bin_index(tap) == model.bins - 1).all()
    assert np.isfinite(model.log_likelihood(tap)).all()


def test_too_few_taps_per_class_names_the_class():
    ds = gap_dataset(depths=4, widths=2, taps_per_class=2, samples=3, dims=2)
    with pytest.raises(DatasetError, match="fewer than 3 training taps.*location .* identity"):
        fit_model(ds, n_locations=4, min_taps_per_class=3)
    with pytest.raises(DatasetError, match="classes have fewer than 1"):
        fit_model(ds.subset(ds.location != 1.0), n_locations=4)


@pytest.mark.parametrize("knob, value", [("n_locations", 0), ("bins", 1), ("epsilon", 0.0),
                                         ("min_taps_per_class", 0)])
def test_bad_knobs_name_the_parameter(small, knob, value):
    with pytest.raises(ValueError, match=knob):
        fit_model(small, **{knob: value})


def test_wrong_tap_shape_and_front_end_are_clear(small):
    model = fit_model(small, n_locations=2)
    with pytest.raises(ModelError, match=r"model trained for tactip taps of 6 samples x 4 dims.*got shape \(6, 80\)"):
        model.log_likelihood(np.zeros((6, 80)))
    with pytest.raises(ModelError, match=r"expected \(N, samples, dims\)"):
        model.log_likelihood_batch(np.zeros((6, 4)))
    taxel = Dataset(np.zeros((2, 6, 12)), [0, 1], [0, 0], None, "taxel")
    with pytest.raises(ModelError, match=r"model trained for tactip \(4 dims, 6 samples\), got taxel taps \(12 dims"):
        model.check_dataset(taxel)


def test_unknown_identity_is_refused(small):
    model = fit_model(small, n_locations=2)
    with pytest.raises(DatasetError, match=r"identity \[2.5\] mm is not one of"):
        model.identity_class([1.0, 2.5])


def test_save_load_round_trip_with_recommended(tmp_path, small):
    model = fit_model(small, n_locations=3, bins=12).with_recommended(decision_threshold=0.99, fixation_location=2.5,
                                                                     policy="active")
    save_model(tmp_path / "m.h5", model)
    back = load_model(tmp_path / "m.h5")
    np.testing.assert_array_equal(back.log_probability, model.log_probability)
    np.testing.assert_array_equal(back.location_edges, model.location_edges)
    assert back.recommended == {"decision_threshold": 0.99, "fixation_location": 2.5, "policy": "active"}
    assert (back.front_end, back.samples, back.dim_names, back.sensor) == ("tactip", 6, small.dim_names, small.sensor)
    np.testing.assert_array_equal(back.log_likelihood(small.taps[0]), model.log_likelihood(small.taps[0]))
    assert [p.name for p in tmp_path.iterdir()] == ["m.h5"]


def test_load_refuses_other_files(tmp_path, small):
    from perception import save_dataset

    save_dataset(tmp_path / "d.h5", small)
    with pytest.raises(ModelError, match="not a tactip-model/1 file .*tactip-dataset/1"):
        load_model(tmp_path / "d.h5")
    save_model(tmp_path / "m.h5", fit_model(small, n_locations=2))
    with h5py.File(tmp_path / "m.h5", "r+") as f:
        del f["identities"]
    with pytest.raises(ModelError, match="misses identities"):
        load_model(tmp_path / "m.h5")
    with pytest.raises(ModelError, match="unknown recommended"):
        fit_model(small, n_locations=2).with_recommended(speed=3)


# -- issue 9: a model's settings and numbers are checked like a station file -------------------------

@pytest.mark.parametrize("settings, word", [
    ({"decision_threshold": 0.0}, "decision_threshold"), ({"decision_threshold": float("nan")}, "decision_threshold"),
    ({"decision_threshold": 1.01}, "decision_threshold"), ({"fixation_location": 1e3}, "fixation_location"),
    ({"fixation_location": float("inf")}, "fixation_location"), ({"policy": "guess"}, "policy"),
])
def test_bad_recommended_settings_are_refused_naming_them(small, tmp_path, settings, word):
    model = fit_model(small, n_locations=4)
    with pytest.raises(ModelError, match=word):
        model.with_recommended(**settings)
    save_model(tmp_path / "m.h5", model)
    with h5py.File(tmp_path / "m.h5", "r+") as f:
        f.attrs["recommended"] = __import__("json").dumps(settings)
    with pytest.raises(ModelError, match=f"m.h5: recommended {word}"):
        load_model(tmp_path / "m.h5")


def test_non_finite_epsilon_and_likelihoods_are_refused(small, tmp_path):
    for epsilon in (float("inf"), 1e308, 0.0):
        with pytest.raises(ValueError, match="epsilon must be a number in"):
            fit_model(small, epsilon=epsilon)
    save_model(tmp_path / "m.h5", fit_model(small, n_locations=4))
    with h5py.File(tmp_path / "m.h5", "r+") as f:
        f["log_probability"][0, 0, :] = np.nan
    with pytest.raises(ModelError, match="NaN or infinite likelihoods"):
        load_model(tmp_path / "m.h5")
