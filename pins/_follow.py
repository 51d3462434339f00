"""Pins followed from their constant-velocity guesses by windowed centroids alone, for
`pins._refine.Refiner` (paper 002, III-A.3).

Following: windows at the constant-velocity guesses, re-centred once; a pin whose window moved by
at most 0.03 spacings (`_GUESS_FRACTION`; 0.1 px at least) and ended within 0.4 spacings of its guess
(`_FOLLOW_FRACTION`) needs no LK. A re-centred window that holds two or more tips (the skin squeezed ahead
of a slide) does not settle between them: its tips are assigned one-to-one to the pins expected there
(`_Following._part_tips`, issue 20), as are those of first-pass pins beside a missing one (a merged blob parting
again: `_Following._first_pass_parted`; such a pin assigned no tip stays, one assigned another's is unplaced).

`_Following` holds that pass; `pins._refine.Refiner` inherits it and sets the state it reads.
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.optimize import linear_sum_assignment

from . import _kernels
from ._identity import keep_own_tips
from ._kernels import compiled
from ._pairfit import _SMALLEST_TIP_PX
from ._window import WindowCentroids, _squared_norm

# A pin followed from its guess by windowed centroids needs no LK when a window moved by at most
# this fraction of the spacing (a few tenths of a px: the window was centred on the tip as LK
# centres it), and it ended within the second fraction of the spacing of its guess (farther, LK
# with its pyramid decides: the identity limit is LK's).
_GUESS_FRACTION = 0.03
_FOLLOW_FRACTION = 0.4
_FOLLOW_PASSES = 4
# Two pins found within this fraction of the spacing of each other sit on one tip (`Refiner._one_pin_per_tip`).
_SAME_TIP_FRACTION = 0.25


class _Following:
    """The follow passes of `pins._refine.Refiner` (windows at the guesses, no LK where they settle)."""

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
        No two pins take one tip (`_one_pin_per_tip`), and a pin placed away from its guess keeps its
        tip only when no other pin is expected nearer to it (`pins._identity.keep_own_tips`). Lost pins,
        and pins whose guesses found no tip, are searched for only where `_trusted`.

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
        # Per-pin state of the windows measured, indexed by `which` (a slice, no copy, when every pin is).
        index = slice(None)
        if lost.size == 0:
            filled, which, n = guess, self._every, len(guess)
        else:
            filled = guess.copy()
            filled[lost] = self._predict(guess, lost, last_seen)
            look = lost if search is None else lost[search[lost]]
            look = look[self._trusted(guess, look, last_seen, filled[look])]
            live = (~missing).nonzero()[0]
            which, n = np.concatenate([live, look]), live.size
            index = which
        radius = self.window_radius(filled)[which]
        start = filled[which]
        first, measures = self.windows.measure(crop, start - self.origin, radius)
        first += self.origin
        kernels = compiled()
        if kernels is not None:
            return self._follow_compiled(kernels, crop, guess, last_seen, filled, which, n, radius, start, first,
                                         measures), filled
        # A window at the guess is judged by its centroid less the pin's own offset at rest (the
        # window's pull by what lies around the tip), so a still tip is placed where it rested.
        placed_at = first - self._pull(start, index)
        moved = _squared_norm(placed_at - start)
        like = self._like_at_rest(measures, index)
        fine, reach = self._guess_px ** 2, (_FOLLOW_FRACTION * self.spacing_px) ** 2
        done = (moved <= fine) & like
        done[n:] = False  # a lost pin's prediction is no guess: two passes
        positions = np.empty(guess.shape)
        positions.fill(np.nan)  # (np.full costs 2-3x more)
        positions[which[done]] = placed_at[done]
        # Second and third passes: pins that moved but not far re-centred on their last centroid;
        # a pin with a guess that found no tip near it searched for from its prediction from the
        # pins just placed (its neighbours' guesses held: a lone pin that vanished, or that moved
        # unlike its guess near a contact); lost pins re-centred on theirs.
        again = ~done & np.isfinite(first[:, 0])
        again[:n] &= moved[:n] <= reach
        far = (~done[:n] & ~again[:n]).nonzero()[0]
        if far.size:
            predicted = self._predict(positions, which[far], last_seen)
            trusted = self._trusted(positions, which[far], last_seen, predicted)
            far, predicted = far[trusted], predicted[trusted]
        chain = np.concatenate([again.nonzero()[0], far]) if far.size else again.nonzero()[0]
        points = placed_at[chain]
        searched = chain >= n
        fresh = None  # (searches start fresh in the first of these passes only: those from predictions)
        if far.size:
            start[far] = points[-far.size:] = predicted
            # Their neighbours' guesses were off too: windows bounded by where the pins now are.
            now = np.where(np.isnan(positions), filled, positions)
            now[which[far]] = start[far]
            radius = self.window_radius(now)[which]
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
            # The step and the offset from the start, squared, in one array: moved, error.
            steps = np.empty((2,) + centres.shape)
            np.subtract(centres, points, out=steps[0])
            np.subtract(centres, start[chain], out=steps[1])
            moved, error = _squared_norm(steps)
            # A search settles within its bound, inside the gate around the prediction; a pin
            # followed from its guess settles to a few tenths of a px, near its guess.
            like = self._like_at_rest(measures, pins)
            settled = moved <= self._settled_px ** 2
            followed = (moved <= fine) & (error <= reach)
            if last:
                # In the last pass a pin followed from its guess may settle as loosely as a searched one
                # (a faint tip's centroid jitters in camera noise by more than a few tenths of a px), but
                # no farther from its guess than that: a window still drifting is no tip of its own.
                followed |= settled & (error <= self._settled_px ** 2)
            ok = like & np.where(searched, settled & (error <= self.gate_px ** 2), followed)
            positions[pins[ok]] = centres[ok]
            placed.append(chain[ok])
            # Go on while the window holds a tip like the pin's (or a search has just started).
            going = ~ok & np.isfinite(centres[:, 0]) & (searched | (error <= reach))
            going &= like if fresh is None else like | fresh
            chain, points, searched = chain[going], centres[going], searched[going]
            fresh = None
        # Pins placed in the first pass sat within a few tenths of a px of their own guesses: only
        # the others can have reached a neighbour's tip.
        placed = np.concatenate(placed[1:]) if len(placed) > 1 else placed[0][:0]
        self._part_placed(crop, positions, which, n, placed, start, filled)
        return positions, filled

    def _follow_compiled(self, kernels, crop: np.ndarray, guess: np.ndarray, last_seen: np.ndarray, filled: np.ndarray,
                         which: np.ndarray, n: int, radius: np.ndarray, start: np.ndarray, first: np.ndarray,
                         measures: np.ndarray) -> np.ndarray:
        """`follow`'s passes after the first window measurement, each pass's judgement by one compiled kernel
        (`pins._jit_track.follow_first`, `follow_pass`; `kernels`: `pins._jit`), the re-centring passes with
        their window measurements in one (`pins._jit.follow_passes`) when the windows are `WindowCentroids`
        themselves: the positions, bit for bit the NumPy passes' in `follow`."""
        fine, reach = self._guess_px ** 2, (_FOLLOW_FRACTION * self.spacing_px) ** 2
        settled_sq, gate_sq = self._settled_px ** 2, self.gate_px ** 2
        at_least, area_at_most = self._at_least, self._area_at_most
        positions = np.empty(guess.shape)
        positions.fill(np.nan)
        which = np.ascontiguousarray(which, dtype=np.int64)
        placed_at, again, far = kernels.follow_first(first, start, measures, which, n, self.rest_positions,
                                                     self._rest_offset, self.spacing_px, self.gate_px, fine, reach,
                                                     at_least, area_at_most, positions)
        if far.size:
            predicted = self._predict(positions, which[far], last_seen)
            trusted = self._trusted(positions, which[far], last_seen, predicted)
            far, predicted = far[trusted], predicted[trusted]
        fresh = None
        if far.size:
            chain = np.concatenate([again, far])
            points = placed_at[chain]
            start[far] = points[-far.size:] = predicted
            now = np.where(np.isnan(positions), filled, positions)
            now[which[far]] = start[far]
            radius = self.window_radius(now)[which]
            fresh = np.zeros(chain.size, dtype=bool)
            fresh[chain.size - far.size:] = True
            searched = (chain >= n) | fresh
        else:
            chain = again
            points = placed_at[chain]
            searched = chain >= n
        none = np.zeros(chain.size, dtype=bool)
        windows = self.windows
        if type(windows) is WindowCentroids and crop.dtype == np.uint8 and crop.flags.c_contiguous:
            # The windows' own kernel inside the passes' (not a stand-in: `pins.accel`'s batches its windows).
            placed = kernels.follow_passes(
                crop, self.origin, windows.half_px, windows.threshold_fraction, windows.above_mean,
                float(windows.least_contrast), points, start, chain, which, radius, searched,
                none if fresh is None else fresh, settled_sq, fine, reach, gate_sq, _FOLLOW_PASSES - 1, at_least,
                area_at_most, positions)
            placed = [placed] if placed.size else []
            chain = chain[:0]
        else:
            placed = []
        chain_radius = radius[chain]
        for last in [False] * (_FOLLOW_PASSES - 2) + [True]:
            if chain.size == 0:
                break
            centres, measures = self.windows.measure(crop, points - self.origin, chain_radius)
            centres += self.origin
            ok, chain, points, searched, chain_radius = kernels.follow_pass(
                centres, measures, points, start, chain, which, radius, searched, none if fresh is None else fresh,
                settled_sq, fine, reach, gate_sq, last, at_least, area_at_most, positions)
            placed.append(ok)
            fresh = None
        # Pins placed in the first pass sat within a few tenths of a px of their own guesses: only
        # the others can have reached a neighbour's tip.
        placed = np.concatenate(placed) if placed else again[:0]
        self._part_placed(crop, positions, which, n, placed, start, filled)
        return positions

    def _part_placed(self, crop: np.ndarray, positions: np.ndarray, which: np.ndarray, n: int, placed: np.ndarray,
                     start: np.ndarray, filled: np.ndarray) -> None:
        """The pins `follow` placed, rows `placed` of `which` re-centred (the first `n` rows: pins with guesses,
        `start` the rows' window starts, px), and first-pass pins beside a missing one, held one-to-one to the tips
        near them (`_part_tips`); re-centred ones one pin a tip, each keeping its tip only where no other pin is
        expected nearer (`pins._identity.keep_own_tips`). In place in `positions`.

        Pins placed in the first pass sat within a few tenths of a px of their own guesses: they reached a
        neighbour's tip only if the guess lies on it. Through a drag two tips merged in the squeezed skin part
        again; the pin that sat on the blob, its neighbour lost (one pin a tip), is guessed on the neighbour's side
        and its window, not moving, takes that tip (`bench/bench_slide_losses.py --onsets`, tactip-331 and dark-331,
        seeds 0-2, main 2bcbdb2: 92 of the drag's 203 follow onsets; in 195 of them the tip's own pin was lost the
        frame before and after). So first-pass pins with a missing window neighbour (`_first_pass_parted`) have
        their windows' tips assigned one-to-one too, against their guesses and the missing pins' predictions
        (`_part_tips`' rows from ``held_from``): one assigned its own tip (within a tip radius of where it is) is
        re-measured there, one assigned another's is unplaced (LK decides), and one assigned none stays where it is.
        Unplacing those assigned none too (session 21, swap21) lost pins that sat on their own tips (tactip-127,
        seeds 0-5: 90 pins, 17 in lifts) and sent them to LK. The re-measurement on the own tip is what gains (its
        window, half-way to the next tip, is not pulled by the neighbour's): without it tactip-331 seeds 0-5 626
        apart pin-frames against 510, tactip-127 seeds 6-23 303 against 209 (`bench/bench_slide_losses.py`).
        """
        first = self._first_pass_parted(positions, which, n, placed)
        if first.size or placed.size:
            rows = np.concatenate([placed, first]) if first.size else placed
            self._part_tips(crop, positions, which[rows], start[rows], filled, placed.size)
        if placed.size:
            pins, start = which[placed], start[placed]
            self._one_pin_per_tip(positions, pins, _squared_norm(positions[pins] - start))
            keep_own_tips(positions, pins, start, filled, self._identity_index)

    def _first_pass_parted(self, positions: np.ndarray, which: np.ndarray, n: int, placed: np.ndarray) -> np.ndarray:
        """Rows of `which` (of its first `n`) placed in `follow`'s first pass (finite `positions`, not in `placed`)
        with a window neighbour missing (NaN in `positions`), in frames where some windows were re-centred
        (`placed`), for tips of at least `pins._pairfit._SMALLEST_TIP_PX` (smaller ones show no two tips in a
        merged blob either; radial-led-120's 2 px: 3 -> 4 apart pin-frames, seeds 0-2, for +8 % of the tracker's
        CPU on `bench_replay.py --slides 8`): those whose windows' tips `_part_placed` assigns. Compiled
        (`pins._jit_follow.first_pass_parted`) where the kernels are: the NumPy calls here cost 0.06 ms a frame on
        tactip-331's slides."""
        if not placed.size or not self.tip_fit_radius_px >= _SMALLEST_TIP_PX:
            return placed[:0]
        kernels = _part_kernels()
        if kernels is not None:
            return kernels.first_pass_parted(positions, which, n, placed, self._window_neighbours)
        missing = np.isnan(positions[:, 0])
        if not np.count_nonzero(missing):
            return placed[:0]
        rows = np.isfinite(positions[which[:n], 0])
        rows[placed[placed < n]] = False
        rows = rows.nonzero()[0]
        beside = np.logical_or.reduce(missing[self._window_neighbours[:, which[rows]]], axis=0)
        return rows[beside]

    def _part_tips(self, crop: np.ndarray, positions: np.ndarray, pins: np.ndarray, start: np.ndarray,
                   filled: np.ndarray, held_from: int | None = None) -> None:
        """Pins placed by re-centred windows holding two or more tips: re-placed on tips assigned one-to-one, in place.

        In the skin squeezed ahead of a slide a pin's window may hold its own tip and one approaching from behind
        (that pin often missing, expected where it lagged): the window settles between the two, and the
        constant-velocity guess carries the pull on frame by frame until the pin sits on the other's tip. Here
        the tips in each window of `pins` (placed by a re-centred window at finite `positions`, (N, 2) px;
        `start` (F, 2) px their guesses) are the local maxima of the crop blurred to a tip's scale (half a tip
        radius) within `half` (0.55 spacings) of its centre that reach half-way from the darkest to the brightest of
        the window's square and of their own, one per tip radius. Where a window holds two or more, they are
        assigned to the pin's guess and to every other pin's expected place near it (a placed pin's position, a
        missing one's `filled` guess or prediction) one-to-one (least summed squared distances); the pin is
        re-measured by a window at its tip, of half the distance to the next tip, and kept within
        `_FOLLOW_FRACTION` of its guess. A pin assigned no tip, or re-measured beyond that, is unplaced (NaN: LK
        decides). Rows from `held_from` on (first-pass pins, `_part_placed`) assigned no tip stay where they are, and
        those assigned a tip farther than a tip radius from where they are are unplaced. One compiled call (`pins._jit_follow.part_tips_measured`: each window's own pixels only), else
        the NumPy reference (`_part_tips_numpy`: OpenCV over the windows' part of the crop).

        Apart pin-frames (`bench/bench_slide_losses.py --onsets`, 120 frames/s, seeds 0-5; session 20, slide17,
        main -> this): tactip-331 941 -> 683, dark-331 1148 -> 985, tactip-127 106 -> 79, dense-1000 (seeds 0-2)
        426 -> 336, radial-led-120 6 -> 7; held out (48-53) tactip-331 815 -> 723, dark-331 1068 -> 910; lost
        visible pin-frames (webcam-like radial-led-120) 8994 -> 8883. Compiled (session 21, part21; main c368916):
        the same apart pin-frames (tactip-331 683, dark-331 985; tactip-127 and radial-led-120 seeds 0-2 43 and 3),
        lost visible pin-frames 8849. Cost, `bench_replay.py --slides 8 --repeats 5`, tracker CPU ms/frame (best of
        5), 9 rounds interleaved with main: 0.51-0.62 against 0.36-0.52 (paired ratios 1.04-1.53, median 1.18; the
        reference: 0.93 against 0.45): the bar, within +10 % of main's, not met.
        """
        tip_px = self.tip_radius_px if np.isfinite(self.tip_radius_px) else 0.15 * self.spacing_px
        tip_px = max(tip_px, 1.0)
        half = int(np.ceil(0.55 * self.spacing_px))
        reach = (_FOLLOW_FRACTION * self.spacing_px) ** 2
        held_from = len(pins) if held_from is None else int(held_from)
        kernels = _part_kernels()
        if kernels is not None and crop.dtype == np.uint8 and crop.flags.c_contiguous:
            settings = (pins, start, half, tip_px, int(np.ceil(0.8 * tip_px)), _gaussian(0.5 * tip_px), self.spacing_px)
            windows = self.windows
            if type(windows) is WindowCentroids:
                kernels.part_tips_measured(crop, self.origin, positions, filled, *settings, reach, windows.half_px,
                                           windows.threshold_fraction, windows.above_mean,
                                           float(windows.least_contrast), held_from)
                return
            moved, aims, radii, unplaced = kernels.part_tips(crop, self.origin, positions, filled, *settings,
                                                             held_from)
            positions[pins[unplaced]] = np.nan
        else:
            tips = positions[pins]
            ok = np.isfinite(tips[:, 0])
            if not ok.any():
                return
            held = np.arange(len(pins)) >= held_from
            pins, start, tips, held = pins[ok], start[ok], tips[ok], held[ok]
            moved, aims, radii = self._part_tips_numpy(crop, positions, pins, start, filled, tips, tip_px, half, held)
        if moved.size:
            centres, _ = self.windows.measure(crop, aims - self.origin, radii)
            centres += self.origin
            keep = np.isfinite(centres[:, 0]) & (_squared_norm(centres - start[moved]) <= reach)
            positions[pins[moved]] = np.where(keep[:, None], centres, np.nan)

    def _part_tips_numpy(self, crop: np.ndarray, positions: np.ndarray, pins: np.ndarray, start: np.ndarray,
                         filled: np.ndarray, tips: np.ndarray, tip_px: float, half: int, held: np.ndarray):
        """`_part_tips`' NumPy reference up to the re-measurement (`pins._jit_follow.part_tips` compiled): the rows
        of `pins` to re-measure, at which tips (px) with which window radii (px); pins assigned no tip unplaced in
        `positions`, in place, unless `held` (first-pass rows: left where they are; unplaced where assigned a tip
        farther than `tip_px` from where they are)."""
        none = (np.zeros(0, np.intp), np.zeros((0, 2)), np.zeros(0))
        height, width = crop.shape
        local = np.rint(tips - self.origin).astype(np.intp)
        # The crop's part around the pins concerned, blurred to a tip's scale: its local maxima are tips.
        x0, y0 = np.maximum(local.min(axis=0) - 2 * half, 0)
        x1, y1 = np.minimum(local.max(axis=0) + 2 * half + 1, (width, height))
        part = cv2.GaussianBlur(crop[y0:y1, x0:x1].astype(np.float32), (0, 0), 0.5 * tip_px)
        size = 2 * int(np.ceil(0.8 * tip_px)) + 1
        box = np.ones((2 * half + 1, 2 * half + 1), np.uint8)
        low, high = cv2.erode(part, box), cv2.dilate(part, box)
        # Only the local maxima inside a window count (the blurred membrane's noise holds hundreds more in the
        # part), those that reach half-way from their surround's darkest to its brightest.
        windows = np.zeros(part.shape, np.uint8)
        windows[local[:, 1] - y0, local[:, 0] - x0] = 1
        offsets = np.arange(-half, half + 1)
        disc = (offsets[:, None] ** 2 + offsets[None, :] ** 2 <= half * half).astype(np.uint8)
        top = (part == cv2.dilate(part, np.ones((size, size), np.uint8))) & (cv2.dilate(windows, disc) > 0)
        ys, xs = np.nonzero(top)
        values, lows, highs = part[ys, xs], low[ys, xs], high[ys, xs]
        rise = (values >= 0.5 * (lows + highs)) & (highs > lows)
        ys, xs, values = ys[rise], xs[rise], values[rise]
        if xs.size < 2:
            return none
        peaks_all = np.stack([xs + x0, ys + y0], axis=1).astype(np.float64)
        at = np.where(np.isfinite(positions), positions, filled)
        at[pins] = start
        # The peaks in each window (within `half` of its centre) that reach half-way from its darkest to its
        # brightest: (F, P), few of each.
        cx, cy = local[:, 0] - x0, local[:, 1] - y0
        floor = 0.5 * (low[cy, cx] + high[cy, cx])
        inside = _squared_norm(local[:, None, :] - peaks_all[None, :, :]) <= half * half
        inside &= values[None, :] >= floor[:, None]
        moved, aims, radii = [], [], []
        for i in np.nonzero(np.count_nonzero(inside, axis=1) >= 2)[0]:
            found = np.nonzero(inside[i])[0]
            # One peak per tip: the brightest of peaks within a tip radius of each other.
            found = found[np.argsort(-values[found])]
            kept = [found[0]]
            for j in found[1:]:
                if _squared_norm(peaks_all[kept] - peaks_all[j]).min() > tip_px ** 2:
                    kept.append(j)
            if len(kept) < 2:
                continue
            peaks = peaks_all[kept] + self.origin
            pin, tip = pins[i], tips[i]
            others = np.nonzero(_squared_norm(at - tip) <= (1.5 * half) ** 2)[0]
            others = others[others != pin]
            expected = np.concatenate([start[i][None], at[others]])
            cost = _squared_norm(expected[:, None, :] - peaks[None, :, :])
            r, c = linear_sum_assignment(cost)
            mine = c[r == 0]
            if mine.size == 0:
                if not held[i]:
                    positions[pin] = np.nan
                continue
            peak = peaks[mine[0]]
            if held[i] and _squared_norm(peak - tip) > tip_px ** 2:
                positions[pin] = np.nan  # (another pin's tip: LK decides)
                continue
            gaps = _squared_norm(peaks - peak)
            gaps[mine[0]] = np.inf
            gap = np.sqrt(gaps.min())
            moved.append(i)
            aims.append(peak)
            radii.append(max(min(0.5 * gap, 0.55 * self.spacing_px), 1.5))
        if not moved:
            return none
        return np.asarray(moved), np.asarray(aims), np.asarray(radii)


def _part_kernels():
    """`_part_tips`' compiled kernels (`pins._jit_follow`), or None: the NumPy reference (`pins._kernels.compiled`)."""
    return _kernels.compiled("_jit_follow")


_GAUSSIANS: dict = {}  # sigma, px -> OpenCV's Gaussian weights for float32 images


def _gaussian(sigma: float) -> np.ndarray:
    """The weights `cv2.GaussianBlur` blurs a float32 image with at `sigma` px (its kernel size, 8 sigma + 1, odd)."""
    weights = _GAUSSIANS.get(sigma)
    if weights is None:
        size = int(round(sigma * 8 + 1)) | 1
        weights = _GAUSSIANS[sigma] = cv2.getGaussianKernel(size, sigma, cv2.CV_32F).ravel()
        if len(_GAUSSIANS) > 64:
            _GAUSSIANS.clear()
    return weights
