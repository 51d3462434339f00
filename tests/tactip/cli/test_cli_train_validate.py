"""`tactip train` and `tactip validate` end to end on small synthetic datasets."""

import json

import numpy as np
import pytest

from perception import Dataset, load_model, save_dataset
from tactip.cli import main
from tests.perception.synthetic import gap_dataset

GRID = dict(depths=6, widths=4, samples=10, dims=8, legible_from=0.5)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    root = tmp_path_factory.mktemp("cli")
    save_dataset(root / "train.h5", gap_dataset(seed=1, taps_per_class=4, **GRID))
    save_dataset(root / "test.h5", gap_dataset(seed=2, taps_per_class=20, **GRID))
    assert main(["train", str(root / "train.h5"), "--out", str(root / "model.h5"), "--locations", "6"]) == 0
    return root


def test_train_prints_the_class_grid_and_writes_a_model(files, capsys):
    assert main(["train", str(files / "train.h5"), "--out", str(files / "m2.h5"), "--locations", "3",
                 "--bins", "50"]) == 0
    out = capsys.readouterr().out
    assert "96 taps of 10 samples x 8 dims" in out
    assert "12 classes = 3 locations (0..5 mm) x 4 identities (1..4 mm)" in out and "50 bins" in out
    assert "training taps per class: 8..8" in out
    model = load_model(files / "m2.h5")
    assert (model.n_locations, model.n_identities, model.bins) == (3, 4, 50)


def test_validate_all_policies_writes_json_and_plot(files, capsys):
    out_json, out_png = files / "curves.json", files / "curves.png"
    code = main(["validate", str(files / "model.h5"), str(files / "test.h5"), "--runs", "1500", "--thresholds",
                 "0.5,0.9", "0.99", "--fixation", "5", "--json", str(out_json), "--plot", str(out_png), "--quiet"])
    assert code == 0
    out = capsys.readouterr().out
    assert "active fixation: 4.58333 mm" in out
    rows = json.loads(out_json.read_text())
    assert [(r["policy"], r["threshold"]) for r in rows] == [
        (p, t) for p in ("active", "random", "stationary") for t in (0.5, 0.9, 0.99)]
    error = {(r["policy"], r["threshold"]): r["mean_identity_error"] for r in rows}
    assert error["active", 0.99] < error["random", 0.99] < error["stationary", 0.99]
    assert all(0 <= r["accuracy"] <= 1 and r["mean_taps"] >= 1 for r in rows)
    assert out_png.read_bytes().startswith(b"\x89PNG")


def test_validate_one_policy_is_reproducible(files, capsys):
    args = ["validate", str(files / "model.h5"), str(files / "test.h5"), "--policy", "random", "--runs", "300",
            "--thresholds", "0.9", "--seed", "4", "--quiet"]
    assert main(args) == 0
    first = capsys.readouterr().out
    assert main(args) == 0
    assert capsys.readouterr().out == first
    assert "stationary" not in first and "random" in first


def test_sweep_fixation_writes_recommended_settings(files, capsys, tmp_path):
    model_path = tmp_path / "model.h5"
    model_path.write_bytes((files / "model.h5").read_bytes())
    assert main(["validate", str(model_path), str(files / "test.h5"), "--sweep-fixation", "--runs", "600",
                 "--thresholds", "0.5,0.9,0.99", "--plot", str(tmp_path / "fix.png"), "--json",
                 str(tmp_path / "fix.json"), "--quiet"]) == 0
    out = capsys.readouterr().out
    recommended = load_model(model_path).recommended
    assert recommended["policy"] == "active" and recommended["fixation_location"] >= 4.0
    assert recommended["decision_threshold"] in (0.5, 0.9, 0.99)
    assert f"best fixation {recommended['fixation_location']:g} mm" in out
    rows = json.loads((tmp_path / "fix.json").read_text())
    assert len(rows) == 6 * 3 and {r["policy"] for r in rows} == {"active"}
    assert all(r["mean_label_error"] == r["mean_identity_error"] and r["label_error_unit"] == "mm" for r in rows)
    # The next validation uses the recommended fixation by default.
    assert main(["validate", str(model_path), str(files / "test.h5"), "--policy", "active", "--runs", "50",
                 "--thresholds", "0.9", "--quiet"]) == 0
    assert f"active fixation: {recommended['fixation_location']:g} mm" in capsys.readouterr().out


