"""pins._jit: the compiled kernels against their NumPy references (`pins._kernels` picks one), on awkward
inputs and through the whole tracker."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

import pins._kernels
from pins import DetectionParams, PinTracker, SensorDisc
from pins._kernels import compiled
from pins._tipfit import _Windows, _centre_step, _centre_step_numpy
from pins._window import WindowCentroids
from pins.disc import as_grey
from tests.pins.conftest import preset_sensor, slide_run
from tests.pins.test_tipfit import _grid, _scene

kernels = compiled()
pytestmark = pytest.mark.skipif(kernels is None, reason="Numba missing or TACTIP_KERNELS=numpy: no kernels to test")


def _agree(got, want):
    """Centroids within 1e-9 px and measures within 1e-9 of their size (1e-9 absolute near 0), NaN and
    inf in the same places."""
    np.testing.assert_allclose(got[0], want[0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(got[1], want[1], rtol=1e-9, atol=1e-9)


def _awkward_points(rng, image, centres, half):
    """Guesses on tips, between them, all over the image and beyond it, and on the edges: windows whose
    corner sits on the image's first and last rows and columns, and one row or column beyond."""
    height, width = image.shape
    edges = []
    for offset in (-1, 0, 1):
        edges += [[half + offset, rng.uniform(0, height)], [width - 1 - half + offset, rng.uniform(0, height)],
                  [rng.uniform(0, width), half + offset], [rng.uniform(0, width), height - 1 - half + offset]]
    return np.concatenate([centres + rng.normal(0.0, 1.0, centres.shape),
                           rng.uniform(-5.0, np.array([width, height]) + 5.0, (60, 2)),
                           np.array(edges) + rng.uniform(-0.45, 0.45, (len(edges), 2))])


@pytest.mark.parametrize("name, seed", [("radial-led-120", 0), ("dark-331", 1), ("brown-127", 2)])
def test_window_kernel_agrees_with_the_reference_on_awkward_windows(name, seed):
    # Both polarities (the tracker's bright-pin image and the raw one), tiny and large windows, flat
    # windows (a blank patch), every radius (none, negative, beyond the masks, NaN), with and without
    # a least contrast and the window's mean, and non-finite guesses (the reference refuses those:
    # the kernel gives NaN there and the reference's answer everywhere else).
    rng = np.random.default_rng(seed)
    s = preset_sensor(name, seed)
    rest = s.render()
    image = as_grey(rest.image).copy()
    image[:40, :40] = 90  # flat windows
    spacing = np.median(cKDTree(rest.centres).query(rest.centres, k=2)[0][:, 1])
    for polarity in (255 - image if s.dark_pins else image, image if s.dark_pins else 255 - image):
        polarity = np.ascontiguousarray(polarity)
        for half_px in (2, int(np.ceil(0.5 * spacing)), 12):
            points = _awkward_points(rng, polarity, rest.centres, half_px)
            points[:5] = rng.uniform(0, 40, (5, 2))  # on the flat patch
            radius = rng.uniform(-1.0, half_px + 3.0, len(points))
            radius[:3] = np.nan
            for above_mean in (False, True):
                windows = WindowCentroids(half_px, above_mean=above_mean)
                for least in (0.0, 30.0):
                    windows.least_contrast = least
                    with np.errstate(divide="ignore", invalid="ignore"):
                        want = windows._measure_numpy(polarity, points, radius)
                    got = windows._measure_compiled(kernels, polarity, points, radius)
                    _agree(got, want)
                    assert np.isfinite(got[0]).sum() > len(rest.centres) // 2  # most windows hold a tip
                    for part in np.array_split(np.arange(len(points)), 9):  # a few windows a call
                        _agree(windows._measure_compiled(kernels, polarity, points[part], radius[part]), (
                            want[0][part], want[1][:, part]))
            # Non-finite guesses: NaN there, the reference's answer for the others.
            bad = points.copy()
            bad[::7, 0], bad[3::7, 1], bad[5::7] = np.nan, np.inf, -np.inf
            finite = np.isfinite(bad).all(axis=1)
            got = windows._measure_compiled(kernels, polarity, bad, radius)
            assert np.isnan(got[0][~finite]).all() and np.isnan(got[1][:, ~finite]).all()
            with np.errstate(divide="ignore", invalid="ignore"):
                want = windows._measure_numpy(polarity, bad[finite], radius[finite])
            _agree((got[0][finite], got[1][:, finite]), want)


