"""Pins recovered from detected blobs, for `pins._refine.Refiner` (paper 002, III-A.3).

Recovery (`Refiner.recover`, at a rate `PinTracker` bounds). The frame's blobs are detected
(`pins.detect`): an implausible pin takes the blob it landed on, one blob per pin, inside a gate
(`match_to_blobs`; no blob: lost), and blobs no pin claimed are assigned to lost pins one-to-one
(Hungarian method, `scipy.optimize.linear_sum_assignment`) within the same gate around each lost
pin's predicted position (its rest position moved by the median displacement of its tracked
neighbours). Gates below half the pin spacing and one-to-one assignments keep identities; a pin that
takes a blob keeps it only where no other pin is expected nearer (`pins._identity`; `PinTracker`
expects a lost pin at its prediction there, as the follow passes do).

Fitting (`Refiner.fit_tips`, every frame, for the few pins just lost on a sloped background): tips
that their windows lose are fitted as opaque ellipses where their windows show a tip. A fit is not
placed where another pin is expected within two tip radii (the tips overlap: one blob, on which a fit
of one tip lands anywhere; issue 20's slides).

`match_to_blobs` and the Hungarian assignment are plain functions; `_Recovery` holds the steps that
use them; `pins._refine.Refiner` inherits it and sets the state it reads.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial import cKDTree

from .detect import _detect
from .disc import SensorDisc
from ._follow import _SAME_TIP_FRACTION
from ._identity import MISSING_MARGIN, keep_own_tips
from ._kernels import compiled
from ._tipfit import _MARGIN_PX, _Windows, _centre_step
from ._window import WindowCentroids, _squared_norm
from .errors import ShapeError

__all__ = ["match_to_blobs"]

# At most this many rounds of assigning free blobs to lost pins (each round's pins help predict the next's).
_ROUNDS = 8


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


class _Recovery:
    """The blob-detection side of `pins._refine.Refiner`: recovery of missing pins from detected blobs."""

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
        free = np.ones(len(blobs), dtype=bool)
        free[claim[has_blob]] = False
        # In rounds: pins whose neighbours are placed first (`_trusted`), then those whose neighbours
        # the round before placed.
        for _ in range(_ROUNDS):
            lost = np.flatnonzero(np.isnan(positions[:, 0]))
            if not (lost.size and free.any()):
                break
            predicted = self._predict(positions, lost, last_seen)  # once: `_trusted` reads it too
            trusted = self._trusted(positions, lost, last_seen, predicted)
            lost, predicted = lost[trusted], predicted[trusted]
            if not lost.size:
                break
            free_index = np.flatnonzero(free)
            pins, chosen = _assign(predicted, blobs[free_index], gate)
            if not pins.size:
                break
            positions[lost[pins]] = blobs[free_index[chosen]]
            free[free_index[chosen]] = False
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

    def fit_tips(self, crop: np.ndarray, positions: np.ndarray, last_seen: np.ndarray,
                 which: np.ndarray) -> np.ndarray:
        """Missing pins `which` (indices) whose tips show at their predictions, placed by fitting the tips.

        A faint tip on a slope (the flank of a reflection or of a bright surround's veil) may be
        lost by its window, which weighs the bright side as tip (too much area, a centroid pulled
        off the tip), and by blob detection. A pin whose window at its prediction (its rest position
        moved by the median displacement of its placed neighbours) shows a tip of at least its
        least contrast (`_like_at_rest`'s) is fitted there as `pins._tipfit` fits tips: an opaque
        ellipse (its own at rest, the median of its neighbours', `tip_shapes`) over a quadratic
        membrane, its centre alone free, its neighbours' feet left out, one damped Gauss-Newton step
        (`pins._tipfit._centre_step`; on radial-led-120's tap, seeds 0-11, three steps tracked as many
        pins with an RMSE max of 0.26 px against 0.23 with one). It is placed where the fit ends when the fit took its step (a
        failed fit keeps its start) and the window there shows its least contrast too, unless a
        neighbour sits on the same tip (`_one_pin_per_tip`) or is expected (placed, or missing where its
        neighbours put it) within two of the pin's tip radii at rest: their tips overlap in one blob.
        By one compiled call (`pins._jit_fit.fit_tips`, bit for bit these steps, `_fit_tips_steps`) unless
        ``TACTIP_KERNELS=numpy``, Numba is missing, or the windows are a stand-in (`pins.accel`).

        Parameters
        ----------
        crop : (h, w) ndarray of uint8
            The frame's crop at `origin`, bright pins.
        positions : (N, 2) ndarray
            Positions so far, px; NaN where missing.
        last_seen : (N, 2) ndarray
            Each pin's last known position, px.
        which : (L,) ndarray of int
            Missing pins to look for.

        Returns
        -------
        positions : (N, 2) ndarray of float64
            `positions`, or a copy with the pins found, px.
        """
        kernels = compiled("_jit_fit")
        if kernels is not None and type(self.windows) is WindowCentroids and crop.dtype == np.uint8:
            # (The steps below in one compiled call, bit for bit: `pins._jit_fit`.)
            crop, _ = self.windows._kernel_arguments(crop, positions[:0])
            tip = self.tip_fit_radius_px
            changed, fitted = kernels.fit_tips(
                crop, positions, last_seen, np.asarray(which, dtype=np.int64), self._fittable, self.rest_positions,
                self._neighbour_index, self.origin, self.windows.half_px, self._at_least, self._window_neighbours,
                tip, 1.5 * tip + 1.0 + _MARGIN_PX, self._tip_ellipses, self._overlap_px, self._identity_index,
                (_SAME_TIP_FRACTION * self.spacing_px) ** 2, MISSING_MARGIN ** 2)
            return fitted if changed else positions
        return self._fit_tips_steps(crop, positions, last_seen, which)

    def _fit_tips_steps(self, crop: np.ndarray, positions: np.ndarray, last_seen: np.ndarray,
                        which: np.ndarray) -> np.ndarray:
        """`fit_tips` step by step (NumPy round the kernels `pins._kernels` picks): the reference of `pins._jit_fit`."""
        which = which[self._fittable[which]]  # (the others' fits never move them)
        if not which.size:
            return positions
        # Just lost: where its neighbours are now (a fit needs the tip's place in the gradient of a press).
        predicted = self._predict_from_neighbours(positions, which, last_seen)
        # (Only the windows' contrast is asked for, before and after the fit: `WindowCentroids.contrast`.)
        shows = self.windows.contrast(crop, predicted - self.origin) >= self._at_least[1, which]
        if not shows.any():
            return positions
        which, start = which[shows], predicted[shows] - self.origin
        around = self._window_neighbours[:, which].T  # (L, k)
        neighbours = np.where(np.isnan(positions[around]), last_seen[around], positions[around]) - self.origin
        nearest = np.sqrt(np.minimum.reduce(_squared_norm(neighbours - start[:, None, :]), axis=1))
        tip = self.tip_fit_radius_px
        reach = np.minimum(1.5 * tip + 1.0 + _MARGIN_PX, nearest - 0.5 * tip)
        theta = np.concatenate([start, self._tip_ellipses[which]], axis=1)  # (L, 5): centre, Q_xx, Q_xy, Q_yy
        window = _Windows(crop, start, reach, neighbours, nearest)
        fitted = _centre_step(window, theta, start)
        # A fit that took a step and ended on a tip of the pin's least contrast places it, unless a neighbour is
        # expected (placed, or missing where its neighbours put it) within two tip radii of it: the tips overlap,
        # one blob, on which a fit of one tip lands anywhere (issue 20: radial-led-120 slides, three tips squeezed
        # within 4 px, of 2 px radius; fitted pins landed on a missing neighbour's tip).
        moved = np.logical_or.reduce(fitted != start, axis=1)
        # (The contrast depends on the window's centre pixel alone: a fit that stayed on it keeps its contrast.)
        again = moved & np.logical_or.reduce(np.rint(fitted) != np.rint(start), axis=1)
        moved[again] = self.windows.contrast(crop, fitted[again]) >= self._at_least[1, which[again]]
        if not moved.any():
            return positions
        missing = np.flatnonzero(np.isnan(positions[:, 0]))
        expected = positions.copy()
        expected[missing] = self._predict_from_neighbours(positions, missing, last_seen)
        # (NaN, a neighbour expected nowhere, is left out by fmin and compares False.)
        moved &= ~(np.fmin.reduce(_squared_norm(expected[around] - self.origin - fitted[:, None, :]), axis=1)
                   < self._overlap_px[which] ** 2)
        if not moved.any():
            return positions
        positions = positions.copy()
        which, fitted = which[moved], fitted[moved] + self.origin
        positions[which] = fitted
        start = predicted[shows][moved]
        self._one_pin_per_tip(positions, which, _squared_norm(fitted - start))
        # ... nor any pin expected nearer to it (`pins._identity`; a missing pin where its neighbours put it):
        # a faint tip fitted on a slide's squeezed skin may be its lost neighbour's (issue 20).
        expected[which] = np.where(np.isnan(positions[which]), start, fitted)
        keep_own_tips(positions, which, start, expected, self._identity_index)
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
