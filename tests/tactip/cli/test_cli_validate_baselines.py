"""`tactip validate` on models of labelled recordings: the label's error, one location, and --baselines."""

import json

import numpy as np
import pytest

from perception import Dataset, save_dataset
from tactip.cli import main
from tests.perception.labelled import labelled_taps
from tests.perception.synthetic import gap_dataset


def _train(tmp_path, train, name="model.h5", kind="gaussian"):
    save_dataset(tmp_path / "train.h5", train)
    assert main(["train", str(tmp_path / "train.h5"), "--out", str(tmp_path / name), "--model", kind]) == 0
    return tmp_path / name


def test_label_error_wraps_across_zero_in_rows_and_baselines(tmp_path, capsys):
    # Every test tap of direction d is labelled d + 45: a perfect reader is 45 deg off on every tap, the
    # taps of 315 deg labelled 0 included (unwrapped they would cost 315 deg).
    kwargs = dict(label="circular", per_class=15, separation=12.0, noise=0.3)
    model = _train(tmp_path, labelled_taps(seed=1, **kwargs))
    test = labelled_taps(seed=2, **kwargs)
    shifted = Dataset(test.taps, test.location, (test.identity + 45) % 360, None, "tactip", "none", "deg",
                      identity_period=360)
    save_dataset(tmp_path / "test.h5", shifted)
    capsys.readouterr()
    assert main(["validate", str(model), str(tmp_path / "test.h5"), "--runs", "400", "--thresholds", "0", "0.99",
                 "--baselines", "--train", str(tmp_path / "train.h5"), "--json", str(tmp_path / "out.json"),
                 "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "errors wrap at 360 deg" in out and "error deg" in out
    assert "shown as stationary" in out and "loc error" not in out and "fixation" not in out
    rows = json.loads((tmp_path / "out.json").read_text())
    curve = [r for r in rows if r["policy"] is not None]
    assert [(r["policy"], r["threshold"]) for r in curve] == [("stationary", t) for t in (0.0, 0.9, 0.99)]
    for row in curve:
        assert (row["mean_label_error"], row["mean_identity_error"], row["accuracy"]) == (45.0, 45.0, 0.0)
        assert row["label_error_unit"] == "deg" and row["mean_taps"] >= 1
    baselines = {r["model"]: r for r in rows if r["model"].startswith("baseline-")}
    assert set(baselines) == {"baseline-knn", "baseline-logistic", "baseline-ridge"}
    assert baselines["baseline-knn"]["mean_label_error"] == baselines["baseline-logistic"]["mean_label_error"] == 45
    assert baselines["baseline-ridge"]["mean_label_error"] == pytest.approx(45, abs=3)
    assert all(b["threshold"] is None and b["mean_taps"] == 1 and b["accuracy"] == 0 for b in baselines.values())
    (verdict,) = [r for r in rows if r.get("check") == "baselines"]
    assert verdict["one_tap_error"] == 45.0 and verdict["held_policy"] == "stationary"


def _xor_pairs(seed, per_class=40, pins=6, samples=4):
    """Two named classes with the same means and per-dim spread: x = y on each pin, or x = -y."""
    rng = np.random.default_rng(seed)
    label = np.repeat([0.0, 1.0], per_class)
    x = rng.standard_normal((2 * per_class, 1, pins)) * np.ones((1, samples, 1))
    y = np.where(label[:, None, None] == 0, x, -x)
    taps = np.stack([x, y], axis=-1).reshape(2 * per_class, samples, 2 * pins)
    taps = taps + 0.1 * rng.standard_normal(taps.shape)
    return Dataset(taps, np.zeros(len(label)), label, None, "tactip", "none", "none", identity_names=("same", "mirror"))


@pytest.mark.parametrize("seed", [0, 1])
def test_the_report_says_when_a_model_is_worse_than_a_baseline(tmp_path, capsys, seed):
    # The class lives in the sign of x * y: every per-dimension histogram and the shared-covariance Gaussian see
    # the same distribution for both classes (chance, 0.5 wrong), while nearest neighbours read it at once.
    model = _train(tmp_path, _xor_pairs(seed), kind="histogram")
    save_dataset(tmp_path / "test.h5", _xor_pairs(seed + 10))
    capsys.readouterr()
    assert main(["validate", str(model), str(tmp_path / "test.h5"), "--runs", "400", "--baselines", "--train",
                 str(tmp_path / "train.h5"), "--json", str(tmp_path / "out.json"), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "label: 2 named classes; error = fraction of decisions wrong" in out
    assert "histogram: WORSE THAN BASELINE at 1 tap" in out and "histogram: NOT WELL BELOW BASELINE" in out
    assert "--split group keeps each recording on one side" in out         # the leak a user should rule out
    rows = json.loads((tmp_path / "out.json").read_text())
    (verdict,) = [r for r in rows if r.get("check") == "baselines"]
    assert verdict["worse_than_baseline"] and not verdict["well_below_baseline"]
    assert verdict["best_baseline"] == "baseline-knn" and verdict["best_baseline_error"] < 0.05
    assert verdict["one_tap_error"] > 0.3 and verdict["label_error_unit"] == "fraction wrong"
    curve = [r for r in rows if r["policy"] is not None]
    assert all(r["mean_label_error"] == pytest.approx(1 - r["accuracy"]) for r in curve)   # names: fraction wrong


@pytest.mark.parametrize("seed", [0, 1])
def test_the_report_is_quiet_when_the_model_earns_its_keep(tmp_path, capsys, seed):
    # Slide directions whose mean taps lie on a circle in a plane of the feature space, in noise on every
    # feature: the Gaussian model finds that plane (its principal components), the generic learners read all
    # features' noise.
    kwargs = dict(label="circular", per_class=30, separation=1.0, noise=1.0, unseen=0.1, structure_seed=seed)
    model = _train(tmp_path, labelled_taps(seed=seed, **kwargs))
    save_dataset(tmp_path / "test.h5", labelled_taps(seed=seed + 10, **kwargs))
    capsys.readouterr()
    assert main(["validate", str(model), str(tmp_path / "test.h5"), "--runs", "1000", "--baselines", "--train",
                 str(tmp_path / "train.h5"), "--thresholds", "0.5", "--json", str(tmp_path / "out.json"),
                 "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "WORSE" not in out and "NOT WELL BELOW" not in out, out
    assert "--split group" not in out
    assert "gaussian: at threshold 0.9 (stationary" in out and "well below it (bar 0.75x)" in out
    rows = json.loads((tmp_path / "out.json").read_text())
    assert sorted(r["threshold"] for r in rows if r["policy"]) == [0.5, 0.9]       # 0.9 added for the verdict
    (verdict,) = [r for r in rows if r.get("check") == "baselines"]
    assert not verdict["worse_than_baseline"] and verdict["well_below_baseline"]
    best = [r for r in rows if r["model"] == verdict["best_baseline"]][0]
    assert 0.6 < best["accuracy"] < 1.0                                              # a fair, not trivial, contest


def test_one_location_models_refuse_a_fixation_and_baselines_need_training_taps(tmp_path, capsys):
    model = _train(tmp_path, labelled_taps("numeric", seed=1, per_class=8))
    save_dataset(tmp_path / "test.h5", labelled_taps("numeric", seed=2, per_class=8))
    test, train = str(tmp_path / "test.h5"), str(tmp_path / "train.h5")
    capsys.readouterr()
    for extra, message in ((["--sweep-fixation"], "nothing to sweep, the model has one location class"),
                           (["--fixation", "0"], "no fixation to choose"),
                           (["--baselines"], "--baselines needs --train TRAIN.h5"),
                           (["--baselines", "--train", test], "is the test dataset"),
                           (["--train", train], "--train is only read by --baselines")):
        assert main(["validate", str(model), test, "--runs", "10", "--quiet", *extra]) == 1
        assert message in capsys.readouterr().err, extra


def test_baselines_beside_a_station_model_predict_its_identity(tmp_path, capsys):
    grid = dict(depths=6, widths=4, samples=10, dims=8, legible_from=0.5)
    save_dataset(tmp_path / "train.h5", gap_dataset(seed=1, taps_per_class=4, **grid))
    save_dataset(tmp_path / "test.h5", gap_dataset(seed=2, taps_per_class=10, **grid))
    assert main(["train", str(tmp_path / "train.h5"), "--out", str(tmp_path / "m.h5"), "--locations", "6"]) == 0
    capsys.readouterr()
    assert main(["validate", str(tmp_path / "m.h5"), str(tmp_path / "test.h5"), "--runs", "300", "--thresholds", "0.9",
                 "--baselines", "--train", str(tmp_path / "train.h5"), "--json", str(tmp_path / "out.json"),
                 "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "label: mm, errors do not wrap" in out and "loc error" in out and "active fixation" in out
    rows = json.loads((tmp_path / "out.json").read_text())
    assert {r["policy"] for r in rows if r["policy"]} == {"active", "random", "stationary"}
    (verdict,) = [r for r in rows if r.get("check") == "baselines"]
    assert verdict["held_policy"] == "active" and verdict["label_error_unit"] == "mm"
    assert {r["model"] for r in rows if r["policy"] is None} == {"histogram", "baseline-knn", "baseline-logistic",
                                                                "baseline-ridge"}
