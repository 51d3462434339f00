"""The hysteresis thresholds of a replay's contacts (`tactip.replay.contacts.find_contacts`), px: from the pins'
spacing and, where it sets them, their tracking noise."""

from __future__ import annotations

import numpy as np

from pins import jitter_floor_px, tap_signal

__all__ = ["REFERENCE_PITCH_PX", "noise_limited", "tap_thresholds_px"]
# Pin spacing, px, at which the tap thresholds are segment_taps' defaults (331 pins, 640x480).
REFERENCE_PITCH_PX = 17.5


def tap_thresholds_px(displacements: np.ndarray, spacing_px: float, *, usable: np.ndarray | None = None,
                      signal: np.ndarray | None = None, medians: np.ndarray | None = None,
                      jitter_px: float | None = None) -> tuple[float, float]:
    """The hysteresis thresholds of `pins.segment_taps` for this sensor, px: (high, low).

    The defaults (1.5 and 0.5 px) fit a pad whose pins are about `REFERENCE_PITCH_PX` apart in the
    image; on a pad seen smaller (a small pad, a low resolution) the pins move proportionally less
    and the thresholds shrink with the pitch (never grow), but stay above the tracking noise: the
    low threshold at least twice the tap signal of a still pad (the lower of the frames' 10th
    percentile and the signal the pins' frame-to-frame jitter gives, `pins.jitter_floor_px`).

    Parameters
    ----------
    displacements : (T, N, 2) ndarray
        px, NaN where lost.
    spacing_px : float
        Median nearest-neighbour pin spacing at rest, px.
    usable : (T,) ndarray of bool, optional
        Frames to measure the noise on (tracked, not blank); all by default.
    signal : (T,) ndarray, optional
        The tap signal of every frame (`pins.tap_signal`) when already computed, px.
    medians : (T, N, 2) ndarray, optional
        The pins' neighbourhood medians (`pins.neighbour_median`), px: the floor is the lower of the pins' and
        theirs. Where the pins' own noise reaches the low threshold, `find_contacts` finds contacts on the
        medians, whose noise is lower where the pins' is their own (radial-led-120's tours: a still pad's tap
        signal 0.55 px on the pins, 0.3 on the medians; a press peaks at 1.0-1.8 px on both).
    jitter_px : float, optional
        `pins.jitter_floor_px` of ``displacements`` (over ``usable``) when already computed, px.
    """
    factor = min(1.0, spacing_px / REFERENCE_PITCH_PX) if np.isfinite(spacing_px) and spacing_px > 0 else 1.0
    if signal is None:
        signal = tap_signal(displacements)
    quiet = signal if usable is None else signal[usable]
    floor = float(np.percentile(quiet, 10)) if quiet.size else 0.0
    # A recording that is mostly contact (slides with short rests between them) has few quiet frames
    # to measure the floor on: the noise is also measured from the frame-to-frame jitter of the pins
    # (`pins.jitter_floor_px`), which contact does not raise, and the lower of the two is kept.
    floor = min(floor, jitter_floor_px(displacements, usable=usable) if jitter_px is None else jitter_px)
    if medians is not None and noise_limited(floor, spacing_px):   # the pins' noise sets them: the medians'
        floor = min(floor, jitter_floor_px(medians, usable=usable))
    low = max(0.5 * factor, 2.0 * floor)
    return max(1.5 * factor, 2.0 * low), low


def noise_limited(floor_px: float, spacing_px: float) -> bool:
    """Whether the pins' own noise sets the tap thresholds: their still tap signal (``floor_px``, e.g.
    `pins.jitter_floor_px`) puts the low threshold (twice it) at twice or more `tap_thresholds_px`' least for this
    pin spacing (px). There `find_contacts` finds contacts on the neighbourhood medians and `tap_thresholds_px`
    takes their noise floor: radial-led-120's tours 2.2-3.8 times that least, tactip-127's and white-dark-331's
    0.2-0.3; the renderer's pins with 0.1 px of noise per axis 1.2-1.3 (331, 127 and 1000 pins), 2.7 (radial,
    120 pins) and 4.7 (100 pins on a small pad)."""
    factor = min(1.0, spacing_px / REFERENCE_PITCH_PX) if np.isfinite(spacing_px) and spacing_px > 0 else 1.0
    return bool(floor_px >= 0.5 * factor)