def test_window_kernel_measures_an_empty_list_and_refuses_an_image_smaller_than_a_window():
    windows = WindowCentroids(5)
    centres, measures = windows._measure_compiled(kernels, np.zeros((30, 30), np.uint8), np.empty((0, 2)), np.empty(0))
    assert centres.shape == (0, 2) and measures.shape == (3, 0)
    with pytest.raises(ValueError, match="smaller than a window"):
        windows._measure_compiled(kernels, np.zeros((8, 30), np.uint8), np.array([[4.0, 4.0]]), np.array([3.0]))


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_centre_step_kernel_agrees_with_the_reference(seed):
    # Tips under reflections with noise, from starts up to 0.8 px off and from between tips, in crops
    # whose edges cut windows; ellipses round and elongated; a neighbour at NaN (no pixel of its window counts).
    rng = np.random.default_rng(seed)
    truth = _grid(rng)
    axes = (2.1, 1.8) if seed % 2 else (2.0, 2.0)
    shape = np.broadcast_to(np.diag(np.square(axes)), (len(truth), 2, 2)).copy()
    scene = _scene(truth, shape, glare=70.0, noise=4.0, seed=seed)
    ellipses = np.tile([1 / axes[0] ** 2, 0.0, 1 / axes[1] ** 2], (len(truth), 1))
    for left, right in ((14, 160), (0, 60), (37, 101)):
        image = np.ascontiguousarray(scene[:, left:right])
        kept = (truth[:, 0] > left - 3) & (truth[:, 0] < right + 3)
        here = truth[kept] - [left, 0]
        start = here + rng.uniform(-0.8, 0.8, here.shape)
        start[0] = here[0] + [6.0, 0.0]  # between two tips
        distance, index = cKDTree(here).query(start, 7)
        nearest = distance[:, 1]
        reach = np.minimum(1.5 * 2.0 + 2.0, nearest - 1.0)
        neighbours = here[index[:, 1:]]
        neighbours[1, 0] = np.nan
        theta = np.concatenate([start, ellipses[kept]], axis=1)
        got = _centre_step(_Windows(image, start, reach, neighbours, nearest), theta, start)
        want = _centre_step_numpy(_Windows(image, start, reach, neighbours, nearest), theta, start)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-9)
        assert (want != start).any(axis=1).mean() > 0.5  # steps were taken (not all kept starts)


def test_the_environment_selects_the_numpy_reference(monkeypatch):
    monkeypatch.setattr(pins._kernels, "_NUMPY", True)
    assert compiled() is None
    monkeypatch.setattr(pins._kernels, "_NUMPY", False)
    assert compiled() is kernels


def test_the_environment_is_read_once_and_choose_switches(monkeypatch):
    # `compiled` runs ~17 times a frame: the environment is read at import (and by `choose()`), not per call.
    monkeypatch.setattr(pins._kernels, "_NUMPY", False)
    monkeypatch.setenv("TACTIP_KERNELS", "numpy")
    assert compiled() is kernels  # (read at every call before: None)
    assert pins._kernels.choose() == "compiled"  # (None: read the environment again)
    assert compiled() is None and compiled("_jit_pairs") is None
    assert pins._kernels.choose("compiled") == "numpy"
    assert compiled() is kernels
    monkeypatch.delenv("TACTIP_KERNELS")
    assert pins._kernels.choose(pins._kernels.choose("numpy")) == "numpy" and compiled() is kernels


@pytest.mark.parametrize("name, seed", [("radial-led-120", 1), ("tactip-331", 0)])
def test_tracking_through_slides_agrees_with_the_reference(name, seed, monkeypatch):
    # The whole tracker on the kernels and on the NumPy reference: the same lost and retired pins and
    # positions within 1e-6 px in every frame of two slides.
    s, run, drawn = slide_run(name, seed, [45, 270], distance_mm=8.0, rest_s=3 / 120,
                              press_s=0.1, slide_s=0.25, lift_s=0.05)
    tracks = []
    for choice in ("numba", "numpy"):
        monkeypatch.setattr(pins._kernels, "_NUMPY", choice == "numpy")
        tracker = PinTracker(detection=DetectionParams(dark_pins=s.dark_pins), disc=SensorDisc(*s.disc))
        tracker.start(run[0].image, pins=run[0].centres[drawn])
        tracks.append([(tracker.update(f.image), tracker.lost.copy(), tracker.retired.copy()) for f in run[1:]])
    for (positions, lost, retired), (want, want_lost, want_retired) in zip(*tracks):
        np.testing.assert_allclose(positions, want, rtol=0, atol=1e-6)
        np.testing.assert_array_equal(lost, want_lost)
        np.testing.assert_array_equal(retired, want_retired)
    assert np.nanmax(np.abs(tracks[0][len(run) // 3][0] - tracks[0][0][0])) > 5.0  # the pins moved
