"""Circular and named identities: stored with datasets and models, and errors that wrap or count wrong."""

import numpy as np
import pytest

from perception import (Dataset, VirtualEnvironment, load_dataset, load_model, make_policy, monte_carlo, save_dataset,
                        save_model, train_model)
from perception.errors import DatasetError, ModelError


def _directions(rng, noise=0.3, per_class=20):
    angles = np.repeat(np.arange(0, 360, 45.0), per_class)
    taps = np.stack([np.cos(np.radians(angles)), np.sin(np.radians(angles))], -1)[:, None, :]
    return angles, taps + noise * rng.standard_normal(taps.shape)


def test_period_and_names_survive_dataset_and_model_files(tmp_path):
    angles, taps = _directions(np.random.default_rng(0))
    ds = Dataset(taps, np.zeros(len(angles)), angles, None, "tactip", "none", "deg", identity_period=360)
    save_dataset(tmp_path / "a.h5", ds)
    back = load_dataset(tmp_path / "a.h5")
    assert back.identity_period == 360.0 and back.identity_names == ()
    assert back.subset(np.arange(8)).identity_period == 360.0
    model = train_model(back, kind="gaussian", n_locations=1)
    save_model(tmp_path / "m.h5", model)
    assert load_model(tmp_path / "m.h5").identity_period == 360.0
    named = Dataset(taps[:40], np.zeros(40), np.repeat([0.0, 1.0], 20), None, "tactip", "none", "none",
                    identity_names=("cube", "ball"))
    save_dataset(tmp_path / "n.h5", named)
    model = train_model(load_dataset(tmp_path / "n.h5"), kind="histogram", n_locations=1, bins=10)
    save_model(tmp_path / "n_model.h5", model)
    back = load_model(tmp_path / "n_model.h5")
    assert back.identity_names == ("cube", "ball") and back.identity_label(1) == "ball"
    with pytest.raises(ModelError, match="identity_names"):   # a test set of other names is refused
        back.check_dataset(Dataset(taps[:40], np.zeros(40), np.repeat([0.0, 1.0], 20), None, "tactip", "none",
                                   "none", identity_names=("ball", "cube")))


def test_bad_labels_are_refused():
    taps = np.zeros((2, 1, 2))
    with pytest.raises(DatasetError, match="period"):
        Dataset(taps, np.zeros(2), np.zeros(2), None, "tactip", identity_period=-1)
    with pytest.raises(DatasetError, match="class indices"):
        Dataset(taps, np.zeros(2), np.array([0.0, 2.0]), None, "tactip", identity_names=("a", "b"))


def test_identity_error_wraps_across_zero():
    angles, taps = _directions(np.random.default_rng(1))
    model = train_model(Dataset(taps, np.zeros(len(angles)), angles, None, "tactip", "none", "deg",
                                identity_period=360), kind="gaussian", n_locations=1)
    assert model.identity_error([315.0, 0.0, 90.0], [0.0, 315.0, 270.0]).tolist() == [45.0, 45.0, 180.0]
    # Monte Carlo errors wrap: the directions beside 0 deg (315 and 45) cost it 45 deg each, as they do any other
    # direction; unwrapped, a 0 <-> 315 confusion would cost 315 and the classes at the ends would stand out.
    rng = np.random.default_rng(2)
    angles, taps = _directions(rng, noise=0.9)
    test = Dataset(taps, np.zeros(len(angles)), angles, None, "tactip", "none", "deg", identity_period=360)
    result = monte_carlo(VirtualEnvironment(model, test), make_policy("stationary", fixation_class=0),
                         thresholds=[0.0], runs=8000, seed=0)
    wrong = 1 - result.accuracy[0]
    assert wrong > 0.1
    per_direction = result.identity_error_map[0, 0]            # (8,) mean error by true direction
    assert per_direction[[0, 7]].max() < 1.5 * per_direction[1:7].mean()
    assert result.mean_identity_error[0] <= 90 * wrong       # mostly neighbours, 45 deg away
