"""The simulated arm: frames, motion timing, taps over the simulated plate, faults, and safety."""

import threading
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from arm import Arm, SimArm, SimSettings, make_arm
from arm.errors import ArmFault, SafetyError
from arm.pose import Pose
from arm.profile import trapezoid_duration, trapezoid_fraction
from arm.world import PlateWorld, Gap

from tests.arm.conftest import make_config


def test_sim_arm_satisfies_the_protocol(config):
    assert isinstance(make_arm(config), Arm)


def test_make_arm_gives_a_plate_without_gaps_of_its_own_the_default_gaps():
    station_gaps = (Gap("s1", 10.0, 0.0, 0.5),)
    arm = make_arm(make_config(sim=SimSettings(placement_noise_mm=0.2, seed=3)), default_gaps=station_gaps)
    assert arm.world.gaps == station_gaps
    assert (arm.world.placement_noise_mm, arm.world.seed) == (0.2, 3)
    own = make_config(sim=SimSettings(gaps=(Gap("own", 5.0, 0.0, 1.0),)))
    assert [g.name for g in make_arm(own, default_gaps=station_gaps).world.gaps] == ["own"]
    world = PlateWorld(gaps=station_gaps)
    assert make_arm(own, default_gaps=station_gaps, world=world).world is world


def test_moves_in_the_work_frame_reach_the_controller_in_the_base_frame(config):
    with SimArm(config) as arm:
        assert arm.pose().is_close(Pose(0.0, 0.0, 30.0, 180.0, 0.0, 0.0), position_mm=1e-9)
        target = Pose(10.0, 5.0, 12.0, 180.0, 0.0, 0.0)
        arm.move_linear(target, speed_mm_s=40.0, acceleration_mm_s2=400.0)
        assert arm.pose().is_close(target, position_mm=1e-9)
        # Independently: the work frame is rotated 30 deg about z and offset by (400, -150, 20).
        c, s = np.cos(np.radians(30)), np.sin(np.radians(30))
        expected = np.array([400 + c * 10 - s * 5, -150 + s * 10 + c * 5, 20 + 12])
        np.testing.assert_allclose(arm.commands[-1].target_base.position, expected, atol=1e-9)
        arm.move_relative(dz=-2.0, speed_mm_s=10.0, acceleration_mm_s2=100.0)
        assert arm.pose().is_close(target.translated(dz=-2.0), position_mm=1e-9)


def test_trapezoid_profile_respects_speed_and_acceleration():
    for distance, v, a in [(30.0, 20.0, 100.0), (1.0, 20.0, 100.0)]:   # trapezoid, then triangle
        total = trapezoid_duration(distance, v, a)
        t = np.linspace(0.0, total, 4001)
        s = trapezoid_fraction(t, distance, v, a) * distance
        speed = np.gradient(s, t)
        assert s[0] == 0.0 and s[-1] == pytest.approx(distance)
        assert speed.max() <= v * 1.001 and np.all(np.diff(s) >= -1e-12)
        assert np.abs(np.diff(speed) / np.diff(t)).max() <= a * 1.01
    assert trapezoid_duration(30.0, 20.0, 100.0) == pytest.approx(30 / 20 + 20 / 100)
    assert trapezoid_duration(1.0, 20.0, 100.0) == pytest.approx(2 * np.sqrt(1 / 100))


def test_tap_calls_back_with_the_world_contact_and_simulated_times(config):
    events = []
    with SimArm(config) as arm:
        release = arm.tap(30.2, 3.0, depth_mm=2.5, on_contact=events.append, on_release=events.append)
    contact, end = events
    assert end is release and [contact.phase, end.phase] == ["contact", "release"]
    assert contact.contact is end.contact
    assert contact.pose.is_close(Pose(30.2, 3.0, 5.0, 180.0, 0.0, 0.0), position_mm=1e-9)
    world = contact.contact
    assert world.gap_name == "narrow" and world.gap_width_mm == 0.5
    assert world.indentation_mm == pytest.approx(2.5) and world.gap_offset_mm == pytest.approx(0.2)
    tap = config.tap
    stroke = trapezoid_duration(7.5, tap.speed_mm_s, tap.acceleration_mm_s2)
    assert end.time_s - contact.time_s == pytest.approx(2 * stroke + tap.dwell_s)
    press = arm.commands[-2]
    assert press.speed_mm_s == tap.speed_mm_s and press.target_base.z == pytest.approx(20.0 - 2.5)


