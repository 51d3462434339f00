"""Arm: one interface, a Universal Robots backend (ur-rtde), a simulated arm, tap motion, safety."""

from .errors import ArmConfigError, ArmConnectionError, ArmError, ArmFault, SafetyError

__all__ = ["ArmError", "ArmConfigError", "SafetyError", "ArmFault", "ArmConnectionError"]
