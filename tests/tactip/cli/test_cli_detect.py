"""`tactip detect`: JSON output as documented, accuracy on the sample frame, the count as a check, pictures, one-line errors."""

import json
import pathlib

import cv2
import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment
from scipy.spatial.distance import cdist

from pins import REJECTION_REASONS
from tactip.cli import main
from tactip.sim import SyntheticTacTip

ROOT = pathlib.Path(__file__).resolve().parents[3]
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
    assert set(data) == {"count", "pins", "pitch_px", "rejected", "dark_pins", "scale", "warnings"}
    assert data["dark_pins"] is False and data["warnings"] == []  # a well exposed frame
    pins = np.array(data["pins"])
    assert data["count"] == len(pins) == 331 and pins.shape == (331, 2)
    assert _rmse_against_truth(pins) <= 0.1
    assert 15.0 < data["pitch_px"] < 20.0
    # The scale from the pin pitch (as calibrate and replay derive it): the renderer's within 5 %, one pitch.
    scale = data["scale"]
    assert scale["pitch_px"] == pytest.approx(data["pitch_px"], abs=1e-3)
    assert scale["mm_per_px"] == pytest.approx(SyntheticTacTip(pins=331).mm_per_px, rel=0.05)  # the sample's sensor
    assert "pin pitch" in scale["source"] and "pad diameter assumed" in scale["source"]
    assert all(len(r) == 3 and r[2] in REJECTION_REASONS for r in data["rejected"])


def test_expected_pins_confirms_and_does_not_steer(capsys):
    assert main(["detect", str(FRAME), "--json"]) == 0
    without = json.loads(capsys.readouterr().out)
    assert main(["detect", str(FRAME), "--expected-pins", "331", "--json"]) == 0
    given = json.loads(capsys.readouterr().out)
    assert given["count"] == 331 and given["count_error"] == 0 and given["expected_pins"] == 331
    assert given["pins"] == without["pins"]


def test_human_summary(capsys):
    assert main(["detect", str(FRAME), "--expected-pins", "331"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("331 pins in") and "radius" in out and out.count("pitch 19.") == 1
    assert "scale 0.14" in out and "mm/px (pin pitch 2.793 mm" in out  # the sample: 0.1460 mm/px true
    assert "expected 331 pins: exactly as expected" in out and "rejected" in out


@pytest.mark.parametrize("count", ["1", "2", "5", "400"])
def test_a_count_far_off_is_a_one_line_warning(count, capsys):
    assert main(["detect", str(FRAME), "--expected-pins", count]) == 0
    captured = capsys.readouterr()
    assert captured.out.startswith("331 pins in") and f"expected {count} pins: {331 - int(count):+d}" in captured.out
    assert captured.err.startswith("tactip detect: warning: 331 pins found") and captured.err.count("\n") == 1
    assert "Traceback" not in captured.err


def test_rejected_blobs_are_counted_by_reason(tmp_path, capsys):
    from tests.pins.conftest import preset_frame

    image = tmp_path / "rim.png"
    cv2.imwrite(str(image), preset_frame("rim-ring-331").image)
    assert main(["detect", str(image), "--expected-pins", "331"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("325 pins in") and "expected 331 pins: -6 (-1.8%)" in out
    # A rim ring bounds the search (its glare is no candidate); the glare round a brown pad's rim is rejected.
    image = tmp_path / "brown.png"
    cv2.imwrite(str(image), preset_frame("brown-127").image)
    assert main(["detect", str(image)]) == 0
    assert "outside field" in capsys.readouterr().out


def test_annotate_draws_kept_and_rejected(tmp_path, capsys):
    out = tmp_path / "pins.png"
    assert main(["detect", str(FRAME), "--annotate", str(out)]) == 0
    picture = cv2.imread(str(out), cv2.IMREAD_COLOR)
    source = cv2.imread(str(FRAME), cv2.IMREAD_GRAYSCALE)
    assert picture.shape == source.shape + (3,)
    green = (picture[:, :, 1] > 150) & (picture[:, :, 0] < 60) & (picture[:, :, 2] < 60)
    assert green.sum() > 331 * 10
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pins.png"]


def test_annotate_never_overwrites_the_image(tmp_path, capsys):
    image = tmp_path / "frame.png"
    image.write_bytes(FRAME.read_bytes())
    before = image.read_bytes()
    assert main(["detect", str(image), "--annotate", str(image)]) == 1
    error = capsys.readouterr().err
    assert error.startswith("tactip detect: error:") and "is the input" in error and error.count("\n") == 1
    assert image.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["frame.png"]


def test_annotate_with_an_unknown_format_is_one_line(tmp_path, capsys):
    assert main(["detect", str(FRAME), "--annotate", str(tmp_path / "pins.xyz")]) == 1
    error = capsys.readouterr().err
    assert error.startswith("tactip detect: error:") and ".png" in error and error.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


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
