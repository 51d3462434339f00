"""Pins followed from their constant-velocity guesses by windowed centroids alone, for
`pins._refine.Refiner` (paper 002, III-A.3).

Following: windows at the constant-velocity guesses, re-centred once; a pin whose window moved by
at most 0.03 spacings (`_GUESS_FRACTION`; 0.1 px at least) and ended within 0.4 spacings of its guess
(`_FOLLOW_FRACTION`) needs no LK.

`_Following` holds that pass; `pins._refine.Refiner` inherits it and sets the state it reads.
"""

from __future__ import annotations

import numpy as np

from ._identity import keep_own_tips
from ._kernels import compiled
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
        if placed.size:
            pins, start = which[placed], start[placed]
            self._one_pin_per_tip(positions, pins, _squared_norm(positions[pins] - start))
            keep_own_tips(positions, pins, start, filled, self._identity_index)
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
        if placed.size:
            pins, start = which[placed], start[placed]
            self._one_pin_per_tip(positions, pins, _squared_norm(positions[pins] - start))
            keep_own_tips(positions, pins, start, filled, self._identity_index)
        return positions
