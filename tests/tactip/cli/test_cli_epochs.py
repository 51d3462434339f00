"""`tactip train --epochs N`: the torch model's networks train at most N epochs; without it, the default model."""

import inspect

import pytest

from perception import save_dataset
from tactip.cli import main
from tactip.cli.train import DEFAULT_EPOCHS
from tests.perception.synthetic import gap_dataset

GRID = dict(depths=4, widths=4, samples=6, dims=8, legible_from=0.3)


def test_the_default_is_the_torch_models_own():
    from perception.learned import fit_torch

    assert inspect.signature(fit_torch).parameters["max_epochs"].default == DEFAULT_EPOCHS


def test_epochs_go_to_the_torch_fit_and_only_there(tmp_path, capsys, monkeypatch):
    import perception.learned
    import perception.model

    save_dataset(tmp_path / "train.h5", gap_dataset(seed=1, taps_per_class=4, **GRID))
    asked = []

    def fit(dataset, **options):                 # records what it was asked; the histogram model stands in
        asked.append(options)
        model = perception.model.train_model(dataset, n_locations=options["n_locations"])
        object.__setattr__(model, "choices", {"inputs": "values", "deviations": "pooled"})   # as a torch fit's
        return model

    monkeypatch.setattr(perception.model, "_KINDS", {**perception.model._KINDS,
                                                     "torch": (perception.learned.TorchModel, fit,
                                                               perception.model._KINDS["torch"][2])})
    train = ["train", str(tmp_path / "train.h5"), "--locations", "4", "--model", "torch"]
    assert main([*train, "--out", str(tmp_path / "a.h5"), "--epochs", "7"]) == 0    # through train_model
    assert asked == [dict(n_locations=4, min_taps_per_class=1, seed=0, max_epochs=7)]
    assert main([*train, "--out", str(tmp_path / "b.h5")]) == 0       # no --epochs: the torch model's default
    assert asked[1] == dict(n_locations=4, min_taps_per_class=1, seed=0)
    capsys.readouterr()
    assert main(["train", str(tmp_path / "train.h5"), "--out", str(tmp_path / "c.h5"), "--epochs", "7"]) == 1
    assert "--epochs sets how long the torch model's networks train; a histogram model has none" in \
        capsys.readouterr().err
    # --choose-fixation: every fit (the folds' and the refit) trains at most N epochs
    assert main([*train, "--out", str(tmp_path / "d.h5"), "--epochs", "7", "--choose-fixation"]) == 0
    assert len(asked) == 2 + 5 and all(a["max_epochs"] == 7 for a in asked[2:])
    assert all(a["inputs"] == "values" and a["deviations"] == "pooled" for a in asked[3:])   # the refit's choices
    with pytest.raises(SystemExit):
        main([*train, "--out", str(tmp_path / "e.h5"), "--epochs", "0"])
    assert "--epochs" in capsys.readouterr().err
