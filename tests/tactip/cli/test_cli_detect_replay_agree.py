"""`tactip detect` and `tactip replay` decide the polarity and refuse a frame without a sensor the same way."""

import json

import cv2
import h5py
import numpy as np
import pytest

from tactip.cli import main
from tactip.sim import SyntheticTacTip


def _still(tmp_path, image, frames=3):
    """`image` as one PNG file and as a folder of `frames` copies (a lossless still video)."""
    folder = tmp_path / "video"
    folder.mkdir()
    for k in range(frames):
        cv2.imwrite(str(folder / f"{k:03d}.png"), image)
    cv2.imwrite(str(tmp_path / "frame.png"), image)
    return tmp_path / "frame.png", folder


def _error(capsys, command: str) -> str:
    err = capsys.readouterr().err
    assert err.startswith(f"tactip {command}: error: ") and err.count("\n") == 1, err
    return err.removeprefix(f"tactip {command}: error: ").strip()


@pytest.mark.parametrize("case", ["blank", "a dozen blobs", "dark, a dozen blobs"])
def test_no_sensor_is_refused_by_both_with_the_same_message(tmp_path, capsys, case):
    """A frame where neither polarity forms a pin lattice: detect refuses it, and replay refuses the
    video (it used to track a dozen spurious blobs of the other polarity), saying the same."""
    if case == "blank":
        image = np.full((240, 320), 40, np.uint8)
    else:
        sensor = SyntheticTacTip.from_preset("dark-331" if case.startswith("dark") else "tactip-331", seed=1)
        hidden = np.ones(sensor.n_pins, dtype=bool)
        hidden[::30] = False
        image = sensor.render(hidden=hidden).image
    frame, video = _still(tmp_path, image)
    assert main(["detect", str(frame)]) == 1
    detected = _error(capsys, "detect")
    assert main(["replay", str(video), "--out", str(tmp_path / "r.h5"), "--quiet"]) == 1
    replayed = _error(capsys, "replay")
    assert detected.startswith("no sensor") and detected in replayed, (detected, replayed)
    assert not (tmp_path / "r.h5").exists()


@pytest.mark.parametrize("name", ["tactip-127", "dark-331", "white-dark-331"])
def test_both_decide_the_same_polarity(tmp_path, capsys, name):
    """Both polarities' presets, and white pins on a dark membrane in a dark casing (no bright surround:
    no disc of their own polarity; detect refused it and replay tracked the dark gaps between them)."""
    sensor = SyntheticTacTip.from_preset(name, seed=2)
    frame, video = _still(tmp_path, sensor.render().image)
    assert main(["detect", str(frame), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["dark_pins"] is sensor.dark_pins and data["count"] == sensor.n_pins
    out = tmp_path / "r.h5"
    assert main(["replay", str(video), "--out", str(out), "--quiet", "--pins", "10"]) == 0
    with h5py.File(out) as h5:
        assert json.loads(h5.attrs["detection_params"])["dark_pins"] is sensor.dark_pins
        assert h5["rest_positions"].shape == (sensor.n_pins, 2)
