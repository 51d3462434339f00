"""The pad back at rest, seen in the image, for `pins.track.PinTracker` (issue 20, outcome 2: identities through
slides filmed slowly).

A slide filmed at 15-20 frames/s moves pins by 1-2 spacings a frame (tactip-127: 8 slides of 3 pitches at 20
frames/s, 90 % of the pins step by 1.7-2.1 spacings in the frames of the drag and the lift), beyond what any
tracker of identical pins follows from frame to frame (half a spacing: the lattice aliases). Pins come out of the
slide on their neighbours' tips or lost, and the tracker's own test that the pad is back at rest
(`pins._rest`'s `snap_to_rest`: half the placed pins near rest) reads the positions it got wrong: with 90 of 127
pins lost and 20 on other tips it never fired, and the swaps stayed through the rests and after the last slide
(bench_conditions ``--checks slides``, tactip-127 at 20 frames/s, seed 40: 11-22 pins swapped in every rest).

The image does not alias: a frame that shows the rest frame again around a pin shows that pin at rest, whatever
the tracker made of the frames between. Per pin, the mean absolute difference between the frame and the rest
frame over a window of 0.6 spacings at its rest position; at rest it is the difference of two frames' noise
(``2 sigma / sqrt(pi)``, from the rest frame's noise, or learnt from the first still frame when a codec smoothed
that: through JPEG 60 ten times as much), in the frames of a slide or a press 2-20 times that over most pins
(tactip-127 at 20 frames/s: at most 43 % of the pins within twice the level in any moving frame, 100 % in every
frame at rest, its largest 1.07 times the level). When `REST_SHARE` of the pins match the rest frame, each
matching pin that is missing or farther than the gate from its rest position is measured there (its window at
rest, as `snap_to_rest` measures it) and placed where that settles on a tip like its own, else left lost; its
motion is not carried into the next frame (`matched`).

The test runs only in frames with such a pin (a still pad whose pins are all near rest pays nothing) and in the
first frames, until it has learnt the level from a still one; first on the windows of `_PROBES` pins (a
contact's frames stop there), then on all: a blur of one frame difference over the crop. On slides at 120
frames/s (`tests.pins.conftest.slide_run`, two slides, seed 0, CPU time, 3 interleaved rounds) an update
costs 0.84 -> 0.88 ms on tactip-331 and 0.47 -> 0.51 ms on radial-led-120 (0.85 -> 1.03, 0.47 -> 0.54
without the probe).
The probe is one compiled call (`pins._jit_rest.probe_matches`) that stops once the answer is known (a few
windows in a contact's frames): 2 us a frame against 21 us (radial-led-120's 8 slides, mp4v).
"""

from __future__ import annotations

import cv2
import numpy as np

from ._kernels import compiled
from ._noise import noise_sigma
from ._window import _squared_norm

# The frame shows the pad at rest when this share of the pins match the rest frame ...
REST_SHARE = 0.9
# ... each within this many times the level of a still frame's difference from it.
MATCH_LEVELS = 2.0
# The level learnt from a still frame (when a codec hid the noise from the rest frame's estimate) is at most
# this many times the rest frame's noise (JPEG 60 on renders: 8-10 times), and a still frame is one with this
# share of the pins placed within `_STILL_FRACTION` of the spacing of rest.
_MOST_LEVELS = 20.0
_LEARN_SHARE = 0.9
_STILL_FRACTION = 0.1
# The level is never below this, grey levels (a noiseless render: quantisation).
_LEAST_LEVEL = 0.5
# First, the windows of this many pins spread over the pad (their pixels gathered, no blur of the whole crop):
# unless `REST_SHARE` of them match, less one, the frame is no rest frame (most frames of a contact).
_PROBES = 24


