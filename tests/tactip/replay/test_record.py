"""`tactip record`: any source to a video file that replay can read; live sources need a limit."""

import cv2
import numpy as np
import pytest

import tactip.sources
from tactip.cli import main
from tactip.errors import SourceError
from tactip.replay.record import record_video
from tests.tactip.station.test_live_camera import FakeCamera



@pytest.mark.parametrize("suffix", [".mp4", ".avi"])
def test_synthetic_taps_recorded_then_replayed(tmp_path, suffix, capsys):
    video = tmp_path / f"taps{suffix}"
    assert main(["record", "synthetic:127", "--out", str(video), "--frames", "30", "--quiet"]) == 0
    assert "recorded 30 frames" in capsys.readouterr().out
    capture = cv2.VideoCapture(str(video))
    assert capture.get(cv2.CAP_PROP_FRAME_COUNT) == 30
    assert (capture.get(cv2.CAP_PROP_FRAME_WIDTH), capture.get(cv2.CAP_PROP_FRAME_HEIGHT)) == (640, 480)
    capture.release()
    assert main(["replay", str(video), "--out", str(tmp_path / "r.h5"), "--quiet", "--pins", "20"]) == 0


def test_seconds_limit_on_a_recording_uses_its_time_stamps(tmp_path):
    result = record_video("synthetic:127", tmp_path / "one_second.mp4", seconds=1.0)
    assert result.frames == 20 and result.frame_rate == 20.0     # the synthetic source runs at 20 frames/s


def test_a_live_camera_is_recorded_for_the_time_asked(tmp_path, monkeypatch):
    # Frames 5 ms apart on the camera's clock; it delivers 62 (never more than the recorder's queue holds,
    # so none is dropped however slow the machine) and then waits: 0.3 s is frames 0..59.
    monkeypatch.setattr(tactip.sources, "open_source", lambda spec, **options: FakeCamera(allowed=62))
    result = record_video(0, tmp_path / "live.avi", seconds=0.3)
    assert result.frames == 60 and result.duration_s == pytest.approx(0.295) and result.dropped_frames == 0
    capture = cv2.VideoCapture(str(tmp_path / "live.avi"))
    values = []
    while True:
        ok, image = capture.read()
        if not ok:
            break
        values.append(int(np.median(image)))
    assert len(values) == result.frames
    assert np.all(np.abs(np.diff(values)) <= 3)                  # consecutive frames, in order (MJPG rounding)


def test_a_live_camera_needs_a_limit_and_nothing_is_left_behind(tmp_path, monkeypatch):
    monkeypatch.setattr(tactip.sources, "open_source", lambda spec, **options: FakeCamera())
    with pytest.raises(SourceError, match="needs --seconds or --frames"):
        record_video(0, tmp_path / "live.mp4")
    assert list(tmp_path.iterdir()) == []


def test_bad_outputs_are_one_line_errors(tmp_path, capsys):
    assert main(["record", "synthetic", "--out", str(tmp_path / "x.mkv"), "--quiet"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "use a .mp4 or .avi" in err[0]
    assert not list(tmp_path.iterdir())
    # a folder that is a file is refused while parsing, before the source opens (a missing one is created)
    (tmp_path / "file").write_text("")
    with pytest.raises(SystemExit) as exit_:
        main(["record", "synthetic", "--out", str(tmp_path / "file" / "x.mp4"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert exit_.value.code == 2 and "argument --out" in err[-1] and "Not a directory" in err[-1]
    assert main(["record", "synthetic", "--out", str(tmp_path / "missing" / "x.mp4"), "--frames", "3", "-q"]) == 0
    assert (tmp_path / "missing" / "x.mp4").is_file()
