"""Auto-tuning of pin detection to a sensor whose pin count is known.

A TacTip has a known number of pins (127, 331, 532 ...). `tune_detection` searches the blur,
the adaptive-threshold block size and offset, and the blob area limits for the parameters that
detect that many pins in a rest frame, preferring, among those that do, the most regular blobs
(similar areas, well-filled bounding boxes). Calibration runs it once per sensor and stores the
result; every later frame is detected with the stored `DetectionParams`.

The search is scaled by the pin spacing expected from the disc size and the pin count, so the
same grid works for any camera resolution and pin density.
"""

from __future__ import annotations

import itertools

import numpy as np

from .detect import DetectionParams, _detect
from .disc import SensorDisc, as_grey, find_sensor_disc
from .errors import PinsError

__all__ = ["tune_detection", "expected_spacing_px"]

_BLURS = (0.8, 1.2, 1.8)
_BLOCK_SPACINGS = (1.0, 1.5, 2.2, 3.2)
_OFFSETS = (5.0, 9.0, 14.0, 22.0, 34.0)
# Final area limits around the median blob area (foreshortened rim pins are smaller).
_AREA_RANGE = (0.25, 2.5)


def expected_spacing_px(disc: SensorDisc, expected_pins: int) -> float:
    """Typical pin spacing, px, if `expected_pins` pins on a hexagonal grid filled the disc.

    Parameters
    ----------
    disc : SensorDisc
    expected_pins : int

    Returns
    -------
    spacing : float
        px; the pins near the centre of a hemispherical pad are a little closer than this.
    """
    # A hexagonal cell of spacing s has area sqrt(3)/2 s^2.
    return float(np.sqrt(np.pi * disc.radius_px**2 / expected_pins / (np.sqrt(3.0) / 2.0)))


def tune_detection(frame: np.ndarray, expected_pins: int, *, start: DetectionParams | None = None,
                   tolerance: float = 0.01, disc: SensorDisc | None = None) -> DetectionParams:
    """Detection parameters that find `expected_pins` pins in a rest frame.

    Parameters
    ----------
    frame : (H, W) or (H, W, 3) ndarray of uint8
        A rest frame (no contact) of the sensor.
    expected_pins : int
        Number of pins the sensor has (visible ones).
    start : DetectionParams, optional
        Starting parameters: tried first; their polarity (`dark_pins`) and `rim_margin_px` are kept.
    tolerance : float
        Accepted relative difference between the detected and the expected count (0.01: 1 %).
    disc : SensorDisc, optional
        The sensor disc, found in `frame` when not given.

    Returns
    -------
    params : DetectionParams
        The best parameters found.

    Raises
    ------
    PinsError
        No parameters detect a count within `tolerance` of `expected_pins` (the message gives
        the closest count).
    NoSensorError
        The frame shows no sensor disc.

    Examples
    --------
    >>> params = tune_detection(rest_frame, 331)            # doctest: +SKIP
    >>> pins = detect_pins(frame, params=params)            # doctest: +SKIP
    """
    if int(expected_pins) != expected_pins or expected_pins < 1:
        raise ValueError(f"expected_pins must be a positive integer, got {expected_pins}")
    if not 0.0 <= tolerance < 1.0:
        raise ValueError(f"tolerance must be in [0, 1), got {tolerance}")
    start = start or DetectionParams()
    grey = as_grey(frame)
    if disc is None:
        disc = find_sensor_disc(grey, dark_pins=start.dark_pins)
    spacing = expected_spacing_px(disc, int(expected_pins))
    # Loose limits for the search: anything from a few px to a merged pair of pins.
    loose = dict(min_area_px=3, max_area_px=max(int(1.5 * spacing**2), 20), min_fill=0.3, max_aspect=4.0,
                 split_radius_px=0.15 * spacing)
    candidates = [start]
    for blur, block, offset in itertools.product(_BLURS, _BLOCK_SPACINGS, _OFFSETS):
        size = max(2 * int(round(block * spacing / 2.0)) + 1, 3)
        candidates.append(start.replace(blur_sigma_px=blur, block_size_px=size, offset=offset, **loose))
    scored = [_score(grey, disc, params, expected_pins) for params in candidates]
    best = min(scored, key=lambda s: (s[0], s[1]))
    # Final area limits and split radius from the median blob of the best candidate, checked again.
    error, _, params, median_area = best
    radius = np.sqrt(median_area / np.pi)
    final = params.replace(min_area_px=max(int(_AREA_RANGE[0] * median_area), 1),
                           max_area_px=max(int(np.ceil(_AREA_RANGE[1] * median_area)), 2),
                           min_fill=0.45, max_aspect=2.5, split_radius_px=round(float(0.4 * radius), 2))
    final_error = _score(grey, disc, final, expected_pins)[0]
    if final_error > error:
        final = params
        final_error = error
    if final_error > tolerance * expected_pins:
        count = expected_pins + _signed_error(grey, disc, final, expected_pins)
        raise PinsError(
            f"could not tune pin detection to {expected_pins} pins: the closest count was {count} "
            f"(tolerance {tolerance:.1%}); check the expected pin count, focus and lighting")
    return final


def _score(grey: np.ndarray, disc: SensorDisc, params: DetectionParams,
           expected: int) -> tuple[int, float, DetectionParams, float]:
    """(count error, irregularity, params, median area) of one candidate."""
    blobs = _detect(grey, disc, params)
    if len(blobs.areas) == 0:
        return expected, np.inf, params, 0.0
    median_area = float(np.median(blobs.areas))
    error = abs(len(blobs.areas) - expected)
    q25, q75 = np.percentile(blobs.areas, [25, 75])
    # Regular pins: similar areas and full boxes.
    irregularity = (q75 - q25) / median_area + (1.0 - float(np.median(blobs.fills)))
    return error, irregularity, params, median_area


def _signed_error(grey: np.ndarray, disc: SensorDisc, params: DetectionParams, expected: int) -> int:
    return len(_detect(grey, disc, params).areas) - expected
