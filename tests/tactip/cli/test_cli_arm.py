"""`tactip arm status|tap` end to end on the simulated arm (the UR cases run in tests/arm/test_ur.py)."""

import pathlib

import pytest

from tactip.cli import main

SAMPLES = pathlib.Path(__file__).resolve().parents[3] / "samples"
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


def test_a_tap_above_the_surface_reports_no_contact(capsys):
    """A negative depth stops the pad above the part (a dry run): no contact, not a negative indentation."""
    assert main(["arm", "tap", "--config", SIM, "--depth", "-1", "--at", "31", "0"]) == 0
    out = capsys.readouterr().out
    assert "simulated contact: none, the pad stopped 1.000 mm above the surface" in out and "indentation" not in out


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


UR_TOML = """
[arm]
backend = "ur"
host = "127.0.0.1"
work_frame = [400.0, -150.0, 20.0, 0.0, 0.0, 0.0]
workspace = [[-10.0, -10.0, -6.0], [100.0, 40.0, 40.0]]
max_tap_depth = 5.0

[arm.tap]
dwell = 0.02
"""


@pytest.fixture(scope="module")
def ur_station(tmp_path_factory):
    """A UR station config and the controller emulator it talks to (skipped when the UR ports are taken)."""
    from tests.arm.ur_emulator import PortsBusy, UrEmulator

    path = tmp_path_factory.mktemp("ur") / "station.toml"
    path.write_text(UR_TOML)
    try:
        with UrEmulator() as emulator:
            yield str(path), emulator
    except PortsBusy as exc:
        pytest.skip(str(exc))


@pytest.fixture
def ur(ur_station):
    path, emulator = ur_station
    # TCP 25 mm above the work frame origin, pad pointing down (base frame, m and rotation vector).
    emulator.reset(tcp=[0.4, -0.15, 0.045, 3.141592653589793, 0.0, 0.0])
    return path, emulator


def test_ur_status_ready(ur, capsys):
    path, _ = ur
    assert main(["arm", "status", "--config", path]) == 0
    out = capsys.readouterr().out
    assert "backend      ur at 127.0.0.1" in out and "x 0.000  y 0.000  z 25.000 mm" in out
    assert "robot mode   RUNNING" in out and "program      running" in out and "ready        yes" in out


def test_ur_status_in_protective_stop_exits_1_with_the_reason(ur, capsys):
    path, emulator = ur
    emulator.protective_stop()
    assert main(["arm", "status", "--config", path]) == 1
    out = capsys.readouterr().out
    assert "safety mode  PROTECTIVE_STOP" in out and "ready        no: the controller reports a protective stop" in out


def test_ur_tap_refused_before_connecting(ur, capsys):
    path, emulator = ur
    assert main(["arm", "tap", "--config", path, "--depth", "5.5"]) == 1
    assert "deeper than max_tap_depth 5 mm" in capsys.readouterr().err
    assert emulator.log() == []                                   # not even the control script was sent


def test_ur_tap_moves_down_to_the_depth_slowly(ur, capsys):
    path, emulator = ur
    assert main(["arm", "tap", "--config", path, "--depth", "1.5", "--at", "20", "5"]) == 0
    assert "tapped at (20, 5) mm of the work frame, depth 1.5 mm" in capsys.readouterr().out
    press = emulator.moves()[-2]
    assert press["pose"][:3] == pytest.approx([0.42, -0.145, 0.0185])
    assert press["speed"] == pytest.approx(0.005)
