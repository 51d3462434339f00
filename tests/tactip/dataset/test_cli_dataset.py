"""`tactip dataset build` -> `tactip train` -> `tactip validate` end to end on synthetic recordings with known labels.

The bar of issue 21: the labels are recovered (accuracy >= 0.95 at one tap on well-separated classes) and a
circular label's error wraps (a slide at 0 deg decided 315 deg is 45 deg off, not 315).
"""

import json

import numpy as np
import pytest

from perception import load_dataset, load_model
from tactip.cli import main
from tests.tactip.dataset.conftest import DIRECTIONS


def _one_tap(rows):
    """The row deciding after one tap (threshold 0: every run decides at its first tap) of the one policy a
    model of one location runs (stationary: the sensor never moves)."""
    assert {r["policy"] for r in rows} == {"stationary"}
    row = next(r for r in rows if r["threshold"] == 0.0)
    assert row["mean_taps"] == 1.0
    return row


def _label_error(row):
    return row["mean_label_error"] if "mean_label_error" in row else row["mean_identity_error"]


def test_slide_directions_are_recovered_at_one_tap(slides_model, capsys):
    assert main(["validate", str(slides_model / "model.h5"), str(slides_model / "test.h5"), "--runs", "800",
                 "--json", str(slides_model / "v.json"), "--quiet"]) == 0
    row = _one_tap(json.loads((slides_model / "v.json").read_text()))
    assert row["accuracy"] >= 0.95, row
    model = load_model(slides_model / "model.h5")
    assert model.identity_period == 360.0 and model.n_locations == 1
    assert model.identity_error(np.array([0.0]), np.array([315.0]))[0] == pytest.approx(45.0)


def test_circular_error_wraps_in_validate(slides_model, slide_videos, tmp_path):
    """The same taps labelled 45 deg further (315 + 45 written as 360): every decision is 45 deg off, wrapped."""
    rows = ["path,direction_deg"] + [f"slide_{a:03d}.avi,{a + 45}" for a in DIRECTIONS]
    labels = slide_videos.root / "labels_turned.csv"
    labels.write_text("\n".join(rows) + "\n")
    turned = tmp_path / "turned"
    assert main(["dataset", "build", str(labels), "--out", str(turned), "--period", "360", "--quiet",
                 "--calibration", str(slides_model / "calibration.h5")]) == 0
    original, shifted = load_dataset(slides_model / "test.h5"), load_dataset(turned / "test.h5")
    assert np.allclose(original.taps, shifted.taps, equal_nan=True)  # the same taps (one calibration)
    assert np.array_equal(shifted.identity, (original.identity + 45.0) % 360.0)
    assert main(["validate", str(slides_model / "model.h5"), str(turned / "test.h5"), "--runs", "800",
                 "--json", str(tmp_path / "v.json"), "--quiet"]) == 0
    row = _one_tap(json.loads((tmp_path / "v.json").read_text()))
    # the decisions are the true directions (accuracy >= 0.95 above), the labels 45 deg on: 45 deg, not
    # (7 x 45 + 315) / 8 = 78.75 deg as an unwrapped error would say
    assert row["accuracy"] <= 0.05
    assert _label_error(row) == pytest.approx(45.0, abs=3.0)


def test_press_depths_binned_into_classes_are_recovered(press_videos, tmp_path):
    out = tmp_path / "depth"
    assert main(["dataset", "build", str(press_videos.labels), "--out", str(out), "--label", "depth_mm",
                 "--classes", "3", "--sensor", "tactip-331", "--quiet"]) == 0
    assert main(["train", str(out / "train.h5"), "--out", str(out / "model.h5"), "--model", "gaussian"]) == 0
    assert main(["validate", str(out / "model.h5"), str(out / "test.h5"), "--runs", "800", "--json",
                 str(out / "v.json"), "--quiet"]) == 0
    row = _one_tap(json.loads((out / "v.json").read_text()))
    assert row["accuracy"] >= 0.95, row
    summary = json.loads((out / "summary.json").read_text())
    assert summary["identity_unit"] == "mm" and len(summary["classes"]) == 3


