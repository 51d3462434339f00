"""The still pad: windows' scatter at rest and pins put back at their rest positions, for `pins._refine.Refiner` (paper
002, III-A.3).

Rest. The rest positions are the windows' own fixed points near the given ones (a few passes of mean shift), and what
still pulls a window at rest is the pin's rest offset, taken off its first window later: the rest frame given again
places every pin. A step within the search's settling bound is camera noise, not velocity. Near its rest position a
window at its guess is judged by its centroid less that offset. On a pad back at rest (half the pins within 0.1 spacing
of rest, hardly any between that and the gate but a faint tip's jitter among still neighbours), pins far from rest,
drifted by more than a few tenths of a px, and missing ones are looked for at their rest positions
(`Refiner.snap_to_rest`): a fast return from a slide cannot leave them on their neighbours' tips, nor a faint rim tip's
window on the veil beside it.

Noise. The bounds the camera's noise sets (each window's scatter in it, its contrast's scatter and with it the tips'
bounds at rest, `pins._like`) are drawn from the rest frame's own noise; through a video codec, which smooths the noise
within a frame but not from frame to frame, that is too little, and the first still frame after the rest frame widens
the tips' bounds to the scatter of the contrast it shows (`_AtRest.heed_camera_noise`). In that frame no window's own
scatter is learnt yet, and the one the rest frame's noise predicts is too small by as much: `snap_to_rest`'s calm test
there reads it grown by the ratio of the two noises (radial-led-120 mp4v seed 3: a tip's area read 66 px^2 at rest, 240
in the first still frame: lost).

Levels. The rest frame is one noisy frame, and a faint tip's measures there (its bounds the noise's, `pins._like`) may
lie several of its scatters from its own level: each faint tip learns that level, the mean of its window's readings at
rest over the frames of a pad at rest, and has the bounds of it (only ever wider) while it is still or steady: lost or
jittering by its window's noise among still neighbours (`_AtRest._learn_levels`, `_AtRest._draw_bounds`).

Each pin has a level, learnt bounds and steadiness in (3, N) and (N,) arrays (only faint tips' change); each frame's
bounds are picked from them by compiled calls (`pins._jit_rest`: 0.07 ms a frame less than NumPy).

`_AtRest` holds these steps; `pins._refine.Refiner` inherits them and sets the state they read (`rest_positions`,
`_rest_offset`, `_rest_radius`, the learnt scatters, `_settled_px`, `_guess_px`)."""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ._kernels import compiled
from ._like import _NOISE_REACH, bounds_at_rest, bounds_from_level
from ._noise import _JITTER_BOUND, _JITTER_FIRST, _JITTER_RATE, _learn_mean_square, noise_sigma
from ._window import _squared_norm

# The pad is back at rest when this share of the placed pins lie within this fraction of the
# spacing of their rest positions.
_STILL_SHARE = 0.5
_STILL_FRACTION = 0.1
# ... and at most this share of them lie between that and the gate (a moving pad's field of
# displacements is continuous: its transition from still to moved pins holds many).
_BETWEEN_SHARE = 0.02
# A pin's window at rest is calm within this many times its learnt scatter of where its still neighbours place it (the
# scatter of its steps misses the constant part: its rest offset's noise); a faint tip's neighbours but this many agree.
_CALM_BOUND = 5.0
_ODD_NEIGHBOURS = 1
_FLOOR_EVERY = 8
# Draws of noise that measure each rest window's scatter before any is learnt.
_NOISE_DRAWS = 4
# The first frame after the rest frame with at least this share of the pins within `_STILL_FRACTION` of the
# spacing of rest (and any pixel changed) is a still pair with it: the camera's noise, as it moves the windows,
# is read from the windows' change between them (`heed_camera_noise`) ...
_PAIR_STILL_SHARE = 0.9
# ... and when the windows' contrast scatters between them by more than this factor times what the rest frame's
# own noise predicts (a codec smoothed that frame: 1.3-11 x on renders through MJPG and mp4v; raw renders never,
# radial-led-120, tactip-331, small-pad-100, white-dark-331 seeds 0-11), the tips' bounds are widened to it.
_WIDER_NOISE = 1.25
# ... and a tip judged by all three measures (`pins._like`) that was still in the last frame may lose this many
# times the reach of its contrast (so much more than the rest frame's noise allows, `pins._like._NOISE_REACH`):
# through a codec the rest frame (an I-frame through mp4v) is less like the frames after it than they are like
# each other, and faint tips on reflections read 3-8 grey levels lower in them on average (radial-led-120 seeds 7,
# 24: 18.7 and 23.2 at rest, 15.3 over 40 still frames, scatter 2.6). sqrt 2: the scatter of a difference of two
# frames. A moving pin keeps the bound of 1 reach (identity through slides unchanged).
_PAIR_REACH = 2.0 ** 0.5
# A faint tip (its contrast at rest below twice the reach of the noise, `pins._like`: its bound on contrast the
# noise's) learns its level, the mean of its measures over the frames it was seen still, and may fall from that as
# far as from its rest frame's (`_AtRest._learn_levels`): bounds only ever widened, the contrast's by at most one
# more reach below the rest frame's bound, the area's and compactness's by at most this factor.
_LEVEL_CAP = 2.0
# ... from at most this many readings (its level's scatter a sixth of one frame's; then no window more a frame).
_LEVEL_READINGS = 36


