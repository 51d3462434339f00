"""pins._tipfit's windows and centre step, cut to fewer NumPy calls, against the code they replaced (bit
for bit: the same pixels, masks and steps), in images of several widths and at their edges."""

import numpy as np
import pytest
from scipy.special import erf
from scipy.spatial import cKDTree

from pins._tipfit import _EDGE_PX, _ERF_SLOPE, _REACH_PX, _RIDGE, _Windows, _centre_step, _solve
from pins._window import _squared_norm
from tests.pins.test_tipfit import _grid, _scene


class ReferenceWindows:
    """`pins._tipfit._Windows` as it was before its gather was cut (main 9a221aa), verbatim."""

    def __init__(self, image, start, reach, neighbours, nearest):
        height, width = image.shape
        offsets = np.arange(-(int(np.ceil(reach.max())) + 1), int(np.ceil(reach.max())) + 2)
        gy, gx = (a.ravel() for a in np.meshgrid(offsets, offsets, indexing="ij"))
        disc = np.hypot(gx, gy) <= int(np.ceil(reach.max())) + 1
        gx, gy = gx[disc], gy[disc]
        anchor = np.rint(start).astype(np.intp)
        ix, iy = anchor[:, 0, None] + gx, anchor[:, 1, None] + gy
        self.xy = np.stack([ix, iy], axis=1).astype(np.float64)
        self.x, self.y = self.xy[:, 0], self.xy[:, 1]
        inside = (ix.view(np.uintp) <= width - 1) & (iy.view(np.uintp) <= height - 1)
        if inside.all():
            values = image[iy, ix]
        else:
            values = image[np.clip(iy, 0, height - 1), np.clip(ix, 0, width - 1)]
        self.values = values.astype(np.float64)
        own = _squared_norm(self.xy.transpose(0, 2, 1)[:, None] - neighbours[:, :, None, :])
        self.usable = inside & (np.minimum.reduce(own, axis=1) > np.square(0.5 * nearest)[:, None])
        self.reach = reach


def reference_centre_step(window, theta, start):
    """`pins._tipfit._centre_step` as it was before its calls were cut (main 9a221aa), verbatim."""
    n, pixels = window.x.shape
    e = window.xy - theta[:, :2, None]
    ex, ey = e[:, 0], e[:, 1]
    length = np.sqrt(ex * ex + ey * ey)
    weight = (window.usable & (length <= window.reach[:, None])).astype(np.float64)
    qxx, qxy, qyy = theta[:, 2, None], theta[:, 3, None], theta[:, 4, None]
    qe = np.empty_like(e)
    qx, qy = qe[:, 0], qe[:, 1]
    np.add(qxx * ex, qxy * ey, out=qx)
    np.add(qxy * ex, qyy * ey, out=qy)
    q = np.maximum(ex * qx + ey * qy, 1e-12)
    root = np.sqrt(q)
    beyond = length * (1.0 - root) / root
    edge = beyond / _EDGE_PX
    coverage = 0.5 + 0.5 * erf(edge)
    dome = np.minimum(q, 1.0)
    surface_rows = np.empty((n, 6, pixels))
    surface_rows[:, 0] = 1.0
    surface_rows[:, 1:3] = e
    np.multiply(ex, ex, out=surface_rows[:, 3])
    np.multiply(ex, ey, out=surface_rows[:, 4])
    np.multiply(ey, ey, out=surface_rows[:, 5])
    basis = np.empty((n, 9, pixels))
    np.multiply(surface_rows, (1.0 - coverage)[:, None, :], out=basis[:, :6])
    basis[:, 6] = coverage
    np.multiply(coverage, dome, out=basis[:, 7])
    basis[:, 8] = window.values
    weighted = basis[:, :8] * weight[:, None, :]
    products = weighted @ basis.transpose(0, 2, 1)
    beta = np.linalg.solve(products[:, :, :8] + _RIDGE, products[:, :, 8:])
    surface = (beta[:, None, :6, 0] @ surface_rows)[:, 0]
    rise = beta[:, 6] + beta[:, 7] * dome - surface
    residual = window.values - (surface + coverage * rise)
    slope = rise * np.exp(-(edge * edge)) * _ERF_SLOPE
    by_q = slope * (length / (-2.0 * q * root)) + beta[:, 7] * coverage * (q < 1.0)
    radial = slope * (1.0 / root - 1.0) / np.maximum(length, 1e-9)
    jacobian = -(e * radial[:, None, :]) - 2.0 * qe * by_q[:, None, :]
    jw = jacobian * weight[:, None, :]
    jacobian = np.concatenate([jacobian, residual[:, None]], axis=1)
    (a, b, g0), (c, d, g1) = (jw @ jacobian.transpose(0, 2, 1)).transpose(1, 2, 0)
    a, d = a * (1.0 + 1e-3) + 1e-9, d * (1.0 + 1e-3) + 1e-9
    det = a * d - b * c
    step = np.empty((n, 2))
    np.divide(d * g0 - b * g1, det, out=step[:, 0])
    np.divide(a * g1 - c * g0, det, out=step[:, 1])
    new = theta[:, :2] + np.minimum(np.maximum(step, -0.5), 0.5)
    good = _squared_norm(new - start) <= _REACH_PX ** 2
    return np.where(good[:, None], new, theta[:, :2])


