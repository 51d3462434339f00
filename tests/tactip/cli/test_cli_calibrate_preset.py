"""`tactip calibrate --sensor NAME` on the simulated station films the named TacTip (issue 20, outcome 5).

The simulated station's camera rendered a hexagonal TacTip of the preset's pin count whatever the preset,
so `tactip calibrate --sensor radial-led-120` calibrated a pad filling the frame (pitch 31.5 px, 0.104
mm/px) and not the radial pad a third of the frame wide that `tactip detect` and `tactip replay` measure
on the preset's frames (0.394 mm/px, seeds 6-9): 73 % apart. Now the station films the preset.
"""

import re
from pathlib import Path

import pytest

from calibration import load_calibration
from pins import find_pin_field, sensor_scale
from tactip.cli import main
from tactip.sim import SyntheticTacTip

SAMPLE = Path(__file__).resolve().parents[3] / "samples" / "station_sim.toml"


def test_calibrate_on_the_simulated_station_measures_the_named_preset(tmp_path, capsys):
    name, seed = "radial-led-120", 7
    text = SAMPLE.read_text()
    for key in ("data_dir", "results", "model"):
        text = re.sub(rf"(?m)^{key} = .*$", f'{key} = "{tmp_path / "station" / key}"', text)
    text = re.sub(r"(?ms)^(\[sim\].*?^seed = )\d+", rf"\g<1>{seed}", text)
    (tmp_path / "station.toml").write_text(text)
    assert main(["calibrate", "--config", str(tmp_path / "station.toml"), "--sensor", name, "--rest-frames", "2",
                 "--out", str(tmp_path / "cal.h5")]) == 0
    capsys.readouterr()
    calibrated = load_calibration(tmp_path / "cal.h5")
    sensor = SyntheticTacTip.from_preset(name, seed=seed)
    detect = sensor_scale(find_pin_field(sensor.render().image).centres, sensor=name).mm_per_px
    assert calibrated.expected_pins == sensor.n_pins and len(calibrated.reference_pins) == sensor.n_pins
    assert calibrated.mm_per_px == pytest.approx(detect, rel=0.02)
    assert calibrated.mm_per_px == pytest.approx(sensor.mm_per_px, rel=0.05)
