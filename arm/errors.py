"""Errors raised by the arm package."""

__all__ = ["ArmError", "ArmConfigError", "SafetyError", "ArmFault", "ArmConnectionError"]


class ArmError(Exception):
    """Base of every error the arm package raises."""


class ArmConfigError(ArmError, ValueError):
    """The `[arm]` configuration is missing a key or has one out of range."""


class SafetyError(ArmError):
    """A requested move breaks a safety limit; nothing was sent to the arm."""


class ArmFault(ArmError):
    """The arm or its controller failed a command (protective stop, rejected move, ...)."""


class ArmConnectionError(ArmFault):
    """The controller cannot be reached, or remote control is off."""
