"""Safety checks run before every move. A move that breaks a limit is refused, never clipped.

Limits (`arm.config.SafetyLimits`, from the ``[arm]`` configuration; work frame, z up, surface reference at
``z = 0``):

- the target TCP position lies in the workspace box (the path is a straight line between two points of a
  convex box, so it stays inside too);
- the target is no deeper than ``max_tap_depth`` below ``z = 0``;
- speed in ``(0, max_speed]``, and in ``(0, max_tap_speed]`` when any part of the move is below ``z = 0``
  (the pad may be in contact with the part);
- acceleration in ``(0, max_acceleration]``;
- the controller reports no protective or emergency stop and the control program is running.

Example
-------
>>> from arm.config import ArmConfig
>>> limits = ArmConfig("sim", (-10, -10, -8), (100, 40, 30), max_tap_depth_mm=6.0).limits
>>> check_move(Pose(0, 0, 5), Pose(0, 0, -7), speed_mm_s=5, acceleration_mm_s2=50, limits=limits)
Traceback (most recent call last):
...
arm.errors.SafetyError: target z = -7 mm is 7 mm below the surface reference, deeper than max_tap_depth 6 mm
"""

from __future__ import annotations

import math

import numpy as np

from .config import SafetyLimits
from .errors import ArmFault, SafetyError
from .interface import ArmState
from .pose import Pose

__all__ = ["check_move", "check_ready", "check_point"]


def check_point(position, limits: SafetyLimits, *, what: str = "target") -> None:
    """Refuse a TCP position (work frame, mm) outside the workspace box or deeper than ``max_tap_depth``.

    Parameters
    ----------
    position : (3,) array_like
        ``(x, y, z)`` in mm.
    limits : SafetyLimits
    what : str
        How the error message names the point.

    Raises
    ------
    SafetyError
        Naming the axis and the limit that is broken.
    """
    position = np.asarray(position, dtype=float)
    if position.shape != (3,) or not np.all(np.isfinite(position)):
        raise SafetyError(f"{what} position must be 3 finite numbers in mm, got {position.tolist()}")
    low, high = np.asarray(limits.workspace_min_mm), np.asarray(limits.workspace_max_mm)
    text = "(" + ", ".join(f"{v:g}" for v in position) + ") mm"
    for axis in range(3):
        if position[axis] < low[axis]:
            raise SafetyError(f"{what} {text} is outside the workspace: {'xyz'[axis]} = {position[axis]:g} mm "
                              f"is below the minimum {low[axis]:g} mm")
        if position[axis] > high[axis]:
            raise SafetyError(f"{what} {text} is outside the workspace: {'xyz'[axis]} = {position[axis]:g} mm "
                              f"is above the maximum {high[axis]:g} mm")
    if -position[2] > limits.max_tap_depth_mm:
        raise SafetyError(f"{what} z = {position[2]:g} mm is {-position[2]:g} mm below the surface reference, "
                          f"deeper than max_tap_depth {limits.max_tap_depth_mm:g} mm")


def check_move(start: Pose, target: Pose, *, speed_mm_s: float, acceleration_mm_s2: float,
               limits: SafetyLimits) -> None:
    """Refuse a straight move that would break a limit; return silently when it is safe.

    Parameters
    ----------
    start : Pose
        Current TCP pose in the work frame (only its height matters: a move starting below the surface
        reference counts as a move in contact).
    target : Pose
        Target TCP pose in the work frame.
    speed_mm_s, acceleration_mm_s2 : float
        Requested tool speed and acceleration.
    limits : SafetyLimits

    Raises
    ------
    SafetyError
        Naming the limit that is broken; nothing must be sent to the arm.
    """
    check_point(target.position, limits)
    speed, accel = float(speed_mm_s), float(acceleration_mm_s2)
    if not (math.isfinite(speed) and speed > 0):
        raise SafetyError(f"speed must be a finite number > 0 mm/s, got {speed:g}")
    if not (math.isfinite(accel) and accel > 0):
        raise SafetyError(f"acceleration must be a finite number > 0 mm/s^2, got {accel:g}")
    if speed > limits.max_speed_mm_s:
        raise SafetyError(f"speed {speed:g} mm/s exceeds max_speed {limits.max_speed_mm_s:g} mm/s")
    if min(start.z, target.z) < 0 and speed > limits.max_tap_speed_mm_s:
        raise SafetyError(f"speed {speed:g} mm/s exceeds max_tap_speed {limits.max_tap_speed_mm_s:g} mm/s "
                          f"for a move below the surface reference (z < 0)")
    if accel > limits.max_acceleration_mm_s2:
        raise SafetyError(f"acceleration {accel:g} mm/s^2 exceeds max_acceleration "
                          f"{limits.max_acceleration_mm_s2:g} mm/s^2")


def check_ready(state: ArmState) -> None:
    """Refuse to move unless the controller is ready.

    Raises
    ------
    ArmFault
        When the arm is disconnected, protective- or emergency-stopped, not running, or its control program
        is not running; the message gives the cause.
    """
    problem = state.problem
    if problem is not None:
        raise ArmFault(f"refusing to move: {problem}")
