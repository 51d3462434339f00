"""Windowed centroids of pin tips, for `pins._refine.Refiner` (paper 002, III-A.3).

All windows are gathered at once from the grey crop (a fancy index into its sliding-window view,
as `numpy.lib.stride_tricks.sliding_window_view` makes) and processed as one (N, P) array,
O(pins x window). `pins._refine` says how the centroids are used and judged.

That NumPy code is the reference: unless ``TACTIP_KERNELS=numpy`` or Numba is missing
(`pins._kernels`), `WindowCentroids.measure` and `WindowCentroids.contrast` run compiled kernels
(`pins._jit`: the same arithmetic, a loop over the windows, bit for bit the same answers) in one
call instead of a few dozen NumPy calls, whose fixed cost, not the pixels, set the time.
"""

from __future__ import annotations

import numpy as np

from ._kernels import compiled

__all__ = ["WindowCentroids"]

# Sub-pixel steps per px of the window masks' centres and radii.
_PHASES = 4
_SINGLE_THREAD_MACS = 262_143
# The background plane's rise across half a window counts only beyond this fraction of the tip's
# contrast (renders: the brown skin's pin shadows and mottling, and the noise of the sides' darkest
# pixels, rise by 2-8 % of it and would bias centroids by 0.1 px; an LED reflection on a faint tip
# rises by 20-50 %).
_FLAT_RISE = 0.1
# The background of a window's side is its darkest run of this many pixels (the mean of a run).
_SIDE_RUN = 4
# Windows x pixels up to which one float32 product sums the windows' pixels (fewer NumPy calls);
# beyond, reductions of the gathered pixels cost less (measured at 9x9, 13x13 and 19x19 windows:
# 120 9 x 9 windows 22 us against 31, 40 19 x 19 ones alike).
_PRODUCT_PIXELS = 12288
# Window pixels up to which the masks are gathered as float32 (9 x 9 px windows: 1.2 of 4.9 us a
# product saved on 25 windows); beyond, as uint8 and cast in the product (19 x 19 px: cheaper so).
_FLOAT_MASK_PIXELS = 169

