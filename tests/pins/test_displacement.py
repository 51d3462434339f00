"""pins.displacement: differences from rest and integrated flows agree; NaN means unknown."""

import numpy as np
import pytest

from pins import ShapeError, displacement_from_rest, displacement_magnitude, integrate_flow


def test_displacement_is_position_minus_rest(rng):
    rest = rng.uniform(0, 640, (50, 2))
    motion = rng.normal(0, 3, (7, 50, 2))
    positions = rest + motion
    assert np.allclose(displacement_from_rest(positions, rest), motion)
    assert np.allclose(displacement_from_rest(positions[3], rest), motion[3])
    assert np.array_equal(displacement_from_rest(rest, rest), np.zeros_like(rest))


def test_integrated_flow_equals_displacement_from_rest(rng):
    rest = rng.uniform(0, 640, (30, 2))
    positions = rest + np.cumsum(rng.normal(0, 1, (12, 30, 2)), axis=0)
    flows = np.diff(np.concatenate([rest[None], positions]), axis=0)
    assert np.allclose(integrate_flow(flows), displacement_from_rest(positions, rest))


def test_lost_flow_makes_the_rest_of_the_integral_unknown(rng):
    flows = rng.normal(0, 1, (6, 4, 2))
    flows[2, 1] = np.nan
    integral = integrate_flow(flows)
    assert np.isnan(integral[2:, 1]).all()
    assert np.isfinite(integral[:2, 1]).all() and np.isfinite(integral[:, [0, 2, 3]]).all()


def test_magnitude():
    assert np.allclose(displacement_magnitude(np.array([[3.0, 4.0], [np.nan, 1.0]])), [5.0, np.nan], equal_nan=True)


@pytest.mark.parametrize("positions, rest", [(np.zeros((5, 2)), np.zeros((4, 2))),
                                             (np.zeros((3, 5, 3)), np.zeros((5, 3))),
                                             (np.zeros((2, 3, 5, 2)), np.zeros((5, 2)))])
def test_shapes_are_checked(positions, rest):
    with pytest.raises(ShapeError):
        displacement_from_rest(positions, rest)


def test_flow_shape_checked():
    with pytest.raises(ShapeError):
        integrate_flow(np.zeros((5, 2)))
    with pytest.raises(ShapeError):
        displacement_magnitude(np.zeros((5, 3)))
