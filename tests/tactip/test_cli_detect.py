"""`tactip detect`: JSON output exactly as documented, accuracy on the sample frame, one-line errors."""

import json
import pathlib

import cv2
import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial.distance import cdist

from tactip.cli import main

ROOT = pathlib.Path(__file__).resolve().parents[2]
FRAME = ROOT / "samples" / "synthetic_frame.png"
TRUTH = ROOT / "samples" / "synthetic_tap_truth.npz"


def _rmse_against_truth(pins):
    truth = np.load(TRUTH)["centres"][0]
    distance = cdist(truth, pins)
    rows, cols = linear_sum_assignment(distance)
    assert distance[rows, cols].max() < 3.0
    return np.sqrt(np.mean(distance[rows, cols] ** 2))


def test_json_output(capsys):
    assert main(["detect", str(FRAME), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert set(data) == {"count", "pins"}
    pins = np.array(data["pins"])
    assert data["count"] == len(pins) == 331 and pins.shape == (331, 2)
    assert _rmse_against_truth(pins) <= 0.15


def test_expected_pins_tunes_first(capsys):
    assert main(["detect", str(FRAME), "--expected-pins", "331", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["count"] == 331


def test_human_summary(capsys):
    assert main(["detect", str(FRAME), "--expected-pins", "331"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("331 pins in") and "(tuned)" in out and "radius" in out


def test_errors_are_one_line(tmp_path, capsys):
    blank = tmp_path / "blank.png"
    cv2.imwrite(str(blank), np.full((480, 640), 30, np.uint8))
    broken = tmp_path / "broken.png"
    broken.write_bytes(b"not a png")
    for path in (tmp_path / "missing.png", blank, broken):
        assert main(["detect", str(path)]) == 1
        error = capsys.readouterr().err
        assert error.startswith("tactip detect: error:") and error.count("\n") == 1
    assert "no sensor disc" in _last_error(blank, capsys)


def _last_error(path, capsys):
    main(["detect", str(path)])
    return capsys.readouterr().err
