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

Followed pins' guesses: a step within the settling bound (0.1 spacings) is a still pin's jitter, not
carried, unless its neighbourhood moves: the median of its neighbours' steps lies beyond what the
camera's noise gives such a median (`carried_velocity`). In the skin squeezed ahead of a slide a window
sitting on the plateau of two overlapping tips steps by a few tenths of a px while its tip moves by px;
it carried its neighbours' median step only beyond the settling bound (1.8 px on tactip-331), and tips
moving 0.4-0.8 px a frame for tens of frames left such windows 4-5 px behind, on the neighbour's tip. The
noise is the rest frame's (`_drift_bound_sq`), not the scatter learnt from still steps: a slide's slow
steps count as still ones and that scatter grows with them (tactip-331: the bound rose from 0.75 to 1.16
px under a pin moving 0.6-0.78 px a frame, seed 4, and nothing was carried). Measured on
`bench/bench_slides.py` (8 slides of 3 pitches; tuned on seeds 0-2, seeds 3-5 held out of the tuning,
seed 4 not of that diagnosis), main 9a221aa -> now, pin-frames on another pin's tip: realistic skin
tactip-331 107 -> 15 (held out 73 -> 5), small-pad-100 32 -> 24 (43 -> 15), radial-led-120 12 -> 4 (13 ->
13); model skin tactip-331 3118 -> 2392 (3263 -> 2415), small-pad-100 108 -> 92 (164 -> 78),
radial-led-120 17 -> 7 (32 -> 21); visible pins lost per frame, seeds 0-5, realistic 1.48 -> 0.90
(tactip-331), 5.02 -> 4.86, 2.95 -> 2.91, model 13.03 -> 10.74, 5.97 -> 5.52, 3.64 -> 3.21; back at rest
nothing changes (0 pins > 1 px). Two slides (`tests/pins/test_track_identity.py`), seeds 0-5,
radial-led-120 4/13/12/0/0/1 -> 0/0/0/0/0/6 pin-frames on another pin's tip.
"""

from __future__ import annotations

import numpy as np

from ._identity import gathered
from ._kernels import compiled
from ._window import _squared_norm

# A lost pin is searched for at its prediction only when this share of its neighbours is placed.
_TRUSTED_SHARE = 2 / 3
# A still pin's step (within the settling bound) is carried only where its neighbours' median step lies
# beyond this many standard deviations of a step's noise; its own step when within this share of that
# median from it, else the median.
_DRIFT_SIGMAS = 3.0
_AGREE_SHARE = 0.5


def settle(positions: np.ndarray, velocity: np.ndarray, lost_run: np.ndarray, retire_after: int,
           last_seen: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A frame's bookkeeping for the next (`pins.track.PinTracker.update`): the steps to carry (N, 2), px (`velocity`,
    NaN as 0), the pins lost (N,) bool (`positions` (N, 2), px, not finite), their runs of frames lost (N,) int
    (`lost_run`, the last frame's, plus one; 0 when found) and the retired ones (runs beyond `retire_after`); the
    found pins' positions into `last_seen` (N, 2), px, in place. By the compiled kernel (`pins._jit_track.settle`,
    one call for ten NumPy calls) unless ``TACTIP_KERNELS=numpy`` or Numba is missing."""
    kernels = compiled()
    if kernels is not None and positions.dtype == velocity.dtype == last_seen.dtype == np.float64 and (
            lost_run.dtype == np.int64):
        return kernels.settle(positions, velocity, lost_run, retire_after, last_seen)
    carried = np.where(np.isnan(velocity), 0.0, velocity)  # (np.nan_to_num costs 5x more)
    # Per column: a reduction over (N, 2) rows costs more than the four calls.
    found = np.isfinite(positions[:, 0]) & np.isfinite(positions[:, 1])
    run = np.where(found, 0, lost_run + 1)
    np.copyto(last_seen, positions, where=found[:, None])
    return carried, ~found, run, run > retire_after


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

    Reads `rest_positions`, `_neighbour_index`, `gate_px`, `still`, `_guess_px`, `_settled_px`, the
    windows' scatter in the rest frame's noise (`_noise_scatter_sq`: `pins._rest`), and `_then` ((N, k, 2)
    px: each pin's neighbours' displacements from rest when it was last placed; zeros at the start, at rest).
    """

    def remember(self, positions: np.ndarray) -> None:
        """Keep, for the pins placed in a frame's final (N, 2) `positions`, px, their neighbours' displacements."""
        kernels = compiled()
        if kernels is not None:
            kernels.remember(positions, self.rest_positions, self._neighbour_index, self._then)
            return
        which = np.flatnonzero(np.isfinite(positions[:, 0]))
        if which.size:
            self._then[which] = gathered(positions - self.rest_positions, self._neighbour_index[which])

    def _predict(self, positions: np.ndarray, which: np.ndarray, last_seen: np.ndarray) -> np.ndarray:
        """Where lost pins `which` should be, px (L, 2): where last seen, moved as their neighbours did since.

        Over each pin's neighbours placed both in `positions` (N, 2), px, and when it was last placed
        (`remember`): its `last_seen` position plus the change of their median displacement. Without
        such neighbours: its rest position moved by the median displacement of its placed neighbours;
        without any: `last_seen`. By the compiled kernel (`pins._jit_track.predict`) unless
        ``TACTIP_KERNELS=numpy`` or Numba is missing; the same figures.
        """
        kernels = compiled()
        if kernels is not None:
            return kernels.predict(positions, self.rest_positions, self._then, self._neighbour_index[which],
                                   np.asarray(which, dtype=np.int64), last_seen)
        index = self._neighbour_index[which]
        # The three medians in one (3 L, k, 2) sort: over the neighbours placed now (`either`), and
        # over those placed both now and then, now and then (their change).
        stack = np.empty((3,) + index.shape + (2,))
        now, both_now, then = stack
        np.subtract(gathered(positions, index), gathered(self.rest_positions, index), out=now)
        then[...] = self._then[which]
        both = np.isfinite(now[..., 0]) & np.isfinite(then[..., 0])
        np.copyto(both_now, now)
        stack[1:, ~both] = np.nan
        either, now_both, then_both = _median(stack.reshape((-1,) + stack.shape[2:])).reshape(3, len(index), 2)
        carried = last_seen[which] + (now_both - then_both)
        fallback = np.where(np.isnan(either), last_seen[which], self.rest_positions[which] + either)
        return np.where(np.isfinite(carried), carried, fallback)

    def _predict_from_neighbours(self, positions: np.ndarray, which: np.ndarray, last_seen: np.ndarray) -> np.ndarray:
        """Pins `which` at their rest positions moved by the median displacement of their placed neighbours, px (L, 2).

        (`last_seen` where none is placed.)
        """
        shift = self.displacement_median(positions, which)
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
        kernels = compiled()
        if kernels is not None:
            return kernels.trusted(positions, self._neighbour_index, np.asarray(which, dtype=np.int64), self.still,
                                   predicted, last_seen, _TRUSTED_SHARE * self._neighbour_index.shape[1],
                                   self.gate_px ** 2)
        index = self._neighbour_index[which]
        placed = np.isfinite(positions[index, 0])
        count = np.count_nonzero(placed, axis=1)
        trusted = count >= _TRUSTED_SHARE * index.shape[1]
        few = np.flatnonzero(~trusted & (count >= 2) & ~np.logical_or.reduce(placed & ~self.still[index], axis=1))
        if few.size:
            moved = _squared_norm(predicted[few] - last_seen[which[few]])
            trusted[few] = moved <= self.gate_px ** 2
        return trusted

    def carried_velocity(self, velocity: np.ndarray, still: np.ndarray) -> np.ndarray:
        """Each pin's step to carry into the next frame's guess, px (N, 2), from its last step `velocity` (N, 2), px.

        A step beyond the settling bound (not `still`, (N,) bool) is carried. A step within it is carried
        only where the pin's neighbourhood moves: the median of its neighbours' steps lies beyond what
        noise gives such a median (`_drift_bound_sq`: a few times its scatter in the camera's noise, at
        least the guess bound). Then the pin carries its own step when that agrees with the median (a
        slow, coherent motion: a slide's start and end), else the median (a window stalled on the
        plateau of two overlapping tips in the skin squeezed ahead of a slide steps by a few tenths of a
        px while its tip and neighbours step by px: issue 20, tactip-331 realistic skin, guesses 4-5 px
        behind tips moving 0.4-2.2 px a frame). Elsewhere (a still pad, a faint tip's jitter) zero.
        `velocity` is changed in place and returned; by the compiled kernel (`pins._jit_track`, one call)
        unless ``TACTIP_KERNELS=numpy`` or Numba is missing.
        """
        bound_sq = self._drift_bound_sq()
        kernels = compiled()
        if kernels is not None and velocity.dtype == np.float64 and velocity.flags.writeable:
            kernels.carried_velocity(velocity, still, bound_sq, self._neighbour_index, _AGREE_SHARE ** 2)
            return velocity
        with np.errstate(invalid="ignore"):
            active = ~still | (_squared_norm(velocity) > bound_sq)  # (NaN, a lost pin: active, not finite)
        active &= np.isfinite(velocity[:, 0])
        if not active.any():
            np.copyto(velocity, 0.0, where=still[:, None])  # (`velocity[still] = 0.0` costs more)
            return velocity  # (a still pad: nothing to carry)
        # Only still pins near a step beyond noise (a gather of bools: the medians are the cost).
        which = np.flatnonzero(still)
        which = which[active[which] | np.logical_or.reduce(active[self._neighbour_index[which]], axis=1)]
        own = velocity[which]  # (a copy)
        around = self.neighbour_median(velocity, which)  # (of the steps as they are: still ones too)
        np.copyto(velocity, 0.0, where=still[:, None])
        size = _squared_norm(around)
        moving = size > bound_sq[which]  # (NaN compares False)
        agree = _squared_norm(own - around) <= _AGREE_SHARE ** 2 * size
        velocity[which[moving]] = np.where(agree[:, None], own, around)[moving]
        return velocity

    def _drift_bound_sq(self) -> np.ndarray:
        """Each pin's bound on its neighbours' median step that is noise, px^2 (N,): `_DRIFT_SIGMAS` times
        that median's scatter in the camera's noise, at least the guess bound. A step is the difference of
        two noisy centroids, each of the scatter the rest frame's own noise gives the pin's window
        (`_noise_scatter_sq`); the median of k of them scatters about sqrt(pi / 2k) times as much. (Not the
        scatter learnt from still steps, `observe_still`: a slide's slow steps lie within the settling
        bound, and that scatter grows with them.)"""
        # (Fixed once the rest frame is measured: kept while `_noise_scatter_sq`, `_guess_px` and the
        # neighbours are those it was computed from; each is assigned, never changed in place.)
        key = (self._noise_scatter_sq, self._guess_px, self._neighbour_index)
        memo = self.__dict__.get("_drift_bound_memo")
        if memo is not None and all(a is b for a, b in zip(memo[0], key)):
            return memo[1]
        k = self._neighbour_index.shape[1]
        bound = np.maximum(_DRIFT_SIGMAS ** 2 * 2.0 * self._noise_scatter_sq * np.pi / (2 * k), self._guess_px ** 2)
        self._drift_bound_memo = (key, bound)
        return bound

    def displacement_median(self, positions: np.ndarray, which: np.ndarray) -> np.ndarray:
        """``neighbour_median(positions - rest_positions, which)``, px (L, 2), of (N, 2) `positions`, px:
        compiled without forming the displacements (`pins._jit_track.displacement_median`)."""
        kernels = compiled()
        if kernels is not None:
            return kernels.displacement_median(positions, self.rest_positions, self._neighbour_index[which])
        return self.neighbour_median(positions - self.rest_positions, which)

    def neighbour_median(self, values: np.ndarray, which: np.ndarray) -> np.ndarray:
        """Median of the finite (N, 2) `values` of each pin's `neighbours` nearest pins at rest, for pins `which`.

        Returns (L, 2), NaN for a pin none of whose neighbours has a finite value. By the compiled kernel
        (`pins._jit_track.neighbour_median`, no gather) unless ``TACTIP_KERNELS=numpy`` or Numba is missing.
        """
        kernels = compiled()
        if kernels is not None:
            return kernels.neighbour_median(values, self._neighbour_index[which])
        return _median(gathered(values, self._neighbour_index[which]))  # (L, k, 2), a copy