@lru_cache(maxsize=1)
def _standard_draws(shape: tuple[int, int]) -> tuple[np.ndarray, ...]:
    """`_NOISE_DRAWS` fields of standard normal noise of ``shape`` from the fixed seed 0, read-only; cached
    per crop shape (a station's taps share one): 12 ms of a tap's start on a 468 x 468 px crop.

    ``rng.normal(0.0, sigma, shape)`` is ``0.0 + sigma * z`` of the same stream's standard normal draws
    ``z`` (numpy's ``random_normal``), so these times ``sigma`` are its draws bit for bit.
    """
    rng = np.random.default_rng(0)  # a fixed draw: the same rest frame, the same bound
    draws = tuple(rng.standard_normal(shape) for _ in range(_NOISE_DRAWS))
    for draw in draws:
        draw.flags.writeable = False
    return draws


def noisy_copies(crop: np.ndarray) -> tuple[np.ndarray, ...]:
    """The grey `crop` with each of the `_NOISE_DRAWS` fixed draws of Gaussian noise of its own level
    (`noise_sigma`) added, clipped and truncated to uint8: what another frame of a still pad could show.
    Empty for a noiseless crop. (Measured once at a tracker's start for the windows' scatter in noise,
    `_AtRest._noise_scatter_sq_px2`, and their contrast's, `pins._like.contrast_noise`: widened if the
    first still frame shows more, `_AtRest.heed_camera_noise`.)"""
    sigma = noise_sigma(crop)
    if not sigma > 0:
        return ()
    copies = []
    for draw in _standard_draws(crop.shape):
        noisy = np.multiply(draw, sigma)  # `rng.normal(0.0, sigma, shape)` of seed 0, bit for bit
        noisy += crop  # in place: the crop plus the draw, clipped and truncated to uint8
        copies.append(np.clip(noisy, 0, 255, out=noisy).astype(np.uint8))
    return tuple(copies)


