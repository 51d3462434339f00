"""Windowed following, refinement, search and recovery of tracked pins, for `pins.track.PinTracker`
(paper 002, III-A.3).

Refinement. Lucas-Kanade errors add up from frame to frame, so each tracked pin is moved onto
the intensity-weighted centroid of its tip in a small window around its estimate (its guess,
`Refiner.follow`, or its LK estimate, `Refiner.refine`; `WindowCentroids`). All windows are gathered at once from the grey crop (a fancy index into its
sliding-window view, as `numpy.lib.stride_tricks.sliding_window_view` makes) and processed as
one (N, P) array (uint8 pixels, float32 weights), O(pins x window):

1. the threshold of each window lies above its local background, a plane through the darkest
   runs of pixels along the window's four sides (`pins._window`; tilted only where it rises by
   more than a tenth of the tip's contrast: an LED reflection's or a veil's flank), by
   `threshold_fraction` of the way up to the pin's top (the mean of the five pixels at the
   window's centre), so that membrane noise never counts and the whole tip above its foot does,
   and at least the window's mean on textured skins;
2. each pixel is weighted by its grey level above the threshold (the positive part);
3. a disc mask centred on the estimate (to a quarter pixel) keeps the pixels nearer to it than
   0.55 of the distance to the nearest neighbouring pin, and no farther than 1.6 tip radii
   (measured at rest) plus 1.5 px, less membrane: that disc lies inside the pin's own
   Voronoi cell but for a sliver that holds at most the neighbour's foot, below the threshold,
   so no neighbour's pixels count, even when contact pushes pins together;
4. the weighted centroid (zeroth, first and second moments, one matrix product) is the centre.

Following (`pins._follow`): windows at the constant-velocity guesses, re-centred; a pin whose
window settles near its guess needs no LK.

A point-symmetric tip whose foot lies inside the mask gives its centre whatever the threshold;
a tip cut by the mask (near the rim, seen obliquely; pushed against a neighbour) is cut
symmetrically when the estimate is good, as LK's is (a few hundredths of a px). On renders with
noise sigma 4, gradient and glare, at rest and under 5 mm contact, this gives 0.02-0.03 px RMSE
against ground truth (blob detection: 0.03).

Plausibility. A centroid is kept when it lies within 0.03 pin spacings (0.4 px at least) of the
LK estimate (half a px at 331 pins in 640x480), and the tip's area (mass over the threshold-to-top height, px),
contrast (top minus darkest pixel) and compactness (area over 2 pi times the mean squared
distance from the centroid: 1 for a disc) are like the pin's own at rest (`pins._like`): a hidden pin
has no contrast; a neighbour, glare or a speck in the window pulls the centroid, adds area and spreads
the mass. A faint tip (by an LED reflection) whose contrast at rest lies within a few times its scatter
in the rest frame's noise of nothing shows no area or compactness to be judged by: its contrast alone
bounds it, and its window places it only while it is still (`still`). Limit: a small bright speck detached from a tip but inside its window pulls it by less
than that bound (up to 0.5 px in tests where blob detection would have kept them apart); a speck
touching a tip fools blob detection as much.

Search. A lost pin (or one whose centroid is implausible) is looked for in a window at its
predicted position (where it was last seen, moved as its neighbours moved since: `pins._predict`),
re-centred once; it is found when that move is at most 0.1 spacings, its tip is like
at rest, it lies within the gate (below half the spacing) of the prediction and no neighbour sits
on the same tip (`Refiner._one_pin_per_tip`), nor any pin expected nearer to it (`pins._identity`).
Only pins whose predictions can be trusted are searched for (`Refiner._trusted`).

Fitting. A faint tip on a slope (a reflection's flank, the veil of a bright surround over the outer
ring) is paint: it hides the light behind it, which no background subtracted before a centroid
models, so its window may count the bright side as tip (twice its area at rest) and lose it, and
blob detection may too. A pin whose window at rest lies on such a slope (`sloped`: the window
tilts its threshold there), placed in the last frame and missing now, is fitted as an opaque
ellipse over a quadratic membrane where its window shows a tip (`pins._recover`, `fit_tips`; the
model of `pins._tipfit`, its ellipse its own at rest). On radial-led-120's 4 mm tap through mp4v,
seeds 0-11, this keeps 98.9-100 % of the visible pin-frames (windows alone: 95.5-98.5 %).

The follow passes (`pins._follow`), the still pad and rest (`pins._rest`, with the noise estimates of
`pins._noise`) and recovery from blobs (`pins._recover`) live in their own modules; `Refiner`
inherits their steps.
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy.spatial import cKDTree

from .detect import DetectionParams
from .disc import SensorDisc
from ._flat import _pin_radius_px
from ._identity import IDENTITY_NEIGHBOURS, keep_own_tips, squared_distances
from ._follow import _GUESS_FRACTION, _SAME_TIP_FRACTION, _Following
from ._predict import _Prediction
from ._tipfit import _SHAPE_NEIGHBOURS, _fittable, tip_shapes
from ._recover import _Recovery, match_to_blobs
from ._kernels import compiled
from ._like import bounds_at_rest, contrast_noise
from ._rest import _AtRest, noisy_copies
from ._window import _FLAT_RISE, WindowCentroids, _squared_norm

__all__ = ["match_to_blobs", "WindowCentroids", "Refiner"]

_TIP_REACH = 1.6
_TIP_MARGIN_PX = 1.5
# A skin is textured when, in the median window at rest, the window's median lies more than this
# fraction of the way from its darkest pixel to the tip's top (0.08 on plain membranes, 0.34 on
# the brown skin preset); tips smaller than this radius, px, are small.
_TEXTURE_GAP = 0.2
_SMALL_TIP_PX = 3.0
# A windowed centroid is plausible when it lies within this fraction of the pin spacing of the LK
# estimate, and the tip is like the pin's own at rest (`pins._like`).
_MAX_SHIFT_FRACTION = 0.03
# Neighbours whose distance bounds each refinement window (a hexagonal lattice has six), and the
# window's radius as a fraction of the distance to the nearest one (see `Refiner.window_radius`).
_WINDOW_NEIGHBOURS = 6
_WINDOW_REACH = 0.55
# A searched pin is found when its second window moved by at most this fraction of the pin
# spacing (its tip, of radius ~0.3 spacings, then lies whole inside the window of radius ~0.55),
# and two positions nearer than this fraction of the spacing are one tip (tips of neighbours
# pushed together stay more than half a spacing apart).
_SEARCH_SETTLED_FRACTION = 0.1
# Passes of mean shift that take the given rest positions to the windows' fixed points.
_REST_PASSES = 4
_MIN_SHIFT_PX = 0.4
_MIN_GUESS_PX = 0.1
# Two tips whose centres lie nearer than this many tip radii (at rest) overlap: one blob, which no one-tip
# fit parts (issue 20: radial-led-120 slides, three tips squeezed within 4 px, of 2 px radius).
_OVERLAP_TIPS = 2.0
# ... of at most this many times the median tip's radius at rest (a faint tip's own area is noise).
_OVERLAP_CAP = 1.5


class Refiner(_Following, _AtRest, _Recovery, _Prediction):
    """Moves LK estimates onto their tips' windowed centroids; detects blobs only when that fails.

    Parameters
    ----------
    rest_crop : (h, w) ndarray of uint8
        The rest frame's crop, bright pins (dark markers inverted).
    rest_positions : (N, 2) ndarray
        Pins at rest (x, y), px in the frame (as given or detected).
    origin : (2,) ndarray
        Frame coordinates (x, y) of the crop's top-left pixel, px.
    spacing_px : float
        Median nearest-neighbour pin spacing at rest, px.
    gate_px : float
        Gate of blob matching and recovery, px (below half the spacing).
    neighbours : int
        Neighbours whose median displacement predicts where a lost pin is.
    detection : DetectionParams
        Blob detection for the frames that need it.
    disc : SensorDisc
        The sensor disc.

    Attributes
    ----------
    rest_positions : (N, 2) ndarray of float64
        The given rest positions moved onto their windowed centroids in `rest_crop` (where those
        lie within the plausibility bound; elsewhere as given): the same estimator as later
        frames, so that displacements from rest carry none of its bias.
    settled_share : float
        Share of the pins whose windowed centroid at rest lies within that bound (about 0 in a
        blank frame).
    """

    def __init__(self, rest_crop: np.ndarray, rest_positions: np.ndarray, origin: np.ndarray, *,
                 spacing_px: float, gate_px: float, neighbours: int, detection: DetectionParams,
                 disc: SensorDisc) -> None:
        self.origin = origin
        self.gate_px = gate_px
        self.spacing_px = spacing_px
        self.detection = detection
        self.disc = disc
        k = min(max(neighbours, _WINDOW_NEIGHBOURS, IDENTITY_NEIGHBOURS), len(rest_positions) - 1)
        index = cKDTree(rest_positions).query(rest_positions, k=k + 1)[1][:, 1:]
        self._identity_index = index[:, :IDENTITY_NEIGHBOURS]  # (for `keep_own_tips`)
        self._neighbour_index = index[:, :neighbours]
        self._every = np.arange(len(rest_positions))
        self._window_neighbours = np.ascontiguousarray(index[:, :_WINDOW_NEIGHBOURS].T)  # (k, N)
        self.windows = WindowCentroids(int(np.clip(np.ceil(0.5 * spacing_px), 2, 32)))
        self._radius_cap = np.inf
        # On a textured skin the darkest pixel of a window lies far below the membrane (its median),
        # and small tips are few pixels among many of the membrane's noise: there the threshold
        # stays above the window's mean, else the membrane would pull the centroids.
        low, median, top = self.windows.levels(rest_crop, rest_positions - origin)
        with np.errstate(divide="ignore", invalid="ignore"):
            texture = (median - low) / (top - low)
        texture = texture[np.isfinite(texture)]
        self.windows.above_mean = bool(texture.size and np.median(texture) > _TEXTURE_GAP)
        centres, area, contrast, compactness = self.windows(rest_crop, rest_positions - origin,
                                                            self.window_radius(rest_positions))
        # Windows no wider than the tip needs: less membrane (texture, shadows) in them.
        tip = np.sqrt(np.where(area > 0, area, np.nan) / np.pi)
        self._radius_cap = np.where(np.isfinite(tip), _TIP_REACH * tip + _TIP_MARGIN_PX, np.inf)
        # Another pin expected nearer than this to a pin's tip (`_OVERLAP_TIPS` of its radii at rest) overlaps
        # it: one blob, on which a one-tip fit lands anywhere (`pins._recover`'s `fit_tips`). A faint tip's
        # area at rest is mostly noise (a contrast of 3 in noise 5: radii of 5-12 px for tips of 3, which
        # paired it with neighbours 16 px away and moved it 1.2 px: `pins._pairfit`); no radius counts for
        # more than `_OVERLAP_CAP` times the median tip's.
        tip_px = tip[np.isfinite(tip)]
        capped = np.minimum(tip, _OVERLAP_CAP * np.median(tip_px)) if tip_px.size else tip
        self._overlap_px = np.where(np.isfinite(tip), _OVERLAP_TIPS * capped, 0.0)  # (no tip measured: none)
        #: Median radius of the tips at rest, px (their area above the window's threshold), nan without tips.
        self.tip_radius_px = float(np.median(tip_px)) if tip_px.size else float("nan")
        self.windows.above_mean |= bool(tip_px.size and np.median(tip_px) < _SMALL_TIP_PX)
        # Fractions of the spacing, with floors in px for the smallest pads (tips of 1 px, 4 px apart,
        # whose centroids scatter by a few tenths of a px in camera noise).
        self._max_shift_px = max(_MAX_SHIFT_FRACTION * spacing_px, _MIN_SHIFT_PX)
        self._guess_px = max(_GUESS_FRACTION * spacing_px, _MIN_GUESS_PX)
        self._settled_px = max(_SEARCH_SETTLED_FRACTION * spacing_px, _MIN_SHIFT_PX)
        # Each pin's rest position is the windows' own fixed point near the given one (mean shift,
        # a few passes): a window there finds its centroid where it stands, so the rest frame given
        # again places every pin, whatever pulled the given position off it (another estimator, a
        # sloped background, the rim). Farther than the plausibility bound, the given position
        # stands (a fixed point on a reflection's or the veil's flank lies up to a px off the tip).
        positions = rest_positions
        for _ in range(_REST_PASSES):
            centres = self.windows(rest_crop, positions - origin, self.window_radius(positions))[0] + origin
            positions = np.where(np.isfinite(centres), centres, positions)
        near = _squared_norm(positions - rest_positions) <= self._max_shift_px ** 2
        positions = np.where(near[:, None], positions, rest_positions)
        centres, area, contrast, compactness = self.windows(rest_crop, positions - origin,
                                                            self.window_radius(positions))
        step = centres + origin - positions
        settled = _squared_norm(step) <= self._max_shift_px ** 2
        self.rest_positions = positions
        # What still pulls a window at rest off its place (a fixed point not quite reached, a
        # window that drifts on the rim or a reflection), up to the gate: taken off every window
        # near the rest position (`_pull`), so that there the windows' fixed point is the rest position.
        offset = np.where(np.isfinite(step), step, 0.0)
        self._rest_offset = np.where((_squared_norm(offset) <= self.gate_px ** 2)[:, None], offset, 0.0)
        # Each window's scatter in the camera's noise while its pin is still, px, learnt frame by frame
        # (`observe_still`): crisp tips scatter by a few hundredths of a px, faint tips in glare by up to a px.
        self._jitter_sq = np.zeros(len(positions))
        self._rest_radius = self.window_radius(positions)
        self._jitter_seen = np.zeros(len(positions))
        self._jitter_floor = 0.0  # the median pin's, updated every `_FLOOR_EVERY` frames
        self._observed = 0
        # The scatter of each pin's window at its rest position about where its still neighbours place
        # it, px^2, learnt by `snap_to_rest`: a pin it places there moves with its neighbours, so its
        # steps (`observe_still`) do not show its own window's noise, which its calm test bounds.
        self._rest_scatter_sq = np.zeros(len(positions))
        self._rest_scatter_seen = np.zeros(len(positions))
        # ... and, before any is learnt (the first frames), what the camera's noise does to it: the
        # windows at rest measured again under noise like the rest frame's (`_noise_scatter_sq`).
        noisy = noisy_copies(rest_crop)  # (the rest crop in camera noise: the two scatters below)
        self._noise_scatter_sq = self._noise_scatter_sq_px2(rest_crop, noisy, positions)
        self.settled_share = float(np.mean(settled & (contrast > 0)))
        positive = contrast[contrast > 0]
        self.windows.least_contrast = 0.25 * float(np.percentile(positive, 5)) if positive.size else 0.0
        # Each pin's tip at rest bounds its tip later: (area, contrast, compactness) from below, area above;
        # a tip within the rest frame's noise of nothing, by its contrast alone (`pins._like`).
        #: Scatter of a window's contrast in the camera's noise, grey levels (the rest frame's, `pins._like.contrast_noise`).
        self.contrast_noise = contrast_noise(self.windows, rest_crop, noisy, positions - origin)
        self._at_least, self._area_at_most_rest = bounds_at_rest(area, contrast, compactness, self.contrast_noise)
        # A tip judged by its contrast alone is told from the membrane only where it rests: placed while still.
        # (`still`'s setter keeps `_area_at_most`, the bound the passes and their compiled kernels read, -inf for
        # such a tip that moved: no tip is like it.)
        self._judged = np.isfinite(self._area_at_most_rest)
        self._await_still_pair(rest_crop, (area, contrast, compactness))  # (redrawn at a still frame's noise: `pins._rest`)
        # Only tips on a slope (their windows tilt their thresholds there) are fitted: on a flat membrane
        # a window that loses its tip has lost it to contact, to the rim or to a neighbour.
        #: (N,) bool: pins whose windows at rest lie on a sloped background (a reflection, a veil).
        self.sloped = self.windows.slopes(rest_crop, positions - origin) > _FLAT_RISE
        # For their fits (`fit_tips`): the tips' radius, px (where their mean profile crosses half-way
        # to the membrane), and each sloped tip's ellipse at rest (Q_xx, Q_xy, Q_yy: the tip covers
        # e^T Q e <= 1), px^-2, the median of its own and its nearest neighbours' (one tip's is noisy).
        # Measured for those pins and their neighbours alone: all 331 of tactip-331 would add 0.15 s
        # CPU to the start; radial-led-120's 52 sloped pins add 6 ms.
        #: Radius of the tips for their fits, px.
        self.tip_fit_radius_px = _pin_radius_px(rest_crop, positions - origin, spacing_px, False)
        near = index[:, :_SHAPE_NEIGHBOURS - 1]
        self._tip_ellipses = np.full((len(positions), 3), np.nan)
        sloped = self.sloped.nonzero()[0]
        if sloped.size:
            needed = np.union1d(sloped, near[sloped])
            shapes = tip_shapes(rest_crop, positions - origin, self.tip_fit_radius_px, which=needed)
            # (Q = shape^-1 in closed form; a blank frame's degenerate shapes give NaN, and NaN fits fail.)
            with np.errstate(divide="ignore", invalid="ignore"):
                q = np.stack([shapes[:, 1, 1], -shapes[:, 0, 1], shapes[:, 0, 0]], axis=1) / np.linalg.det(shapes)[:, None]
            every = np.full((len(positions), 3), np.nan)
            every[needed] = np.where(np.isfinite(q).all(axis=1)[:, None], q, np.nan)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)  # (all NaN: a NaN ellipse, whose fit fails)
                self._tip_ellipses[sloped] = np.nanmedian(
                    np.concatenate([every[sloped, None], every[near[sloped]]], axis=1), axis=1)
        # Pins whose ellipses a fit can keep (`pins._tipfit._fittable`): the others' fits never move them.
        self._fittable = _fittable(self._tip_ellipses, self.tip_fit_radius_px)
        self.still = np.ones(len(positions), dtype=bool)
        self._then = np.zeros((len(positions), self._neighbour_index.shape[1], 2))  # (`pins._predict.remember`)

    def window_radius(self, points: np.ndarray) -> np.ndarray:
        """Radius of each pin's window at finite `points` (N, 2), px: (N,).

        A little more than half the distance to the nearest neighbour (0.55 of it): the window
        may take the foot of that neighbour, which lies below the threshold, and cuts less of the
        pin's own tip, which near the rim is elongated across the direction of its nearest
        neighbours (on renders at 0-6 mm contact: max error 0.06-0.15 px, against 0.05-0.22 px
        at half the distance and 0.16-0.57 px at 0.65 of it).
        """
        x, y = points[:, 0], points[:, 1]
        dx = x.take(self._window_neighbours) - x  # (k, N): a minimum over rows is fast
        dy = y.take(self._window_neighbours) - y
        dx *= dx
        dy *= dy
        dx += dy
        nearest = np.sqrt(np.minimum.reduce(dx, axis=0))
        nearest *= _WINDOW_REACH
        return np.minimum(nearest, self._radius_cap, out=nearest)

    def __call__(self, grey: np.ndarray, crop: np.ndarray, tracked: np.ndarray,
                 last_seen: np.ndarray) -> tuple[np.ndarray, bool]:
        """Refined positions of the tracked pins, lost pins searched for, blobs detected if still needed.

        `refine` (searching for every lost pin), then `recover` only when some pin is still
        missing; `pins.track.PinTracker` runs the same steps on its own schedule (retired pins
        searched for in turns, detection at a bounded rate).

        Parameters
        ----------
        grey : (H, W) ndarray of uint8
            The frame.
        crop : (h, w) ndarray of uint8
            Its crop at `origin`, bright pins.
        tracked : (N, 2) ndarray
            LK estimates (x, y), px in the frame; NaN where LK lost the pin.
        last_seen : (N, 2) ndarray
            Each pin's last known position, px.

        Returns
        -------
        positions : (N, 2) ndarray of float64
            Refined or recovered positions, px; NaN where lost.
        detected : bool
            Whether this frame needed blob detection (some pin neither plausible nor found by search).
        """
        positions = self.refine(crop, tracked, last_seen)
        if not np.isnan(positions[:, 0]).any():
            return positions, False
        return self.recover(grey, tracked, positions, last_seen, crop), True

    def refine(self, crop: np.ndarray, tracked: np.ndarray, last_seen: np.ndarray,
               search: np.ndarray | None = None, settled: np.ndarray | None = None, *,
               filled: np.ndarray | None = None) -> np.ndarray:
        """Tracked pins onto their windowed centroids; lost pins searched for around their predictions.

        First pass: one window per tracked pin, at its estimate, and one per lost pin to search for,
        at its prediction (`_predict`). A tracked pin whose centroid is plausible takes it; one
        whose centroid is implausible gets a window at its prediction. Second pass, for the
        pins searched for: a window re-centred on the first centroid, where a tip cut by the first
        window is whole (a step of mean shift). Such a pin is found when that last move is within
        `_SEARCH_SETTLED_FRACTION` of the spacing, its tip's area, contrast and compactness are like
        its own at rest, the centroid lies within `gate_px` (below half the pin spacing) of its
        prediction, and no neighbour is within `_SAME_TIP_FRACTION` of the spacing (two pins
        never share a tip: a found pin yields to a refined one, and of two found pins the one
        farther from its prediction yields). Blob detection is never run here (`recover` does).

        Parameters
        ----------
        crop : (h, w) ndarray of uint8
            The frame's crop at `origin`, bright pins.
        tracked : (N, 2) ndarray
            Estimates (x, y), px in the frame; NaN where the pin is lost.
        last_seen : (N, 2) ndarray
            Each pin's last known position, px (the prediction of a pin without tracked neighbours).
        search : (N,) ndarray of bool, optional
            Lost pins to search for (default: all of them).
        settled : (N,) ndarray of bool, optional
            Pins whose `tracked` position is already a plausible windowed centroid (`follow`):
            kept as they are, without a window.
        filled : (N, 2) ndarray, optional
            `tracked` with lost pins at their predictions, when already known (`follow`).

        Returns
        -------
        positions : (N, 2) ndarray of float64
            Windowed centroids, px; NaN where a pin was neither plausible nor found.
        """
        missing = np.isnan(tracked[:, 0])
        lost = np.flatnonzero(missing)
        if lost.size == 0 and settled is None:
            radius = self.window_radius(tracked)
            centres, measures = self.windows.measure(crop, tracked - self.origin, radius)
            centres += self.origin
            plausible = self._plausible(centres, tracked, measures, slice(None))
            if plausible.all():
                return centres
            positions = centres
            positions[~plausible] = np.nan
            look, first, predicted = np.empty(0, dtype=np.intp), np.empty((0, 2)), np.empty((0, 2))
            implausible = np.flatnonzero(~plausible)
        else:
            # A lost pin still bounds its neighbours' windows, at its predicted position.
            if filled is None:
                filled = tracked.copy()
                filled[lost] = self._predict(tracked, lost, last_seen)
            else:
                unknown = lost[np.isnan(filled[lost, 0])]
                if unknown.size:
                    filled = filled.copy()
                    filled[unknown] = self._predict(tracked, unknown, last_seen)
            radius = self.window_radius(filled)
            live = ~missing if settled is None else ~missing & ~settled
            live = np.flatnonzero(live)
            look = lost if search is None else lost[search[lost]]
            look = look[self._trusted(tracked, look, last_seen, filled[look])]
            which = np.concatenate([live, look])
            centres, measures = self.windows.measure(crop, filled[which] - self.origin, radius[which])
            centres += self.origin
            n = live.size
            plausible = self._plausible(centres[:n], tracked[live], measures[:, :n], live)
            if settled is None:
                positions = np.full_like(tracked, np.nan)
            else:
                positions = tracked.copy()
                positions[~settled] = np.nan
            positions[live[plausible]] = centres[:n][plausible]
            implausible = live[~plausible]
            first, predicted = centres[n:], filled[look]
        retry = look
        if implausible.size:
            # A tracked pin whose centroid is implausible (LK between two tips, or on a vanished
            # one) is searched for from its prediction too (where its neighbours are placed).
            guess = self._predict(positions, implausible, last_seen)
            trusted = self._trusted(positions, implausible, last_seen, guess)
            implausible, guess = implausible[trusted], guess[trusted]
        if implausible.size:
            again = self.windows(crop, guess - self.origin, radius[implausible])[0] + self.origin
            retry = np.concatenate([look, implausible])
            first, predicted = np.concatenate([first, again]), np.concatenate([predicted, guess])
        # Second pass, from the first centroids (NaN where a window was empty or off the image).
        ok = np.isfinite(first[:, 0])
        retry, first, predicted = retry[ok], first[ok], predicted[ok]
        if retry.size == 0:
            return positions
        second, measures = self.windows.measure(crop, first - self.origin, radius[retry])
        second += self.origin
        step, offset = second - first, second - predicted
        error = _squared_norm(offset)
        found = ((_squared_norm(step) <= (_SEARCH_SETTLED_FRACTION * self.spacing_px) ** 2)
                 & (error <= self.gate_px ** 2) & self._like_at_rest(measures, retry))
        if not found.any():
            return positions
        retry, second, error = retry[found], second[found], error[found]
        positions[retry] = second
        self._one_pin_per_tip(positions, retry, error)
        keep_own_tips(positions, retry, predicted[found], tracked if filled is None else filled,
                      self._identity_index)
        return positions

    def _pull(self, points: np.ndarray, which: np.ndarray) -> np.ndarray:
        """What pulls windows at finite `points` (L, 2), px, of pins `which` off their tips: (L, 2), px.

        A pin's rest offset (what its window found around its tip at rest: the rim's veil, a
        reflection's flank) while the window lies within the gate of its rest position, fading
        to nothing a spacing away (there the window sees other surroundings).
        """
        distance = np.sqrt(_squared_norm(points - self.rest_positions[which]))
        # (fmax takes a NaN weight, a pin at no point, to 0; np.clip and np.where cost twice as much)
        weight = np.fmin(np.fmax((self.spacing_px - distance) / (self.spacing_px - self.gate_px), 0.0), 1.0)
        return self._rest_offset[which] * weight[:, None]

    def _one_pin_per_tip(self, positions: np.ndarray, found: np.ndarray, error: np.ndarray) -> None:
        """Unplace (NaN, in place) found pins that share a tip with a neighbour.

        Two pins on one tip are among each other's nearest `IDENTITY_NEIGHBOURS` at rest (not only the
        6 nearest: on radial layouts a followed pin slid onto the tip of a pin a ring away, 1.5 px from
        it, issue 20): the one farther from its prediction (squared distance `error`, px^2) yields; a pin
        placed otherwise (not in `found`) never yields to a found one; ties: both yield. By the compiled
        kernel (`pins._jit_track.one_pin_per_tip`, the same decisions) unless ``TACTIP_KERNELS=numpy``.
        """
        kernels = compiled()
        if kernels is None:
            self._one_pin_per_tip_numpy(positions, found, error)
        else:
            kernels.one_pin_per_tip(positions, np.asarray(found, dtype=np.int64), np.asarray(error, dtype=np.float64),
                                    self._identity_index, (_SAME_TIP_FRACTION * self.spacing_px) ** 2)

    def _one_pin_per_tip_numpy(self, positions: np.ndarray, found: np.ndarray, error: np.ndarray) -> None:
        """`_one_pin_per_tip` in NumPy: the reference of its compiled kernel."""
        neighbours = self._identity_index[found]  # (F, m)
        near = squared_distances(positions, neighbours, positions[found]) < (_SAME_TIP_FRACTION * self.spacing_px) ** 2
        if np.count_nonzero(near):  # (count_nonzero: `ndarray.any` costs more)
            rank = np.full(len(positions), -1.0)
            rank[found] = error
            yields = (near & (rank[neighbours] <= error[:, None])).any(axis=1)
            positions[found[yields]] = np.nan

    def _plausible(self, centres: np.ndarray, estimates: np.ndarray, measures: np.ndarray,
                   which: np.ndarray | slice) -> np.ndarray:
        """Whether windowed centroids of pins `which` are plausible: near their estimates, tips like at rest."""
        step = centres - estimates
        # NaN compares False: an empty window is not plausible.
        return (_squared_norm(step) <= self._max_shift_px ** 2) & self._like_at_rest(measures, which)

    def _like_at_rest(self, measures: np.ndarray, which: np.ndarray | slice) -> np.ndarray:
        """Whether tips' (area, contrast, compactness), stacked (3, L), are like those of pins `which` at rest."""
        like = np.logical_and.reduce(measures >= self._at_least[:, which], axis=0)
        like &= measures[0] <= self._area_at_most[which]  # (-inf for a tip judged by contrast alone that moved)
        return like

    @property
    def still(self) -> np.ndarray:
        """(N,) bool: pins that did not move in the last frame (`pins.track.PinTracker` sets it)."""
        return self._still

    @still.setter
    def still(self, still: np.ndarray) -> None:
        """Set the pins that did not move in the last frame, (N,) bool, and with them the area bound."""
        self._still = still
        # A tip judged by its contrast alone (`pins._like`) is placed only while still: above, its area bound;
        # a faint tip still or steady has the bounds of its level (`pins._rest._AtRest._draw_bounds`).
        self._draw_bounds()
