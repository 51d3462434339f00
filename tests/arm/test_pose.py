"""Pose maths: composition, inverse and the UR conversion agree with independent constructions."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from arm.pose import Pose, pose_from_ur, pose_to_ur

coordinates = st.floats(-500, 500, allow_nan=False)
angles = st.floats(-179, 179, allow_nan=False)
poses = st.builds(Pose, coordinates, coordinates, coordinates, angles, st.floats(-80, 80), angles)


def test_composition_moves_a_point_like_the_matrix_product():
    frame = Pose(100.0, -50.0, 20.0, 0.0, 0.0, 90.0)   # rotated 90 deg about z
    point = Pose(10.0, 0.0, 5.0)
    base = frame @ point
    # x of the rotated frame points along base +y.
    np.testing.assert_allclose(base.position, [100.0, -40.0, 25.0], atol=1e-9)
    assert base.yaw == pytest.approx(90.0)


@settings(max_examples=50, deadline=None)
@given(poses, poses)
def test_inverse_undoes_composition(a, b):
    assert (a.inverse() @ (a @ b)).is_close(b, position_mm=1e-6, angle_deg=1e-6)


@settings(max_examples=50, deadline=None)
@given(poses)
def test_ur_round_trip_and_units(pose):
    ur = pose_to_ur(pose)
    np.testing.assert_allclose(ur[:3], pose.position / 1000.0)
    rotvec = Rotation.from_euler("xyz", [pose.roll, pose.pitch, pose.yaw], degrees=True).as_rotvec()
    assert Rotation.from_rotvec(ur[3:]).approx_equal(Rotation.from_rotvec(rotvec), atol=1e-9)
    assert pose_from_ur(ur).is_close(pose, position_mm=1e-9, angle_deg=1e-6)


def test_tool_pointing_down_is_a_half_turn_about_x():
    ur = pose_to_ur(Pose(0, 0, 0, 180.0, 0, 0))
    np.testing.assert_allclose(np.abs(ur[3:]), [np.pi, 0, 0], atol=1e-12)


def test_invalid_poses_are_refused():
    with pytest.raises(ValueError, match="x must be finite"):
        Pose(float("nan"), 0, 0)
    with pytest.raises(ValueError, match="3 or 6 numbers"):
        Pose.from_array([1, 2])
    with pytest.raises(ValueError, match="6 numbers"):
        pose_from_ur([0, 0, 0])