def test_build_refuses_a_bad_csv_in_one_line(tmp_path, capsys):
    (tmp_path / "labels.csv").write_text("file,depth_mm\na.avi,1\n")
    assert main(["dataset", "build", str(tmp_path / "labels.csv"), "--out", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    assert err.startswith("tactip dataset: error:") and "no 'path' column" in err and err.count("\n") == 1


def test_build_help_shows_examples(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["dataset", "build", "--help"])
    assert stop.value.code == 0
    out = capsys.readouterr().out
    assert "Examples:" in out and "tactip dataset build" in out and "--period" in out and "--split" in out


def test_named_shapes_from_images_are_recovered_at_one_tap(shape_images, tmp_path):
    out = tmp_path / "shapes"
    assert main(["dataset", "build", str(shape_images.labels), "--out", str(out), "--rest", str(shape_images.rest),
                 "--sensor", "tactip-127", "--quiet"]) == 0
    assert main(["train", str(out / "train.h5"), "--out", str(out / "model.h5"), "--model", "gaussian"]) == 0
    assert main(["validate", str(out / "model.h5"), str(out / "test.h5"), "--runs", "800", "--json",
                 str(out / "v.json"), "--quiet"]) == 0
    row = _one_tap(json.loads((out / "v.json").read_text()))
    assert row["accuracy"] >= 0.95, row
    assert load_model(out / "model.h5").identity_names == ("deep", "gap", "shallow")


def test_replay_with_the_built_calibration_and_model_decides_a_new_recording(slides_model, tmp_path):
    """The calibration written beside the datasets makes a new video's taps line up with the model's."""
    import h5py

    from tactip.sim import SyntheticTacTip
    from tests.tactip.dataset.conftest import slide_run, write_video

    sensor = SyntheticTacTip.from_preset("radial-led-120", seed=0)
    sensor.reseed_noise(77)
    video = write_video(tmp_path / "new.avi", slide_run(sensor, [135], count=2), 120.0)
    assert main(["replay", str(video), "--out", str(tmp_path / "new.h5"), "--calibration",
                 str(slides_model / "calibration.h5"), "--model", str(slides_model / "model.h5"), "--quiet"]) == 0
    with h5py.File(tmp_path / "new.h5") as h5:
        assert bool(h5["decisions"].attrs["decided"]) and h5["decisions"].attrs["identity_estimate"] == 135.0


def test_build_on_a_dask_scheduler_gives_the_same_datasets(press_videos, tmp_path, capsys):
    """`--scheduler` (a local cluster of worker threads on 127.0.0.1 here) builds what a build one by one builds."""
    from distributed import LocalCluster

    from tactip.cluster import LOOPBACK_ONLY

    args = ["dataset", "build", str(press_videos.labels), "--label", "depth_mm", "--classes", "3", "--sensor",
            "tactip-331", "--quiet"]
    assert main([*args, "--out", str(tmp_path / "here")]) == 0
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, protocol="tcp://", host="127.0.0.1",
                      **LOOPBACK_ONLY) as cluster:
        assert main([*args, "--out", str(tmp_path / "there"), "--scheduler", cluster.scheduler_address]) == 0
    for name in ("train.h5", "test.h5"):
        here, there = load_dataset(tmp_path / "here" / name), load_dataset(tmp_path / "there" / name)
        assert len(here) > 0 and np.array_equal(here.taps, there.taps, equal_nan=True)
        assert np.array_equal(here.identity, there.identity)
    assert main([*args, "--out", str(tmp_path / "x"), "--workers", "2", "--scheduler", "tcp://127.0.0.1:9"]) == 1
    assert "--workers sizes the embedded Dask cluster" in capsys.readouterr().err
