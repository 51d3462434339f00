"""pins._tipfit: tips fitted as opaque ellipses over a curved background are placed where they are."""

import numpy as np
import pytest

from scipy.spatial import cKDTree

from pins._tipfit import _Windows, _centre_step, _fittable, _gauss_newton, fit_tip_centres
from tactip.sim import _render


def _scene(centres, shape, *, glare, noise=0.0, seed=0, size=(160, 120)):
    """Opaque tips of level 200 over a membrane of 60 under flat-topped glare blobs (reflections) of
    `glare` grey levels and 15 px radius whose flanks rise by up to 0.09 `glare` grey/px, as the
    renderer paints them; uint8."""
    width, height = size
    yy, xx = np.mgrid[0:height, 0:width].astype(np.float32)
    scene = np.full((height, width), 60.0, np.float32)
    for cx, cy in ((40.0, 35.0), (115.0, 80.0), (70.0, 100.0)):
        scene += glare * np.exp2(-(np.hypot(xx - cx, yy - cy) / 15.0) ** 4)
    flat = scene.reshape(-1)
    _render.paint_pins(flat, size, centres, shape, np.full(len(centres), 200.0))
    image = flat.reshape(height, width)
    if noise:
        image = image + np.random.default_rng(seed).normal(0, noise, image.shape)
    return np.clip(image + 0.5, 0, 255).astype(np.uint8)


def _grid(rng, pitch=12.0, size=(160, 120)):
    xs, ys = np.meshgrid(np.arange(20.0, size[0] - 19, pitch), np.arange(20.0, size[1] - 19, pitch))
    return np.column_stack([xs.ravel(), ys.ravel()]) + rng.uniform(-0.5, 0.5, (xs.size, 2))


def _centroid(image, centres, reach):
    """The plain intensity-weighted centroid above the window's darkest level: leans up the slope."""
    out = []
    for x, y in centres:
        x0, y0 = int(round(x)), int(round(y))
        patch = image[y0 - reach:y0 + reach + 1, x0 - reach:x0 + reach + 1].astype(float)
        weight = np.clip(patch - np.median(patch) - 10, 0, None)
        gy, gx = np.mgrid[-reach:reach + 1, -reach:reach + 1]
        out.append([x0 + (weight * gx).sum() / weight.sum(), y0 + (weight * gy).sum() / weight.sum()])
    return np.array(out)


