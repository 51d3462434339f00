"""Calibration: sensor calibration, data collection protocol, training and fixation search."""

from .errors import CalibrationError

__all__ = ["CalibrationError"]
