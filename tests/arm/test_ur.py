"""The UR backend driven through the real ur-rtde client against the controller emulator (real TCP on loopback)."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from arm import Arm, make_arm
from arm.commissioning import arm_status
from arm.errors import ArmConnectionError, ArmFault, SafetyError
from arm.pose import Pose, pose_from_ur, pose_to_ur
from arm.tap import TapMotion
from arm.ur import UrArm

from tests.arm.conftest import make_config
from tests.arm.ur_emulator import PortsBusy, UrEmulator

CONFIG = make_config(backend="ur", host="127.0.0.1")
HOME = Pose(0.0, 0.0, 30.0, 180.0, 0.0, 0.0)                  # TCP in the work frame at start
MOTION = TapMotion(approach_height_mm=4.0, speed_mm_s=8.0, acceleration_mm_s2=80.0, dwell_s=0.02,
                   travel_speed_mm_s=40.0)


@pytest.fixture(scope="module")
def emulator_process():
    """One emulator process for the module (started in ~0.2 s); skipped when the UR ports are taken."""
    try:
        with UrEmulator() as emulator:
            yield emulator
    except PortsBusy as exc:
        pytest.skip(str(exc))


@pytest.fixture
def emulator(emulator_process):
    """A fresh controller with the TCP at HOME, moving 20x faster than real time."""
    emulator_process.reset(tcp=pose_to_ur(CONFIG.work_frame @ HOME))
    return emulator_process


def work_pose(ur_pose) -> Pose:
    """A UR base-frame pose (m, rad) seen in the work frame (mm, deg)."""
    return CONFIG.work_frame.inverse() @ pose_from_ur(ur_pose)


def test_tap_sequence_arrives_in_metres_and_radians_as_sent(emulator):
    events = []
    with UrArm(CONFIG) as arm:
        assert isinstance(arm, Arm)
        assert arm.pose().is_close(HOME, position_mm=1e-6, angle_deg=1e-6)
        arm.tap(30.0, 2.0, depth_mm=1.5, motion=MOTION, on_contact=events.append, on_release=events.append)
        assert arm.pose().is_close(Pose(30.0, 2.0, 4.0, 180.0, 0.0, 0.0), position_mm=1e-6, angle_deg=1e-6)
    log = emulator.log()
    tcp = [entry for entry in log if entry["cmd"] == 29]
    np.testing.assert_allclose(tcp[0]["tcp"], [0.0, 0.0, 0.060, 0.0, 0.0, 0.0], atol=1e-12)
    moves = [entry for entry in log if entry["cmd"] == 3]
    expected = [(Pose(0, 0, 4, 180, 0, 0), 40.0), (Pose(30, 2, 4, 180, 0, 0), 40.0),
                (Pose(30, 2, -1.5, 180, 0, 0), 8.0), (Pose(30, 2, 4, 180, 0, 0), 8.0)]
    assert len(moves) == len(expected)
    for move, (pose, speed) in zip(moves, expected):
        np.testing.assert_allclose(move["pose"], pose_to_ur(CONFIG.work_frame @ pose), atol=1e-12)
        assert work_pose(move["pose"]).is_close(pose, position_mm=1e-9, angle_deg=1e-6)
        assert move["speed"] == pytest.approx(speed / 1000.0)
        assert move["acceleration"] == pytest.approx(80.0 / 1000.0)
        assert move["asynchronous"] == 1
    assert [e.phase for e in events] == ["contact", "release"] and events[0].time_s < events[1].time_s
    assert events[0].contact is None
    assert log[-1]["cmd"] == 255                                  # the script was stopped on the way out


def test_protective_stop_during_a_move_fails_then_refuses(emulator):
    with UrArm(CONFIG) as arm:
        emulator.protective_stop(during_next_move=True)
        with pytest.raises(ArmFault, match="protective stop"):
            arm.move_linear(Pose(0, 0, 10, 180, 0, 0), speed_mm_s=40.0, acceleration_mm_s2=400.0)
        assert 10.0 < arm.pose().z < 30.0
        sent = len(emulator.moves())
        with pytest.raises(ArmFault, match="refusing to move: the controller reports a protective stop"):
            arm.tap(30.0, 0.0, depth_mm=1.0, motion=MOTION)
        with pytest.raises(ArmFault, match="protective stop"):
            arm.move_relative(dz=1.0, speed_mm_s=10.0, acceleration_mm_s2=100.0)
        assert len(emulator.moves()) == sent
        assert not arm.state().ready
        arm.recover_protective_stop()                              # explicit, never automatic
        arm.move_relative(dz=-1.0, speed_mm_s=10.0, acceleration_mm_s2=100.0)
    assert len(emulator.moves()) == sent + 1
    assert [e["cmd"] for e in emulator.log()].count(29) == 2       # the TCP is set again after the restart


def test_stopped_program_refuses_moves_and_status_says_why(emulator):
    with UrArm(CONFIG) as arm:
        emulator.stop_program()
        with pytest.raises(ArmFault, match="control program is not running"):
            arm.move_relative(dz=-1.0, speed_mm_s=10.0, acceleration_mm_s2=100.0)
        assert emulator.moves() == []
    report = arm_status(CONFIG)                                    # a new connection restarts it
    assert report.ready and report.state.program_running


def test_move_that_does_not_finish_is_stopped_by_the_watchdog(emulator):
    emulator.set(time_scale=0.01)                                  # the arm crawls 100x slower than asked
    with UrArm(CONFIG, move_timeout_margin_s=0.1) as arm:
        with pytest.raises(ArmFault, match="did not finish within"):
            arm.move_relative(dz=-1.0, speed_mm_s=20.0, acceleration_mm_s2=200.0)
        commands = [e["cmd"] for e in emulator.log()]
        assert commands[-2:] == [3, 33]                            # moveL, then stopL


def test_powered_off_robot_connects_for_monitoring_only(emulator):
    emulator.set(robot_mode="POWER_OFF")
    with UrArm(CONFIG) as arm:
        state = arm.state()
        assert state.robot_mode == "POWER_OFF" and not state.ready and "power on" in state.problem
        with pytest.raises(ArmFault, match="robot mode is POWER_OFF"):
            arm.move_relative(dz=-1.0, speed_mm_s=10.0, acceleration_mm_s2=100.0)
    assert [e["cmd"] for e in emulator.log()] == []                # no script was even uploaded


def test_remote_control_off_is_a_clear_error(emulator):
    emulator.set(remote_control=False)
    with pytest.raises(ArmConnectionError, match="Local Control: switch the teach pendant to Remote Control"):
        UrArm(CONFIG).connect()


def test_unreachable_controller_is_a_clear_error():
    # Nothing listens on 127.0.0.2 (the emulator binds 127.0.0.1 only): connection refused.
    with pytest.raises(ArmConnectionError, match="cannot reach the UR controller at 127.0.0.2"):
        make_arm(make_config(backend="ur", host="127.0.0.2")).connect()


def test_control_script_that_never_runs_fails_instead_of_hanging(emulator):
    emulator.set(run_uploaded_script=False)                        # ur-rtde gives up after 5 s
    with pytest.raises(ArmConnectionError, match="cannot start the ur-rtde control script.*timeout"):
        UrArm(CONFIG).connect()


@pytest.fixture(scope="module")
def connected_arm(emulator_process):
    emulator_process.reset(tcp=pose_to_ur(CONFIG.work_frame @ HOME), time_scale=1000.0)
    with UrArm(CONFIG) as arm:
        yield arm, emulator_process


def _not_tiny(value):
    """Keep zero and negative requests (refused), but no crawling moves that would take minutes."""
    return value if value <= 0 or value >= 1 else value + 1


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(st.tuples(st.floats(-30, 130), st.floats(-30, 50), st.floats(-10, 45),
                          st.floats(-5, 60).map(_not_tiny), st.floats(-50, 600).map(_not_tiny)),
                min_size=1, max_size=3))
def test_no_move_reaching_the_controller_breaks_a_limit(connected_arm, requests):
    arm, emulator = connected_arm
    limits = CONFIG.limits
    for x, y, z, speed, accel in requests:
        here, sent = arm.pose(), len(emulator.moves())
        try:
            arm.move_linear(Pose(x, y, z, 180, 0, 0), speed_mm_s=speed, acceleration_mm_s2=accel)
        except SafetyError:
            assert len(emulator.moves()) == sent                  # refused: nothing reached the controller
            continue
        move = emulator.moves()[-1]
        target = work_pose(move["pose"])
        assert np.all(target.position >= np.array(limits.workspace_min_mm) - 1e-6)
        assert np.all(target.position <= np.array(limits.workspace_max_mm) + 1e-6)
        assert target.z >= -limits.max_tap_depth_mm - 1e-6
        cap = limits.max_tap_speed_mm_s if min(here.z, target.z) < 0 else limits.max_speed_mm_s
        assert 0 < move["speed"] <= cap / 1000.0 + 1e-12
        assert 0 < move["acceleration"] <= limits.max_acceleration_mm_s2 / 1000.0 + 1e-12


def test_the_emulators_protective_stop_halts_half_way_however_late_its_step_runs(monkeypatch):
    # The stop test above asks the arm to halt between start and target. On a loaded machine the emulator's
    # first step after the move can come after the move's whole duration; the stop must still land where
    # the move had taken the tool at the stop's moment, not at the start (as it did once, z = 30.0).
    from tests.arm import ur_controller
    clock = [100.0]
    monkeypatch.setattr(ur_controller.time, "monotonic", lambda: clock[0])
    controller = ur_controller.Controller(ur_controller.Options(tcp=[0.0, 0.0, 0.03, np.pi, 0.0, 0.0], time_scale=1.0))
    controller.stop_during_next_move = True
    controller._start_motion(np.array([0.0, 0.0, 0.01, np.pi, 0.0, 0.0]), 0.04, sync=False)   # 20 mm at 40 mm/s
    clock[0] += 5.0                                                   # ten times the move's 0.5 s before a step
    controller.step()
    assert controller.safety == "PROTECTIVE_STOP" and controller.motion is None
    np.testing.assert_allclose(controller.tcp[2], 0.02, atol=1e-12)   # half-way, where the stop was due
