"""A flat gel's recordings through the whole pipeline (issue 26, outcome 5): `tactip detect`, `tactip replay`,
`tactip dataset build`, `tactip train`, `tactip validate` on synthetic GelSight-Mini-like videos, named
by ``--sensor gelsight-mini``: the contacts (slides in four directions) are classified."""

import json

import cv2
import pytest

from pins import sensor_preset
from tactip.cli import main
from tactip.sim import SyntheticGel

DIRECTIONS = (0, 90, 180, 270)


def _write(path, frames, frame_rate):
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), frame_rate, (320, 240), isColor=True)
    assert writer.isOpened()
    for frame in frames:
        writer.write(frame.image)
    writer.release()


@pytest.fixture(scope="module")
def gel_videos(tmp_path_factory):
    """slide_DDD.avi (4 slides of 1.2 mm each) per direction, colour MJPG at 25 frames/s, and labels.csv."""
    root = tmp_path_factory.mktemp("gel")
    sensor = SyntheticGel.from_preset("gelsight-mini", seed=0)
    rows = ["path,direction_deg"]
    for k, angle in enumerate(DIRECTIONS):
        sensor.reseed_noise(k + 1)
        run = sensor.slides([angle] * 4, distance_mm=1.2, indentation_mm=3.0, rest_s=0.12, press_s=0.12,
                            slide_s=0.2, lift_s=0.12)
        _write(root / f"slide_{angle:03d}.avi", run, sensor.frame_rate)
        rows.append(f"slide_{angle:03d}.avi,{angle}")
    (root / "labels.csv").write_text("\n".join(rows) + "\n")
    cv2.imwrite(str(root / "rest.png"), sensor.render().image)
    return root


def test_detect_and_replay_name_the_sensor_and_find_its_markers(gel_videos, capsys):
    assert main(["detect", str(gel_videos / "rest.png"), "--sensor", "gelsight-mini", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["count"] == 80 and data["dark_pins"] is True
    truth = SyntheticGel.from_preset("gelsight-mini", seed=0)
    assert data["scale"]["pitch_mm"] == pytest.approx(1.8)
    assert data["scale"]["mm_per_px"] == pytest.approx(truth.mm_per_px, rel=0.03)
    assert data["scale"]["sensor"]["grid"] == [8, 10]
    assert main(["replay", str(gel_videos / "slide_090.avi"), "--out", str(gel_videos / "r.h5"),
                 "--sensor", "gelsight-mini"]) == 0
    out = capsys.readouterr().out
    assert "sensing region: the whole frame" in out and "Taps: 4 (" in out and "80 tracked" in out


def test_slides_on_a_flat_gel_are_classified(gel_videos, capsys):
    out = gel_videos / "data"
    assert main(["dataset", "build", str(gel_videos / "labels.csv"), "--out", str(out), "--period", "360",
                 "--sensor", "gelsight-mini", "--pins", "20", "--min-separation-mm", "2", "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["taps"]["train"] == summary["taps"]["test"] == 8, summary["taps"]  # 4 slides x 4 directions
    assert main(["train", str(out / "train.h5"), "--out", str(out / "model.h5"), "--model", "gaussian"]) == 0
    assert main(["validate", str(out / "model.h5"), str(out / "test.h5"), "--runs", "400", "--json",
                 str(out / "v.json"), "--quiet"]) == 0
    rows = json.loads((out / "v.json").read_text())
    row = next(r for r in rows if r["threshold"] == 0.0)
    assert row["accuracy"] >= 0.9, row


def test_the_named_sensor_describes_a_flat_gel():
    gel = sensor_preset("gelsight-mini")
    assert gel.flat and gel.grid == (8, 10) and gel.pitch_mm == 1.8 and gel.frame_rate == 25.0
    assert "flat gel, 8 x 10 markers" in gel.describe() and "25 frames/s" in gel.describe()
    assert not sensor_preset("tactip-331").flat and sensor_preset("tactip-331").pitch_mm == pytest.approx(2.793, abs=1e-3)


def test_calibrate_names_the_flat_gel(tmp_path):
    """`tactip calibrate --sensor gelsight-mini` on the simulated station filming the flat gel: its 80 markers
    are the count expected, found over the whole frame, with the gel's scale and whole-frame region kept."""
    from calibration import load_calibration
    from tests.tactip.conftest import run_cli, small_station_table, write_station

    toml = write_station(tmp_path, small_station_table(tmp_path))
    code, out, err = run_cli(["calibrate", "--config", toml, "--sensor", "gelsight-mini", "--rest-frames", "3",
                              "--out", tmp_path / "cal.h5"])
    assert code == 0, err
    assert "80 pins (expected 80)" in out + err
    calibration = load_calibration(tmp_path / "cal.h5")
    assert calibration.disc.whole_frame and len(calibration.reference_pins) == 80
    assert calibration.mm_per_px == pytest.approx(SyntheticGel.from_preset("gelsight-mini").mm_per_px, rel=0.03)
    code, _, err = run_cli(["calibrate", "--config", toml, "--sensor", "nope"])
    assert code == 1 and "unknown sensor 'nope'" in err and "gelsight-mini" in err
