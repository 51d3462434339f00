"""Checks for setting up a station: is the arm ready, and does one slow tap go where it should.

These are the functions behind ``tactip arm status`` and ``tactip arm tap``.

Example
-------
>>> from arm.config import ArmConfig
>>> config = ArmConfig("sim", (-10, -10, -8), (100, 40, 30), max_tap_depth_mm=6.0)
>>> arm_status(config).ready
True
>>> check_tap(config, depth_mm=1.0).phase
'release'
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from .config import ArmConfig
from .errors import SafetyError
from .factory import make_arm
from .interface import ArmState, TapCallback, TapEvent
from .pose import Pose

__all__ = ["StatusReport", "arm_status", "check_tap", "CHECK_TAP_SPEED_MM_S"]

# A set-up tap is slow: half the default tap speed.
CHECK_TAP_SPEED_MM_S = 5.0


@dataclass(frozen=True)
class StatusReport:
    """What ``tactip arm status`` prints: backend, TCP pose in the work frame, robot and safety state."""

    backend: str
    host: str
    pose: Pose
    state: ArmState

    @property
    def ready(self) -> bool:
        """Whether the arm is ready to move."""
        return self.state.ready

    def format(self) -> str:
        """The report as aligned text lines."""
        p = self.pose
        where = f" at {self.host}" if self.host else ""
        lines = [
            f"backend      {self.backend}{where}",
            f"tcp pose     x {p.x:.3f}  y {p.y:.3f}  z {p.z:.3f} mm   "
            f"roll {p.roll:.2f}  pitch {p.pitch:.2f}  yaw {p.yaw:.2f} deg (work frame)",
            f"robot mode   {self.state.robot_mode}",
            f"safety mode  {self.state.safety_mode}",
            f"program      {'running' if self.state.program_running else 'not running'}",
            f"ready        {'yes' if self.ready else 'no: ' + str(self.state.problem)}",
        ]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """The report as JSON-ready values: pose in mm and degrees of the work frame."""
        p, state = self.pose, self.state
        return {"backend": self.backend, "host": self.host or None, "ready": bool(self.ready),
                "problem": None if self.ready else str(state.problem),
                "pose": {"x_mm": p.x, "y_mm": p.y, "z_mm": p.z, "roll_deg": p.roll, "pitch_deg": p.pitch,
                         "yaw_deg": p.yaw},
                "robot_mode": str(state.robot_mode), "safety_mode": str(state.safety_mode),
                "program_running": bool(state.program_running)}


def arm_status(config: ArmConfig, **options) -> StatusReport:
    """Connect, read the TCP pose and the robot and safety state, disconnect.

    Parameters
    ----------
    config : ArmConfig
    **options
        Passed to the backend (`arm.factory.make_arm`).
    """
    with make_arm(config, **options) as arm:
        return StatusReport(config.backend, config.host, arm.pose(), arm.state())


def check_tap(config: ArmConfig, *, depth_mm: float, x_mm: float = 0.0, y_mm: float = 0.0,
              speed_mm_s: float = CHECK_TAP_SPEED_MM_S, on_contact: TapCallback | None = None,
              on_release: TapCallback | None = None, **options) -> TapEvent:
    """One slow tap at ``(x_mm, y_mm)`` of the work frame down to ``z = -depth_mm``.

    The tap point, the approach point and the depth are checked against the limits before connecting, so
    a request outside them is refused before anything moves.

    Parameters
    ----------
    config : ArmConfig
    depth_mm : float
        Depth below the surface reference, mm (positive = into the part).
    x_mm, y_mm : float
        Tap point in the work frame, mm.
    speed_mm_s : float
        Stroke speed, mm/s (also used for the travel to the tap point).
    on_contact, on_release : callable(TapEvent), optional
    **options
        Passed to the backend (`arm.factory.make_arm`).

    Returns
    -------
    TapEvent
        The release event (with the world contact on the simulated arm).
    """
    try:
        motion = replace(config.tap, speed_mm_s=speed_mm_s,
                         travel_speed_mm_s=min(2 * speed_mm_s, config.max_speed_mm_s))
    except ValueError as exc:
        raise SafetyError(f"check tap: {exc}") from None
    arm = make_arm(config, **options)
    arm.check_tap(x_mm, y_mm, depth_mm=depth_mm, motion=motion)
    with arm:
        return arm.tap(x_mm, y_mm, depth_mm=depth_mm, motion=motion, on_contact=on_contact, on_release=on_release)