class _AtRest:
    """The rest side of `pins._refine.Refiner`: noise of the rest windows, still steps, snapping to rest."""

    # The contrast bounds of still and moving pins, (N,) each, once a still pair widened them (`heed_camera_noise`):
    # `pins._refine.Refiner.still`'s setter puts them in `_at_least`.
    _contrast_still = None
    _contrast_moving = None
    # The faint tips (`_await_levels`; none till a rest frame is seen); per pin (N,), False but for faint tips: steady
    # in the last frame (`observe_still`), and on a pad at rest round it (`_learn_levels`).
    _faint = np.empty(0, dtype=np.intp)
    _steady = _at_rest_here = np.empty(0, dtype=bool)

    def _noise_scatter_sq_px2(self, rest_crop: np.ndarray, noisy: tuple, positions: np.ndarray) -> np.ndarray:
        """Each rest window's mean square displacement, px^2 (N,), in the `noisy` copies of the rest crop
        (`noisy_copies`): how far one frame's noise moves the window (a faint tip in glare: tenths of a
        px; a crisp one: hundredths); 0 without copies (a noiseless crop)."""
        if not noisy:
            return np.zeros(len(positions))
        points, radius = positions - self.origin, self.window_radius(positions)
        base = self.windows.measure(rest_crop, points, radius)[0]
        total = np.zeros(len(positions))
        for copy in noisy:
            total += _squared_norm(self.windows.measure(copy, points, radius)[0] - base)
        return np.where(np.isfinite(total), total / _NOISE_DRAWS, 0.0)

    def _await_still_pair(self, rest_crop: np.ndarray, measures: tuple) -> None:
        """Keep the rest crop and its tips' (area, contrast, compactness) at rest, (N,) each, for `heed_camera_noise`."""
        self._rest_for_noise = (rest_crop, measures)
        self._await_levels(measures)

    def _await_levels(self, measures: tuple) -> None:
        """Start each faint tip's level (`_learn_levels`) from its (area, contrast, compactness) at rest, (N,)
        each: the tips whose contrast at rest lies below twice the noise's reach, one reading each.

        Every pin has a level, its bounds and its steadiness, in (3, N) and (N,) arrays (`_draw_bounds` picks
        each pin's bounds in a few whole-array steps); only the faint tips' are ever read or changed."""
        self._rest_least = self._at_least.copy()  # (the bounds from below the rest frame draws)
        contrast = measures[1]
        self._faint = np.flatnonzero(contrast < 2.0 * _NOISE_REACH * self.contrast_noise)  # (NaN compares False)
        faint = np.zeros(len(contrast), dtype=bool)
        faint[self._faint] = True
        self._odd_neighbours = faint * np.int64(_ODD_NEIGHBOURS)  # (N,): `snap_to_rest`'s quiet test, per pin
        level = np.stack(measures)
        seen = np.isfinite(level) & faint
        self._level_seen = seen.astype(np.float64)
        self._level_sum = np.where(seen, level, 0.0)
        self._learnt_least = self._still_least(self._rest_least)
        self._learnt_most = self._area_at_most_rest.copy()
        self._steady = np.zeros(len(contrast), dtype=bool)
        self._at_rest_here = np.zeros(len(contrast), dtype=bool)  # (`_learn_levels`: the pad at rest round it)

    def _still_least(self, least: np.ndarray, pins: np.ndarray | slice = slice(None)) -> np.ndarray:
        """Bounds from below (3, L) of `pins` held still (faint tips' learnt bounds, `_draw_bounds`): no higher than
        a still tip's from the rest frame (its contrast's `_contrast_still` after a codec's still pair)."""
        if self._contrast_still is None:
            return least.copy()
        still = self._rest_least[:, pins]  # (a copy)
        still[1] = self._contrast_still[pins]
        return np.fmin(still, least)

    def _learn_levels(self, crop: np.ndarray, positions: np.ndarray) -> None:
        """Each faint tip placed near its rest position (within `_STILL_FRACTION` of the spacing; or lost, one judged by
        its contrast alone) on a pad at rest (`_PAIR_STILL_SHARE` of the pins there) among neighbours that lie within
        the guess bound of rest reads its window at rest (the rest frame's) in `crop`: its level is the mean of these
        readings and its rest frame's, its bounds those of that level (`pins._like.bounds_from_level`), which
        `_draw_bounds` gives it while it is still or steady.

        The rest frame is one noisy frame: a faint tip's contrast there may lie several of its scatters above its level
        (radial-led-120 seed 37: 22.6 at rest, 14.0 +- 2.3 over 40 still frames; its area 7.9 at rest, 13.2 +- 3.0), and
        its bounds from that frame then lose it on a still pad. A tip judged by all three measures reads only while
        placed (one that vanished is lost and teaches nothing); one judged by its contrast alone, which no frame tells
        from nothing, reads while lost too (its readings while placed would be those its bound let through: seed 46's
        tip of contrast 9.6 at rest, 4.2 +- 2.8 over the still frames, 7.9 over those it was placed in). The bounds only
        ever widen, the contrast's by at most one reach more than the rest frame's (a tip fading under glare walks them
        no farther), the area's and compactness's by at most `_LEVEL_CAP` times; and a judged tip whose level sank
        within the reach of nothing keeps its rest frame's bounds (a tip that vanished on a still pad, the windows that
        placed it by their contrast alone, `snap_to_rest`'s calm pins, reading the membrane: its bounds would follow).
        """
        faint = self._faint
        if not faint.size:
            return
        near_sq = (_STILL_FRACTION * self.spacing_px) ** 2
        kernels = compiled("_jit_rest")
        if kernels is not None:  # (one compiled call, the same pins)
            pins = kernels.faint_here(positions, self.rest_positions, faint, self._neighbour_index, near_sq,
                                      _PAIR_STILL_SHARE, self._guess_px ** 2, self._judged, self._level_seen[1],
                                      _LEVEL_READINGS, self._at_rest_here)
        else:
            pins = self._faint_here(positions, near_sq)
        if not pins.size:
            return
        readings = np.stack(self.windows.measure(crop, self.rest_positions[pins] - self.origin, self._rest_radius[pins])[1])
        finite = np.isfinite(readings)
        self._level_sum[:, pins] += np.where(finite, readings, 0.0)
        self._level_seen[:, pins] += finite
        seen = self._level_seen[:, pins]
        with np.errstate(invalid="ignore", divide="ignore"):
            level = self._level_sum[:, pins] / seen  # (NaN where none was finite)
        judged = self._judged[pins]
        least, most = bounds_from_level(level, seen, judged, self.contrast_noise)
        rest_least, rest_most = self._rest_least[:, pins], self._area_at_most_rest[pins]
        # Only ever wider, and within the caps (NaN, a measure never read, leaves the rest frame's bound) ...
        reach = _NOISE_REACH * self.contrast_noise
        least[1] = np.maximum(least[1], rest_least[1] - reach)
        least[2] = np.fmax(least[2], rest_least[2] / _LEVEL_CAP)
        least, most = np.fmin(rest_least, least), np.fmax(rest_most, np.fmin(most, _LEVEL_CAP * rest_most))
        # ... and not for a tip judged by all three measures whose level sank within the reach of nothing: it
        # vanished (the windows that placed it read the membrane) or was never there; its rest frame's bounds stand.
        sunk = judged & ~(level[1] > reach)
        self._learnt_least[:, pins] = self._still_least(np.where(sunk, rest_least, least), pins)
        self._learnt_most[pins] = np.where(sunk, rest_most, most)

    def _faint_here(self, positions: np.ndarray, near_sq: float) -> np.ndarray:
        """`_learn_levels`' checks (the NumPy reference of `pins._jit_rest.faint_here`): on a pad at rest, which
        faint tips are at rest there (`_at_rest_here`, set) and which read their windows at rest (returned)."""
        faint = self._faint
        distance = _squared_norm(positions - self.rest_positions)
        if np.count_nonzero(distance <= near_sq) < _PAIR_STILL_SHARE * len(distance):
            self._at_rest_here[faint] = False
            return faint[:0]  # not a pad at rest
        here = _squared_norm(self.displacement_median(positions, faint)) <= self._guess_px ** 2
        self._at_rest_here[faint] = here
        away = distance[faint]
        # (A lost tip compares False to both: it reads only if judged by its contrast alone.)
        near = (away <= near_sq) | (np.isnan(away) & ~self._judged[faint])
        near &= here
        near &= self._level_seen[1, faint] < _LEVEL_READINGS
        return faint[near]

    def heed_camera_noise(self, crop: np.ndarray, positions: np.ndarray) -> bool:
        """Widen the bounds that the camera's noise sets to the noise the first still frame after the rest
        frame shows, once, when a codec hid it from the rest frame; whether they were widened.

        A video codec smooths the noise within a frame: the windows at rest measured again under noise of
        the rest frame's own level (Immerkaer's estimate, `noisy_copies`) scatter 0.25-0.85 times as much as
        they do from frame to frame through MJPG and mp4v, and faint tips on reflections, whose contrast may
        fall by a few times that scatter (`pins._like`), were lost on a still pad. The windows' contrast in
        the rest crop and in `crop` (a frame, bright pins, whose placed `positions` (N, 2), px, lie mostly
        within `_STILL_FRACTION` of the spacing of rest: `_PAIR_STILL_SHARE`) differ by the noise that moves
        them: the median absolute difference over 0.6745 sqrt 2 is the contrast's scatter. Above
        `_WIDER_NOISE` times the rest frame's figure (`contrast_noise`), it replaces it and the tips' bounds at
        rest are drawn again from it (never narrower), and a judged tip still in the last frame may lose
        `_PAIR_REACH` times the contrast's reach (the still setter, `pins._refine.Refiner.still`, picks the
        bound per pin each frame). The first such pair decides (a frame identical to the
        rest frame is none): till then a frame costs a few vector operations, after it nothing.

        Each window's scatter in noise (`_noise_scatter_sq`: the calm test at rest, the drift bound) is left
        as the rest frame draws it. Grown by the square of the same ratio it swapped more identities through
        slides (radial-led-120, 8 slides of 3 pitches, seeds 0-5, MJPG: pin-frames on another pin's tip 213
        -> 259, half a spacing apart 8 -> 22, > 3 px 56 -> 86; without it 210, 8, 57)."""
        if self._rest_for_noise is None:
            return False
        distance = _squared_norm(positions - self.rest_positions)  # NaN where missing: not near
        if np.count_nonzero(distance <= (_STILL_FRACTION * self.spacing_px) ** 2) < _PAIR_STILL_SHARE * len(distance):
            return False
        rest_crop, (area, contrast, compactness) = self._rest_for_noise
        points = self.rest_positions - self.origin
        change = np.abs(self.windows.contrast(crop, points) - self.windows.contrast(rest_crop, points))
        change = change[np.isfinite(change)]
        scatter = float(np.median(change)) / (0.6745 * np.sqrt(2.0)) if change.size else 0.0
        if scatter == 0.0:
            return False  # the rest frame again: no pair
        self._rest_for_noise = None
        if not scatter > _WIDER_NOISE * self.contrast_noise:
            return False
        self.contrast_noise = scatter
        self._at_least, self._area_at_most_rest = bounds_at_rest(area, contrast, compactness, scatter)
        self._contrast_moving = self._at_least[1].copy()
        self._contrast_still = bounds_at_rest(area, contrast, compactness, scatter, _PAIR_REACH)[0][1]
        self._judged = np.isfinite(self._area_at_most_rest)
        self._await_levels((area, contrast, compactness))  # (faint at this noise: from their rest frame again)
        self.still = self.still  # (its setter redraws the area bound the passes read)
        return True

    def _draw_bounds(self) -> None:
        """The bounds the passes read (`_at_least`, `_area_at_most`) for the pins still in the last frame
        (`pins._refine.Refiner.still`) and the faint tips steady in it (`observe_still`) on a pad at rest round
        them (`_learn_levels`), from the bounds at rest: a tip judged by its contrast alone has an area bound only
        while still (its window places it only then: steady, its centroid would walk off the tip); a judged tip
        still or steady may lose `_PAIR_REACH` reaches once a codec's still pair widened the bounds
        (`heed_camera_noise`); a faint tip still or steady on a pad at rest round it has the bounds of its level.
        (Not on a pad in contact, however still the tip: radial-led-120's realistic slides, seed 4, kept a faint
        tip 5.5-6.7 px off its centre for 20 frames of a slide's end by its level's wider area bound.)"""
        still = self._still
        kernels = compiled("_jit_rest") if self._faint.size else None  # (without faint tips two NumPy calls do)
        if kernels is not None:  # (one compiled call, the same bounds)
            pair = self._contrast_still is not None
            self._at_least, self._area_at_most = kernels.draw_bounds(
                still, self._steady, self._at_rest_here, self._judged, self._rest_least, self._learnt_least,
                self._learnt_most, self._area_at_most_rest, self._contrast_still if pair else self._area_at_most_rest,
                self._contrast_moving if pair else self._area_at_most_rest, pair)
            return
        area_at_most = np.where(self._judged | still, self._area_at_most_rest, -np.inf)
        if not self._faint.size:
            if self._contrast_still is not None:
                self._at_least[1] = np.where(still, self._contrast_still, self._contrast_moving)
            self._area_at_most = area_at_most
            return
        mine = still | self._steady
        mine &= self._at_rest_here  # (N,): faint tips still or steady on a pad at rest round them
        at_least = np.where(mine, self._learnt_least, self._rest_least)
        if self._contrast_still is not None:
            at_least[1] = np.where(mine, at_least[1], np.where(still, self._contrast_still, self._contrast_moving))
        self._at_least = at_least
        mine &= self._judged  # (-inf for a tip judged by its contrast alone that is not still: kept)
        np.copyto(area_at_most, self._learnt_most, where=mine)
        self._area_at_most = area_at_most

    def still(self, steps: np.ndarray) -> np.ndarray:
        """Whether each (N, 2) step, px, lies within the search's settling bound (camera noise, not motion): (N,) bool."""
        return _squared_norm(steps) <= self._settled_px ** 2

    def observe_still(self, steps: np.ndarray) -> np.ndarray:
        """Learn each window's scatter from one frame's (N, 2) steps, px; returns which steps were still (N,) bool.

        A step within the settling bound (`still`) is the difference of two noisy centroids: half its
        square updates the pin's running mean square scatter (the mean of its first `_JITTER_FIRST`,
        then weight `_JITTER_RATE` for steps within `_JITTER_BOUND` times the scatter so far).
        """
        kernels = compiled()
        if kernels is not None and self._jitter_seen.dtype == np.float64:  # (one compiled call, the same figures)
            still = kernels.observe_still(steps, self._settled_px ** 2, self._jitter_sq, self._jitter_seen,
                                          _JITTER_FIRST, _JITTER_BOUND ** 2, _JITTER_RATE)
        else:
            half = _squared_norm(steps)
            still = half <= self._settled_px ** 2  # NaN (lost) compares False
            half *= 0.5
            # Slow motion (a tap's onset) is no noise: `_learn_mean_square`'s bound leaves it out.
            _learn_mean_square(self._jitter_sq, self._jitter_seen, slice(None), half, still)
        if self._faint.size and kernels is not None:
            if compiled("_jit_rest").faint_steady(steps, self._faint, self._neighbour_index, self._guess_px ** 2,
                                                  self._settled_px ** 2, self._steady):
                self._draw_bounds()  # (else the still setter drew them as they are)
        elif self._faint.size:
            # A faint tip whose window stepped within the settling bound, or that was lost, among neighbours that
            # stepped within the guess bound is steady: the membrane there is still (its window's jitter in
            # noise, tenths of a px, is no motion), and it is judged as a still tip (`_draw_bounds`).
            faint = self._faint
            own = _squared_norm(steps[faint])
            steady = ~(own <= self._guess_px ** 2) & ~(own > self._settled_px ** 2)  # (NaN, lost: a candidate)
            if np.count_nonzero(steady):
                around = self.neighbour_median(steps, faint[steady])
                steady[steady] = _squared_norm(around) <= self._guess_px ** 2
            if not np.array_equal(steady, self._steady[faint]):  # (else the still setter drew them as they are)
                self._steady[faint] = steady
                self._draw_bounds()
        seen, jitter = self._jitter_seen, self._jitter_sq
        self._observed += 1
        if self._observed % _FLOOR_EVERY == 1:
            learnt = jitter[seen >= _JITTER_FIRST]
            self._jitter_floor = float(np.median(learnt)) if learnt.size else 0.0
        return still

    def snap_to_rest(self, crop: np.ndarray, positions: np.ndarray, search: np.ndarray) -> np.ndarray:
        """Pins far from rest on a pad back at rest placed on the tips at their own rest positions.

        When at least `_STILL_SHARE` of the placed pins lie within `_STILL_FRACTION` of the spacing of their rest
        positions and hardly any (`_BETWEEN_SHARE`) lie between that and `gate_px` (the pad is back at rest: a moving
        pad's field of displacements is continuous; a pin within twice that fraction whose neighbours are still is a
        faint tip's jitter), a pin farther than `gate_px` from its rest position (a fast return from a slide carried its
        stale guess onto a neighbour's tip), drifted by more than a few tenths of a px, or missing is looked for in a
        window at its rest position (its centroid less the rest offset). A pin far from rest or missing is placed there
        when the window settles within the search's bound on a tip like its own at rest. A *calm* pin (its still
        neighbours' median displacement within a few tenths of a px, the neighbours agreeing as a still membrane's do,
        and its window within `_CALM_BOUND` times its learnt scatter of where they place it: from its steps,
        `observe_still`, or from its windows at rest here, whichever is larger) is placed where they place it, its tip
        shown by its contrast. A pin placed near rest that is not calm keeps its place. Whatever a moving pad does,
        nothing is moved: the check costs a few vector operations per frame. (First, till a still frame has been paired
        with the rest frame, the bounds the camera's noise sets are checked against it: `heed_camera_noise`.) By two
        compiled kernels round the window measurement (`pins._jit_rest`: the same positions and learnt scatters) unless
        ``TACTIP_KERNELS=numpy`` or Numba is missing.

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
        noise_scatter_sq = self._noise_scatter_sq
        if self._rest_for_noise is not None:
            contrast_noise = self.contrast_noise
            if self.heed_camera_noise(crop, positions) and contrast_noise > 0:  # (0: a noiseless rest frame)
                # The still pair itself: no window's scatter is learnt yet (a pin its follow passes lost here
                # has no step), and the rest frame's noise, which a codec hid, predicts each window's 1.4-8 x
                # too small (`bench/bench_noise_codecs.py`): its calm test reads it grown by the pair's own
                # ratio of noises, this frame only (grown for good it swapped identities through slides).
                noise_scatter_sq = noise_scatter_sq * (self.contrast_noise / contrast_noise) ** 2
        positions = self._snap_to_rest(crop, positions, search, noise_scatter_sq)
        if self._faint.size and self._rest_for_noise is None:  # (after the first still pair: not the rest frame again)
            self._learn_levels(crop, positions)
        return positions

    def _snap_to_rest(self, crop: np.ndarray, positions: np.ndarray, search: np.ndarray,
                      noise_scatter_sq: np.ndarray) -> np.ndarray:
        """`snap_to_rest`'s placing: the positions, or a copy with pins found at their rest positions (each window's
        scatter in the camera's noise `noise_scatter_sq`, px^2 (N,), for the calm test)."""
        kernels = compiled()
        if kernels is not None:
            return self._snap_to_rest_compiled(kernels, crop, positions, search, noise_scatter_sq)
        distance = _squared_norm(positions - self.rest_positions)  # NaN where missing
        # Pins drifted from rest by more than a window's settling in noise are looked at again (count_nonzero: `any`
        # costs several times more on a hundred pins).
        drifted = distance > self._guess_px ** 2
        if not (np.count_nonzero(drifted) or np.count_nonzero(np.isnan(distance) & search)):
            return positions
        still = distance <= (_STILL_FRACTION * self.spacing_px) ** 2
        placed = np.count_nonzero(np.isfinite(distance))
        if np.count_nonzero(still) < _STILL_SHARE * placed:
            return positions  # the pad is not at rest (most frames of a contact: decided before the rest)
        # A moving pad's field of displacements is continuous: between its still pins and those moved farther than the
        # gate lie pins moved by less. Pins put on wrong tips are off by a whole spacing, with none in between. A faint
        # tip's window jitters in noise by up to a fifth of the spacing: a pin within that of rest whose neighbours are
        # still is such jitter, not motion.
        far = distance > self.gate_px ** 2
        between = np.flatnonzero(~still & ~far & np.isfinite(distance))
        if between.size:
            around = _squared_norm(self.displacement_median(positions, between))
            jitter = (around <= (_STILL_FRACTION * self.spacing_px) ** 2) & (
                distance[between] <= (2.0 * _STILL_FRACTION * self.spacing_px) ** 2)
            between = between[~jitter]
        if between.size > _BETWEEN_SHARE * placed:
            return positions  # the pad is not at rest
        look = np.flatnonzero(drifted | (np.isnan(distance) & search))
        rest = self.rest_positions[look]
        centres, measures = self.windows.measure(crop, rest - self.origin, self._rest_radius[look])
        centres += self.origin - self._rest_offset[look]
        # Where its neighbours say the pin is: its rest position moved by their median displacement. When they lie
        # within a few tenths of a px of rest, the membrane there is at rest (it is continuous: no pin moves by a px
        # alone), and a window that settles within a few times its own scatter in noise (`observe_still`; up to twice
        # the search's bound) shows the pin there. (A pin's scatter, or the median pin's if more: learnt from steps.)
        shift = self.displacement_median(positions, look)
        quiet = _squared_norm(shift) <= self._guess_px ** 2  # NaN (no placed neighbour) compares False
        # ... among neighbours that agree as a still membrane's do, each within the guess bound of their median or 5
        # scatters, or on another tip (tactip-127 seed 0's creeping patch: pin 10 1.2 px off, its 0-2.3, median 0.6).
        index = self._neighbour_index[look]
        moved, noise = positions[index] - self.rest_positions[index], np.maximum(np.maximum(
            self._jitter_sq[index], noise_scatter_sq[index]), self._jitter_floor)  # (NaN, not placed, compares False)
        apart = _squared_norm(moved - shift[:, None]) > np.maximum(self._guess_px ** 2, _CALM_BOUND ** 2 * noise)
        apart &= _squared_norm(moved) <= self.gate_px ** 2
        quiet &= np.count_nonzero(apart, axis=1) <= self._odd_neighbours[look]
        residual = _squared_norm(centres - rest - shift)
        scatter = np.maximum(np.maximum(self._jitter_sq[look], self._rest_scatter_sq[look]),
                             np.maximum(noise_scatter_sq[look], self._jitter_floor))
        calm = quiet & (residual <= _CALM_BOUND ** 2 * scatter)
        bound = np.where(calm, 2.0 * self._settled_px, self._settled_px)
        # A calm pin's window need only show a tip (its contrast): its area and compactness near the rim's veil swing
        # with the noise of its top pixels.
        like = np.where(calm, measures[1] >= self._at_least[1, look], self._like_at_rest(measures, look))
        found = (_squared_norm(centres - rest) <= bound ** 2) & like
        # A pin placed near rest that really moved keeps its place (a window at rest cuts its tip).
        found &= calm | ~(distance[look] <= self.gate_px ** 2)
        # The window's own scatter about where its still neighbours place the pin, learnt from the windows that showed
        # it here, after the test (a window never widens its own bound): a faint tip in the veil scatters by tenths of a
        # px, and its steps, taken with its neighbours once it is placed where they say, do not show that.
        _learn_mean_square(self._rest_scatter_sq, self._rest_scatter_seen, look, residual, quiet & found)
        if not np.count_nonzero(found):
            return positions
        positions = positions.copy()
        positions[look[found]] = np.where(calm[found, None], rest[found] + shift[found], centres[found])
        return positions

    def _snap_to_rest_compiled(self, kernels, crop: np.ndarray, positions: np.ndarray, search: np.ndarray,
                               noise_scatter_sq: np.ndarray) -> np.ndarray:
        """`snap_to_rest` by two compiled kernels (`pins._jit_track.rest_look`, `rest_judge`; `kernels`: `pins._jit`)
        round its window measurement: the same positions and learnt scatters, bit for bit."""
        spacing = self.spacing_px
        distance, look, go = kernels.rest_look(
            positions, self.rest_positions, search, self._neighbour_index, self._guess_px ** 2,
            (_STILL_FRACTION * spacing) ** 2, _STILL_SHARE, self.gate_px ** 2, (2.0 * _STILL_FRACTION * spacing) ** 2,
            _BETWEEN_SHARE)
        if not go:
            return positions
        rest = self.rest_positions[look]
        centres, measures = self.windows.measure(crop, rest - self.origin, self._rest_radius[look])
        return kernels.rest_judge(
            centres, measures, look, positions, distance, self.rest_positions, self._rest_offset, self.origin,
            self._neighbour_index, self._guess_px ** 2, _CALM_BOUND ** 2, self._settled_px, self.gate_px ** 2,
            self._jitter_sq, self._rest_scatter_sq, self._rest_scatter_seen, noise_scatter_sq,
            float(self._jitter_floor), self._at_least, self._area_at_most, _JITTER_FIRST, _JITTER_BOUND ** 2,
            _JITTER_RATE, self._odd_neighbours)[0]
