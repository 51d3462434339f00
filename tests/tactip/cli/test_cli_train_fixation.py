"""`tactip train --choose-fixation`: settings chosen on a split of the training taps, never on the test taps."""

import numpy as np

from calibration import choose_fixation, cross_fitted_environment
from perception import load_model, save_dataset, train_model
from tactip.cli import main
from tests.perception.synthetic import gap_dataset

# Widths are legible only in the deeper half of the depth range (0..5 mm): the fixation must go there.
GRID = dict(depths=6, widths=3, samples=10, dims=8, legible_from=0.5)


def test_train_chooses_the_fixation_on_its_own_validation_split(tmp_path, capsys):
    train = gap_dataset(seed=1, taps_per_class=4, **GRID)
    save_dataset(tmp_path / "train.h5", train)
    assert main(["train", str(tmp_path / "train.h5"), "--out", str(tmp_path / "model.h5"), "--model", "gaussian",
                 "--locations", "6", "--choose-fixation", "--target-accuracy", "0.9"]) == 0
    out = capsys.readouterr().out
    assert "held out in 4 folds" in out
    model = load_model(tmp_path / "model.h5")
    assert model.recommended["fixation_location"] > 2.5 and model.recommended["policy"] == "active"
    # A model of every training tap, with the settings the out-of-fold scores of the held-out taps give: those of
    # fold models of its components and shrinkage, its beta the one fitted on their pooled scores.
    full = train_model(train, kind="gaussian", n_locations=6)
    fitted, environment = cross_fitted_environment(train, n_locations=6, kind="gaussian", pool_tempering=True,
                                                   components=full.n_components, shrinkages=full.shrinkage)
    chosen, _, _ = choose_fixation(fitted, None, environment=environment, target_accuracy=0.9, log=lambda _: None)
    assert model.recommended == chosen.recommended
    assert np.allclose(model.class_means, full.class_means) and np.isclose(model.tempering, chosen.tempering)
    assert model.tap_tempering == chosen.tap_tempering and len(model.tap_tempering) == 5


def test_fixation_options_need_choose_fixation(tmp_path, capsys):
    save_dataset(tmp_path / "train.h5", gap_dataset(seed=1, taps_per_class=2, **GRID))
    assert main(["train", str(tmp_path / "train.h5"), "--out", str(tmp_path / "m.h5"), "--target-accuracy",
                 "0.9"]) != 0
    assert "go with --choose-fixation" in capsys.readouterr().err
    assert not (tmp_path / "m.h5").exists()
