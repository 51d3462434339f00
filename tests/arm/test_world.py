"""The simulated plate: indentation, nearest gap and its signed lateral offset, placement noise."""

import numpy as np
import pytest

from arm.pose import Pose
from arm.world import Gap, PlateWorld


def test_indentation_and_offset_for_a_gap_along_y():
    world = PlateWorld(gaps=[Gap("a", 30.0, 0.0, 1.0), Gap("b", 60.0, 0.0, 2.0)], surface_z_mm=1.0)
    contact = world.contact(Pose(31.5, 5.0, -2.0))
    assert contact.gap_name == "a"
    assert contact.gap_width_mm == 1.0
    assert contact.gap_offset_mm == pytest.approx(1.5)
    assert contact.indentation_mm == pytest.approx(3.0)
    assert contact.in_contact
    assert not world.contact(Pose(31.5, 5.0, 2.0)).in_contact
    left = world.contact(Pose(57.0, 0.0, 0.0))
    assert (left.gap_name, left.gap_offset_mm) == ("b", pytest.approx(-3.0))


def test_rotated_gap_offset_is_measured_across_its_axis():
    # At 90 deg the gap runs along -x, so the offset is measured along +y.
    world = PlateWorld(gaps=[Gap("r", 0.0, 0.0, 1.0, angle_deg=90.0)])
    assert world.contact(Pose(7.0, 2.0, 0.0)).gap_offset_mm == pytest.approx(2.0)


def test_nearest_gap_accounts_for_gap_length():
    # Two gaps on the same line along y: the pad beyond the end of one is nearest the other.
    world = PlateWorld(gaps=[Gap("south", 0.0, -30.0, 1.0, length_mm=20.0), Gap("north", 0.0, 30.0, 2.0, length_mm=20.0)])
    assert world.contact(Pose(0.5, 25.0, 0.0)).gap_name == "north"
    assert world.contact(Pose(0.5, -25.0, 0.0)).gap_name == "south"


def test_placement_noise_statistics_and_seed():
    def offsets(seed):
        world = PlateWorld(gaps=[Gap("g", 0.0, 0.0, 1.0)], placement_noise_mm=0.2, seed=seed)
        return np.array([world.contact(Pose(0.0, 0.0, -1.0)).gap_offset_mm for _ in range(2000)])

    first = offsets(7)
    assert abs(first.mean()) < 0.02 and first.std() == pytest.approx(0.2, rel=0.1)
    np.testing.assert_array_equal(first, offsets(7))


def test_plate_without_gaps():
    contact = PlateWorld().contact(Pose(0, 0, -1.0))
    assert contact.gap_name is None and contact.gap_width_mm == 0.0 and np.isnan(contact.gap_offset_mm)


def test_invalid_worlds():
    with pytest.raises(ValueError, match="unique"):
        PlateWorld(gaps=[Gap("g", 0, 0, 1), Gap("g", 1, 0, 1)])
    with pytest.raises(ValueError, match="width_mm"):
        Gap("g", 0, 0, 0.0)
    with pytest.raises(KeyError, match="no gap 'x'"):
        PlateWorld(gaps=[Gap("g", 0, 0, 1)]).gap("x")
