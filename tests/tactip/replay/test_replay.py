"""tactip.replay.video and `tactip replay`: the sample video end to end, against its ground truth."""

import functools
import json
import pathlib
import warnings

import cv2
import h5py
import numpy as np
import pytest
from scipy.spatial import cKDTree

from pins import NoSensorError, PinsError
from tactip.cli import main
from tactip.errors import SourceError
from tactip.replay.video import FORMAT, replay_video
from tactip.sim import Contact, SyntheticTacTip

ROOT = pathlib.Path(__file__).resolve().parents[3]
SAMPLE = ROOT / "samples" / "synthetic_tap.mp4"
TRUTH = ROOT / "samples" / "synthetic_tap_truth.npz"
TRUE_MM_PER_PX = SyntheticTacTip(pins=331).mm_per_px  # the sample's sensor (samples/make_samples.py)


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
        lost, retired = h5["lost"][:], h5["retired"][:]
        assert lost.dtype == bool and lost.shape == (86, 331) and retired.shape == (86, 331)
        assert np.array_equal(h5["lost_count"][:], lost.sum(axis=1))
        assert np.array_equal(h5["retired_count"][:], retired.sum(axis=1))
        assert np.array_equal(lost, np.isnan(positions[:, :, 0]))
        assert h5["blank"].shape == (86,) and not h5["blank"][:].any() and h5["tracked"][:].all()
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
        assert h5["tap_pins_seen"][:].tolist() == [40, 40, 40] and h5["tap_pins_seen"].attrs["of"] == 40
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
    # The scale from the pin pitch of the 331 pins detected on a 40 mm pad: the renderer's within 5 %.
    scale = json.loads(attrs["scale"])
    assert scale["mm_per_px"] == pytest.approx(TRUE_MM_PER_PX, rel=0.05) and "331 pins" in scale["source"]
    assert json.loads(attrs["warnings"]) == [] and result.warnings == []
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
    assert "pins seen 40/40 in the poorest tap" in text and result.pins_seen == [40, 40, 40]
    assert "Lost pins per frame (retired included): median 0, max 0 of 331" in text and "mm/px (pin pitch" in text
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
    (tmp_path / "file").write_text("")                               # a folder that is a file (a missing one is made)
    with pytest.raises(OSError, match="cannot write"):
        replay_video(SAMPLE, tmp_path / "file" / "r.h5")
    with pytest.raises(OSError, match="cannot write"):
        replay_video(SAMPLE, tmp_path / "r.h5", annotate_path=tmp_path / "file" / "sub" / "a.mp4")
    assert [p.name for p in tmp_path.iterdir()] == ["file"]


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


def _tap_video(path, sensor, *, black_at=None):
    """One 4 mm tap of ``sensor`` as an mp4v video (frame ``black_at`` all black); the true centres."""
    width, height = sensor.image_size
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 20.0, (width, height), True)
    truth = []
    for k, frame in enumerate(sensor.tap(Contact(4.0, 2.0), frame_rate=20.0, rest_before_s=0.1, rest_after_s=0.2)):
        image = frame.image if frame.image.ndim == 3 else cv2.cvtColor(frame.image, cv2.COLOR_GRAY2BGR)
        writer.write(np.zeros_like(image) if k == black_at else image)
        truth.append(frame.centres)
    writer.release()
    return np.array(truth)


def test_black_frame_is_marked_and_pins_recovered_after(tmp_path):
    sensor = SyntheticTacTip(pins=331, seed=3)
    video = tmp_path / "black.mp4"
    truth = _tap_video(video, sensor, black_at=8)  # mid-rise: the pins move while the LEDs are off
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = replay_video(video, tmp_path / "r.h5", sensor="tactip-331", annotate_path=tmp_path / "a.mp4")
    assert not [w for w in caught if w.filename.endswith("replay.py")]  # no NaN cast while drawing
    assert cv2.VideoCapture(str(tmp_path / "a.mp4")).get(cv2.CAP_PROP_FRAME_COUNT) == len(truth)
    with h5py.File(tmp_path / "r.h5") as h5:
        positions, blank, lost_count = h5["positions"][:], h5["blank"][:], h5["lost_count"][:]
        assert list(h5.attrs["blank_frames"]) == [8]
    assert blank.tolist() == [k == 8 for k in range(len(truth))]
    assert np.isnan(positions[8]).all() and lost_count[8] == 331
    assert result.blank_frames == [8] and "1 blank frame(s)" in result.summary()
    # Every pin back in the next frame, on its own true centre.
    identity = cKDTree(truth[0]).query(positions[0])[1]
    assert len(set(identity.tolist())) == 331
    after = positions[9:] - truth[9:, identity]
    assert np.isfinite(after).all() and np.sqrt(np.mean(np.sum(after**2, axis=2))) < 0.2
    assert len(result.tap_bounds) == 1 and not result.invalid_taps


