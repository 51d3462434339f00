"""Errors raised by the tactip package (front ends, streaming, station)."""

__all__ = ["TactipError", "SourceError", "ConfigError"]


class TactipError(Exception):
    """Base of every error the tactip package raises."""


class SourceError(TactipError):
    """A frame source cannot be opened or stopped delivering (missing camera, corrupt video)."""


class ConfigError(TactipError, ValueError):
    """A station configuration file is invalid; the message names the key."""
