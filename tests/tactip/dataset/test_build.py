"""`build_dataset` on synthetic recordings with known labels: videos and images, every label kind and split,
bad rows named by line, nothing half-written, unseen pins kept as NaN columns."""

import json
import shutil

import numpy as np
import pytest

from calibration import load_calibration
from perception import load_dataset
from tactip.dataset import OUTPUTS, LabelsError, build_dataset, recording_taps
from tactip.sim import SyntheticTacTip
from tests.tactip.dataset.conftest import DIRECTIONS, SHAPES, press_run, write_video


def _datasets(out):
    return load_dataset(out / "train.h5"), load_dataset(out / "test.h5"), json.loads((out / "summary.json").read_text())


def test_slide_videos_become_angle_identities_with_a_period(slides_model):
    """Built with ``--period 360`` (the `slides_model` fixture runs the CLI)."""
    train, test, summary = _datasets(slides_model)
    for ds in (train, test):
        assert ds.identity_period == 360.0 and ds.identity_unit == "deg"
        assert ds.location_unit == "none" and not ds.location.any()
        assert sorted(set(ds.identity.tolist())) == list(map(float, DIRECTIONS))
        assert ds.samples == 40 and ds.dims == 80
    # 4 slides per video, alternating: 2 training and 2 test taps per direction
    assert [(c["train"], c["test"]) for c in summary["classes"]] == [(2, 2)] * len(DIRECTIONS)
    assert summary["pins"]["feature_pins"] == 40 and summary["recordings"] == {"used": 8, "left_out": 0}
    # every video's taps on both sides: the summary says the test figures score recordings the model has seen
    assert any(w.startswith("8 of 8 recordings have taps in both training and test") and "--split group" in w
               for w in summary["warnings"])
    # one calibration for the set: its feature pins are the datasets' columns
    calibration = load_calibration(slides_model / "calibration.h5")
    assert calibration.n_selected * 2 == train.dims and train.sensor["selected_pins"] == calibration.n_selected


def test_press_videos_binned_into_depth_classes_with_a_group_split(press_videos, tmp_path):
    build_dataset(press_videos.labels, tmp_path / "out", label="depth_mm", classes=3, split="group", seed=3,
                  sensor="tactip-331")
    train, test, summary = _datasets(tmp_path / "out")
    low, high = summary["scheme"]["range"]
    width = (high - low) / 3
    centres = low + width * (np.arange(3) + 0.5)
    assert np.allclose(sorted(set(train.identity.tolist()) | set(test.identity.tolist())), centres)
    assert train.identity_unit == "mm" and train.identity_period is None
    # whole recordings on one side: each of the 6 rows' 3 taps all train or all test, one recording per side and class
    for row in summary["rows"]:
        assert row["taps"] == 3 and sorted([row["train"], row["test"]]) == [0, 3]
    assert all((c["train"], c["test"], c["recordings"]) == (3, 3, 2) for c in summary["classes"])
    assert not any("in both training and test" in w for w in summary["warnings"])
    # each depth class holds the presses of its true depth (the label noise of +-0.2 mm never crosses a bin)
    truth = {row["path"]: float(row["path"].split("_")[1]) for row in summary["rows"]}
    for row in summary["rows"]:
        assert abs(row["identity"] - truth[row["path"]]) < width / 2


def test_column_split_follows_the_csv(press_videos, tmp_path):
    lines = press_videos.labels.read_text().splitlines()
    rows = [lines[0] + ",split"] + [f"{line},{'test' if k % 2 else 'train'}" for k, line in enumerate(lines[1:])]
    labels = press_videos.root / "labels_split.csv"
    labels.write_text("\n".join(rows) + "\n")
    result = build_dataset(labels, tmp_path / "out", label="depth_mm", classes=3, split="column",
                           sensor="tactip-331")
    assert [(r["train"], r["test"]) for r in result.summary["rows"]] == [(3, 0), (0, 3)] * 3


def test_images_give_one_tap_each_from_the_rest_image_with_named_labels(shape_images, tmp_path):
    build_dataset(shape_images.labels, tmp_path / "out", rest=shape_images.rest, sensor="tactip-127")
    train, test, summary = _datasets(tmp_path / "out")
    assert train.identity_names == tuple(sorted(SHAPES)) and train.identity_unit == "none"
    assert train.samples == 1 and len(train) + len(test) == 6 * len(SHAPES)
    assert all((c["train"], c["test"]) == (3, 3) for c in summary["classes"])
    # a deep press moves the pins more than a shallow one: the images' displacements are the contacts'
    names = train.identity_names
    size = {name: np.nanmean(np.abs(train.taps[train.identity == names.index(name)])) for name in names}
    assert size["deep"] > 1.5 * size["shallow"], size