@pytest.mark.parametrize("rest_frame, suspect", [(0, False), (17, True), (42, True)])
def test_rest_frame_taken_during_a_tap_is_reported(tmp_path, rest_frame, suspect):
    truth = np.load(TRUTH)
    result = replay_video(SAMPLE, tmp_path / "r.h5", rest_frame=rest_frame)
    warned = [w for w in result.warnings if "--rest-frame" in w]
    assert bool(warned) == suspect
    with h5py.File(tmp_path / "r.h5") as h5:  # written all the same, warning included
        assert h5["positions"].shape == (86, 331, 2)
        assert json.loads(h5.attrs["warnings"]) == result.warnings
    if suspect:
        assert f"rest frame {rest_frame} looks taken during a tap" in warned[0]
        suggested = int(warned[0].rsplit("(frame ", 1)[1].split()[0])
        assert truth["indentation_mm"][suggested] == 0.0


def test_a_video_without_taps_is_still_written(tmp_path):
    sensor = SyntheticTacTip(pins=127, seed=4)
    video = tmp_path / "rest.mp4"
    _write_video(video, [sensor.render().image for _ in range(6)])
    result = replay_video(video, tmp_path / "r.h5")
    with h5py.File(tmp_path / "r.h5") as h5:
        assert h5["positions"].shape == (6, 127, 2) and h5["tap_bounds"].shape == (0, 2) and "taps" not in h5
        assert len(h5["selected_pins"]) == 40 and h5["timestamps"].shape == (6,)
    assert result.tap_bounds == [] and any("no taps" in w for w in result.warnings)


def test_a_pad_without_room_gets_closer_pins_not_an_error(tmp_path):
    # 100 pins on a 20 mm pad (pitch 2.3 mm): 40 pins cannot be 4 mm apart.
    sensor = SyntheticTacTip(pins=100, pad_diameter_mm=20.0, seed=5)
    video = tmp_path / "small.mp4"
    _tap_video(video, sensor)
    result = replay_video(video, tmp_path / "r.h5", pins_on_pad=100, pad_diameter_mm=20.0)
    assert result.mm_per_px == pytest.approx(sensor.mm_per_px, rel=0.05)
    assert result.selection.n_pins == 40 and 2.0 < result.selection.separation_mm < 4.0
    assert any("cannot be 4 mm apart" in w for w in result.warnings)
    with h5py.File(tmp_path / "r.h5") as h5:
        selected = h5["selected_pins"]
        assert len(selected) == 40 and selected.attrs["separation_mm"] == pytest.approx(result.selection.separation_mm)
        assert h5["taps"].shape == (1, 40, 80)
    assert "40 pins at least" in result.summary() and "(4 mm asked)" in result.summary()


def test_cli_sensor_and_scale_options(tmp_path, capsys):
    out = tmp_path / "s.h5"
    assert main(["replay", str(SAMPLE), "--out", str(out), "--sensor", "tactip-331", "--pins", "12"]) == 0
    printed = capsys.readouterr().out
    assert "tactip-331: 331 pins on a 40 mm pad" in printed and "Lost pins per frame" in printed
    with h5py.File(out) as h5:
        assert json.loads(h5.attrs["scale"])["sensor"]["name"] == "tactip-331" and len(h5["selected_pins"]) == 12
    assert main(["replay", str(SAMPLE), "--out", str(out), "--mm-per-px", "0.2", "--quiet"]) == 1   # a replay: ours
    assert "--overwrite" in capsys.readouterr().err
    assert main(["replay", str(SAMPLE), "--out", str(out), "--mm-per-px", "0.2", "--quiet", "--overwrite"]) == 0
    with h5py.File(out) as h5:
        assert h5.attrs["mm_per_px"] == 0.2
    for bad in (["--mm-per-px", "inf"], ["--sensor", "nope"], ["--pins-on-pad", "3"]):
        with pytest.raises(SystemExit):
            main(["replay", str(SAMPLE), "--out", str(tmp_path / "x.h5"), *bad])
        assert bad[0] in capsys.readouterr().err
    assert not (tmp_path / "x.h5").exists()


