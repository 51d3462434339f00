"""Arm: one interface, a Universal Robots backend (ur-rtde), a simulated arm, tap motion, safety.

Poses are TCP poses in the work frame (z up, origin on the part's surface reference), mm and degrees;
a positive tap depth goes down into the part. See `arm.interface` for the contract.
"""

from .base import BaseArm
from .commissioning import StatusReport, arm_status, check_tap
from .config import ArmConfig, SafetyLimits, SimSettings, arm_config_from_table, load_arm_config
from .errors import ArmConfigError, ArmConnectionError, ArmError, ArmFault, SafetyError
from .factory import make_arm
from .interface import Arm, ArmState, TapEvent
from .pose import Pose, pose_from_ur, pose_to_ur
from .safety import check_move, check_ready
from .profile import trapezoid_duration
from .sim import SimArm
from .tap import TapMotion, plan_tap
from .world import Gap, PlateWorld, WorldContact

__all__ = [
    "ArmError", "ArmConfigError", "SafetyError", "ArmFault", "ArmConnectionError",
    "Arm", "ArmState", "TapEvent", "BaseArm",
    "ArmConfig", "SimSettings", "arm_config_from_table", "load_arm_config",
    "Pose", "pose_to_ur", "pose_from_ur",
    "SafetyLimits", "check_move", "check_ready",
    "TapMotion", "plan_tap",
    "SimArm", "trapezoid_duration", "Gap", "PlateWorld", "WorldContact",
    "make_arm", "StatusReport", "arm_status", "check_tap",
]