def _windows_of(image, truth, start, tip_px):
    """Both windows' inputs as `pins._recover`'s fits give them: reach from the nearest neighbour."""
    distance, index = cKDTree(truth).query(start, 7)
    nearest = distance[:, 1]
    reach = np.minimum(1.5 * tip_px + 2.0, nearest - 0.5 * tip_px)
    return start, reach, truth[index[:, 1:]], nearest


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_windows_and_steps_equal_the_reference_in_crops_of_several_widths(seed):
    # Crops of three widths measured in turn with windows of the same size (the flat offsets of the
    # disc are cached per window size and image width: a stale width would gather other pixels), tips
    # well inside and tips whose windows cross the image's edge, on reflections, with noise.
    rng = np.random.default_rng(seed)
    truth = _grid(rng)
    shape = np.broadcast_to(np.diag([2.1 ** 2, 1.8 ** 2]), (len(truth), 2, 2)).copy()
    scene = _scene(truth, shape, glare=70.0, noise=4.0, seed=seed)
    ellipses = np.tile([1 / 2.1 ** 2, 0.0, 1 / 1.8 ** 2], (len(truth), 1))
    for left, right in ((14, 160), (15, 148), (17, 137), (14, 160)):
        image = np.ascontiguousarray(scene[:, left:right])
        kept = (truth[:, 0] > left + 2) & (truth[:, 0] < right - 3)
        pins_here = truth[kept] - [left, 0]
        start = pins_here + rng.uniform(-0.8, 0.8, pins_here.shape)
        inputs = _windows_of(image, pins_here, start, 2.0)
        # Some windows cross an edge (the clipped gather), and a batch wholly inside (the flat one).
        width = image.shape[1]
        crosses = (start[:, 0] < 8) | (start[:, 0] > width - 9) | (start[:, 1] < 8) | (start[:, 1] > 111)
        assert crosses.any() and (~crosses).sum() > 10
        for which in (np.arange(len(start)), np.flatnonzero(~crosses)):
            part = tuple(x[which] for x in inputs)
            got, want = _Windows(image, *part), ReferenceWindows(image, *part)
            for name in ("xy", "x", "y", "values", "usable", "reach"):
                np.testing.assert_array_equal(getattr(got, name), getattr(want, name), err_msg=name)
            theta = np.concatenate([part[0], ellipses[kept][which]], axis=1)
            stepped = _centre_step(got, theta, part[0])
            np.testing.assert_array_equal(stepped, reference_centre_step(want, theta, part[0]))
            assert (stepped != part[0]).any(axis=1).mean() > 0.5  # steps were taken (not all kept starts)


def test_solve_is_numpys_bit_for_bit_and_raises_on_a_singular_matrix():
    rng = np.random.default_rng(3)
    a = rng.normal(size=(9, 8, 8))
    a = a @ a.transpose(0, 2, 1) + _RIDGE
    b = rng.normal(size=(9, 8, 1))
    np.testing.assert_array_equal(_solve(a, b), np.linalg.solve(a, b))
    singular = a.copy()
    singular[4] = 0.0
    with pytest.raises(np.linalg.LinAlgError):
        _solve(singular, b)