def test_bad_rows_are_named_by_line_and_left_out(press_videos, tmp_path):
    folder = tmp_path / "set"
    shutil.copytree(press_videos.root, folder, ignore=shutil.ignore_patterns("*.csv"))
    (folder / "broken.avi").write_bytes(b"not a video at all")
    sensor = SyntheticTacTip.from_preset("tactip-331", seed=0)
    write_video(folder / "still.avi", [sensor.render()] * 12, 60.0)  # no contact
    small = SyntheticTacTip.from_preset("small-pad-100", seed=0)
    write_video(folder / "small.avi", [small.render()] * 3, 60.0)  # another camera's frame size
    good = [line for line in press_videos.labels.read_text().splitlines()[1:]]
    rows = ["path,depth_mm,operator", good[0], "missing.avi,2.0,op0", good[1], "broken.avi,1.0,op0",
            good[2].split(",")[0] + ",,op0", "still.avi,3.0,op1", "small.avi,2.0,op1", *good[3:]]
    (folder / "labels.csv").write_text("\n".join(rows) + "\n")
    result = build_dataset(folder / "labels.csv", tmp_path / "out", label="depth_mm", classes=3, sensor="tactip-331")
    reasons = {r["line"]: r["reason"] for r in result.summary["left_out"]}
    assert sorted(reasons) == [3, 5, 6, 7, 8]
    assert "no such file" in reasons[3] and "empty label" in reasons[6] and "no contact" in reasons[7]
    assert "320x240" in reasons[8] and "640x480" in reasons[8]
    assert reasons[5]  # the unreadable video, in its own words
    assert all(any(w.startswith(f"line {n} ") for w in result.summary["warnings"]) for n in reasons)
    assert result.summary["recordings"]["used"] == len(good) - 1


def test_nothing_is_written_when_nothing_is_left_or_on_an_interrupt(press_videos, tmp_path, monkeypatch):
    labels = tmp_path / "labels.csv"
    labels.write_text("path,depth_mm\nmissing.avi,1\nalso_missing.avi,2\n")
    with pytest.raises(LabelsError, match="line 2: no such file.*line 3: no such file"):
        build_dataset(labels, tmp_path / "out")
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())

    import tactip.dataset.build as build_module

    calls = []

    def interrupted(*args, **kwargs):
        calls.append(args[0])
        if len(calls) == 3:
            raise KeyboardInterrupt
        return recording_taps(*args, **kwargs)

    monkeypatch.setattr(build_module, "recording_taps", interrupted)
    with pytest.raises(KeyboardInterrupt):
        build_dataset(press_videos.labels, tmp_path / "out", label="depth_mm", classes=3, sensor="tactip-331")
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_existing_outputs_are_kept_unless_overwrite(press_videos, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "train.h5").write_text("an older set")
    labels = press_videos.root / "labels_two.csv"  # one recording of two depths
    lines = press_videos.labels.read_text().splitlines()
    labels.write_text("\n".join([lines[0], lines[1], lines[3]]) + "\n")
    with pytest.raises(LabelsError, match="already holds train.h5.*--overwrite"):
        build_dataset(labels, out, label="depth_mm")
    assert (out / "train.h5").read_text() == "an older set"
    build_dataset(labels, out, label="depth_mm", overwrite=True, sensor="tactip-331")
    assert sorted(p.name for p in out.iterdir()) == sorted(OUTPUTS)  # no temporary file left


def test_a_given_calibration_is_used_and_copied(press_videos, tmp_path):
    from calibration import save_calibration
    from tactip.dataset import make_calibration, rest_frame_of

    rest = rest_frame_of(press_videos.root / "press_5_1.avi")
    save_calibration(tmp_path / "given.h5", make_calibration(rest, sensor="tactip-331", n_pins=30))
    result = build_dataset(press_videos.labels, tmp_path / "out", label="depth_mm", classes=3,
                           calibration=tmp_path / "given.h5")
    given, copied = load_calibration(tmp_path / "given.h5"), load_calibration(tmp_path / "out" / "calibration.h5")
    assert np.array_equal(given.selected_pins, copied.selected_pins)
    assert np.allclose(given.reference_pins, copied.reference_pins)
    assert result.summary["calibration"]["made_on"] == "given" and load_dataset(tmp_path / "out" / "test.h5").dims == 60
    with pytest.raises(LabelsError, match="sensor cannot be combined"):
        build_dataset(press_videos.labels, tmp_path / "other", label="depth_mm", sensor="tactip-331",
                      calibration=tmp_path / "given.h5")


