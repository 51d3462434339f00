"""Where lost pins are and whether to look for them there, for `pins._refine.Refiner`: predictions from
placed neighbours (`_predict`), trusted only where enough neighbours are placed (`_trusted`), and the
search in rounds that brings back a cluster of lost pins from its edge inwards (`search_in_rounds`).

A slide squeezes the skin ahead of it until tips merge: a cluster of pins is lost at once. A pin
inside it has too few placed neighbours for a prediction to be trusted (from one side of the squeezed
skin it lies a spacing off, on another pin's tip), so it waits until its neighbours come back. Those
on the cluster's edge are found first; each round searches again the pins next to ones just found,
from predictions that now interpolate them: the cluster is peeled within one frame instead of a ring
per frame (or per blob detection).
"""

from __future__ import annotations

import numpy as np

from ._window import _squared_norm

# A lost pin is searched for at its prediction only when this share of its neighbours is placed.
_TRUSTED_SHARE = 2 / 3
CARRY = False
GROWTH_FROM, GROWTH_AT_MOST = 0.1, 3.0


def _median(values: np.ndarray) -> np.ndarray:
    """Median over axis 1 of (L, k, 2) `values` of the finite rows (NaN sort last): (L, 2), NaN where none; sorts in place."""
    count = np.add.reduce(np.isfinite(values[..., 0]), axis=1)
    values.sort(axis=1)
    rows = np.arange(len(values))
    return 0.5 * (values[rows, (count - 1) // 2] + values[rows, count // 2])


# Rounds of `_Prediction.search_in_rounds` per frame (a cluster lost ahead of a slide is a few rings deep).
SEARCH_ROUNDS = 4


class _Prediction:
    """The prediction side of `pins._refine.Refiner` (reads `rest_positions`, `_neighbour_index`,
    `gate_px`, `still`; `search_in_rounds` calls `refine`)."""

    def remember(self, positions: np.ndarray, found: np.ndarray) -> None:
        """Keep, for the (N,) bool `found` pins of final (N, 2) `positions`, px, their neighbours' displacements now."""
        which = np.flatnonzero(found)
        if which.size:
            self._then[which] = (positions - self.rest_positions)[self._neighbour_index[which]]

    def _predict(self, positions: np.ndarray, which: np.ndarray, last_seen: np.ndarray) -> np.ndarray:
        """Where lost pins should be: rest position moved by the median displacement of tracked neighbours."""
        if CARRY:
            return self._carried(positions, which, last_seen)
        shift = self.neighbour_median(positions - self.rest_positions, which)
        return np.where(np.isnan(shift), last_seen[which], self.rest_positions[which] + shift)

    def _carried(self, positions: np.ndarray, which: np.ndarray, last_seen: np.ndarray) -> np.ndarray:
        """Lost pins `which` where last seen, carried along by the same neighbours since (px, (L, 2))."""
        rest = self.rest_positions[which]
        now = (positions - self.rest_positions)[self._neighbour_index[which]]  # (L, k, 2), a copy
        then = self._then[which]
        both = np.isfinite(now[..., 0]) & np.isfinite(then[..., 0])
        shift = _median(now.copy())  # any placed neighbours
        now[~both] = np.nan
        then = np.where(both[..., None], then, np.nan)
        median_now, median_then = _median(now), _median(then)
        offset = last_seen[which] - rest - median_then
        size = _squared_norm(median_then)
        growth = np.einsum("ij,ij->i", median_now, median_then) / np.where(size > 0, size, 1.0)
        growth = np.where(size >= (GROWTH_FROM * self.spacing_px) ** 2, np.clip(growth, 0.0, GROWTH_AT_MOST), 1.0)
        carried = median_now + growth[:, None] * offset
        shift = np.where(np.isfinite(carried), carried, shift)
        return np.where(np.isnan(shift), last_seen[which], rest + shift)

    def _trusted(self, positions: np.ndarray, which: np.ndarray, last_seen: np.ndarray,
                 predicted: np.ndarray | None = None) -> np.ndarray:
        """Whether pins `which` may be searched for at their predictions (`_predict`): (L,) bool.

        Where most of a pin's neighbours are placed (`_TRUSTED_SHARE` of them), its prediction
        interpolates their displacements. Where fewer are (at least two), only when they did not move
        in the last frame (`still`) and the prediction lies within the gate of where the pin was last
        seen: nothing moved there since (a whole rim ring coming back under a held press). From a
        few on one side of the squeezed skin ahead of a slide (its displacement changes by most of a
        spacing per spacing there) a prediction lies a spacing off, on another pin's tip (issue 20:
        tactip-331 slides, 2 or 3 of 6 neighbours placed, predictions 10-25 px off at a 17.7 px spacing).
        `predicted` (L, 2), px: the pins' predictions from `positions`, when known.
        """
        index = self._neighbour_index[which]
        placed = np.isfinite(positions[index, 0])
        count = np.count_nonzero(placed, axis=1)
        trusted = count >= _TRUSTED_SHARE * index.shape[1]
        few = np.flatnonzero(~trusted & (count >= 2) & ~(placed & ~self.still[index]).any(axis=1))
        if few.size:
            guess = self._predict(positions, which[few], last_seen) if predicted is None else predicted[few]
            moved = _squared_norm(guess - last_seen[which[few]])
            trusted[few] = moved <= self.gate_px ** 2
        return trusted

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


    def search_in_rounds(self, crop: np.ndarray, positions: np.ndarray, last_seen: np.ndarray,
                         search: np.ndarray, rounds: int | None = None) -> np.ndarray:
        """Lost pins searched for again (`refine`) while the last round placed some of their neighbours.

        Parameters
        ----------
        crop : (h, w) ndarray of uint8
            The frame's crop at `origin`, bright pins.
        positions : (N, 2) ndarray
            Positions so far, px; NaN where missing (placed ones are kept as they are).
        last_seen : (N, 2) ndarray
            Each pin's last known position, px.
        search : (N,) ndarray of bool
            Missing pins that may be searched for (retired ones take turns).
        rounds : int, optional
            At most this many rounds (default `SEARCH_ROUNDS`): the first searches every such pin, each later one those with
            a neighbour found in the round before.

        Returns
        -------
        positions : (N, 2) ndarray of float64
            `positions`, or a copy with the pins found, px.
        """
        want = np.isnan(positions[:, 0]) & search
        for _ in range(SEARCH_ROUNDS if rounds is None else rounds):
            if not want.any():
                break
            placed = np.isfinite(positions[:, 0])
            after = self.refine(crop, positions, last_seen, want, placed)
            fresh = np.isfinite(after[:, 0]) & ~placed
            if not fresh.any():
                break
            positions = after
            lost = np.isnan(positions[:, 0]) & search
            want = lost & fresh[self._neighbour_index].any(axis=1)
        return positions