def test_placement_noise_is_drawn_per_tap(config):
    world = PlateWorld(gaps=[Gap("g", 30.0, 0.0, 1.0)], placement_noise_mm=0.3, seed=11)
    with SimArm(config, world=world) as arm:
        offsets = [arm.tap(30.0, 0.0, depth_mm=1.0).contact.gap_offset_mm for _ in range(40)]
    assert len(set(offsets)) == 40 and 0.15 < np.std(offsets) < 0.45


def test_refused_tap_moves_nothing(config):
    with SimArm(config) as arm:
        for request in [dict(depth_mm=6.5), dict(depth_mm=-6.0)]:
            with pytest.raises(SafetyError):
                arm.tap(30.0, 0.0, **request)
        with pytest.raises(SafetyError, match="outside the workspace"):
            arm.tap(130.0, 0.0, depth_mm=1.0)
        assert arm.commands == []


def test_protective_stop_during_a_move_fails_then_refuses_until_recovered(config):
    with SimArm(config) as arm:
        arm.trigger_protective_stop(during_next_move=True)
        with pytest.raises(ArmFault, match="protective stop during the move"):
            arm.move_linear(Pose(0, 0, 10, 180, 0, 0), speed_mm_s=20, acceleration_mm_s2=200)
        assert 10.0 < arm.pose().z < 30.0
        sent = len(arm.commands)
        with pytest.raises(ArmFault, match="refusing to move: the controller reports a protective stop"):
            arm.move_relative(dz=1.0, speed_mm_s=10, acceleration_mm_s2=100)
        with pytest.raises(ArmFault, match="protective stop"):
            arm.tap(30.0, 0.0, depth_mm=1.0)
        assert len(arm.commands) == sent
        arm.recover_protective_stop()
        arm.tap(30.0, 0.0, depth_mm=1.0)


def test_emergency_stop_and_stopped_program_refuse(config):
    with SimArm(config) as arm:
        arm.stop_program()
        with pytest.raises(ArmFault, match="control program is not running"):
            arm.move_relative(dz=1.0, speed_mm_s=10, acceleration_mm_s2=100)
        arm.trigger_emergency_stop()
        with pytest.raises(ArmFault, match="emergency stop"):
            arm.move_relative(dz=1.0, speed_mm_s=10, acceleration_mm_s2=100)
        with pytest.raises(ArmFault, match="cannot be recovered from software"):
            arm.recover_protective_stop()


def test_not_connected_and_context_exit():
    arm = SimArm(make_config())
    with pytest.raises(ArmFault, match="not connected"):
        arm.pose()
    assert not arm.state().connected
    with pytest.raises(RuntimeError):
        with arm:
            raise RuntimeError("boom")
    assert not arm.connected


def test_realtime_move_can_be_stopped_from_another_thread():
    config = make_config()
    with SimArm(config, realtime=True) as arm:
        timer = threading.Timer(0.1, arm.stop)
        timer.start()
        started = time.monotonic()
        with pytest.raises(ArmFault, match="was stopped at"):
            arm.move_linear(Pose(0, 0, 10, 180, 0, 0), speed_mm_s=20, acceleration_mm_s2=200)
        assert time.monotonic() - started < trapezoid_duration(20, 20, 200)
        timer.join()
        assert 10.0 < arm.pose().z < 30.0


LIMITS = make_config().limits


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(st.tuples(st.floats(-60, 160), st.floats(-60, 80), st.floats(-15, 60),
                          st.floats(-5, 120), st.floats(-50, 900)), min_size=1, max_size=6))
def test_no_command_reaching_the_controller_breaks_a_limit(config, requests):
    arm = SimArm(config).connect()
    to_work = config.work_frame.inverse()
    for x, y, z, speed, accel in requests:
        try:
            arm.move_linear(Pose(x, y, z, 180, 0, 0), speed_mm_s=speed, acceleration_mm_s2=accel)
        except SafetyError:
            pass
    here = to_work @ (config.work_frame @ arm.home)
    for command in arm.commands:
        target = to_work @ command.target_base
        assert np.all(target.position >= np.array(LIMITS.workspace_min_mm) - 1e-9)
        assert np.all(target.position <= np.array(LIMITS.workspace_max_mm) + 1e-9)
        assert target.z >= -LIMITS.max_tap_depth_mm - 1e-9
        cap = LIMITS.max_tap_speed_mm_s if min(here.z, target.z) < 0 else LIMITS.max_speed_mm_s
        assert 0 < command.speed_mm_s <= cap
        assert 0 < command.acceleration_mm_s2 <= LIMITS.max_acceleration_mm_s2
        here = target
