"""`tactip detect` and `tactip replay` warn alike about a frame that may hide pins (a saturated pad, faint tips)."""

import json

import cv2
import h5py
import pytest

from tactip.cli import main
from tests.pins.test_detect_exposure import filmed


@pytest.fixture(scope="module")
def saturated(tmp_path_factory):
    """A folder of three frames of radial-led-120 filmed at exposure x1.5 (its veil at the top grey level)."""
    folder = tmp_path_factory.mktemp("saturated")
    for k in range(3):
        cv2.imwrite(str(folder / f"frame_{k:02d}.png"), filmed("radial-led-120", 1, gain=1.5)[0])
    return folder


def test_detect_warns_in_text_and_json(saturated, capsys):
    image = str(saturated / "frame_00.png")
    assert main(["detect", image, "--json"]) == 0
    captured = capsys.readouterr()
    warnings = json.loads(captured.out)["warnings"]
    assert len(warnings) == 1 and warnings[0].startswith("the pad is saturated") and "lower the exposure" in warnings[0]
    assert main(["detect", image]) == 0
    err = capsys.readouterr().err
    assert err.count("tactip detect: warning: the pad is saturated") == 1 and err.count("\n") == 1


def test_detect_warns_of_small_faint_tips(tmp_path, capsys):
    path = tmp_path / "small.png"
    cv2.imwrite(str(path), filmed("radial-led-120", 2, height=240)[0])
    assert main(["detect", str(path), "--json"]) == 0
    captured = capsys.readouterr()
    (warning,) = json.loads(captured.out)["warnings"]
    assert warning.startswith("the pins are faint") and "film the pad larger" in warning
    assert "tactip detect: warning: the pins are faint" in captured.err


def test_replay_lists_the_same_warning(saturated, tmp_path, capsys):
    assert main(["detect", str(saturated / "frame_00.png"), "--json"]) == 0
    (detected,) = json.loads(capsys.readouterr().out)["warnings"]
    out = tmp_path / "r.h5"
    assert main(["replay", str(saturated), "--out", str(out)]) == 0
    with h5py.File(out) as h5:
        warnings = json.loads(h5.attrs["warnings"])
    assert f"rest frame: {detected}" in warnings
    assert f"Warning: rest frame: {detected}" in capsys.readouterr().out
