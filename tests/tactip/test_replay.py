"""tactip.replay and `tactip replay`: the sample video end to end, against its ground truth."""

import functools
import json
import pathlib

import cv2
import h5py
import numpy as np
import pytest
from scipy.spatial import cKDTree

from pins import NoSensorError, PinsError
from tactip.cli import main
from tactip.errors import SourceError
from tactip.replay import FORMAT, replay_video

ROOT = pathlib.Path(__file__).resolve().parents[2]
SAMPLE = ROOT / "samples" / "synthetic_tap.mp4"
TRUTH = ROOT / "samples" / "synthetic_tap_truth.npz"


@functools.lru_cache(maxsize=None)
def _replayed(directory: str):
    out = pathlib.Path(directory) / "replay.h5"
    annotated = pathlib.Path(directory) / "annotated.mp4"
    result = replay_video(SAMPLE, out, annotate_path=annotated)
    return result, out, annotated


@pytest.fixture(scope="module")
def replayed(tmp_path_factory):
    return _replayed(str(tmp_path_factory.mktemp("replay")))


def test_positions_match_ground_truth(replayed):
    _, out, _ = replayed
    truth = np.load(TRUTH)
    with h5py.File(out) as h5:
        positions = h5["positions"][:]
        displacements = h5["displacements"][:]
        timestamps = h5["timestamps"][:]
        assert h5["positions"].dtype == np.float32 and positions.shape == (86, 331, 2)
    identity = cKDTree(truth["centres"][0]).query(positions[0])[1]
    assert len(set(identity.tolist())) == 331
    error = positions - truth["centres"][:, identity]
    assert np.isfinite(error).all()
    # The video is MPEG-4 compressed on top of the sensor noise; the bar still holds.
    assert np.sqrt(np.mean(np.sum(error**2, axis=2))) <= 0.15
    assert np.allclose(displacements, positions - positions[0], atol=1e-4)
    assert np.allclose(timestamps, truth["timestamps_s"], atol=1e-6)


def test_taps_found_and_featured(replayed):
    result, out, _ = replayed
    truth = np.load(TRUTH)
    touching = truth["indentation_mm"] > 0.2
    with h5py.File(out) as h5:
        bounds = h5["tap_bounds"][:]
        taps = h5["taps"][:]
        selected = h5["selected_pins"][:]
        assert h5["tap_valid"][:].all()
        names = json.loads(h5["taps"].attrs["feature_names"])
        attrs = dict(h5.attrs)
    assert len(bounds) == 3 and taps.shape == (3, 40, 80) and len(names) == 80 and len(selected) == 40
    covered = np.zeros(len(touching), dtype=bool)
    for start, stop in bounds:
        covered[start:stop] = True
        assert touching[start:stop].mean() > 0.5
    assert covered[touching].all()
    # Deeper taps move the pins more (2, 3.5, 5 mm).
    peaks = np.abs(taps).max(axis=(1, 2))
    assert peaks[0] < peaks[1] < peaks[2]
    assert attrs["format"] == FORMAT and attrs["frame_rate"] == pytest.approx(20.0)
    assert json.loads(attrs["detection_params"])["block_size_px"] > 0
    assert attrs["mm_per_px"] == pytest.approx(result.mm_per_px)
    assert str(SAMPLE) == attrs["video"] and list(attrs["frame_size"]) == [640, 480]


def test_annotated_video_and_summary(replayed):
    result, out, annotated = replayed
    capture = cv2.VideoCapture(str(annotated))
    frames = int(capture.get(cv2.CAP_PROP_FRAME_COUNT))
    ok, image = capture.read()
    capture.release()
    assert ok and image.shape == (480, 640, 3) and frames == 86
    text = result.summary()
    assert "86 frames" in text and "331 tracked" in text and "Taps: 3" in text and str(out) in text
    assert not list(out.parent.glob(".*part*"))


def test_rest_frame_option(tmp_path):
    result = replay_video(SAMPLE, tmp_path / "r.h5", rest_frame=5)
    with h5py.File(tmp_path / "r.h5") as h5:
        positions = h5["positions"][:]
    assert np.isnan(positions[:5]).all() and np.isfinite(positions[5:]).all()
    assert result.frames == 86 and result.lost_pin_frames == 0


def test_unwritable_output_fails_before_processing(tmp_path, monkeypatch):
    import tactip.sources

    def never(*args, **kwargs):
        raise AssertionError("the video was opened before the output was checked")

    monkeypatch.setattr(tactip.sources, "open_source", never)
    with pytest.raises(OSError, match="cannot write"):
        replay_video(SAMPLE, tmp_path / "missing" / "r.h5")
    with pytest.raises(OSError, match="cannot write"):
        replay_video(SAMPLE, tmp_path / "r.h5", annotate_path=tmp_path / "missing" / "a.mp4")
    assert list(tmp_path.iterdir()) == []


def _write_video(path, frames):
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 20.0, (640, 480), True)
    for image in frames:
        writer.write(cv2.cvtColor(image, cv2.COLOR_GRAY2BGR))
    writer.release()


@pytest.mark.parametrize("case", ["corrupt", "no-disc", "short"])
def test_bad_input_leaves_nothing(tmp_path, case):
    video = tmp_path / "in.mp4"
    if case == "corrupt":
        video.write_bytes(np.random.default_rng(0).integers(0, 256, 4000, dtype=np.uint8).tobytes())
        expected = SourceError
    elif case == "no-disc":
        _write_video(video, [np.full((480, 640), 40, np.uint8)] * 3)
        expected = NoSensorError
    else:
        video = SAMPLE
        expected = SourceError
    out = tmp_path / "r.h5"
    with pytest.raises((expected, PinsError)):
        replay_video(video, out, rest_frame=1000 if case == "short" else 0)
    assert not out.exists() and not list(tmp_path.glob(".*part*"))


def test_cli_replay(tmp_path, capsys):
    out = tmp_path / "cli.h5"
    assert main(["replay", str(SAMPLE), "--out", str(out), "--quiet", "--samples", "20", "--pins", "10"]) == 0
    assert capsys.readouterr().out == ""
    with h5py.File(out) as h5:
        assert h5["taps"].shape == (3, 20, 20)
    assert main(["replay", str(SAMPLE), "--out", str(tmp_path / "b.h5"), "--rest-frame", "999", "--quiet"]) == 1
    error = capsys.readouterr().err
    assert error.startswith("tactip replay: error:") and error.count("\n") == 1 and "Traceback" not in error
