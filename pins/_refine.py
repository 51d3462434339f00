"""Windowed following, refinement, search and recovery of tracked pins, for `pins.track.PinTracker`
(paper 002, III-A.3).

Refinement. Lucas-Kanade errors add up from frame to frame, so each tracked pin is moved onto
the intensity-weighted centroid of its tip in a small window around its estimate (its guess,
`Refiner.follow`, or its LK estimate, `Refiner.refine`; `WindowCentroids`). All windows are gathered at once from the grey crop (a fancy index into its
sliding-window view, as `numpy.lib.stride_tricks.sliding_window_view` makes) and processed as
one (N, P) uint8 array, O(pins x window):

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

Following: windows at the constant-velocity guesses, re-centred once; a pin whose window moved by
at most 0.01 spacings (0.1 px at least) and ended within 0.25 spacings of its guess needs no LK.

A point-symmetric tip whose foot lies inside the mask gives its centre whatever the threshold;
a tip cut by the mask (near the rim, seen obliquely; pushed against a neighbour) is cut
symmetrically when the estimate is good, as LK's is (a few hundredths of a px). On renders with
noise sigma 4, gradient and glare, at rest and under 5 mm contact, this gives 0.02-0.03 px RMSE
against ground truth (blob detection: 0.03).

Plausibility. A centroid is kept when it lies within 0.03 pin spacings (0.4 px at least) of the
LK estimate (half a px at 331 pins in 640x480), and the tip's area (mass over the threshold-to-top height, px),
contrast (top minus darkest pixel) and compactness (area over 2 pi times the mean squared
distance from the centroid: 1 for a disc) are like the pin's own at rest: a hidden pin has no
contrast; a neighbour, glare or a speck in the window pulls the centroid, adds area and spreads
the mass. Limit: a small bright speck detached from a tip but inside its window pulls it by less
than that bound (up to 0.5 px in tests where blob detection would have kept them apart); a speck
touching a tip fools blob detection as much.

Rest. The rest positions are the windows' own fixed points near the given ones (a few passes of
mean shift), and what still pulls a window at rest is the pin's rest offset, taken off its first
window later: the rest frame given again places every pin. A step within the search's settling
bound is camera noise, not velocity. Near its rest position a window at its guess is judged by
its centroid less that offset. On a pad back at rest (half the pins within 0.1 spacing of rest,
hardly any between that and the gate but a faint tip's jitter among still neighbours), pins far
from rest, drifted by more than a few tenths of a px, and missing ones are looked for at their
rest positions (`Refiner.snap_to_rest`): a fast return from a slide cannot leave them on their
neighbours' tips, nor a faint rim tip's window on the veil beside it.

Search. A lost pin (or one whose centroid is implausible) is looked for in a window at its
predicted position (its rest position moved by the median displacement of its tracked
neighbours), re-centred once; it is found when that move is at most 0.1 spacings, its tip is like
at rest, it lies within the gate (below half the spacing) of the prediction and no neighbour sits
on the same tip (`Refiner._one_pin_per_tip`).

Recovery (`Refiner.recover`, at a rate `PinTracker` bounds). The frame's blobs are detected
(`pins.detect`): an implausible pin takes the blob it landed on, one blob per pin, inside a gate
(`match_to_blobs`; no blob: lost), and blobs no pin claimed are assigned to lost pins one-to-one
(Hungarian method, `scipy.optimize.linear_sum_assignment`) within the same gate around each lost
pin's predicted position (its rest position moved by the median displacement of its tracked
neighbours). Gates below half the pin spacing and one-to-one assignments keep identities.
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial import cKDTree

from .detect import DetectionParams, _detect
from .disc import SensorDisc
from ._window import WindowCentroids, _squared_norm
from .errors import ShapeError

__all__ = ["match_to_blobs", "WindowCentroids", "Refiner"]

_TIP_REACH = 1.6
_TIP_MARGIN_PX = 1.5
# A skin is textured when, in the median window at rest, the window's median lies more than this
# fraction of the way from its darkest pixel to the tip's top (0.08 on plain membranes, 0.34 on
# the brown skin preset); tips smaller than this radius, px, are small.
_TEXTURE_GAP = 0.2
_SMALL_TIP_PX = 3.0
# A windowed centroid is plausible when it lies within this fraction of the pin spacing of the LK
# estimate, and the tip's area, contrast and compactness are within these factors of the pin's own
# at rest. On renders and the sample video (5-6 mm taps) centroids stay within 0.01 spacings of
# LK, area within 0.9-1.3 and compactness within 0.92-1.09 of rest.
_MAX_SHIFT_FRACTION = 0.03
_AREA_RATIO = (0.5, 2.0)
_MIN_CONTRAST_RATIO = 0.5
_MIN_COMPACTNESS_RATIO = 0.6
# Neighbours whose distance bounds each refinement window (a hexagonal lattice has six), and the
# window's radius as a fraction of the distance to the nearest one (see `Refiner.window_radius`).
_WINDOW_NEIGHBOURS = 6
_WINDOW_REACH = 0.55
# A searched pin is found when its second window moved by at most this fraction of the pin
# spacing (its tip, of radius ~0.3 spacings, then lies whole inside the window of radius ~0.55),
# and two positions nearer than this fraction of the spacing are one tip (tips of neighbours
# pushed together stay more than half a spacing apart).
_SEARCH_SETTLED_FRACTION = 0.1
# The pad is back at rest when this share of the placed pins lie within this fraction of the
# spacing of their rest positions.
_STILL_SHARE = 0.5
_STILL_FRACTION = 0.1
# ... and at most this share of them lie between that and the gate (a moving pad's field of
# displacements is continuous: its transition from still to moved pins holds many).
_BETWEEN_SHARE = 0.02
# A pin followed from its guess by windowed centroids needs no LK when a window moved by at most
# this fraction of the spacing (a few tenths of a px: the window was centred on the tip as LK
# centres it), and it ended within the second fraction of the spacing of its guess (farther, LK
# with its pyramid decides: the identity limit is LK's).
_GUESS_FRACTION = 0.03
_FOLLOW_FRACTION = 0.4
_FOLLOW_PASSES = 4
# Passes of mean shift that take the given rest positions to the windows' fixed points.
_REST_PASSES = 4
_MIN_SHIFT_PX = 0.4
_MIN_GUESS_PX = 0.1
_SAME_TIP_FRACTION = 0.25
# Weight of each still step in a window's learnt scatter (`Refiner.observe_still`), and how many
# times that scatter a still pin's window may lie from where its still neighbours place it.
_JITTER_RATE = 0.2
_JITTER_FIRST = 3
_JITTER_BOUND = 3.0
# A pin's window at rest is calm within this many times its learnt scatter of where its still
# neighbours place it (the scatter of its steps misses the constant part: its rest offset's noise).
_CALM_BOUND = 5.0
_FLOOR_EVERY = 8
# Draws of noise that measure each rest window's scatter before any is learnt.
_NOISE_DRAWS = 4


def noise_sigma(image: np.ndarray) -> float:
    """Standard deviation of a grey image's pixel noise, grey levels (Immerkaer's Laplacian-difference
    estimator made robust: the median absolute response over 6 sigma, so that edges and tips, a
    minority of pixels, do not count; saturated or flat regions, which show none, are left out)."""
    kernel = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], np.float32)
    response = np.abs(cv2.filter2D(image.astype(np.float32), -1, kernel))
    # A saturated surround (and its clipped fringe) or a black margin shows no noise, or less.
    clipped = cv2.dilate(((image <= 2) | (image >= 253)).astype(np.uint8), np.ones((5, 5), np.uint8))
    response = response[1:-1, 1:-1][clipped[1:-1, 1:-1] == 0]
    return float(np.median(response) / (0.6745 * 6.0)) if response.size else 0.0


def _learn_mean_square(mean_sq: np.ndarray, seen: np.ndarray, index, value: np.ndarray, candidate: np.ndarray) -> None:
    """Update running mean squares in place: ``mean_sq[index]`` (px^2) with ``value`` where ``candidate``.

    The first `_JITTER_FIRST` values of each entry are averaged; later ones count, with weight
    `_JITTER_RATE`, only within `_JITTER_BOUND` times the mean so far (a pin that begins to move with a
    contact is no noise). ``seen[index]`` counts the values learnt; NaN values learn nothing.
    """
    so_far, count = mean_sq[index], seen[index]
    first = count < _JITTER_FIRST
    learn = candidate & (first | (value <= _JITTER_BOUND ** 2 * so_far))
    rate = np.where(first, 1.0 / (count + 1.0), _JITTER_RATE)
    mean_sq[index] = so_far + np.where(learn, rate * (value - so_far), 0.0)
    seen[index] = count + learn


def match_to_blobs(points: np.ndarray, blobs: np.ndarray, *, gate_px: float) -> np.ndarray:
    """One-to-one nearest blob for each point, within a gate.

    Each point takes its nearest blob if that blob lies within `gate_px`; when several points
    take the same blob, the nearest point keeps it and the others get none.

    Parameters
    ----------
    points : (N, 2) ndarray
        (x, y) px; NaN rows get no blob.
    blobs : (M, 2) ndarray
        Detected blob centres (x, y), px.
    gate_px : float
        Largest accepted distance, px.

    Returns
    -------
    index : (N,) ndarray of int
        Index into `blobs` for each point, -1 where it has none.
    """
    points = _as_points(points, "points")
    blobs = _as_points(blobs, "blobs")
    index = np.full(len(points), -1, dtype=np.intp)
    live = np.flatnonzero(np.isfinite(points).all(axis=1))
    if live.size == 0 or len(blobs) == 0:
        return index
    distance, nearest = cKDTree(blobs).query(points[live], k=1, distance_upper_bound=gate_px)
    found = np.isfinite(distance)
    live, distance, nearest = live[found], distance[found], nearest[found]
    # Nearest point first, then keep each blob's first claimant.
    order = np.argsort(distance, kind="stable")
    _, first = np.unique(nearest[order], return_index=True)
    winners = order[first]
    index[live[winners]] = nearest[winners]
    return index


class Refiner:
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
        k = min(max(neighbours, _WINDOW_NEIGHBOURS), len(rest_positions) - 1)
        index = cKDTree(rest_positions).query(rest_positions, k=k + 1)[1][:, 1:]
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
        tip_px = tip[np.isfinite(tip)]
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
        self._noise_scatter_sq = self._noise_scatter_sq_px2(rest_crop, positions)
        self.settled_share = float(np.mean(settled & (contrast > 0)))
        positive = contrast[contrast > 0]
        self.windows.least_contrast = 0.25 * float(np.percentile(positive, 5)) if positive.size else 0.0
        # Each pin's tip at rest bounds its tip later: (area, contrast, compactness) from below, area above.
        self._at_least = np.stack([_AREA_RATIO[0] * area, _MIN_CONTRAST_RATIO * contrast,
                                   _MIN_COMPACTNESS_RATIO * compactness])  # (3, N)
        self._area_at_most = _AREA_RATIO[1] * area

    def _noise_scatter_sq_px2(self, rest_crop: np.ndarray, positions: np.ndarray) -> np.ndarray:
        """Each rest window's mean square displacement, px^2 (N,), under `_NOISE_DRAWS` draws of Gaussian
        noise of the rest crop's own level (`noise_sigma`) added to it: how far one frame's noise
        moves the window (a faint tip in glare: tenths of a px; a crisp one: hundredths)."""
        sigma = noise_sigma(rest_crop)
        if not sigma > 0:
            return np.zeros(len(positions))
        points, radius = positions - self.origin, self.window_radius(positions)
        base = self.windows.measure(rest_crop, points, radius)[0]
        rng = np.random.default_rng(0)  # a fixed draw: the same rest frame, the same bound
        total = np.zeros(len(positions))
        for _ in range(_NOISE_DRAWS):
            noisy = np.clip(rest_crop + rng.normal(0.0, sigma, rest_crop.shape), 0, 255).astype(np.uint8)
            total += _squared_norm(self.windows.measure(noisy, points, radius)[0] - base)
        return np.where(np.isfinite(total), total / _NOISE_DRAWS, 0.0)

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

    def follow(self, crop: np.ndarray, guess: np.ndarray, last_seen: np.ndarray,
               search: np.ndarray | None = None) -> np.ndarray:
        """Pins followed from their guesses by windowed centroids alone; lost pins searched for.

        Two passes of windows (steps of mean shift), all pins in one array per pass. First pass:
        a window per pin with a guess (its constant-velocity guess) and per lost pin to search for
        (at its prediction, `_predict`). Second pass, re-centred on the first centroid, for the
        pins whose first centroid moved. A pin with a guess is placed when a pass moved its window
        by at most `_GUESS_FRACTION` of the spacing (a few tenths of a px: the window was centred
        on the tip as LK would centre it), its tip is like at rest, and it ended within
        `_FOLLOW_FRACTION` of the spacing of its guess; the others need LK (`refine` then checks
        them). A lost pin is found as in `refine`'s search: its second window moved by at most
        `_SEARCH_SETTLED_FRACTION` of the spacing and it lies within `gate_px` of its prediction.
        No two pins take one tip (`_one_pin_per_tip`).

        Parameters
        ----------
        crop : (h, w) ndarray of uint8
            The frame's crop at `origin`, bright pins.
        guess : (N, 2) ndarray
            Guessed positions (x, y), px in the frame; NaN for lost pins.
        last_seen : (N, 2) ndarray
            Each pin's last known position, px.
        search : (N,) ndarray of bool, optional
            Lost pins to search for (default: all of them).

        Returns
        -------
        positions : (N, 2) ndarray of float64
            Pins placed or found, px; NaN elsewhere (a pin with a guess and NaN here needs LK).
        filled : (N, 2) ndarray of float64
            `guess` with lost pins at their predictions, px (for `refine`).
        """
        missing = np.isnan(guess[:, 0])
        lost = missing.nonzero()[0]
        if lost.size == 0:
            filled, which, n = guess, self._every, len(guess)
        else:
            filled = guess.copy()
            filled[lost] = self._predict(guess, lost, last_seen)
            look = lost if search is None else lost[search[lost]]
            live = (~missing).nonzero()[0]
            which, n = np.concatenate([live, look]), live.size
        radius = self.window_radius(filled)[which]
        start = filled[which]
        first, measures = self.windows.measure(crop, start - self.origin, radius)
        first += self.origin
        # A window at the guess is judged by its centroid less the pin's own offset at rest (the
        # window's pull by what lies around the tip), so a still tip is placed where it rested.
        placed_at = first - self._pull(start, which)
        moved = _squared_norm(placed_at - start)
        like = self._like_at_rest(measures, which)
        fine, reach = self._guess_px ** 2, (_FOLLOW_FRACTION * self.spacing_px) ** 2
        done = (moved <= fine) & like
        done[n:] = False  # a lost pin's prediction is no guess: two passes
        positions = np.full(guess.shape, np.nan)
        positions[which[done]] = placed_at[done]
        # Second and third passes: pins that moved but not far re-centred on their last centroid;
        # a pin with a guess that found no tip near it searched for from its prediction from the
        # pins just placed (its neighbours' guesses held: a lone pin that vanished, or that moved
        # unlike its guess near a contact); lost pins re-centred on theirs.
        again = ~done & np.isfinite(first[:, 0])
        again[:n] &= moved[:n] <= reach
        far = (~done[:n] & ~again[:n]).nonzero()[0]
        chain = np.concatenate([again.nonzero()[0], far])
        points = placed_at[chain]
        if far.size:
            start[far] = points[-far.size:] = self._predict(positions, which[far], last_seen)
            # Their neighbours' guesses were off too: windows bounded by where the pins now are.
            now = np.where(np.isnan(positions), filled, positions)
            now[which[far]] = start[far]
            radius = self.window_radius(now)[which]
        searched = chain >= n
        searched[chain.size - far.size:] = True
        fresh = np.zeros(chain.size, dtype=bool)
        fresh[chain.size - far.size:] = True
        placed = [done.nonzero()[0]]
        for last in [False] * (_FOLLOW_PASSES - 2) + [True]:
            if chain.size == 0:
                break
            pins = which[chain]
            # Re-centred windows follow their centroids as they are: less the rest offset they would
            # hold a pin whose tip leaves slowly near its rest position (a still pin drifted onto the
            # veil is re-measured at rest by `snap_to_rest`).
            centres, measures = self.windows.measure(crop, points - self.origin, radius[chain])
            centres += self.origin
            step, offset = centres - points, centres - start[chain]
            moved = _squared_norm(step)
            error = _squared_norm(offset)
            # A search settles within its bound, inside the gate around the prediction; a pin
            # followed from its guess settles to a few tenths of a px, near its guess.
            like = self._like_at_rest(measures, pins)
            settled = moved <= self._settled_px ** 2
            # In the last pass a pin followed from its guess may settle as loosely as a searched one
            # (a faint tip's centroid jitters in camera noise by more than a few tenths of a px), but
            # no farther from its guess than that: a window still drifting is no tip of its own.
            ok = like & np.where(searched, settled & (error <= self.gate_px ** 2),
                                 ((moved <= fine) & (error <= reach)) | (last & settled & (error <= self._settled_px ** 2)))
            positions[pins[ok]] = centres[ok]
            placed.append(chain[ok])
            # Go on while the window holds a tip like the pin's (or a search has just started).
            going = ~ok & np.isfinite(centres[:, 0]) & (searched | (error <= reach)) & (like | fresh)
            chain, points, searched = chain[going], centres[going], searched[going]
            fresh = np.zeros(chain.size, dtype=bool)
        # Pins placed in the first pass sat within a few tenths of a px of their own guesses: only
        # the others can have reached a neighbour's tip.
        placed = np.concatenate(placed[1:]) if len(placed) > 1 else placed[0][:0]
        if placed.size:
            offset = positions[which[placed]] - start[placed]
            self._one_pin_per_tip(positions, which[placed], _squared_norm(offset))
        return positions, filled

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
            # one) is searched for from its prediction too.
            guess = self._predict(positions, implausible, last_seen)
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
        return positions

    def _pull(self, points: np.ndarray, which: np.ndarray) -> np.ndarray:
        """What pulls windows at finite `points` (L, 2), px, of pins `which` off their tips: (L, 2), px.

        A pin's rest offset (what its window found around its tip at rest: the rim's veil, a
        reflection's flank) while the window lies within the gate of its rest position, fading
        to nothing a spacing away (there the window sees other surroundings).
        """
        distance = np.sqrt(_squared_norm(points - self.rest_positions[which]))
        weight = np.clip((self.spacing_px - distance) / (self.spacing_px - self.gate_px), 0.0, 1.0)
        return self._rest_offset[which] * np.where(np.isnan(weight), 0.0, weight)[:, None]

    def still(self, steps: np.ndarray) -> np.ndarray:
        """Whether each (N, 2) step, px, lies within the search's settling bound (camera noise, not motion): (N,) bool."""
        return _squared_norm(steps) <= self._settled_px ** 2

    def observe_still(self, steps: np.ndarray) -> np.ndarray:
        """Learn each window's scatter from one frame's (N, 2) steps, px; returns which steps were still (N,) bool.

        A step within the settling bound (`still`) is the difference of two noisy centroids: half its
        square updates the pin's running mean square scatter (the mean of its first `_JITTER_FIRST`,
        then weight `_JITTER_RATE` for steps within `_JITTER_BOUND` times the scatter so far).
        """
        half = _squared_norm(steps)
        still = half <= self._settled_px ** 2  # NaN (lost) compares False
        half *= 0.5
        # Slow motion (a tap's onset) is no noise: `_learn_mean_square`'s bound leaves it out.
        _learn_mean_square(self._jitter_sq, self._jitter_seen, slice(None), half, still)
        seen, jitter = self._jitter_seen, self._jitter_sq
        self._observed += 1
        if self._observed % _FLOOR_EVERY == 1:
            learnt = jitter[seen >= _JITTER_FIRST]
            self._jitter_floor = float(np.median(learnt)) if learnt.size else 0.0
        return still

    def snap_to_rest(self, crop: np.ndarray, positions: np.ndarray, search: np.ndarray) -> np.ndarray:
        """Pins far from rest on a pad back at rest placed on the tips at their own rest positions.

        When at least `_STILL_SHARE` of the placed pins lie within `_STILL_FRACTION` of the spacing
        of their rest positions and hardly any (`_BETWEEN_SHARE`) lie between that and `gate_px`
        (the pad is back at rest: a moving pad's field of displacements is continuous; a pin within
        twice that fraction whose neighbours are still is a faint tip's jitter), a pin farther than
        `gate_px` from its rest position (a fast return from a slide carried its stale guess onto a
        neighbour's tip), drifted by more than a few tenths of a px, or missing is looked for in a
        window at its rest position (its centroid less the rest offset). A pin far from rest or
        missing is placed there when the window settles within the search's bound on a tip like its
        own at rest. A *calm* pin (its still neighbours' median displacement within a few tenths of a
        px, and its window within `_CALM_BOUND` times its learnt scatter of where they place it: from its
        steps, `observe_still`, or from its windows at rest here, whichever is larger) is placed where they place it, its tip shown by its contrast. A pin placed
        near rest that is not calm keeps its place. Whatever a moving pad does, nothing is moved:
        the check costs a few vector operations per frame.

        Parameters
        ----------
        crop : (h, w) ndarray of uint8
            The frame's crop at `origin`, bright pins.
        positions : (N, 2) ndarray
            Positions so far, px; NaN where missing.
        search : (N,) ndarray of bool
            Missing pins to look for (retired ones take turns).

        Returns
        -------
        positions : (N, 2) ndarray of float64
            `positions`, or a copy with the pins found at their rest positions, px.
        """
        distance = _squared_norm(positions - self.rest_positions)  # NaN where missing
        far = distance > self.gate_px ** 2
        # Pins that drifted from rest by more than a window's settling in noise are looked at again.
        drifted = distance > self._guess_px ** 2
        if not (drifted.any() or (np.isnan(distance) & search).any()):
            return positions
        still = distance <= (_STILL_FRACTION * self.spacing_px) ** 2
        placed = np.count_nonzero(np.isfinite(distance))
        # A moving pad's field of displacements is continuous: between its still pins and those
        # moved farther than the gate lie pins moved by less. Pins put on wrong tips are off by
        # a whole spacing, with none in between.
        # A faint tip's window jitters in noise by up to a fifth of the spacing: a pin within that of
        # rest whose neighbours are still is such jitter, not motion.
        between = np.flatnonzero(~still & ~far & np.isfinite(distance))
        if between.size and np.count_nonzero(still) >= _STILL_SHARE * placed:
            around = _squared_norm(self.neighbour_median(positions - self.rest_positions, between))
            jitter = (around <= (_STILL_FRACTION * self.spacing_px) ** 2) & (
                distance[between] <= (2.0 * _STILL_FRACTION * self.spacing_px) ** 2)
            between = between[~jitter]
        if np.count_nonzero(still) < _STILL_SHARE * placed or between.size > _BETWEEN_SHARE * placed:
            return positions  # the pad is not at rest
        look = np.flatnonzero(drifted | (np.isnan(distance) & search))
        rest = self.rest_positions[look]
        centres, measures = self.windows.measure(crop, rest - self.origin, self._rest_radius[look])
        centres += self.origin - self._rest_offset[look]
        # Where its neighbours say the pin is: its rest position moved by their median displacement.
        # When they lie within a few tenths of a px of rest, the membrane there is at rest (it is
        # continuous: no pin moves by a px alone), and a window that settles within a few times its
        # own scatter in noise (`observe_still`; up to twice the search's bound) shows the pin there.
        # (A pin's scatter, or the median pin's if more: it is learnt from steps.)
        shift = self.neighbour_median(positions - self.rest_positions, look)
        quiet = _squared_norm(shift) <= self._guess_px ** 2  # NaN (no placed neighbour) compares False
        residual = _squared_norm(centres - rest - shift)
        scatter = np.maximum(np.maximum(self._jitter_sq[look], self._rest_scatter_sq[look]),
                             np.maximum(self._noise_scatter_sq[look], self._jitter_floor))
        calm = quiet & (residual <= _CALM_BOUND ** 2 * scatter)
        bound = np.where(calm, 2.0 * self._settled_px, self._settled_px)
        # A calm pin's window need only show a tip (its contrast): its area and compactness near the
        # rim's veil swing with the noise of its top pixels.
        like = np.where(calm, measures[1] >= self._at_least[1, look], self._like_at_rest(measures, look))
        found = (_squared_norm(centres - rest) <= bound ** 2) & like
        # A pin placed near rest that really moved keeps its place (a window at rest cuts its tip).
        found &= calm | ~(distance[look] <= self.gate_px ** 2)
        # The window's own scatter about where its still neighbours place the pin, learnt from the
        # windows that showed it here, after the test (a window never widens its own bound): a faint
        # tip in the veil scatters by tenths of a px, and its steps, taken with its neighbours once
        # it is placed where they say, do not show that.
        _learn_mean_square(self._rest_scatter_sq, self._rest_scatter_seen, look, residual, quiet & found)
        if not found.any():
            return positions
        positions = positions.copy()
        positions[look[found]] = np.where(calm[found, None], rest[found] + shift[found], centres[found])
        return positions

    def _one_pin_per_tip(self, positions: np.ndarray, found: np.ndarray, error: np.ndarray) -> None:
        """Unplace (NaN, in place) found pins that share a tip with a neighbour.

        Two pins on one tip are neighbours at rest: the one farther from its prediction (squared
        distance `error`, px^2) yields; a pin placed otherwise (not in `found`) never yields to a
        found one; ties: both yield.
        """
        neighbours = self._window_neighbours[:, found].T  # (F, k)
        gap = positions[neighbours] - positions[found][:, None, :]
        near = _squared_norm(gap) < (_SAME_TIP_FRACTION * self.spacing_px) ** 2
        if near.any():
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
        like &= measures[0] <= self._area_at_most[which]
        return like

    def recover(self, grey: np.ndarray, tracked: np.ndarray, refined: np.ndarray,
                last_seen: np.ndarray, crop: np.ndarray | None = None, *,
                around: np.ndarray | None = None) -> np.ndarray:
        """Detected blobs for pins without a position; leftover blobs to lost pins (a blob detection).

        Parameters
        ----------
        grey : (H, W) ndarray of uint8
            The frame.
        tracked : (N, 2) ndarray
            LK estimates, px; NaN where LK lost the pin.
        refined : (N, 2) ndarray
            Positions so far (refined or found), px; NaN where missing.
        last_seen : (N, 2) ndarray
            Each pin's last known position, px.
        crop : (h, w) ndarray of uint8, optional
            The frame's crop at `origin`, bright pins: when given, a pin keeps its blob only if the
            blob's window holds a tip like the pin's at rest, and takes its windowed centroid.
        around : (N,) ndarray of bool, optional
            Missing pins around which blobs are detected (default: all of them); any missing pin
            may take a blob detected there.

        Returns
        -------
        positions : (N, 2) ndarray of float64
            `refined` with blobs for missing pins (an LK estimate's own blob, else one assigned
            one-to-one within the gate around the pin's prediction), px; NaN where still lost.
        """
        # Only blobs near the missing pins matter: at their LK estimates or their predictions.
        missing = np.isnan(refined[:, 0])
        near = np.flatnonzero(missing if around is None else missing & around)
        blobs = self._detect_near(grey, np.concatenate([tracked[near], self._predict(refined, near, last_seen)]))
        gate = self.gate_px
        # Placed pins claim their blobs too, so that no other pin takes them.
        claim = match_to_blobs(np.where(np.isfinite(refined), refined, tracked), blobs, gate_px=gate)
        positions = refined.copy()
        has_blob = claim >= 0
        take = has_blob & np.isnan(refined[:, 0])
        positions[take] = blobs[claim[take]]
        lost = np.flatnonzero(np.isnan(positions[:, 0]))
        free = np.ones(len(blobs), dtype=bool)
        free[claim[has_blob]] = False
        if lost.size and free.any():
            predicted = self._predict(positions, lost, last_seen)
            free_index = np.flatnonzero(free)
            pins, chosen = _assign(predicted, blobs[free_index], gate)
            positions[lost[pins]] = blobs[free_index[chosen]]
        if crop is not None:
            # A blob is a pin's only when its window holds a tip like the pin's own at rest (not LED
            # glare or a speck), centred on it: the pin then takes the windowed centroid.
            new = np.flatnonzero(np.isnan(refined[:, 0]) & np.isfinite(positions[:, 0]))
            if new.size:
                radius = self.window_radius(np.where(np.isnan(positions), last_seen, positions))[new]
                centres, measures = self.windows.measure(crop, positions[new] - self.origin, radius)
                centres += self.origin
                step = centres - positions[new]
                keep = (_squared_norm(step) <= self._settled_px ** 2) & self._like_at_rest(measures, new)
                positions[new] = np.where(keep[:, None], centres, np.nan)
        return positions

    def _detect_near(self, grey: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Blob centres (M, 2), px, detected in the part of the disc around `points` (the missing pins).

        The box around them reaches a spacing and a gate beyond (the blobs of their placed neighbours,
        which claim theirs) and a threshold block beyond that (the neighbourhood means); the image
        outside the box counts as outside the disc, as the surround does. The whole disc when the
        box covers most of it.
        """
        disc = self.disc
        points = points[np.isfinite(points[:, 0])]
        if len(points) == 0:
            return np.empty((0, 2))
        reach = self.spacing_px + self.gate_px + self.detection.block_size_px
        low = np.maximum(np.floor(points.min(axis=0) - reach).astype(int), 0)
        high = np.minimum(np.ceil(points.max(axis=0) + reach).astype(int) + 1, grey.shape[::-1])
        if np.prod(high - low) > 0.5 * np.pi * disc.radius_px ** 2:
            return _detect(grey, disc, self.detection).centres
        (x0, y0), (x1, y1) = low, high
        part = SensorDisc(disc.cx - x0, disc.cy - y0, disc.radius_px)
        return _detect(grey[y0:y1, x0:x1], part, self.detection).centres + (x0, y0)

    def _predict(self, positions: np.ndarray, which: np.ndarray, last_seen: np.ndarray) -> np.ndarray:
        """Where lost pins should be: rest position moved by the median displacement of tracked neighbours."""
        shift = self.neighbour_median(positions - self.rest_positions, which)
        return np.where(np.isnan(shift), last_seen[which], self.rest_positions[which] + shift)

    def neighbour_median(self, values: np.ndarray, which: np.ndarray) -> np.ndarray:
        """Median of the finite (N, 2) `values` of each pin's `neighbours` nearest pins at rest, for pins `which`.

        Returns (L, 2), NaN for a pin none of whose neighbours has a finite value.
        """
        index = self._neighbour_index[which]
        near = values[index]  # (L, k, 2), a copy
        count = np.add.reduce(np.isfinite(near[..., 0]), axis=1)
        # Median over the finite neighbours (sorting puts NaN last): mean of the middle one or two;
        # NaN where there are none (the middle index is then -1, a NaN too).
        near.sort(axis=1)
        rows = np.arange(len(index))
        return 0.5 * (near[rows, (count - 1) // 2] + near[rows, count // 2])


def _assign(predicted: np.ndarray, candidates: np.ndarray, gate: float) -> tuple[np.ndarray, np.ndarray]:
    """One-to-one assignment of candidates to predictions inside a gate (Hungarian method)."""
    cost = np.linalg.norm(predicted[:, None, :] - candidates[None, :, :], axis=2)
    inside = cost <= gate
    rows = np.flatnonzero(inside.any(axis=1))
    cols = np.flatnonzero(inside.any(axis=0))
    if rows.size == 0:
        return rows, cols
    sub = np.where(inside[np.ix_(rows, cols)], cost[np.ix_(rows, cols)], 1e6)
    r, c = linear_sum_assignment(sub)
    accepted = sub[r, c] <= gate
    return rows[r[accepted]], cols[c[accepted]]


def _as_points(points: np.ndarray, name: str) -> np.ndarray:
    array = np.asarray(points, dtype=np.float64)
    if array.size == 0:
        return array.reshape(0, 2)
    if array.ndim != 2 or array.shape[1] != 2:
        raise ShapeError(f"{name} must have shape (N, 2), got {array.shape}")
    return array