class RestMatch:
    """Whether each pin's neighbourhood shows the rest frame again, and pins put back at rest where it does.

    Parameters
    ----------
    rest_crop : (h, w) ndarray of uint8
        The rest frame's crop as the tracker sees it (bright pins, the surround at the membrane's level).
    rest_positions : (N, 2) ndarray
        The pins at rest, px in the frame.
    origin : (2,) ndarray
        The crop's origin in the frame, px.
    spacing_px : float
        The pins' median spacing, px.

    Attributes
    ----------
    level : float
        Mean absolute difference, grey levels, between a still frame and the rest frame over a pin's window.
    matched : (N,) ndarray of bool or None
        After `restore`: the pins matching the rest frame when the frame showed the pad at rest, else None.
    """

    def __init__(self, rest_crop: np.ndarray, rest_positions: np.ndarray, origin: np.ndarray, spacing_px: float):
        self._rest = np.array(rest_crop, dtype=np.uint8, copy=True)
        self._side = max(2 * int(round(0.3 * spacing_px)) + 1, 3)
        height, width = rest_crop.shape[:2]
        points = np.rint(rest_positions - origin).astype(np.int64)
        self._x, self._y = np.clip(points[:, 0], 0, width - 1), np.clip(points[:, 1], 0, height - 1)
        probes = np.unique(np.linspace(0, len(rest_positions) - 1, min(_PROBES, len(rest_positions))).astype(int))
        half = self._side // 2
        offsets = np.arange(-half, half + 1)
        rows = np.clip(self._y[probes, None] + offsets, 0, height - 1)  # (P, side)
        columns = np.clip(self._x[probes, None] + offsets, 0, width - 1)
        self._probe_index = (rows[:, :, None] * width + columns[:, None, :]).reshape(len(probes), -1)
        self._probe_rest = self._rest.ravel()[self._probe_index].astype(np.int16)
        self._noise_level = max(2.0 * noise_sigma(rest_crop) / np.sqrt(np.pi), _LEAST_LEVEL)
        self.level = self._noise_level
        self._learnt = False
        self.matched: np.ndarray | None = None

    def _probe_matches(self, crop: np.ndarray) -> bool:
        """Whether enough of the probe pins' windows match the rest frame for the frame to be a rest frame.
        By a compiled kernel that stops once the answer is known (`pins._jit_rest.probe_matches`: 3-5 windows in
        most frames of a contact) unless ``TACTIP_KERNELS=numpy`` or Numba is missing."""
        kernels = compiled("_jit_rest")
        if kernels is not None:
            return kernels.probe_matches(crop.ravel(), self._probe_index, self._probe_rest, MATCH_LEVELS * self.level,
                                         REST_SHARE * len(self._probe_index) - 1)
        values = crop.ravel()[self._probe_index].astype(np.int16)
        differences = np.abs(values - self._probe_rest).mean(axis=1)
        return np.count_nonzero(differences <= MATCH_LEVELS * self.level) >= REST_SHARE * len(differences) - 1

    def differences(self, crop: np.ndarray) -> np.ndarray:
        """Each pin's mean absolute difference between `crop` and the rest crop over its window at rest,
        grey levels (N,)."""
        mean = cv2.boxFilter(cv2.absdiff(crop, self._rest), cv2.CV_32F, (self._side, self._side),
                             borderType=cv2.BORDER_REPLICATE)
        return mean[self._y, self._x].astype(np.float64)

    def restore(self, refiner, crop: np.ndarray, positions: np.ndarray) -> np.ndarray:
        """`positions` (N, 2), px, with the pins put back at rest where the frame shows the rest frame again
        (those beyond the gate or missing, and those off rest by more than the guess bound).

        `refiner` is the tracker's `pins._refine.Refiner` (rest positions, gate, windows and their judgement at
        rest); `crop` the frame's crop as the tracker sees it. Returns `positions` itself when nothing changed,
        else a copy; sets `matched`.
        """
        self.matched = None
        rest = refiner.rest_positions
        distance = _squared_norm(positions - rest)
        far = ~(distance <= refiner.gate_px ** 2)  # (missing too: NaN)
        if self._learnt and not (np.count_nonzero(far) and self._probe_matches(crop)):
            return positions
        differences = self.differences(crop)
        if not self._learnt:
            near = np.count_nonzero(distance <= (_STILL_FRACTION * refiner.spacing_px) ** 2)
            median = float(np.median(differences))
            if near >= _LEARN_SHARE * len(rest) and median > 0.0:  # (a still frame; not the rest frame again)
                self.level = max(self._noise_level, min(median, _MOST_LEVELS * self._noise_level))
                self._learnt = True
            if not np.count_nonzero(far):
                return positions
        match = differences <= MATCH_LEVELS * self.level
        if np.count_nonzero(match) < REST_SHARE * len(rest):
            return positions
        self.matched = match
        # Matching pins missing or beyond the gate, and those placed within it but off rest by more than the guess
        # bound (a window a neighbour's stale guess cut may settle a px off its tip: a slide filmed at 20 frames/s
        # left tactip-127's pin 41, seed 40, 1.28 px off at rest), are measured at rest; where their windows do not
        # settle there on a tip like at rest, the first are lost and the second stay where they were.
        drifted = _squared_norm(positions - rest) > refiner._guess_px ** 2  # (NaN: False)
        look = np.flatnonzero(match & (far | drifted))
        if not look.size:
            return positions
        centres, measures = refiner.windows.measure(crop, rest[look] - refiner.origin, refiner._rest_radius[look])
        centres += refiner.origin - refiner._rest_offset[look]
        ok = (_squared_norm(centres - rest[look]) <= refiner._settled_px ** 2) & refiner._like_at_rest(measures, look)
        if not np.count_nonzero(ok | far[look]):
            return positions
        positions = positions.copy()
        positions[look] = np.where(ok[:, None], centres, np.where(far[look, None], np.nan, positions[look]))
        return positions


def taken_off(before: np.ndarray, after: np.ndarray, rest_positions: np.ndarray, gate_px: float) -> int:
    """How many pins a frame's rest steps (`snap_to_rest`, `RestMatch.restore`) took off other pins' tips: placed
    in `before` (N, 2), px, farther than `gate_px` from their `rest_positions`, and within it in `after`.

    >>> taken_off(np.array([[30.0, 0.0], [0.0, 0.0]]), np.zeros((2, 2)), np.zeros((2, 2)), 5.0)
    1
    """
    with np.errstate(invalid="ignore"):
        far = _squared_norm(before - rest_positions) > gate_px ** 2
        back = _squared_norm(after - rest_positions) <= gate_px ** 2
    return int(np.count_nonzero(far & back))


def motion_warning(restored: int, frames: int, first: int, spacing_px: float) -> str:
    """What a user reads when pins came back to rest on other pins' tips (`taken_off`, summed over a
    video: `restored` pin-frames in `frames` frames, the first `first` frames after the rest frame), else "".

    >>> motion_warning(0, 0, 0, 20.0)
    ''
    """
    if not restored:
        return ""
    return (f"{restored} times a pin was on another pin's tip when the pad came back to rest ({frames} frames, the "
            f"first {first} frames after the rest frame): the pins moved farther between frames than the tracker "
            f"follows (about a quarter of a pin spacing, {0.25 * spacing_px:.0f} px, a frame; beyond half a spacing "
            f"it cannot). Identities were restored at "
            f"rest, but within contacts pins may be swapped: record at a higher frame rate or move more slowly")
