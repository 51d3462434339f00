"""Refinement and recovery of tracked pins, for `pins.track.PinTracker` (paper 002, III-A.3).

Refinement. Lucas-Kanade errors add up from frame to frame, so each tracked pin is moved onto
the intensity-weighted centroid of its tip in a small window around its LK estimate
(`WindowCentroids`). All windows are gathered at once from the grey crop (a fancy index into its
sliding-window view, as `numpy.lib.stride_tricks.sliding_window_view` makes) and processed as
one (N, P) uint8 array, O(pins x window):

1. the threshold of each window is its darkest pixel (the membrane, less the noise) plus
   `threshold_fraction` of the way up to the pin's top (the mean of the five pixels at the
   window's centre), so that membrane noise never counts and the whole tip above its foot does;
2. each pixel is weighted by its grey level above the threshold (the positive part);
3. a disc mask centred on the estimate (to a quarter pixel) keeps the pixels nearer to it than
   0.55 of the distance to the nearest neighbouring pin: that disc lies inside the pin's own
   Voronoi cell but for a sliver that holds at most the neighbour's foot, below the threshold,
   so no neighbour's pixels count, even when contact pushes pins together;
4. the weighted centroid (zeroth, first and second moments, one matrix product) is the centre.

A point-symmetric tip whose foot lies inside the mask gives its centre whatever the threshold;
a tip cut by the mask (near the rim, seen obliquely; pushed against a neighbour) is cut
symmetrically when the estimate is good, as LK's is (a few hundredths of a px). On renders with
noise sigma 4, gradient and glare, at rest and under 5 mm contact, this gives 0.02-0.03 px RMSE
against ground truth (blob detection: 0.03).

Plausibility. A centroid is kept when it lies within 0.03 pin spacings of the LK estimate (half
a px at 331 pins in 640x480), and the tip's area (mass over the threshold-to-top height, px),
contrast (top minus darkest pixel) and compactness (area over 2 pi times the mean squared
distance from the centroid: 1 for a disc) are like the pin's own at rest: a hidden pin has no
contrast; a neighbour, glare or a speck in the window pulls the centroid, adds area and spreads
the mass. Limit: a small bright speck detached from a tip but inside its window pulls it by less
than that bound (up to 0.5 px in tests where blob detection would have kept them apart); a speck
touching a tip fools blob detection as much.

Recovery. Only in frames where some pin is lost or implausible, the frame's blobs are detected
(`pins.detect`): an implausible pin takes the blob it landed on, one blob per pin, inside a gate
(`match_to_blobs`; no blob: lost), and blobs no pin claimed are assigned to lost pins one-to-one
(Hungarian method, `scipy.optimize.linear_sum_assignment`) within the same gate around each lost
pin's predicted position (its rest position moved by the median displacement of its tracked
neighbours). Gates below half the pin spacing and one-to-one assignments keep identities.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial import cKDTree

from .detect import DetectionParams, _detect
from .disc import SensorDisc
from .errors import ShapeError

__all__ = ["match_to_blobs", "WindowCentroids", "Refiner"]

# Sub-pixel steps per px of the window masks' centres and radii.
_PHASES = 4
# A windowed centroid is plausible when it lies within this fraction of the pin spacing of the LK
# estimate, and the tip's area, contrast and compactness are within these factors of the pin's own
# at rest. On renders and the sample video (5-6 mm taps) centroids stay within 0.01 spacings of
# LK, area within 0.9-1.3 and compactness within 0.92-1.09 of rest.
_MAX_SHIFT_FRACTION = 0.03
_AREA_RATIO = (0.5, 2.0)
_MIN_CONTRAST_RATIO = 0.5
_MIN_COMPACTNESS_RATIO = 0.85
# Neighbours whose distance bounds each refinement window (a hexagonal lattice has six), and the
# window's radius as a fraction of the distance to the nearest one (see `Refiner.window_radius`).
_WINDOW_NEIGHBOURS = 6
_WINDOW_REACH = 0.55
# Windows per searched pin (each re-centred on the last centroid), and how near two positions
# must be, as a fraction of the pin spacing, to be one tip (tips of neighbours pushed together
# stay more than half a spacing apart).
_SEARCH_STEPS = 3
_SAME_TIP_FRACTION = 0.25


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


class WindowCentroids:
    """Centroids of pin tips in square windows of side ``2 * half_px + 1`` around guesses.

    Parameters
    ----------
    half_px : int
        Half side of the windows, px: about half the pin spacing (masks reach half_px + 0.5 at most).
    threshold_fraction : float
        Where the threshold sits between the darkest pixel of a window and the pin's top, in (0, 1).
    """

    def __init__(self, half_px: int, *, threshold_fraction: float = 0.2) -> None:
        if int(half_px) != half_px or half_px < 2:
            raise ValueError(f"half_px must be an integer >= 2, got {half_px}")
        if not 0.0 < threshold_fraction < 1.0:
            raise ValueError(f"threshold_fraction must be in (0, 1), got {threshold_fraction}")
        self.half_px = int(half_px)
        self.threshold_fraction = float(threshold_fraction)
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

    def __repr__(self) -> str:
        return f"WindowCentroids(half_px={self.half_px}, threshold_fraction={self.threshold_fraction})"

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
            Pin top minus the darkest pixel of the window, grey levels.
        compactness : (N,) ndarray
            Area over 2 pi times the weights' mean squared distance from the centroid: 1 for a
            uniform disc, more for a domed tip, less for an elongated one or one with a speck.
        """
        half, side = self.half_px, 2 * self.half_px + 1
        if len(points) == 0:
            empty = np.empty(0)
            return np.empty((0, 2)), empty, empty.copy(), empty.copy()
        image = np.ascontiguousarray(image)
        height, width = image.shape
        anchor = np.rint(points).astype(np.intp)
        corner = anchor - half
        fits = ((corner[:, 0] >= 0) & (corner[:, 1] >= 0) & (corner[:, 0] <= width - side)
                & (corner[:, 1] <= height - side))
        corner[~fits] = 0
        # All windows at once: a (H - side + 1, W - side + 1, side, side) sliding view, fancy-indexed.
        view = np.ndarray((height - side + 1, width - side + 1, side, side), np.uint8, image, 0, image.strides * 2)
        patches = view[corner[:, 1], corner[:, 0]].reshape(len(points), -1)  # (N, P) copy
        low = patches.min(axis=1)
        top = patches[:, self._top].mean(axis=1)
        contrast = top - low
        threshold = np.rint(low + self.threshold_fraction * np.maximum(contrast, 0.0)).astype(np.uint8)
        # Positive part of (pixel - threshold), in place, without leaving uint8.
        np.maximum(patches, threshold[:, None], out=patches)
        patches -= threshold[:, None]
        # Mask of the guess's quarter-pixel phase (in [-0.5, 0.5] where the window fits) and radius.
        phase = np.rint((points - anchor) * _PHASES).astype(np.intp) + _PHASES // 2
        radius = np.rint(np.asarray(radius_px) * _PHASES).astype(np.intp) - 1
        np.minimum(np.maximum(radius, 0, out=radius), len(self._radii) - 1, out=radius)
        patches *= self._masks[(radius * self._n_phases + phase[:, 1]) * self._n_phases + phase[:, 0]]
        moments = patches.astype(np.float32) @ self._moments  # (N, 4): mass, sum x, sum y, sum r^2
        mass = moments[:, 0].astype(np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            offset = moments[:, 1:3] / mass[:, None]
            area = mass / (top - threshold)
            # Mean squared distance from the centroid; a disc of area A has A / (2 pi).
            spread = moments[:, 3] / mass - np.einsum("nd,nd->n", offset, offset)
            compactness = area / (2 * np.pi * spread)
        centres = anchor + offset
        centres[~fits | (mass <= 0)] = np.nan
        return centres, area, contrast, compactness


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
        self._window_neighbours = np.ascontiguousarray(index[:, :_WINDOW_NEIGHBOURS].T)  # (k, N)
        self.windows = WindowCentroids(int(np.clip(np.ceil(0.5 * spacing_px), 2, 32)))
        centres, area, contrast, compactness = self.windows(rest_crop, rest_positions - origin,
                                                            self.window_radius(rest_positions))
        self._max_shift_px = _MAX_SHIFT_FRACTION * spacing_px
        step = centres + origin - rest_positions
        settled = np.einsum("nd,nd->n", step, step) <= self._max_shift_px ** 2
        self.rest_positions = np.where(settled[:, None], centres + origin, rest_positions)
        self._area_range = (_AREA_RATIO[0] * area, _AREA_RATIO[1] * area)
        self._min_contrast = _MIN_CONTRAST_RATIO * contrast
        self._min_compactness = _MIN_COMPACTNESS_RATIO * compactness

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
        return _WINDOW_REACH * np.sqrt(np.min(dx * dx + dy * dy, axis=0))

    def __call__(self, grey: np.ndarray, crop: np.ndarray, tracked: np.ndarray,
                 last_seen: np.ndarray) -> tuple[np.ndarray, bool]:
        """Refined positions of the tracked pins, lost pins searched for, blobs detected if still needed.

        The three steps of `refine`, `search` (every pin without a plausible centroid) and
        `recover` (only when some pin is still missing); `pins.track.PinTracker` runs the same
        steps with its own schedule (search and detection at bounded rates).

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
        positions, radius = self.refine(crop, tracked, last_seen)
        missing = np.flatnonzero(np.isnan(positions[:, 0]))
        if missing.size == 0:
            return positions, False
        positions = self.search(crop, positions, missing, last_seen, radius)
        if not np.isnan(positions[:, 0]).any():
            return positions, False
        return self.recover(grey, tracked, positions, last_seen), True

    def refine(self, crop: np.ndarray, tracked: np.ndarray, last_seen: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Tracked pins moved onto their windowed centroids where those are plausible.

        Parameters
        ----------
        crop : (h, w) ndarray of uint8
            The frame's crop at `origin`, bright pins.
        tracked : (N, 2) ndarray
            Estimates (x, y), px in the frame; NaN where the pin is lost.
        last_seen : (N, 2) ndarray
            Each pin's last known position, px.

        Returns
        -------
        positions : (N, 2) ndarray of float64
            Windowed centroids, px; NaN where the estimate was NaN or its centroid implausible.
        radius : (N,) ndarray of float64
            Each pin's window radius, px (lost pins at their predicted positions), for `search`.
        """
        lost = np.flatnonzero(np.isnan(tracked[:, 0]))
        if lost.size == 0:
            radius = self.window_radius(tracked)
            centres, plausible = self._centroids(crop, tracked, radius, slice(None))
            if plausible.all():
                return centres, radius
            centres[~plausible] = np.nan
            return centres, radius
        # A lost pin still bounds its neighbours' windows, at its predicted position.
        filled = tracked.copy()
        filled[lost] = self._predict(tracked, lost, last_seen)
        radius = self.window_radius(filled)
        positions = np.full_like(tracked, np.nan)
        live = np.flatnonzero(np.isfinite(tracked[:, 0]))
        if live.size:
            centres, plausible = self._centroids(crop, tracked[live], radius[live], live)
            positions[live[plausible]] = centres[plausible]
        return positions, radius

    def _centroids(self, crop: np.ndarray, points: np.ndarray, radius: np.ndarray,
                   which: np.ndarray | slice) -> tuple[np.ndarray, np.ndarray]:
        """Windowed centroids (frame px) at finite `points` of pins `which`, and whether each is plausible."""
        centres, area, contrast, compactness = self.windows(crop, points - self.origin, radius)
        centres += self.origin
        step = centres - points
        # NaN compares False: an empty window is not plausible.
        plausible = ((np.einsum("nd,nd->n", step, step) <= self._max_shift_px ** 2)
                     & self._like_at_rest(area, contrast, compactness, which))
        return centres, plausible

    def _like_at_rest(self, area: np.ndarray, contrast: np.ndarray, compactness: np.ndarray,
                      which: np.ndarray | slice) -> np.ndarray:
        """Whether tips' area, contrast and compactness are like those of pins `which` at rest."""
        return ((area >= self._area_range[0][which]) & (area <= self._area_range[1][which])
                & (contrast >= self._min_contrast[which]) & (compactness >= self._min_compactness[which]))

    def search(self, crop: np.ndarray, positions: np.ndarray, which: np.ndarray, last_seen: np.ndarray,
               radius: np.ndarray) -> np.ndarray:
        """Look for lost pins in windows around their predicted positions (no blob detection).

        Each pin's window starts at its prediction (`_predict`) and moves onto the centroid it
        finds, `_SEARCH_STEPS` times (a mean shift: a tip cut by the first window is whole in the
        next). A pin is found when the last move is within the plausibility bound (converged),
        the tip's area, contrast and compactness are like the pin's own at rest, the centroid lies
        within `gate_px` (below half the pin spacing) of the prediction, and no other pin is within
        `_SAME_TIP_FRACTION` of the spacing (two pins never take one tip; a found pin yields to a
        tracked one, and of two found pins the one farther from its prediction yields).
        Cost: `_SEARCH_STEPS` windows per searched pin, as cheap as refinement.

        Parameters
        ----------
        crop : (h, w) ndarray of uint8
            The frame's crop at `origin`, bright pins.
        positions : (N, 2) ndarray
            Positions so far, px; NaN where missing.
        which : (L,) ndarray of int
            Missing pins to look for.
        last_seen : (N, 2) ndarray
            Each pin's last known position, px (the prediction when no neighbour is tracked).
        radius : (N,) ndarray
            Window radii, px (`refine`).

        Returns
        -------
        positions : (N, 2) ndarray of float64
            `positions` with the pins found filled in.
        """
        positions = positions.copy()
        which = np.asarray(which, dtype=np.intp)
        if which.size == 0:
            return positions
        predicted = self._predict(positions, which, last_seen)
        point = predicted.copy()
        active = np.arange(which.size)
        moved = np.full(which.size, np.inf)
        area = contrast = compactness = None
        for _ in range(_SEARCH_STEPS):
            inside = np.isfinite(point[active, 0])
            active = active[inside]
            if active.size == 0:
                break
            centres, area_a, contrast_a, compactness_a = self.windows(crop, point[active] - self.origin,
                                                                      radius[which[active]])
            centres += self.origin
            step = centres - point[active]
            moved[active] = np.einsum("nd,nd->n", step, step)
            point[active] = centres
            if area is None:
                area, contrast, compactness = (np.full(which.size, np.nan) for _ in range(3))
            area[active], contrast[active], compactness[active] = area_a, contrast_a, compactness_a
        if area is None:
            return positions
        offset = point - predicted
        found = ((moved <= self._max_shift_px ** 2) & (np.einsum("nd,nd->n", offset, offset) <= self.gate_px ** 2)
                 & self._like_at_rest(area, contrast, compactness, which))
        if not found.any():
            return positions
        candidates, point, offset = which[found], point[found], offset[found]
        # No two pins on one tip: a found pin yields to any pin already placed ...
        same_px = _SAME_TIP_FRACTION * self.spacing_px
        placed = np.isfinite(positions[:, 0])
        keep = np.ones(candidates.size, dtype=bool)
        if placed.any():
            keep = ~np.isfinite(cKDTree(positions[placed]).query(point, k=1, distance_upper_bound=same_px)[0])
        # ... and of two found pins on one tip, the one farther from its prediction yields.
        pairs = cKDTree(point).query_pairs(same_px, output_type="ndarray")
        if len(pairs):
            error = np.einsum("nd,nd->n", offset, offset)
            a, b = pairs[:, 0], pairs[:, 1]
            keep[np.where(error[a] > error[b], a, b)] = False
        positions[candidates[keep]] = point[keep]
        return positions

    def recover(self, grey: np.ndarray, tracked: np.ndarray, refined: np.ndarray,
                last_seen: np.ndarray) -> np.ndarray:
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

        Returns
        -------
        positions : (N, 2) ndarray of float64
            `refined` with blobs for missing pins (an LK estimate's own blob, else one assigned
            one-to-one within the gate around the pin's prediction), px; NaN where still lost.
        """
        blobs = _detect(grey, self.disc, self.detection).centres
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
        return positions

    def _predict(self, positions: np.ndarray, which: np.ndarray, last_seen: np.ndarray) -> np.ndarray:
        """Where lost pins should be: rest position moved by the median displacement of tracked neighbours."""
        neighbour_shift = (positions - self.rest_positions)[self._neighbour_index[which]]  # (L, k, 2)
        seen = np.isfinite(neighbour_shift[..., 0]).any(axis=1)
        predicted = last_seen[which].copy()
        if seen.any():
            shift = np.nanmedian(neighbour_shift[seen], axis=1)
            predicted[seen] = self.rest_positions[which[seen]] + shift
        return predicted


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
