"""Errors raised by the calibration package."""

__all__ = ["CalibrationError"]


class CalibrationError(Exception):
    """Calibration cannot proceed (no sensor in view, pin count far from expected, ...)."""
