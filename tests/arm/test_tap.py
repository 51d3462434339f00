"""Tap planning: the segments, heights and speeds of one tap."""

import pytest

from arm.pose import Pose
from arm.tap import TapMotion, plan_tap

MOTION = TapMotion(approach_height_mm=4.0, speed_mm_s=8.0, acceleration_mm_s2=80.0, dwell_s=0.1,
                   travel_speed_mm_s=25.0)


def test_full_plan_from_above():
    start = Pose(0.0, 0.0, 20.0, 180.0, 0.0, 0.0)
    plan = plan_tap(start, 30.0, 2.0, depth_mm=1.5, motion=MOTION)
    assert [s.name for s in plan] == ["approach", "travel", "press", "release"]
    assert [s.target.position.tolist() for s in plan] == [[0, 0, 4], [30, 2, 4], [30, 2, -1.5], [30, 2, 4]]
    assert [s.speed_mm_s for s in plan] == [25.0, 25.0, 8.0, 8.0]
    assert all(s.target.roll == 180.0 for s in plan)


def test_from_below_the_approach_height_goes_up_slowly_first():
    plan = plan_tap(Pose(30.0, 2.0, -1.0), 30.0, 2.0, depth_mm=2.0, motion=MOTION)
    assert [s.name for s in plan] == ["approach", "press", "release"]
    assert plan[0].speed_mm_s == MOTION.speed_mm_s and plan[0].target.z == 4.0


def test_next_tap_in_place_is_only_the_stroke():
    plan = plan_tap(Pose(30.0, 2.0, 4.0), 30.0, 2.0, depth_mm=1.55, motion=MOTION)
    assert [s.name for s in plan] == ["press", "release"]
    assert plan[0].target.z == -1.55


def test_invalid_motion_and_request():
    with pytest.raises(ValueError, match="speed_mm_s must be"):
        TapMotion(speed_mm_s=0)
    with pytest.raises(ValueError, match="dwell_s must be"):
        TapMotion(dwell_s=-0.1)
    with pytest.raises(ValueError, match="depth_mm must be finite"):
        plan_tap(Pose(0, 0, 4), 0, 0, depth_mm=float("nan"), motion=MOTION)