def test_validate_refuses_a_test_set_of_another_front_end(files, capsys, tmp_path):
    taxel = Dataset(np.zeros((24, 50, 12)), np.repeat(np.arange(6.0), 4), np.tile(np.arange(1.0, 5.0), 6), None,
                    "taxel")
    save_dataset(tmp_path / "taxel.h5", taxel)
    assert main(["validate", str(files / "model.h5"), str(tmp_path / "taxel.h5"), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert err.strip() == ("tactip validate: error: model trained for tactip (8 dims, 10 samples), "
                           "got taxel taps (12 dims, 50 samples)")


def test_user_errors_are_one_line(files, capsys, tmp_path):
    assert main(["train", str(tmp_path / "missing.h5"), "--out", str(tmp_path / "m.h5")]) == 1
    assert "tactip train: error: no such dataset file" in capsys.readouterr().err
    assert main(["validate", str(files / "test.h5"), str(files / "test.h5")]) == 1
    assert "is not a tactip-model/1 file" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["validate", str(files / "model.h5"), str(files / "test.h5"), "--thresholds", "1.5"])
    assert "thresholds must be in [0, 1]" in capsys.readouterr().err
    assert main(["train", str(files / "train.h5"), "--out", str(tmp_path / "g.h5"), "--model", "gaussian",
                 "--bins", "50"]) == 1
    assert "a gaussian model has none (leave --bins out)" in capsys.readouterr().err
    assert not (tmp_path / "g.h5").exists()


def test_sweep_lateral_shows_errors_growing_with_placement_noise(files, capsys, tmp_path):
    # Test taps placed laterally within [-2, 2] mm; the further off, the more their features are corrupted.
    rng = np.random.default_rng(5)
    base = gap_dataset(seed=2, taps_per_class=40, **GRID)
    lateral = rng.uniform(-2.0, 2.0, len(base))
    taps = base.taps + (rng.standard_normal(base.taps.shape) * 3.0 * np.abs(lateral)[:, None, None]).astype(np.float32)
    save_dataset(tmp_path / "jitter.h5", Dataset(taps, base.location, base.identity, lateral, base.front_end))
    out_json = tmp_path / "lateral.json"
    assert main(["validate", str(files / "model.h5"), str(tmp_path / "jitter.h5"), "--sweep-lateral", "0.5", "1", "2",
                 "--runs", "400", "--quiet", "--json", str(out_json), "--plot", str(tmp_path / "lateral.png")]) == 0
    text = capsys.readouterr().out
    lines = text[text.index("sigma"):].splitlines()[1:4]
    errors = [float(line.split()[1]) for line in lines]
    ratios = [float(line.split()[2]) for line in lines]
    assert ratios[0] == 1.0 and errors[2] > errors[0]
    assert {row["sigma"] for row in json.loads(out_json.read_text())} == {0.5, 1.0, 2.0}
    assert (tmp_path / "lateral.png").stat().st_size > 1000


def test_sweep_lateral_needs_lateral_offsets(files, capsys):
    assert main(["validate", str(files / "model.h5"), str(files / "test.h5"), "--sweep-lateral", "1", "--quiet"]) == 1
    assert "no lateral offsets" in capsys.readouterr().err


def test_train_each_model_kind_and_validate_them_side_by_side(files, capsys):
    for kind in ("calibrated-histogram", "gaussian"):
        assert main(["train", str(files / "train.h5"), "--out", str(files / f"{kind}.h5"), "--locations", "6",
                     "--model", kind]) == 0
        assert kind.split("-")[0] in capsys.readouterr().out
        assert load_model(files / f"{kind}.h5").KIND == kind
    out_json, out_png = files / "models.json", files / "models.png"
    code = main(["validate", str(files / "gaussian.h5"), str(files / "test.h5"), "--compare", str(files / "model.h5"),
                 str(files / "calibrated-histogram.h5"), "--policy", "active", "--fixation", "5", "--runs", "800",
                 "--thresholds", "0.9", "--json", str(out_json), "--plot", str(out_png), "--quiet"])
    assert code == 0
    out = capsys.readouterr().out
    assert "expected calibration error" in out
    table = {line.split()[0]: [float(v) for v in line.split()[1:]] for line in out.splitlines()
             if line.split() and line.split()[0] in ("gaussian", "histogram", "calibrated-histogram")
             and len(line.split()) == 4}
    assert set(table) == {"gaussian", "histogram", "calibrated-histogram"}
    rows = json.loads(out_json.read_text())
    assert {r["model"] for r in rows} == set(table)
    for row in rows:  # the JSON holds the printed ECE after 1, 3 and 5 taps
        assert [round(row[f"ece_{t}_taps"], 3) for t in (1, 3, 5)] == table[row["model"]]
    assert sum(table["gaussian"]) < sum(table["histogram"]), table
    assert (files / "models_reliability.png").read_bytes().startswith(b"\x89PNG")


def test_sweep_fixation_for_a_target_accuracy_writes_the_threshold(files, capsys, tmp_path):
    import shutil

    model = tmp_path / "g.h5"
    assert main(["train", str(files / "train.h5"), "--out", str(model), "--locations", "6", "--model", "gaussian"]) == 0
    trained = load_model(model).tempering
    assert load_model(model).tap_tempering == ()
    code = main(["validate", str(model), str(files / "test.h5"), "--sweep-fixation", "--target-accuracy", "0.9",
                 "--tolerance", "1", "--runs", "500", "--quiet"])
    assert code == 0
    out = capsys.readouterr().out
    recommended = load_model(model).recommended
    # the tap tempering fitted for the beliefs after taps 1-5 is the one written (the one-tap tempering kept)
    printed = [float(g) for g in out.split("tap tempering g1..g5 ")[1].split(" for the beliefs")[0].split(", ")]
    written = load_model(model)
    assert written.tempering == trained and len(written.tap_tempering) == 5
    assert written.tap_tempering == pytest.approx(printed, rel=1e-2)  # printed to 3 figures
    assert f"best fixation {recommended['fixation_location']:g} mm (threshold {recommended['decision_threshold']:g}" \
        in out
    assert recommended["fixation_location"] > 2.5  # the width is legible deep only (legible_from=0.5)
    shutil.copy(model, tmp_path / "g2.h5")
    assert main(["validate", str(tmp_path / "g2.h5"), str(files / "test.h5"), "--sweep-fixation", "--target-accuracy",
                 "1", "--runs", "300", "--max-taps", "1", "--tap-budget", "1", "--quiet"]) == 1
    assert "is not reached at any fixation" in capsys.readouterr().err
    assert main(["validate", str(model), str(files / "test.h5"), "--target-accuracy", "0.9"]) == 1
    assert "--target-accuracy needs --sweep-fixation" in capsys.readouterr().err


def test_train_torch_without_torch_is_one_line(files, capsys, monkeypatch):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "torch" else real(name, *a))
    assert main(["train", str(files / "train.h5"), "--out", str(files / "t.h5"), "--model", "torch"]) == 1
    err = capsys.readouterr().err
    assert "pip install torch==2.13.0" in err and len(err.strip().splitlines()) == 1
    assert not (files / "t.h5").exists()
