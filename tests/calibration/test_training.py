"""Training the station model and choosing its fixation depth, on datasets of known structure."""

import numpy as np
import pytest

from calibration import carve_validation, recommend_fixation, train_station_model
from perception import DEFAULT_THRESHOLDS, fit_model, load_model, save_dataset
from tests.perception.synthetic import gap_dataset

# Widths are legible only in the deeper half of the depth range (0..5 mm): the fixation must go there.
GRID = dict(depths=6, widths=3, samples=10, dims=8, legible_from=0.5)


@pytest.fixture
def files(tmp_path):
    train = gap_dataset(seed=1, taps_per_class=4, **GRID)
    save_dataset(tmp_path / "train.h5", train)
    save_dataset(tmp_path / "test.h5", gap_dataset(seed=2, taps_per_class=10, **GRID))
    return tmp_path, train


def test_training_writes_the_model_fit_model_makes(files):
    root, train = files
    lines = []
    model = train_station_model(root / "train.h5", root / "model.h5", n_locations=3, bins=20, log=lines.append)
    loaded = load_model(root / "model.h5")
    expected = fit_model(train, n_locations=3, bins=20)
    assert (loaded.n_locations, loaded.n_identities, loaded.bins) == (3, 3, 20)
    assert np.array_equal(loaded.identities, [1.0, 2.0, 3.0])
    assert np.allclose(loaded.log_likelihood_batch(train.taps), expected.log_likelihood_batch(train.taps))
    assert np.allclose(model.log_likelihood_batch(train.taps), expected.log_likelihood_batch(train.taps))
    assert lines == [model.summary()]


def test_the_fixation_goes_where_the_width_is_legible(files):
    root, _ = files
    train_station_model(root / "train.h5", root / "model.h5", n_locations=6, log=lambda _: None)
    lines = []
    model, sweep = recommend_fixation(root / "model.h5", root / "test.h5", runs=300, log=lines.append)
    fixation = model.recommended["fixation_location"]
    assert fixation > 2.5                                  # the deeper half, where widths differ
    assert sweep.errors[sweep.best] == sweep.errors.min() < sweep.errors[0]
    assert fixation == sweep.best_fixation and model.recommended["decision_threshold"] == sweep.best_threshold
    assert sweep.best_threshold in DEFAULT_THRESHOLDS and model.recommended["policy"] == "active"
    assert load_model(root / "model.h5").recommended == model.recommended    # written into the file
    assert f"fixation depth {fixation:g} mm" in lines[0]


def test_a_repeated_recommendation_is_the_same(files):
    root, _ = files
    train_station_model(root / "train.h5", root / "model.h5", n_locations=6, log=lambda _: None)
    first, _ = recommend_fixation(root / "model.h5", root / "test.h5", runs=200, seed=5, log=lambda _: None)
    again, _ = recommend_fixation(root / "model.h5", root / "test.h5", runs=200, seed=5, log=lambda _: None)
    assert first.recommended == again.recommended


def test_the_validation_split_is_carved_within_every_width(files):
    _, train = files                                      # 6 depths x 3 widths x 4 taps, depths spread out
    fit, validation = carve_validation(train)
    assert len(np.intersect1d(fit, validation)) == 0 and len(fit) + len(validation) == len(train)
    assert abs(len(fit) - len(validation)) <= 3
    for width in np.unique(train.identity):
        for part in (fit, validation):
            depths = train.location[part][train.identity[part] == width]
            assert len(depths) and depths.min() < 1.0 and depths.max() > 4.0   # both parts span the range
    assert all(np.array_equal(a, b) for a, b in zip((fit, validation), carve_validation(train)))  # deterministic


def test_the_station_model_is_chosen_without_the_test_collection(files):
    """prepare_station_model reads no test taps: its settings are the validation split's, its model the
    whole training collection's; the test collection only reports (a test with other taps reports other
    figures of the same model)."""
    from calibration import final_figures, prepare_station_model
    from perception import load_dataset, train_model

    root, train = files
    lines = []
    model = prepare_station_model(root / "train.h5", root / "model.h5", kind="gaussian", n_locations=6,
                                  target_accuracy=0.9, tolerance=0.0, runs=300, log=lines.append)
    assert "validation split of the training taps" in lines[0]
    assert model.recommended["fixation_location"] > 2.5 and model.recommended["policy"] == "active"
    full = train_model(train, kind="gaussian", n_locations=6)        # fitted on every training tap ...
    assert np.allclose(model.class_means, full.class_means)
    assert model.tempering != full.tempering                        # ... tempered as chosen on the split
    assert load_model(root / "model.h5").recommended == model.recommended
    test = load_dataset(root / "test.h5")
    fair = final_figures(model, test, runs=500)
    shuffled = test.subset(np.arange(len(test)))
    shuffled = type(test)(shuffled.taps, shuffled.location, np.random.default_rng(0).permutation(test.identity),
                          None, test.front_end, test.location_unit, test.identity_unit, test.dim_names, test.sensor)
    unfair = final_figures(model, shuffled, runs=500)
    assert fair.accuracy > 0.8 > 0.5 > unfair.accuracy
    assert fair.threshold == model.recommended["decision_threshold"] and fair.runs == 500
