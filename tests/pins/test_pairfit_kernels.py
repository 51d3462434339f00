"""The compiled pair fit (`pins._jit_pairs`) against its NumPy reference (`pins._pairfit`): the same fits within
1e-9 px on awkward inputs (one pair, coincident starts, a flat crop, pairs at the crop's edge, chains of pairs,
missing pins), and both near the true centres drawn."""

import types

import numpy as np
import pytest
from scipy.spatial import cKDTree

import pins._kernels
from pins import PinTracker
from pins._kernels import compiled
from pins._pairfit import fit_tip_pairs, part_overlapping

pytest.importorskip("numba")
from pins._jit_pairs import fit_pairs  # noqa: E402


def _tips(shape, centres, radius_px, seed, slope=0.3):
    """Bright discs of `radius_px` at `centres` (x, y) over a sloped membrane with noise: uint8."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:shape[0], 0:shape[1]]
    image = 60.0 + slope * xx
    for cx, cy in centres:
        image = np.where(np.hypot(xx - cx, yy - cy) <= radius_px, 200.0, image)
    return np.clip(image + rng.normal(0.0, 4.0, shape), 0, 255).astype(np.uint8)


def _both(crop, first, second, radius_px, others):
    reference = fit_tip_pairs(crop, first, second, radius_px, others)
    kernel = fit_pairs(crop, first, second, radius_px, others)
    return reference, kernel


def _agree(reference, kernel):
    for a, b in zip(reference, kernel):
        assert np.array_equal(np.isnan(a), np.isnan(b))
        assert np.nanmax(np.abs(a - b), initial=0.0) < 1e-9


def test_one_pair_fitted_as_the_reference_does_and_near_the_truth():
    a, b = np.array([20.3, 20.2]), np.array([28.6, 21.0])
    crop = _tips((50, 60), [a, b], 5.0, 0)
    reference, kernel = _both(crop, np.array([[23.0, 20.0]]), np.array([[27.0, 20.5]]), 5.0, np.full((1, 1, 2), np.nan))
    _agree(reference, kernel)
    assert np.linalg.norm(kernel[0][0] - a) < 0.3 and np.linalg.norm(kernel[1][0] - b) < 0.3


def test_many_pairs_with_others_at_the_crops_edge_and_coincident_starts():
    # Pairs of 3 px tips 4.5-5.5 px apart over a crop, some cut by its edge, with a third tip nearby as an
    # "other"; starts 1-2 px off (one pair's two starts coincident: the blob's middle).
    rng = np.random.default_rng(1)
    radius = 3.0
    middles = np.array([[20.0, 20.0], [60.0, 25.0], [1.0, 40.0], [79.0, 10.0], [40.0, 58.5], [40.0, 1.5],
                        [25.0, 45.0]])
    angle = rng.uniform(0, np.pi, len(middles))
    half = rng.uniform(2.25, 2.75, len(middles))[:, None] * np.stack([np.cos(angle), np.sin(angle)], axis=1)
    a, b = middles - half, middles + half
    third = middles + 3.2 * radius * np.stack([-np.sin(angle), np.cos(angle)], axis=1)
    crop = _tips((60, 80), np.concatenate([a, b, third]), radius, 2)
    first = a + rng.uniform(-1.5, 1.5, a.shape)
    second = b + rng.uniform(-1.5, 1.5, b.shape)
    others = np.full((len(a), 12, 2), np.nan)
    others[:, 3] = third
    reference, kernel = _both(crop, first, second, radius, others)
    _agree(reference, kernel)
    # Pairs inside the crop are fitted near their truth (the two fits' order: the nearer truth to each start).
    inside = np.flatnonzero((np.minimum(a, b).min(axis=1) > radius) & (np.maximum(a[:, 0], b[:, 0]) < 80 - radius)
                            & (np.maximum(a[:, 1], b[:, 1]) < 60 - radius))
    assert inside.size >= 2
    assert (np.linalg.norm(kernel[0][inside] - a[inside], axis=1) < 0.5).all()
    assert (np.linalg.norm(kernel[1][inside] - b[inside], axis=1) < 0.5).all()


def test_coincident_starts_are_never_parted():
    # Both starts at the blob's middle: the two tips' columns of the Jacobian are equal, the fit keeps them together
    # but for its rounding (amplified along the undamped difference: the kernel and the reference part by up to
    # 1e-3 px here). Neither parts them by the half radius `part_overlapping` asks for.
    a, b = np.array([20.0, 20.0]), np.array([25.0, 20.5])
    crop = _tips((40, 45), [a, b], 3.0, 4)
    start = 0.5 * (a + b)[None]
    reference, kernel = _both(crop, start, start.copy(), 3.0, np.full((1, 1, 2), np.nan))
    for first, second in (reference, kernel):
        assert np.linalg.norm(first - second) < 0.5 * 3.0
    assert np.abs(reference[0] - kernel[0]).max() < 1e-2 and np.abs(reference[1] - kernel[1]).max() < 1e-2


def test_a_flat_crop_is_no_fit_in_either():
    # No tip: the coverage's amplitude is 0 (or below), the Jacobian vanishes; both give NaN, not an error.
    crop = np.full((30, 30), 90, np.uint8)
    reference, kernel = _both(crop, np.array([[14.0, 15.0], [15.0, 15.0]]), np.array([[17.0, 15.0], [15.0, 15.0]]),
                              3.0, np.full((2, 2, 2), np.nan))
    _agree(reference, kernel)
    assert np.isnan(kernel[0]).all() and np.isnan(kernel[1]).all()


def test_no_pixel_kept_is_no_fit():
    # The pair wholly off the crop: no pixel to fit, NaN in both.
    crop = _tips((30, 30), [[10.0, 10.0]], 3.0, 3)
    reference, kernel = _both(crop, np.array([[-20.0, -20.0]]), np.array([[-16.0, -20.0]]), 3.0,
                              np.full((1, 1, 2), np.nan))
    _agree(reference, kernel)
    assert np.isnan(kernel[0]).all()


def _lattice_scene(seed):
    """A row lattice of 3 px tips 10 px apart, some neighbours squeezed to 5 px (one chain of three), a few
    missing: the crop, positions (with pins placed 1-2 px off, towards the blob's middle), expected positions,
    a refiner stand-in and the truth."""
    rng = np.random.default_rng(seed)
    xs, ys = np.meshgrid(np.arange(6.0, 100.0, 10.0), np.arange(6.0, 70.0, 10.0))
    truth = np.stack([xs.ravel(), ys.ravel()], axis=1) + rng.normal(0, 0.3, (xs.size, 2))
    n = len(truth)
    # Squeeze pairs (and one chain of three) along their rows.
    for i in rng.choice(np.arange(1, n - 2), 8, replace=False):
        truth[i + 1] = truth[i] + [5.0 + rng.uniform(-0.4, 0.4), rng.uniform(-0.5, 0.5)]
    truth[20:23, 0] = truth[20, 0] + np.array([0.0, 5.2, 10.4])
    crop = _tips((70, 100), truth, 3.0, seed)
    positions = truth + rng.normal(0, 1.0, truth.shape)
    expected = truth + rng.normal(0, 1.0, truth.shape)
    positions[rng.choice(n, 6, replace=False)] = np.nan
    origin = np.array([3.0, -2.0])
    neighbours = np.ascontiguousarray(cKDTree(truth).query(truth, k=7)[1][:, 1:].T)
    refiner = types.SimpleNamespace(tip_fit_radius_px=3.0, _window_neighbours=neighbours,
                                    _overlap_px=np.full(n, 6.0), gate_px=4.0, origin=origin)
    return crop, positions + origin, expected + origin, refiner, truth + origin


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_part_overlapping_compiled_as_the_reference(seed, monkeypatch):
    crop, positions, expected, refiner, truth = _lattice_scene(seed)
    monkeypatch.setattr(pins._kernels, "_NUMPY", True)
    assert compiled("_jit_pairs") is None
    reference = part_overlapping(refiner, crop, positions, expected)
    monkeypatch.setattr(pins._kernels, "_NUMPY", False)
    assert compiled("_jit_pairs") is not None
    kernel = part_overlapping(refiner, crop, positions, expected)
    assert np.array_equal(np.isnan(reference), np.isnan(kernel))
    assert np.nanmax(np.abs(reference - kernel)) < 1e-9
    moved = np.flatnonzero((np.abs(kernel - positions) > 1e-6).any(axis=1))
    assert moved.size >= 4  # (pairs were parted)
    # The parted pins came nearer their truth (placed 1 px off at random, the fit within a few tenths).
    before = np.linalg.norm(positions[moved] - truth[moved], axis=1)
    after = np.linalg.norm(kernel[moved] - truth[moved], axis=1)
    assert np.median(after) < 0.5 < np.median(before)
    assert np.isnan(kernel[np.isnan(positions[:, 0])]).all()  # (a missing pin stays missing)


def test_no_overlap_leaves_positions_as_they_were(monkeypatch):
    crop, positions, expected, refiner, _ = _lattice_scene(0)
    refiner._overlap_px = np.full(len(positions), 2.0)  # (no neighbour within 2 px)
    for numpy in (True, False):
        if numpy:
            monkeypatch.setattr(pins._kernels, "_NUMPY", True)
        else:
            monkeypatch.setattr(pins._kernels, "_NUMPY", False)
        out = part_overlapping(refiner, crop, positions, expected)
        assert np.array_equal(out, positions, equal_nan=True)


def test_tips_under_3_px_are_not_fitted_and_the_tracker_fits_by_default():
    # The scene's pairs are parted with tips of 3 px (above); with radial-led-120's tips of 2 px the fit is no better
    # than the windows on a realistic skin (fitted pins 0.20 px off before, 0.22 after; more pins lost): not fitted,
    # whatever overlaps. `PinTracker` fits overlapping tips by default (only those of 3 px or more, then).
    crop, positions, expected, refiner, _ = _lattice_scene(0)
    assert not np.array_equal(part_overlapping(refiner, crop, positions, expected), positions, equal_nan=True)
    refiner.tip_fit_radius_px = 2.0
    assert part_overlapping(refiner, crop, positions, expected) is positions
    assert PinTracker().part_overlaps