class WindowCentroids:
    """Centroids of pin tips in square windows of side ``2 * half_px + 1`` around guesses.

    Parameters
    ----------
    half_px : int
        Half side of the windows, px: about half the pin spacing (masks reach half_px + 0.5 at most).
    threshold_fraction : float
        Where the threshold sits between the local background (a plane through the darkest runs of
        pixels along the window's sides) and the pin's top, in (0, 1).
    above_mean : bool
        Keep the threshold at least at the window's mean (textured skins, small tips).

    Attributes
    ----------
    least_contrast : float
        Windows whose tip rises less above the background, grey levels, weigh their pixels over a
        flat threshold whatever the plane's slope (no tip to pull; `Refiner` sets a quarter of the
        faintest tips' contrast at rest).
    """

    def __init__(self, half_px: int, *, threshold_fraction: float = 0.2, above_mean: bool = False) -> None:
        if int(half_px) != half_px or half_px < 2:
            raise ValueError(f"half_px must be an integer >= 2, got {half_px}")
        if not 0.0 < threshold_fraction < 1.0:
            raise ValueError(f"threshold_fraction must be in (0, 1), got {threshold_fraction}")
        self.half_px = int(half_px)
        self.threshold_fraction = float(threshold_fraction)
        self.above_mean = bool(above_mean)
        self.least_contrast = 0.0
        side = 2 * self.half_px + 1
        offsets = np.arange(-self.half_px, self.half_px + 1, dtype=np.float32)
        gy, gx = (a.ravel() for a in np.meshgrid(offsets, offsets, indexing="ij"))
        # Moments of each window pixel: mass, x, y and squared distance from the window's centre pixel.
        self._moments = np.column_stack([np.ones_like(gx), gx, gy, gx * gx + gy * gy])  # (P, 4)
        middle = gx.size // 2
        self._top = np.array([middle, middle - 1, middle + 1, middle - side, middle + side])
        # Disc masks for every quarter-pixel centre in [-0.5, 0.5]^2 and radius up to half_px + 0.5.
        phases = np.arange(-_PHASES // 2, _PHASES // 2 + 1) / _PHASES
        self._radii = np.arange(1, (self.half_px + 0.5) * _PHASES + 1) / _PHASES
        dx2 = (gx[None, :] - phases[:, None]) ** 2  # (phase x, P)
        dy2 = (gy[None, :] - phases[:, None]) ** 2  # (phase y, P)
        d2 = dy2[:, None, :] + dx2[None, :, :]  # (phase y, phase x, P)
        masks = d2[None] <= (self._radii ** 2)[:, None, None, None]
        self._n_phases = len(phases)
        self._masks = masks.reshape(-1, gx.size).astype(np.uint8)  # (radius, phase y, phase x) -> P
        # The masks `_measure` gathers: float32 on small windows (no cast in the product with the
        # weights), uint8 on large ones (a quarter of the bytes to gather; `_FLOAT_MASK_PIXELS`).
        self._gathered_masks = self._masks.astype(np.float32) if gx.size <= _FLOAT_MASK_PIXELS else self._masks
        # The four sides' pixels (left, right, top, bottom) and each pixel's (x, y) for the
        # threshold plane.
        index = np.arange(gx.size).reshape(side, side)
        # Runs of `_SIDE_RUN` pixels end to end along the middle of each side: (4 x runs x run,).
        runs = side // _SIDE_RUN
        middle = slice((side - runs * _SIDE_RUN) // 2, (side - runs * _SIDE_RUN) // 2 + runs * _SIDE_RUN)
        self._sides = np.concatenate([index[middle, 0], index[middle, -1], index[0, middle], index[-1, middle]])
        # (level, rise x, rise y) of the plane through the four sides' values: (4, 3).
        self._side_plane = np.array([[0.25, -0.5, 0.0], [0.25, 0.5, 0.0], [0.25, 0.0, -0.5], [0.25, 0.0, 0.5]]) / _SIDE_RUN
        self._plane = np.stack([np.ones_like(gx), gx, gy]).astype(np.float32)  # (3, P): 1, x and y of each pixel
        # Rows of the moment product per call: OpenBLAS keeps to one thread below 2^18 multiply-adds
        # (4 moments of P pixels a row; `_dot`).
        self._moment_rows = max(1, _SINGLE_THREAD_MACS // (4 * gx.size))
        # Columns summing the five centre pixels, the sides' runs (run by run, each of the sides left,
        # right, top, bottom) and the whole window: (P, 1 + runs x 4 + 1), float32.
        sums = np.zeros((gx.size, 2 + len(self._sides) // _SIDE_RUN), np.float32)
        sums[self._top, 0] = 1.0
        run = np.arange(len(self._sides)) // _SIDE_RUN  # (side, run along it), side-major
        sums[self._sides, 1 + (run % runs) * 4 + run // runs] = 1.0
        sums[:, -1] = 1.0
        self._sums = sums
        self._runs = runs
        self._counts = np.array([float(len(self._top)), float(gx.size)])  # the pixels the first and last columns sum
        self._product_pixels = min(_PRODUCT_PIXELS, _SINGLE_THREAD_MACS // sums.shape[1])
        # The mask index (radius, phase y, phase x) from the phases (x, y) in quarter px and the radius.
        # (x, y phase and radius, in quarter px) -> (radius, phase y, phase x) index, less `_mask_base`.
        self._mask_base = float((_PHASES // 2) * (self._n_phases + 1) - self._n_phases ** 2)
        # (Its fourth step takes `_mask_base` from a column of ones scaled to quarter px: exact, -13 / 4.)
        self._mask_steps = np.array([1.0, float(self._n_phases), float(self._n_phases ** 2), self._mask_base / _PHASES])
        self._layouts: dict = {}
        self._viewed = (None, None, None)  # (image, corner bounds, sliding view): the last image measured

    def __repr__(self) -> str:
        return (f"WindowCentroids(half_px={self.half_px}, threshold_fraction={self.threshold_fraction}, "
                f"above_mean={self.above_mean})")

    def levels(self, image: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Darkest pixel, median and tip top (the mean of the five centre pixels) of each window, grey levels.

        Windows at the finite `points` (N, 2), px, that fit in `image`; NaN elsewhere. (N,) each.
        """
        side = 2 * self.half_px + 1
        image = np.ascontiguousarray(image)
        height, width = image.shape
        corner = np.rint(points).astype(np.intp) - self.half_px
        fits = ((corner >= 0).all(axis=1) & (corner[:, 0] <= width - side) & (corner[:, 1] <= height - side))
        out = np.full((3, len(points)), np.nan)
        if fits.any():
            view = np.ndarray((height - side + 1, width - side + 1, side, side), np.uint8, image, 0,
                              image.strides * 2)
            patches = view[corner[fits, 1], corner[fits, 0]].reshape(int(fits.sum()), -1)
            out[:, fits] = (patches.min(axis=1), np.median(patches, axis=1), patches[:, self._top].mean(axis=1))
        return out[0], out[1], out[2]

    def slopes(self, image: np.ndarray, points: np.ndarray) -> np.ndarray:
        """How steep each window's background is: the rise of its plane (through the darkest runs of its
        sides, as `measure` fits it) across half the window over the tip's contrast above it, (N,).

        Windows at the finite `points` (N, 2), px, that fit in `image`; NaN elsewhere (and inf where
        no tip rises). Beyond `_FLAT_RISE` the window tilts its threshold: the tip lies on a slope.
        """
        n = len(points)
        out = np.full(n, np.nan)
        if n == 0:
            return out
        bounds, view = self._view(image)
        corner = np.rint(points).astype(np.intp) - self.half_px
        fits = (corner.view(np.uintp) <= bounds).all(axis=1)
        patches = view[corner[fits, 1], corner[fits, 0]].reshape(int(fits.sum()), -1)
        top, darkest, _ = self._sums_of(patches, patches.astype(np.float32))
        plane = np.dot(darkest, self._side_plane)
        with np.errstate(divide="ignore", invalid="ignore"):
            out[fits] = np.sqrt(_squared_norm(plane[:, 1:])) / np.maximum(top - plane[:, 0], 0.0)
        return out

    def contrast(self, image: np.ndarray, points: np.ndarray) -> np.ndarray:
        """The tips' contrast alone, grey levels (N,): `measure`'s (its second row), at a fraction of its cost.

        The top (the mean of the five centre pixels) above the plane through the darkest runs of the
        sides, at the window's centre, of the windows at the finite `points` (N, 2), px; a window that
        does not fit in `image` is measured at the image's corner, as `measure` measures it. No mask
        and no weights: the contrast depends on neither (`Refiner.fit_tips` asks for it before and
        after each fit).
        """
        n = len(points)
        if n == 0:
            return np.empty(0)
        kernels = compiled()
        if kernels is not None:  # (the compiled kernel, `pins._jit.window_contrast`: one call)
            image, points = self._kernel_arguments(image, points)
            return kernels.window_contrast(image, points, self.half_px)
        return self._contrast_numpy(image, points)

    def _contrast_numpy(self, image: np.ndarray, points: np.ndarray) -> np.ndarray:
        """`contrast` in NumPy: the reference of the compiled kernel."""
        n = len(points)
        bounds, view = self._view(image)
        corner = np.rint(points).astype(np.intp)
        corner -= self.half_px
        inside = corner.view(np.uintp) <= bounds
        if np.count_nonzero(inside) < inside.size:
            corner *= (inside[:, 0] & inside[:, 1])[:, None]
        patches = view[corner[:, 1], corner[:, 0]].reshape(n, -1)
        top, darkest, _ = self._sums_of(patches, patches.astype(np.float32))
        return top - np.dot(darkest, self._side_plane[:, 0])

    def __call__(self, image: np.ndarray, points: np.ndarray,
                 radius_px: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Centroids of the bright tips around `points`.

        Parameters
        ----------
        image : (H, W) ndarray of uint8
            Grey image, bright pins on a dark membrane.
        points : (N, 2) ndarray
            Finite guesses (x, y), px.
        radius_px : (N,) ndarray
            Radius of each mask, px (a little more than half the distance to the nearest
            neighbouring pin); clipped to [0.25, half_px + 0.5].

        Returns
        -------
        centres : (N, 2) ndarray of float64
            Weighted centroids (x, y), px; NaN where the window is empty or does not fit in the image.
        area : (N,) ndarray of float64
            Mass over the threshold-to-top height: about the tip's area, px.
        contrast : (N,) ndarray of float64
            Pin top minus the local background (the plane through the darkest runs of pixels along
            the window's sides, at its centre), grey levels; negative where no tip rises above it.
        compactness : (N,) ndarray
            Area over 2 pi times the weights' mean squared distance from the centroid: 1 for a
            uniform disc, more for a domed tip, less for an elongated one or one with a speck.
        """
        centres, measures = self.measure(image, points, radius_px)
        return centres, measures[0], measures[1], measures[2]

    def measure(self, image: np.ndarray, points: np.ndarray, radius_px: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """As `__call__`: the centroids (N, 2), px, and (area, contrast, compactness) stacked (3, N)."""
        # Empty windows and flat planes divide by zero (NaN and inf are the answers there): one
        # error state for the whole measurement, which runs a few times a frame on a few windows.
        with np.errstate(divide="ignore", invalid="ignore"):
            return self._measure(image, points, radius_px)

    def _layout(self, shape: tuple[int, int]) -> tuple[np.ndarray, tuple[int, int, int, int]]:
        """Per image size (H, W): the bounds (2,) of a window's corner (x, y), px, as uintp, and the
        shape of the image's sliding-window view (H - side + 1, W - side + 1, side, side). Cached.

        Raises ValueError when the image is smaller than a window.
        """
        layout = self._layouts.get(shape)
        if layout is None:
            side = 2 * self.half_px + 1
            height, width = shape
            if height < side or width < side:
                raise ValueError(f"image of {width}x{height} px is smaller than a window of {side}x{side} px "
                                 f"(half_px={self.half_px})")
            layout = (np.array((width - side, height - side), np.uintp), (height - side + 1, width - side + 1, side, side))
            self._layouts[shape] = layout
        return layout

    def _view(self, image: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The bounds of a window's corner (`_layout`) and the (H - side + 1, W - side + 1, side, side)
        sliding-window view of a grey `image`; kept for the last image (a frame's windows are measured
        a few times, on the same crop)."""
        seen, bounds, view = self._viewed
        if image is seen:
            return bounds, view
        contiguous = np.ascontiguousarray(image)
        bounds, view_shape = self._layout(contiguous.shape)
        view = np.ndarray(view_shape, np.uint8, contiguous, 0, contiguous.strides * 2)
        if contiguous is image:  # (a copy would not show later changes to the image)
            self._viewed = (image, bounds, view)
        return bounds, view

    def _sums_of(self, patches: np.ndarray, grey: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """Of (N, P) uint8 windows (`grey`: the same as float32): the tip's top (the mean of the five centre pixels, (N,)), the darkest
        run of `_SIDE_RUN` pixels along each side (left, right, top, bottom; their sums, (N, 4)) and,
        with `above_mean`, the window's mean (N,, else None), float64, grey levels.

        A few windows (most calls): one float32 product gives every sum (exact: integers below 2^24),
        in a few NumPy calls; many pixels: reductions of the pixels gathered, cheaper per pixel.
        """
        n, pixels = patches.shape
        if n * pixels <= self._product_pixels:
            # (Few enough multiply-adds for one BLAS thread.)
            sums = np.dot(grey, self._sums).astype(np.float64)
            # The darkest run of each side: a pairwise minimum over the few runs (a reduction's own
            # cost is several of them).
            darkest = sums[:, 1:5]
            for run in range(1, self._runs):
                darkest = np.minimum(darkest, sums[:, 1 + 4 * run:5 + 4 * run])
            if not self.above_mean:
                return sums[:, 0] / len(self._top), darkest, None
            scaled = sums[:, ::sums.shape[1] - 1] / self._counts  # (top, mean): the first and last columns
            return scaled[:, 0], darkest, scaled[:, 1]
        top = np.add.reduce(patches[:, self._top], axis=1, dtype=np.float64) / len(self._top)
        # (Gathered contiguous: reductions over strided sides cost several times more.)
        runs = np.add.reduce(patches[:, self._sides].reshape(n, 4, -1, _SIDE_RUN), axis=3, dtype=np.uint16)
        darkest = np.minimum.reduce(runs, axis=2).astype(np.float64)
        mean = np.add.reduce(patches, axis=1, dtype=np.float64) / pixels if self.above_mean else None
        return top, darkest, mean

    def _measure(self, image: np.ndarray, points: np.ndarray, radius_px: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """`measure`'s work: the compiled kernel (`pins._jit.window_measure`, one call) or, with
        ``TACTIP_KERNELS=numpy`` or without Numba (`pins._kernels`), the NumPy reference."""
        kernels = compiled()
        if kernels is None:
            return self._measure_numpy(image, points, radius_px)
        return self._measure_compiled(kernels, image, points, radius_px)

    def _measure_compiled(self, kernels, image: np.ndarray, points: np.ndarray,
                          radius_px: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """`_measure` by the compiled kernel `kernels.window_measure` (`kernels`: `pins._jit`)."""
        if len(points) == 0:
            return np.empty((0, 2)), np.empty((3, 0))
        image, points = self._kernel_arguments(image, points)
        if not (type(radius_px) is np.ndarray and radius_px.dtype == np.float64 and radius_px.shape == (len(points),)
                and radius_px.flags.c_contiguous):
            radius_px = np.ascontiguousarray(np.broadcast_to(radius_px, len(points)), dtype=np.float64)
        return kernels.window_measure(image, points, radius_px, self.half_px, self.threshold_fraction, self.above_mean,
                                      float(self.least_contrast))

    def _kernel_arguments(self, image: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """`image` and `points` as the kernels are compiled for them: C-contiguous uint8 (H, W) and float64
        (N, 2) (no copy when they are). Raises ValueError when the image is smaller than a window."""
        if image.shape not in self._layouts:
            self._layout(image.shape)
        if not (image.flags.c_contiguous and image.dtype == np.uint8):
            image = np.ascontiguousarray(image, dtype=np.uint8)
        if not (type(points) is np.ndarray and points.dtype == np.float64 and points.flags.c_contiguous):
            points = np.ascontiguousarray(points, dtype=np.float64)
        return image, points.reshape(-1, 2)

    def _measure_numpy(self, image: np.ndarray, points: np.ndarray, radius_px: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """`_measure` in NumPy: the reference of the compiled kernel."""
        half = self.half_px
        n = len(points)
        if n == 0:
            return np.empty((0, 2)), np.empty((3, 0))
        # Called a few times a frame, mostly on a few dozen windows: each NumPy call's own cost
        # counts, so the work is in as few calls as possible (ufuncs and np.dot called directly).
        seen, bounds, view = self._viewed
        if image is not seen:  # (a frame's windows are measured a few times on the same crop)
            bounds, view = self._view(image)
        anchor = np.rint(points)
        corner = anchor.astype(np.intp)
        corner -= half
        # A negative corner, read as unsigned, lies beyond either bound: one comparison a side.
        inside = corner.view(np.uintp) <= bounds
        everywhere = np.count_nonzero(inside) == inside.size  # (`ndarray.all` costs 3x more)
        if not everywhere:
            fits = inside[:, 0] & inside[:, 1]
            corner *= fits[:, None]  # a window that does not fit: the image's corner's (its centre NaN)
        # All windows at once: a (H - side + 1, W - side + 1, side, side) sliding view, fancy-indexed.
        patches = view[corner[:, 1], corner[:, 0]].reshape(n, -1)  # (N, P) copy
        weights = patches.astype(np.float32)  # the pixels' grey levels, then (in place) their weights
        top, darkest, mean = self._sums_of(patches, weights)
        # The local background: a plane through the darkest of the runs of `_SIDE_RUN` pixels along
        # each of the window's sides (left, right, top, bottom), where no neighbour's foot or glare
        # lies, a run averaging the noise down. Judged above that plane, a tip on the slope of an LED
        # reflection or of a bright surround's veil is weighed as on a flat membrane: its centroid
        # is not pulled towards the bright side, nor is its contrast taken from a darkest pixel far
        # below it. The plane: its level at the centre and its rise across half the window (x, y).
        plane = np.dot(darkest, self._side_plane)  # (N, 3)
        background = plane[:, 0]
        measures = np.empty((3, n))  # area, contrast, compactness
        contrast = np.subtract(top, background, out=measures[1])  # the tip's height above the local background
        # A rise below `_FLAT_RISE` of the tip's contrast pulls no centroid (the threshold lies a
        # fifth of the way up), and there the plane is mostly noise, the pin's own shadow or the
        # skin's texture: the rise shrinks by that much (soft threshold), to nothing for most windows.
        rise = plane[:, 1:]
        shrink = _FLAT_RISE * contrast / np.sqrt(_squared_norm(rise))
        # (Windows without a tip of some contrast, a lost pin's empty window, need no plane.)
        sloped = (shrink < 1.0) & (contrast > self.least_contrast)  # NaN compares False
        positive = np.maximum(contrast, 0.0)
        lift = self.threshold_fraction * positive
        if self.above_mean:
            # Above the window's mean too (over the plane, whose mean over the window is its centre
            # value): on a textured or shadowed skin the membrane's texture must not count.
            lift = np.minimum(np.maximum(lift, mean - background), positive)
        level = background + lift  # the threshold at the window's centre, <= top
        # Each pixel weighs its grey level above the threshold (its positive part), in whole grey levels
        # so that weights are integers: windows on a slope above the threshold plane, the others above
        # a flat threshold. One plane for all (fewer NumPy calls): a flat window's has no slope and its
        # level already whole (rounded in float64, as its threshold always was), so that it is exact.
        # (Written as float32 by the ufuncs themselves: computed in float64 and cast, as assigned.)
        coefficients = np.empty((n, 3), np.float32)  # level, slope x, y (grey levels per px)
        np.rint(level, out=coefficients[:, 0])
        np.copyto(coefficients[:, 0], level, where=sloped)
        np.multiply(rise, np.where(sloped, (1.0 - np.maximum(shrink, 0.0)) / half, 0.0)[:, None],
                    out=coefficients[:, 1:])
        np.subtract(weights, np.rint(np.dot(coefficients, self._plane)), out=weights)
        np.maximum(weights, 0.0, out=weights)
        # Mask of the guess's quarter-pixel phase (in [-0.5, 0.5] where the window fits) and radius
        # (in quarter px, clipped to the masks'), as one index: (radius, phase y, phase x). All three in
        # quarter px in one (N, 4) array: a few calls on it instead of one each per column (exact: small
        # integers); its last column a 1 that carries `_mask_base` through the product.
        quarters = np.empty((n, 4))
        np.subtract(points, anchor, out=quarters[:, :2])
        quarters[:, 2] = radius_px
        quarters[:, 3] = 1.0
        quarters *= _PHASES
        np.rint(quarters, out=quarters)
        radius = quarters[:, 2]
        np.fmin(np.maximum(radius, 1.0, out=radius), float(len(self._radii)), out=radius)  # NaN: the widest
        # Phases run from -_PHASES // 2 and radius indices from 1 (the mask of radius r/4 is row r - 1).
        mask = np.dot(quarters, self._mask_steps)
        np.multiply(weights, self._gathered_masks[mask.astype(np.intp)], out=weights)
        # (N, 4): mass, sum x, sum y, sum r^2.
        moments = (np.dot(weights, self._moments) if n <= self._moment_rows
                   else _dot(weights, self._moments, self._moment_rows)).astype(np.float64)
        mass = moments[:, 0]
        # Centroid offset (x, y) and mean r^2; an empty window (no mass) gives NaN. (A new array: in
        # place, the divisor's overlap with the quotient costs numpy a buffered pass, twice the time.)
        means = moments[:, 1:] / moments[:, :1]
        offset = means[:, :2]
        np.divide(mass, top - level, out=measures[0])
        # Mean squared distance from the centroid; a disc of area A has A / (2 pi).
        spread = means[:, 2] - _squared_norm(offset)
        np.divide(measures[0], 2 * np.pi * spread, out=measures[2])
        centres = anchor + offset
        if not everywhere:
            centres[~fits] = np.nan
        return centres, measures


def _dot(a: np.ndarray, b: np.ndarray, rows: int) -> np.ndarray:
    """``a @ b`` of float32 matrices, in blocks of `rows` rows of `a` that keep OpenBLAS on one thread.

    Threaded, these tiny products cost 20 ms on a busy machine instead of 0.2.
    """
    if len(a) <= rows:
        return np.dot(a, b)
    out = np.empty((len(a), b.shape[1]), np.float32)
    for row in range(0, len(a), rows):
        np.dot(a[row:row + rows], b, out=out[row:row + rows])
    return out


def _squared_norm(vectors: np.ndarray) -> np.ndarray:
    """x^2 + y^2 of (..., 2) vectors (as ``np.einsum("...d,...d->...")`` gives it, at half its cost)."""
    square = vectors * vectors
    return square[..., 0] + square[..., 1]
