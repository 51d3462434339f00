"""Pins: detection, tracking, displacement integration, pin selection and tap features.

Pure array code: nothing here opens a camera, a file or an arm.
"""

from .errors import NoSensorError, PinsError, ShapeError

__all__ = ["PinsError", "NoSensorError", "ShapeError"]