@pytest.mark.parametrize("axes", [(2.1, 2.1), (1.7, 2.9), (5.0, 5.0)])
@pytest.mark.parametrize("glare", [0.0, 70.0])
def test_opaque_tips_on_reflections_are_placed_within_a_few_hundredths(axes, glare):
    """Round, foreshortened (an ellipse at 45 degrees) and large tips on a flat membrane and under
    reflections (their flanks sloped and curved), noise-free: the fit's centres lie within 0.05 px (0.08 for
    the ellipse) of the truth, started a third of a px off, where a centroid leans up the slopes by tenths."""
    rng = np.random.default_rng(1)
    pitch = 4.5 * max(axes) + 3
    truth = _grid(rng, pitch=pitch)
    angle = np.pi / 4
    rotation = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    shape = np.broadcast_to(rotation @ np.diag(np.square(axes)) @ rotation.T, (len(truth), 2, 2)).copy()
    image = _scene(truth, shape, glare=glare)
    start = truth + rng.uniform(-0.35, 0.35, truth.shape)
    fitted = fit_tip_centres(image, start, float(np.sqrt(np.prod(axes))))
    assert np.hypot(*(fitted - truth).T).max() < (0.05 if axes[0] == axes[1] else 0.08)
    if glare and axes[0] < 3:
        leaning = _centroid(image, truth, int(pitch // 2) - 1)
        assert np.sqrt(np.mean(np.sum((leaning - truth) ** 2, axis=1))) > 0.15


def test_noise_gives_no_bias_and_little_scatter():
    """Small tips (radius 2.1 px, contrast 70-140) under reflections with noise sigma 5: mean
    error under 0.03 px, RMSE under 0.08 (the Cramer-Rao bound is about 0.03)."""
    rng = np.random.default_rng(2)
    errors = []
    for seed in range(3):
        truth = _grid(rng)
        shape = np.broadcast_to(np.diag([2.1 ** 2, 2.1 ** 2]), (len(truth), 2, 2)).copy()
        image = _scene(truth, shape, glare=70.0, noise=5.0, seed=seed)
        errors.append(fit_tip_centres(image, truth + rng.uniform(-0.3, 0.3, truth.shape), 2.1) - truth)
    errors = np.vstack(errors)
    assert np.abs(errors.mean(axis=0)).max() < 0.03
    assert np.sqrt(np.mean(np.sum(errors ** 2, axis=1))) < 0.08


def test_dark_markers_are_fitted_inverted():
    rng = np.random.default_rng(3)
    truth = _grid(rng)
    shape = np.broadcast_to(np.diag([4.0, 4.0]), (len(truth), 2, 2)).copy()
    image = 255 - _scene(truth, shape, glare=70.0)
    fitted = fit_tip_centres(image, truth + 0.3, 2.0, dark_pins=True)
    assert np.hypot(*(fitted - truth).T).max() < 0.05


def test_a_fit_that_fails_keeps_its_start_and_too_few_pins_are_returned_as_given():
    rng = np.random.default_rng(4)
    truth = _grid(rng)
    shape = np.broadcast_to(np.diag([4.0, 4.0]), (len(truth), 2, 2)).copy()
    image = _scene(truth, shape, glare=0.0)
    start = truth.copy()
    start[0] += [5.0, 0.0]  # between two tips: nothing to fit within reach of the start
    fitted = fit_tip_centres(image, start, 2.0)
    assert np.hypot(*(fitted[0] - start[0])) <= 0.8
    assert np.hypot(*(fitted[1:] - truth[1:]).T).max() < 0.05
    np.testing.assert_array_equal(fit_tip_centres(image, start[:1], 2.0), start[:1])
    assert fit_tip_centres(image, np.empty((0, 2)), 2.0).shape == (0, 2)
    np.testing.assert_array_equal(fit_tip_centres(image, start, 0.0), start)


def test_the_trackers_centre_step_is_the_first_centre_only_pass():
    """`_centre_step` (the tracker's fits, every frame) takes the step `_gauss_newton(free=2, passes=1)` takes,
    from starts up to 0.8 px off on noisy tips under reflections, and from between two tips (no step); a tip
    ellipse out of range (semi-axes of 0.5 px for a 2 px tip, NaN, not positive definite) is not `_fittable`."""
    rng = np.random.default_rng(5)
    truth = _grid(rng)
    shape = np.broadcast_to(np.diag([2.1 ** 2, 1.8 ** 2]), (len(truth), 2, 2)).copy()
    image = _scene(truth, shape, glare=70.0, noise=4.0)
    start = truth + rng.uniform(-0.8, 0.8, truth.shape)
    start[0] = truth[0] + [6.0, 0.0]  # between two tips
    distance, index = cKDTree(truth).query(start, 7)
    nearest = distance[:, 1]
    reach = np.minimum(1.5 * 2.0 + 2.0, nearest - 1.0)
    window = _Windows(image, start, reach, truth[index[:, 1:]], nearest)
    ellipses = np.tile([1 / 2.1 ** 2, 0.0, 1 / 1.8 ** 2], (len(truth), 1))
    theta = np.concatenate([start, ellipses], axis=1)
    want = _gauss_newton(window, theta.copy(), start, 2.0, free=2, passes=1)[:, :2]
    got = _centre_step(window, theta, start)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-9)
    assert (got[1:] != start[1:]).any(axis=1).mean() > 0.9  # most took their step, nearer the truth
    assert np.hypot(*(got[1:] - truth[1:]).T).mean() < 0.6 * np.hypot(*(start[1:] - truth[1:]).T).mean()
    assert _fittable(ellipses[:2], 2.0).all()
    assert not _fittable(np.array([[4.0, 0.0, 4.0], [np.nan, 0.0, 0.25], [0.25, 0.3, 0.25]]), 2.0).any()
    assert not _fittable(ellipses[:2], 0.0).any() and not _fittable(ellipses[:2], np.nan).any()  # no tips
