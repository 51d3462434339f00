"""`tactip arm status|tap` end to end on the simulated arm (the UR cases run in tests/arm/test_ur.py)."""

import pathlib

import pytest

from tactip.cli import main

SAMPLES = pathlib.Path(__file__).resolve().parents[2] / "samples"
SIM = str(SAMPLES / "arm_sim.toml")


def test_status_prints_pose_and_state_and_exits_0_when_ready(capsys):
    assert main(["arm", "status", "--config", SIM]) == 0
    out = capsys.readouterr().out
    assert "x 0.000  y 0.000  z 30.000 mm" in out
    assert "safety mode  NORMAL" in out and "ready        yes" in out


def test_tap_reports_the_simulated_contact(capsys):
    assert main(["arm", "tap", "--config", SIM, "--depth", "1.5", "--at", "31", "0"]) == 0
    out = capsys.readouterr().out
    assert "contact" in out and "release" in out
    assert "indentation 1.500 mm, gap w1.00 width 1 mm offset 1.000 mm" in out


@pytest.mark.parametrize("argv, message", [
    (["--depth", "7"], "deeper than max_tap_depth 6 mm"),
    (["--depth", "1", "--at", "500", "0"], "x = 500 mm is above the maximum 200 mm"),
    (["--depth", "1", "--speed", "25"], "exceeds max_tap_speed 20 mm/s"),
])
def test_tap_outside_the_limits_is_refused_in_one_line(capsys, argv, message):
    assert main(["arm", "tap", "--config", SIM, *argv]) == 1
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith("tactip arm: error: ") and message in captured.err
    assert captured.err.count("\n") == 1


def test_bad_config_is_one_line(tmp_path, capsys):
    path = tmp_path / "station.toml"
    path.write_text('[arm]\nbackend = "sim"\nworkspace = [[0, 0, -5], [10, 10, 10]]\n')
    assert main(["arm", "status", "--config", str(path)]) == 1
    assert "missing the key 'max_tap_depth'" in capsys.readouterr().err
    assert main(["arm", "status", "--config", str(tmp_path / "missing.toml")]) == 1
    assert "missing.toml" in capsys.readouterr().err


def test_subcommand_is_required(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["arm"])
    assert exc.value.code == 2
