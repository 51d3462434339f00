"""Detection tuned to a sensor whose pin count is known: the count confirms, it does not steer.

A TacTip has a known number of pins (127, 331, 532 ...). `tune_detection` finds the pin field
without the count (`pins.find_pin_field`: the blobs that form the pin lattice, at detection
parameters scaled to the measured pitch) and then checks the count: within `tolerance` it returns
the field's detection parameters; far off it refuses, saying how far off and what may be wrong.
A pin or two hidden by a rim ring or cut by the image edge no longer makes tuning fail, as it did
when the count drove a search over parameters.

Calibration runs it once per sensor and stores the result; every later frame is detected with the
stored `DetectionParams`.
"""

from __future__ import annotations

import numpy as np

from .detect import DetectionParams
from .disc import SensorDisc
from .errors import PinsError
from .lattice import find_pin_field

__all__ = ["tune_detection", "expected_spacing_px"]


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
                   tolerance: float = 0.1, disc: SensorDisc | None = None) -> DetectionParams:
    """Detection parameters for a sensor of `expected_pins` pins, found in a rest frame.

    The pin field is found without the count (`find_pin_field`); the count only confirms it.

    Parameters
    ----------
    frame : (H, W) or (H, W, 3) ndarray of uint8
        A rest frame (no contact) of the sensor.
    expected_pins : int
        Number of pins the sensor has.
    start : DetectionParams, optional
        Starting parameters: tried among the candidates; their polarity (`dark_pins`) is kept, and
        their `rim_margin_px` at least (widened to leave out the membrane beyond the pin field).
    tolerance : float
        Largest accepted relative difference between the pins found and `expected_pins` (0.1:
        10 %; rim pins hidden by a rim ring or the image edge are usually a few %).
    disc : SensorDisc, optional
        The sensor disc, found in `frame` when not given.

    Returns
    -------
    params : DetectionParams
        The pin field's detection parameters (`PinField.params`).

    Raises
    ------
    PinsError
        The pin lattice found differs from `expected_pins` by more than `tolerance` (the message
        gives the count found, how far off it is, and likely causes).
    NoSensorError
        The frame shows no sensor disc.
    ValueError
        `expected_pins` is not a positive integer or `tolerance` is outside [0, 1).

    Examples
    --------
    >>> params = tune_detection(rest_frame, 331)            # doctest: +SKIP
    >>> pins = detect_pins(frame, params=params)            # doctest: +SKIP
    """
    if isinstance(expected_pins, bool) or int(expected_pins) != expected_pins or expected_pins < 1:
        raise ValueError(f"expected_pins must be a positive integer, got {expected_pins!r}")
    if not 0.0 <= tolerance < 1.0:
        raise ValueError(f"tolerance must be in [0, 1), got {tolerance}")
    start = start or DetectionParams()
    field = find_pin_field(frame, expected_pins=int(expected_pins), params=start, disc=disc,
                           dark_pins=start.dark_pins)
    _check_pin_count(field.count, int(expected_pins), tolerance=tolerance)
    return field.params


def _check_pin_count(found: int, expected_pins: int, *, tolerance: float) -> None:
    """Refuse (`PinsError`) a pin count more than `tolerance` (relative) away from `expected_pins`.

    Parameters
    ----------
    found : int
        Pins in the pin field.
    expected_pins : int
        The sensor's pin count.
    tolerance : float
        Largest accepted relative difference.

    Raises
    ------
    PinsError
        One line: the count found, how far off, and likely causes.
    """
    error = int(found) - int(expected_pins)
    if abs(error) <= tolerance * expected_pins:
        return
    if found == 0:
        why = "no pin lattice in view (lens covered, out of focus, or dark pins without --dark-pins?)"
    elif error < 0:
        why = ("pins hidden (a rim ring, the image edge, something touching the pad), out of focus or too "
               "faint, or a wrong count")
    else:
        why = "is the count right? (the lattice holds more pins than that)"
    raise PinsError(f"could not tune pin detection to {expected_pins} pins: the pin lattice has {found} pins "
                    f"({error:+d}, {error / expected_pins:+.0%}; tolerance {tolerance:.0%}): {why}")