@pytest.mark.parametrize("hidden", [10, 25])
def test_unseen_feature_pins_leave_nan_columns_not_dropped_taps(tmp_path, hidden):
    from tactip.dataset import make_calibration

    sensor = SyntheticTacTip.from_preset("tactip-331", seed=0)
    calibration = make_calibration(sensor.render().image, sensor="tactip-331")
    sensor.reseed_noise(99)
    # the sensor's pins nearest the first `hidden` feature pins, hidden in every frame of contact
    from scipy.spatial import cKDTree

    feature_xy = calibration.reference_pins[calibration.selected_pins[:hidden]]
    sim_pins = cKDTree(sensor.render().centres).query(feature_xy)[1]
    mask = np.zeros(sensor.n_pins, dtype=bool)
    mask[sim_pins] = True
    run = press_run(sensor, 3.0)
    frames = [sensor.render(c, hidden=mask if c.indentation_mm > 0 else None) for c in run.contacts]
    video = write_video(tmp_path / "occluded.avi", frames, 60.0)
    if hidden > 20:  # fewer than half the 40 feature pins seen: no usable tap
        with pytest.raises(Exception, match="half the feature pins"):
            recording_taps(video, calibration)
        return
    got = recording_taps(video, calibration)
    assert len(got.taps) == 3 and got.pins_seen.tolist() == [40 - hidden] * 3
    unseen = np.isnan(got.taps).all(axis=1)  # (taps, 80): columns NaN for the whole tap
    expected = np.zeros(80, dtype=bool)
    expected[:hidden] = expected[40:40 + hidden] = True
    assert (unseen == expected).all()
    assert np.isfinite(got.taps[:, :, ~expected]).all()


def test_videos_and_images_mix_with_a_rest_column(press_videos, tmp_path):
    """Images of the same pad beside its videos: the image taps repeat their displacement over the video's samples."""
    import cv2

    folder = tmp_path / "set"
    shutil.copytree(press_videos.root, folder, ignore=shutil.ignore_patterns("*.csv"))
    sensor = SyntheticTacTip.from_preset("tactip-331", seed=0)
    sensor.reseed_noise(7)
    cv2.imwrite(str(folder / "rest.png"), sensor.render().image)
    from tactip.sim.contact import Contact

    for name, depth in (("held_2.png", 2.0), ("held_5.png", 5.0)):
        cv2.imwrite(str(folder / name), sensor.render(Contact(depth)).image)
    rows = ["path,depth_mm,rest", "press_2_0.avi,2.0,", "press_5_0.avi,5.0,", "held_2.png,2.0,rest.png",
            "held_5.png,5.0,rest.png", "held_5.png,5.0,"]
    (folder / "labels.csv").write_text("\n".join(rows) + "\n")
    result = build_dataset(folder / "labels.csv", tmp_path / "out", sensor="tactip-331")
    assert [r["line"] for r in result.summary["left_out"]] == [6]  # an image without a rest image
    assert "rest image" in result.summary["left_out"][0]["reason"]
    assert any("videos and images mixed" in w for w in result.summary["warnings"])
    train, test, _ = _datasets(tmp_path / "out")
    taps = np.concatenate([train.taps, test.taps])
    assert taps.shape[1:] == (40, 80) and len(taps) == 3 + 3 + 1 + 1
    image_rows = [r for r in result.summary["rows"] if r["kinds"] == ["image"]]
    assert [r["taps"] for r in image_rows] == [1, 1]
    same = (taps == taps[:, :1]) | (np.isnan(taps) & np.isnan(taps[:, :1]))
    constant = same.all(axis=(1, 2))  # an image's tap: one displacement, held (NaN for a pin it lost)
    assert constant.sum() == 2


def test_recordings_on_a_dask_cluster_build_the_same_datasets(press_videos, tmp_path):
    """Many recordings tracked on Dask workers (`tactip.cluster`): the datasets of a build one by one, bad rows alike."""
    from tactip.cluster import cluster_map, open_client

    folder = tmp_path / "set"
    shutil.copytree(press_videos.root, folder, ignore=shutil.ignore_patterns("*.csv"))
    (folder / "broken.avi").write_bytes(b"not a video at all")
    good = press_videos.labels.read_text().splitlines()[1:]
    rows = ["path,depth_mm,operator", good[0], "broken.avi,3.0,op0", *good[1:]]
    (folder / "labels.csv").write_text("\n".join(rows) + "\n")
    options = dict(label="depth_mm", classes=3, split="group", seed=2, sensor="tactip-331")
    here = build_dataset(folder / "labels.csv", tmp_path / "here", **options)
    with open_client(workers=2, processes=False) as client:
        there = build_dataset(folder / "labels.csv", tmp_path / "there", map_fn=cluster_map(client), **options)
    assert there.summary == here.summary and [r["line"] for r in here.summary["left_out"]] == [3]
    for name in ("train.h5", "test.h5"):
        a, b = load_dataset(tmp_path / "here" / name), load_dataset(tmp_path / "there" / name)
        assert len(a) == len(b) > 0
        assert np.array_equal(a.taps, b.taps, equal_nan=True) and np.array_equal(a.identity, b.identity)
