"""Training the station model and choosing its fixation depth, on datasets of known structure."""

import numpy as np
import pytest

from calibration import recommend_fixation, train_station_model
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
