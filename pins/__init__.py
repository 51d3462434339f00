"""Pins: detection, tracking, displacement integration, pin selection and tap features.

Pure array code: nothing here opens a camera, a file or an arm.
"""

from .detect import Blobs, DetectionParams, detect_blobs, detect_pins
from .disc import SensorDisc, as_grey, find_sensor_disc
from .errors import NoSensorError, PinsError, ShapeError

__all__ = [
    "PinsError", "NoSensorError", "ShapeError",
    "SensorDisc", "find_sensor_disc", "as_grey",
    "DetectionParams", "Blobs", "detect_pins", "detect_blobs",
]
