"""Errors raised by the pins package."""

__all__ = ["PinsError", "NoSensorError", "ShapeError"]


class PinsError(Exception):
    """Base of every error the pins package raises on bad input or state."""


class NoSensorError(PinsError):
    """The frame shows no sensor disc (lens cap on, camera pointing elsewhere)."""


class ShapeError(PinsError, ValueError):
    """An array does not have the shape a function expects."""
