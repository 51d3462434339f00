"""Where lost pins are and whether to look for them there, for `pins._refine.Refiner` (issue 20:
identities through slides).

A slide squeezes the skin ahead of it until tips merge: pins are lost there and come back as the skin
relaxes. Their neighbours' median displacement now mixes both sides of the squeezed skin, whose
displacement changes by most of a spacing per spacing there, and the pin's own place in that gradient
is not the median's: a prediction from it lies up to a spacing off, on another pin's tip. So each pin
keeps its neighbours' displacements from the last frame it was placed in (`remember`), and a lost
pin's prediction is where it was last seen, moved as the median displacement of the *same*
neighbours (those placed then and now) changed since (`_predict`): its own offset from them, when it
was last seen, is carried along. Without such neighbours, the median displacement of the placed ones
moves its rest position; without any, it is where it was last seen.

Measured on `bench/bench_slides.py` (8 slides of 3 pitches, seeds 0-5), against the median of the
neighbours now: pin-frames on another pin's tip radial-led-120 548 -> 214, small-pad-100 604 -> 436,
tactip-331 11272 -> 7535; lost visible pins per frame (mean) 4.68 -> 4.46, 6.60 -> 5.82, 14.3 -> 15.1.
On a stiffer skin (``min_area=0.5``, seeds 0-2): 310 -> 78, 145 -> 81, 187 -> 196; lost 4.1 -> 3.0,
6.0 -> 4.9, 2.9 -> 2.1. Fits of tips just lost (`pins._recover`'s `fit_tips`) start where the
neighbours are now (`_predict_from_neighbours`): a tip on a press's veil lies where the press's
gradient puts it, not where its offset from its neighbours a frame ago does (carried, radial-led-120's
20 frames/s tap put 22 pin-frames > 1 px off against 4, seed 0).

A prediction is searched at only where it can be trusted (`_trusted`).
"""

from __future__ import annotations

import numpy as np

from ._window import _squared_norm

# A lost pin is searched for at its prediction only when this share of its neighbours is placed.
_TRUSTED_SHARE = 2 / 3


def _median(values: np.ndarray) -> np.ndarray:
    """Median over axis 1 of (L, k, 2) `values`, of its finite rows: (L, 2), NaN where none. Sorts `values` in place.

    >>> _median(np.array([[[1.0, 0.0], [np.nan, np.nan], [3.0, 4.0]]]))
    array([[2., 2.]])
    """
    count = np.add.reduce(np.isfinite(values[..., 0]), axis=1)
    values.sort(axis=1)  # NaN last: the mean of the middle one or two finite rows (NaN where none)
    rows = np.arange(len(values))
    return 0.5 * (values[rows, (count - 1) // 2] + values[rows, count // 2])


class _Prediction:
    """The prediction side of `pins._refine.Refiner`.

    Reads `rest_positions`, `_neighbour_index`, `gate_px`, `still`, and `_then` ((N, k, 2) px: each
    pin's neighbours' displacements from rest when it was last placed; zeros at the start, at rest).
    """

    def remember(self, positions: np.ndarray) -> None:
        """Keep, for the pins placed in a frame's final (N, 2) `positions`, px, their neighbours' displacements."""
        which = np.flatnonzero(np.isfinite(positions[:, 0]))
        if which.size:
            self._then[which] = (positions - self.rest_positions)[self._neighbour_index[which]]

    def _predict(self, positions: np.ndarray, which: np.ndarray, last_seen: np.ndarray) -> np.ndarray:
        """Where lost pins `which` should be, px (L, 2): where last seen, moved as their neighbours did since.

        Over each pin's neighbours placed both in `positions` (N, 2), px, and when it was last placed
        (`remember`): its `last_seen` position plus the change of their median displacement. Without
        such neighbours: its rest position moved by the median displacement of its placed neighbours;
        without any: `last_seen`.
        """
        rest = self.rest_positions[which]
        now = (positions - self.rest_positions)[self._neighbour_index[which]]  # (L, k, 2), a copy
        either = _median(now.copy())  # over the neighbours placed now
        then = self._then[which]
        both = np.isfinite(now[..., 0]) & np.isfinite(then[..., 0])
        now[~both] = np.nan
        change = _median(now) - _median(np.where(both[..., None], then, np.nan))
        carried = last_seen[which] + change
        fallback = np.where(np.isnan(either), last_seen[which], rest + either)
        return np.where(np.isfinite(carried), carried, fallback)

    def _predict_from_neighbours(self, positions: np.ndarray, which: np.ndarray, last_seen: np.ndarray) -> np.ndarray:
        """Pins `which` at their rest positions moved by the median displacement of their placed neighbours, px (L, 2).

        (`last_seen` where none is placed.)
        """
        shift = self.neighbour_median(positions - self.rest_positions, which)
        return np.where(np.isnan(shift), last_seen[which], self.rest_positions[which] + shift)

    def _trusted(self, positions: np.ndarray, which: np.ndarray, last_seen: np.ndarray,
                 predicted: np.ndarray) -> np.ndarray:
        """Whether pins `which` may be searched for at their predictions (`_predict`): (L,) bool.

        Where most of a pin's neighbours are placed (`_TRUSTED_SHARE` of them), its prediction
        interpolates their displacements. Where fewer are (at least two), only when they did not move
        in the last frame (`still`) and the prediction lies within the gate of where the pin was last
        seen: nothing moved there since (a whole rim ring coming back under a held press). From a
        few on one side of the squeezed skin ahead of a slide (its displacement changes by most of a
        spacing per spacing there) a prediction lies a spacing off, on another pin's tip (issue 20:
        tactip-331 slides, 2 or 3 of 6 neighbours placed, predictions 10-25 px off at a 17.7 px spacing).
        `predicted` (L, 2), px: the pins' predictions from `positions` (`_predict`; every caller has them).
        """
        index = self._neighbour_index[which]
        placed = np.isfinite(positions[index, 0])
        count = np.count_nonzero(placed, axis=1)
        trusted = count >= _TRUSTED_SHARE * index.shape[1]
        few = np.flatnonzero(~trusted & (count >= 2) & ~(placed & ~self.still[index]).any(axis=1))
        if few.size:
            moved = _squared_norm(predicted[few] - last_seen[which[few]])
            trusted[few] = moved <= self.gate_px ** 2
        return trusted

    def neighbour_median(self, values: np.ndarray, which: np.ndarray) -> np.ndarray:
        """Median of the finite (N, 2) `values` of each pin's `neighbours` nearest pins at rest, for pins `which`.

        Returns (L, 2), NaN for a pin none of whose neighbours has a finite value.
        """
        return _median(values[self._neighbour_index[which]])  # (L, k, 2), a copy
