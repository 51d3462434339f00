"""The still pad: windows' scatter at rest and pins put back at their rest positions, for
`pins._refine.Refiner` (paper 002, III-A.3).

Rest. The rest positions are the windows' own fixed points near the given ones (a few passes of
mean shift), and what still pulls a window at rest is the pin's rest offset, taken off its first
window later: the rest frame given again places every pin. A step within the search's settling
bound is camera noise, not velocity. Near its rest position a window at its guess is judged by
its centroid less that offset. On a pad back at rest (half the pins within 0.1 spacing of rest,
hardly any between that and the gate but a faint tip's jitter among still neighbours), pins far
from rest, drifted by more than a few tenths of a px, and missing ones are looked for at their
rest positions (`Refiner.snap_to_rest`): a fast return from a slide cannot leave them on their
neighbours' tips, nor a faint rim tip's window on the veil beside it.

Noise. The bounds the camera's noise sets (each window's scatter in it, its contrast's scatter and with
it the tips' bounds at rest, `pins._like`) are drawn from the rest frame's own noise; through a video
codec, which smooths the noise within a frame but not from frame to frame, that is too little, and the
first still frame after the rest frame widens the tips' bounds to the scatter of the contrast it shows
(`_AtRest.heed_camera_noise`).

`_AtRest` holds these steps; `pins._refine.Refiner` inherits them and sets the state they read
(`rest_positions`, `_rest_offset`, `_rest_radius`, the learnt scatters, `_settled_px`, `_guess_px`).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ._kernels import compiled
from ._like import bounds_at_rest
from ._noise import _JITTER_BOUND, _JITTER_FIRST, _JITTER_RATE, _learn_mean_square, noise_sigma
from ._window import _squared_norm

# The pad is back at rest when this share of the placed pins lie within this fraction of the
# spacing of their rest positions.
_STILL_SHARE = 0.5
_STILL_FRACTION = 0.1
# ... and at most this share of them lie between that and the gate (a moving pad's field of
# displacements is continuous: its transition from still to moved pins holds many).
_BETWEEN_SHARE = 0.02
# A pin's window at rest is calm within this many times its learnt scatter of where its still
# neighbours place it (the scatter of its steps misses the constant part: its rest offset's noise).
_CALM_BOUND = 5.0
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
        -> 259, half a spacing apart 8 -> 22, > 3 px 56 -> 86; without it 210, 8, 57).
        """
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
        self.still = self.still  # (its setter redraws the area bound the passes read)
        return True

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
        the check costs a few vector operations per frame. (First, till a still frame has been paired with
        the rest frame, the bounds the camera's noise sets are checked against it: `heed_camera_noise`.)
        By two compiled kernels round the window
        measurement (`pins._jit_rest`: the same positions and learnt scatters) unless
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
        if self._rest_for_noise is not None:
            self.heed_camera_noise(crop, positions)
        kernels = compiled()
        if kernels is not None:
            return self._snap_to_rest_compiled(kernels, crop, positions, search)
        distance = _squared_norm(positions - self.rest_positions)  # NaN where missing
        # Pins that drifted from rest by more than a window's settling in noise are looked at again.
        # (count_nonzero: `ndarray.any` costs several times more on a hundred pins.)
        drifted = distance > self._guess_px ** 2
        if not (np.count_nonzero(drifted) or np.count_nonzero(np.isnan(distance) & search)):
            return positions
        still = distance <= (_STILL_FRACTION * self.spacing_px) ** 2
        placed = np.count_nonzero(np.isfinite(distance))
        if np.count_nonzero(still) < _STILL_SHARE * placed:
            return positions  # the pad is not at rest (most frames of a contact: decided before the rest)
        # A moving pad's field of displacements is continuous: between its still pins and those
        # moved farther than the gate lie pins moved by less. Pins put on wrong tips are off by
        # a whole spacing, with none in between.
        # A faint tip's window jitters in noise by up to a fifth of the spacing: a pin within that of
        # rest whose neighbours are still is such jitter, not motion.
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
        # Where its neighbours say the pin is: its rest position moved by their median displacement.
        # When they lie within a few tenths of a px of rest, the membrane there is at rest (it is
        # continuous: no pin moves by a px alone), and a window that settles within a few times its
        # own scatter in noise (`observe_still`; up to twice the search's bound) shows the pin there.
        # (A pin's scatter, or the median pin's if more: it is learnt from steps.)
        shift = self.displacement_median(positions, look)
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
        if not np.count_nonzero(found):
            return positions
        positions = positions.copy()
        positions[look[found]] = np.where(calm[found, None], rest[found] + shift[found], centres[found])
        return positions


    def _snap_to_rest_compiled(self, kernels, crop: np.ndarray, positions: np.ndarray, search: np.ndarray) -> np.ndarray:
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
            self._jitter_sq, self._rest_scatter_sq, self._rest_scatter_seen, self._noise_scatter_sq,
            float(self._jitter_floor), self._at_least, self._area_at_most, _JITTER_FIRST, _JITTER_BOUND ** 2,
            _JITTER_RATE)[0]
