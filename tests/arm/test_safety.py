"""Safety checks: every limit refuses with a message naming it; moves inside the limits pass."""

import pytest

from arm.errors import ArmFault, SafetyError
from arm.interface import ArmState
from arm.pose import Pose
from arm.safety import check_move, check_ready

from tests.arm.conftest import make_config

LIMITS = make_config().limits
ABOVE = Pose(10.0, 0.0, 5.0)


def move(target, speed=10.0, accel=100.0, start=ABOVE):
    check_move(start, target, speed_mm_s=speed, acceleration_mm_s2=accel, limits=LIMITS)


def test_move_inside_limits_passes():
    move(Pose(10.0, 0.0, -5.9), speed=20.0)
    move(Pose(119.0, 39.0, 39.0), speed=50.0, accel=500.0)


@pytest.mark.parametrize("target, message", [
    (Pose(121.0, 0, 5), "x = 121 mm is above the maximum 120 mm"),
    (Pose(0, -21.0, 5), "y = -21 mm is below the minimum -20 mm"),
    (Pose(0, 0, 41.0), "z = 41 mm is above the maximum 40 mm"),
    (Pose(0, 0, -6.5), "deeper than max_tap_depth 6 mm"),
    (Pose(0, 0, -9.0), "z = -9 mm is below the minimum -8 mm"),
])
def test_workspace_and_depth(target, message):
    with pytest.raises(SafetyError, match=message):
        move(target)


def test_speed_and_acceleration_caps():
    with pytest.raises(SafetyError, match="speed 51 mm/s exceeds max_speed 50"):
        move(Pose(10, 0, 20), speed=51)
    with pytest.raises(SafetyError, match="exceeds max_tap_speed 20 mm/s for a move below"):
        move(Pose(10, 0, -1), speed=25)
    with pytest.raises(SafetyError, match="max_tap_speed"):       # leaving the part also counts
        move(Pose(10, 0, 5), speed=25, start=Pose(10, 0, -1))
    with pytest.raises(SafetyError, match="acceleration 501 mm/s\\^2 exceeds max_acceleration"):
        move(Pose(10, 0, 20), accel=501)
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(SafetyError, match="speed must be a finite number > 0"):
            move(Pose(10, 0, 20), speed=bad)
        with pytest.raises(SafetyError, match="acceleration must be a finite number > 0"):
            move(Pose(10, 0, 20), accel=bad)


@pytest.mark.parametrize("state, cause", [
    (ArmState(False, "DISCONNECTED", "UNKNOWN", False), "not connected"),
    (ArmState(True, "RUNNING", "PROTECTIVE_STOP", True, protective_stop=True), "protective stop"),
    (ArmState(True, "RUNNING", "ROBOT_EMERGENCY_STOP", False, emergency_stop=True), "emergency stop"),
    (ArmState(True, "RUNNING", "NORMAL", False), "control program is not running"),
    (ArmState(True, "POWER_OFF", "NORMAL", True), "robot mode is POWER_OFF"),
    (ArmState(True, "RUNNING", "FAULT", True), "safety mode is FAULT"),
])
def test_not_ready_states_refuse(state, cause):
    assert not state.ready
    with pytest.raises(ArmFault, match=cause):
        check_ready(state)


def test_ready_state_passes():
    check_ready(ArmState(True, "RUNNING", "NORMAL", True))
