"""The flags that describe the sensor for the scale (mm/px), shared by ``tactip detect`` and ``tactip replay``.

Both derive the scale by one rule (`pins.sensor_scale`: the sensor's pin pitch in mm over the central
pin pitch in px), so the same flags mean the same thing in both; ``tactip calibrate`` reads the same
description from ``[sensor]`` (pins, pad_diameter_mm).
"""

from __future__ import annotations

import argparse

from tactip.cli._types import float_in_range, int_in_range

__all__ = ["add_scale_arguments", "pin_count", "MAX_PINS"]

#: Most pins of a pad (a dense one); a count above it is a typo (``--expected-pins 1e30``).
MAX_PINS = 2000


def pin_count(text: str) -> int:
    """An argparse type: a pin count of at least one ring and at most a dense pad (7..2000)."""
    return int_in_range(7, MAX_PINS)(text)


def add_scale_arguments(parser: argparse.ArgumentParser) -> None:
    """--sensor, --pins-on-pad, --pad-diameter-mm and --mm-per-px (the arguments of `pins.sensor_scale`)."""
    from pins import SENSOR_PRESETS

    parser.add_argument("--sensor", choices=sorted(SENSOR_PRESETS), metavar="NAME",
                        help="the sensor, for the scale from its pin (or marker) pitch: "
                        + "; ".join(f"{d.name} ({d.brief()})" for d in SENSOR_PRESETS.values()))
    parser.add_argument("--pins-on-pad", type=pin_count, metavar="N",
                        help="pins on the whole pad, in view or not, for the pin pitch (default: the sensor's, "
                        "else --expected-pins, else the pins detected)")
    parser.add_argument("--pad-diameter-mm", type=float_in_range(0, 500, low_open=True, unit="mm"), metavar="MM",
                        help="diameter of the hemispherical pad, mm, for the pin pitch (default: the sensor's, "
                        "else 40)")
    parser.add_argument("--mm-per-px", type=float_in_range(0, 10, low_open=True, unit="mm/px"), metavar="MM",
                        help="image scale at the pad, mm per px, instead of the one from the pin pitch")
