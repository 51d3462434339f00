"""pins._window: windowed centroids, checked against the reference measurement they replaced (bit for
bit: the same windows give the same centroids and measures, and a tracker the same positions)."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

import pins._refine
from pins import DetectionParams, PinTracker, SensorDisc
from pins.disc import as_grey
from pins._window import _FLAT_RISE, _PHASES, _SIDE_RUN, WindowCentroids, _squared_norm
from tests.pins.conftest import preset_sensor, slide_run


class ReferenceWindows(WindowCentroids):
    """Windowed centroids measured as before the measurement was cut to fewer NumPy calls (kept
    here verbatim as the reference: each window gathered from a sliding view, its sums by
    reductions, its weights in uint8)."""

    def _measure(self, image, points, radius_px):
        """`WindowCentroids._measure` as it was before its calls were cut (commit 90a2d9c)."""
        half, side = self.half_px, 2 * self.half_px + 1
        n = len(points)
        if n == 0:
            return np.empty((0, 2)), np.empty((3, 0))
        # Called a few times a frame, mostly on a few dozen windows: each NumPy call's own cost
        # counts, so ufuncs and their reductions are called directly (not through array methods).
        image = np.ascontiguousarray(image)
        height, width = image.shape
        anchor = np.rint(points)
        corner = anchor.astype(np.intp)
        corner -= half
        # A negative corner, read as unsigned, lies beyond either bound: one comparison a side.
        inside = corner.view(np.uintp) <= np.array((width - side, height - side), np.uintp)
        fits = inside[:, 0] & inside[:, 1]
        corner *= fits[:, None]
        # All windows at once: a (H - side + 1, W - side + 1, side, side) sliding view, fancy-indexed.
        view = np.ndarray((height - side + 1, width - side + 1, side, side), np.uint8, image, 0, image.strides * 2)
        patches = view[corner[:, 1], corner[:, 0]].reshape(n, -1)  # (N, P) copy
        top = np.add.reduce(patches[:, self._top], axis=1, dtype=np.float64) / len(self._top)  # their mean
        # The local background: a plane through the darkest of the runs of `_SIDE_RUN` pixels along
        # each of the window's sides (left, right, top, bottom), where no neighbour's foot or glare
        # lies, a run averaging the noise down (gathered contiguous: reductions over strided sides
        # cost several times more). Judged above that plane, a tip on the slope of an LED
        # reflection or of a bright surround's veil is weighed as on a flat membrane: its centroid
        # is not pulled towards the bright side, nor is its contrast taken from a darkest pixel far
        # below it. The plane: its level at the centre and its rise across half the window (x, y).
        runs = np.add.reduce(patches[:, self._sides].reshape(n, 4, -1, _SIDE_RUN), axis=3, dtype=np.uint16)
        plane = np.matmul(np.minimum.reduce(runs, axis=2).astype(np.float64), self._side_plane)  # (N, 3)
        background = plane[:, 0]
        measures = np.empty((3, n))  # area, contrast, compactness
        area, contrast, compactness = measures
        np.subtract(top, background, out=contrast)  # the tip's height above the local background
        # A rise below `_FLAT_RISE` of the tip's contrast pulls no centroid (the threshold lies a
        # fifth of the way up), and there the plane is mostly noise, the pin's own shadow or the
        # skin's texture: the rise shrinks by that much (soft threshold), to nothing for most windows.
        rise = plane[:, 1:]
        shrink = _FLAT_RISE * contrast / np.sqrt(_squared_norm(rise))
        # (Windows without a tip of some contrast, a lost pin's empty window, need no plane.)
        sloped = np.flatnonzero((shrink < 1.0) & (contrast > self.least_contrast))  # NaN compares False
        lift = self.threshold_fraction * np.maximum(contrast, 0.0)
        if self.above_mean:
            # Above the window's mean too (over the plane, whose mean over the window is its centre
            # value): on a textured or shadowed skin the membrane's texture must not count.
            mean = np.add.reduce(patches, axis=1, dtype=np.float64) / patches.shape[1]
            lift = np.minimum(np.maximum(lift, mean - background), np.maximum(contrast, 0.0))
        level = background + lift  # the threshold at the window's centre, <= top
        # Windows on a slope (few) weigh their pixels above the threshold plane, in whole grey
        # levels so that weights stay integers; the others above a flat threshold, in uint8.
        if sloped.size:
            coefficients = np.empty((sloped.size, 3), np.float32)  # level, slope x, y (grey levels per px)
            coefficients[:, 0] = level[sloped]
            coefficients[:, 1:] = rise[sloped] * ((1.0 - np.maximum(shrink[sloped], 0.0)) / half)[:, None]
            tilted = np.rint(np.matmul(coefficients, self._plane))  # (k, P) threshold plane
            np.subtract(patches[sloped], tilted, out=tilted)
            np.maximum(tilted, 0.0, out=tilted)
        threshold = np.rint(level).astype(np.uint8)
        # Positive part of (pixel - threshold), in place, without leaving uint8.
        below = threshold[:, None]
        np.maximum(patches, below, out=patches)
        np.subtract(patches, below, out=patches)
        # Mask of the guess's quarter-pixel phase (in [-0.5, 0.5] where the window fits) and radius
        # (in quarter px, clipped to the masks'), as one index: (radius, phase y, phase x).
        phase = np.rint((points - anchor) * _PHASES)
        radius = np.rint(np.asarray(radius_px, dtype=np.float64) * _PHASES)
        np.fmin(np.maximum(radius, 1.0, out=radius), float(len(self._radii)), out=radius)  # NaN: the widest
        phases = self._n_phases
        mask = (radius * phases + phase[:, 1]) * phases + phase[:, 0]
        # Phases run from -_PHASES // 2 and radius indices from 1 (the mask of radius r/4 is row r - 1).
        mask += (_PHASES // 2) * (phases + 1) - phases * phases
        masks = self._masks[mask.astype(np.intp)]
        np.multiply(patches, masks, out=patches)
        weights = patches.astype(np.float32)
        if sloped.size:
            weights[sloped] = tilted * masks[sloped]
        # (N, 4): mass, sum x, sum y, sum r^2; in blocks of rows that keep OpenBLAS on one thread.
        rows = self._moment_rows
        if n <= rows:
            moments = np.matmul(weights, self._moments)
        else:
            moments = np.empty((n, 4), np.float32)
            for row in range(0, n, rows):
                np.matmul(weights[row:row + rows], self._moments, out=moments[row:row + rows])
        moments = moments.astype(np.float64)
        mass = moments[:, 0]
        moments[:, 1:] /= mass[:, None]  # centroid offset (x, y) and mean r^2
        offset = moments[:, 1:3]
        np.divide(mass, top - level, out=area)
        # Mean squared distance from the centroid; a disc of area A has A / (2 pi).
        spread = moments[:, 3] - _squared_norm(offset)
        np.divide(area, 2 * np.pi * spread, out=compactness)
        centres = anchor + offset
        centres[~fits | (mass <= 0)] = np.nan
        return centres, measures


def _windows_like(windows, cls):
    """A `cls` with the same settings and learnt state as `windows`."""
    other = cls(windows.half_px, threshold_fraction=windows.threshold_fraction, above_mean=windows.above_mean)
    other.least_contrast = windows.least_contrast
    return other


def test_an_image_smaller_than_a_window_raises_a_clear_value_error():
    windows = WindowCentroids(4)
    with pytest.raises(ValueError, match="smaller than a window of 9x9 px"):
        windows.measure(np.zeros((8, 40), np.uint8), np.array([[4.0, 4.0]]), np.array([3.0]))
    # One px more fits one window.
    centres, _ = windows.measure(np.full((9, 9), 10, np.uint8), np.array([[4.0, 4.0]]), np.array([3.0]))
    assert centres.shape == (1, 2)


@pytest.mark.parametrize("name", ["tactip-331", "radial-led-120", "brown-127", "rim-ring-331", "dark-331"])
@pytest.mark.parametrize("above_mean", [False, True])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_windows_equal_the_reference_bit_for_bit(name, above_mean, seed):
    # Windows on tips, between them, half off the image and on the blank surround, of every
    # radius and quarter-px phase, with and without a least contrast (the sloped planes).
    rng = np.random.default_rng(seed)
    s = preset_sensor(name, seed)
    rest = s.render()
    image = as_grey(rest.image)
    image = 255 - image if s.dark_pins else image  # bright pins, as the tracker measures them
    # Windows about half the pin spacing, as the tracker sizes them, and narrower and wider.
    half = int(np.ceil(0.5 * np.median(cKDTree(rest.centres).query(rest.centres, k=2)[0][:, 1])))
    points = np.concatenate([rest.centres + rng.normal(0.0, 1.0, rest.centres.shape),
                             rng.uniform(-5.0, np.array(image.shape[::-1]) + 5.0, (60, 2))])
    radius = np.concatenate([rng.uniform(0.0, half + 2.0, len(points) - 2), [np.nan, -1.0]])
    for half_px in (max(half - 2, 2), half, half + 4):
        windows = WindowCentroids(half_px, above_mean=above_mean)
        for least in (0.0, 30.0):
            windows.least_contrast = least
            reference = _windows_like(windows, ReferenceWindows)
            got, want = windows.measure(image, points, radius), reference.measure(image, points, radius)
            np.testing.assert_array_equal(got[0], want[0])
            np.testing.assert_array_equal(got[1], want[1])
            np.testing.assert_array_equal(windows.contrast(image, points), got[1][1])  # the contrast alone
            assert np.isfinite(got[0]).sum() > len(rest.centres) // 2  # most windows hold a tip
            # A few windows at a time (most of the tracker's calls; their sums are taken another way).
            for part in np.array_split(np.arange(len(points)), len(points) // 7):
                few = windows.measure(image, points[part], radius[part])
                want = reference.measure(image, points[part], radius[part])
                np.testing.assert_array_equal(few[0], want[0])
                np.testing.assert_array_equal(few[1], want[1])
                np.testing.assert_array_equal(windows.contrast(image, points[part]), few[1][1])


@pytest.mark.parametrize("name, seed", [("radial-led-120", 0), ("radial-led-120", 3), ("tactip-331", 1)])
def test_tracking_through_slides_gives_the_reference_positions(name, seed, monkeypatch):
    # The whole tracker (rest passes, following, search, snap to rest) on the reference windows and
    # on the measured ones: the same positions, lost and retired pins in every frame.
    s, run, drawn = slide_run(name, seed, [0, 135], distance_mm=8.0, rest_s=3 / 120,
                              press_s=0.1, slide_s=0.25, lift_s=0.05)
    tracks = []
    for windows in (WindowCentroids, ReferenceWindows):
        monkeypatch.setattr(pins._refine, "WindowCentroids", windows)
        tracker = PinTracker(detection=DetectionParams(dark_pins=s.dark_pins), disc=SensorDisc(*s.disc))
        tracker.start(run[0].image, pins=run[0].centres[drawn])
        assert type(tracker.windows) is windows
        tracks.append([(tracker.update(f.image), tracker.lost.copy(), tracker.retired.copy()) for f in run[1:]])
    for (positions, lost, retired), (want, want_lost, want_retired) in zip(*tracks):
        np.testing.assert_array_equal(positions, want)
        np.testing.assert_array_equal(lost, want_lost)
        np.testing.assert_array_equal(retired, want_retired)
    # The slides moved the pins (the comparison is not of still frames).
    assert np.nanmax(np.abs(tracks[0][len(run) // 3][0] - tracks[0][0][0])) > 5.0