def test_a_full_disk_is_named_and_leaves_nothing(tmp_path, monkeypatch):
    import errno

    import tactip.replay.video

    def full(path, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    out = tmp_path / "r.h5"
    out.write_bytes(b"old result")
    monkeypatch.setattr(tactip.replay.video, "write_hdf5", full)
    with pytest.raises(OSError, match="disk full while writing"):
        replay_video(SAMPLE, out)
    assert out.read_bytes() == b"old result" and sorted(p.name for p in tmp_path.iterdir()) == ["r.h5"]


def test_feature_pins_avoid_a_pin_lost_most_of_the_time(tmp_path):
    sensor = SyntheticTacTip(pins=127, seed=6)
    centre = int(np.argmin(np.linalg.norm(sensor.rest_centres - sensor.rest_centres.mean(axis=0), axis=1)))
    hidden = np.zeros(127, dtype=bool)
    hidden[centre] = True  # a dead pin at the centre: seen in the rest frame only
    depths = [0.0] * 3 + [1.0, 2.5, 4.0, 4.0, 2.5, 1.0] + [0.0] * 4
    frames = [sensor.render(Contact(d, 2.0), hidden=hidden if k else None).image for k, d in enumerate(depths)]
    video = tmp_path / "dead.mp4"
    _write_video(video, frames)
    result = replay_video(video, tmp_path / "r.h5")
    with h5py.File(tmp_path / "r.h5") as h5:
        rest, lost = h5["rest_positions"][:], h5["lost"][:]
    dead = int(np.argmin(np.linalg.norm(rest - sensor.rest_centres[centre], axis=1)))
    assert lost[1:, dead].all()
    assert dead not in result.selected_pins.tolist() and len(result.selected_pins) == 40
    assert len(result.tap_bounds) == 1 and not result.invalid_taps


def test_a_tracker_error_mid_video_loses_that_frame_not_the_replay(tmp_path, monkeypatch):
    from pins import PinTracker

    update = PinTracker.update
    calls = []

    def faulty(self, frame):
        calls.append(None)
        if len(calls) == 30:  # frame 30
            raise ValueError("simulated tracker fault")
        return update(self, frame)

    monkeypatch.setattr(PinTracker, "update", faulty)
    result = replay_video(SAMPLE, tmp_path / "r.h5")
    with h5py.File(tmp_path / "r.h5") as h5:
        positions, lost = h5["positions"][:], h5["lost"][:]
    assert np.isnan(positions[30]).all() and lost[30].all()
    assert result.lost_per_frame[30] == 331 and result.lost_per_frame[31:].max() < 331
    assert any("tracking failed in 1 frame(s)" in w and "simulated tracker fault" in w for w in result.warnings)
    assert len(result.tap_bounds) == 3


def test_a_video_damaged_mid_way_keeps_the_frames_before(tmp_path, monkeypatch):
    from tactip.sources.files import VideoSource

    read = VideoSource._read

    def damaged(self):
        if self._index == 40:
            raise SourceError("cannot decode frame 40 (damaged file)")
        return read(self)

    monkeypatch.setattr(VideoSource, "_read", damaged)
    result = replay_video(SAMPLE, tmp_path / "r.h5")
    with h5py.File(tmp_path / "r.h5") as h5:
        assert h5["positions"].shape == (40, 331, 2) and np.isfinite(h5["positions"][:]).all()
    assert result.frames == 40 and result.tap_bounds[0] == (11, 25)
    assert any("could not be read after frame 39" in w and "damaged file" in w for w in result.warnings)

