"""The one arm interface that station and calibration code use, whatever arm is behind it.

Frames and sign conventions
---------------------------
- Every pose at this interface is the pose of the TCP (the apex of the fingertip pad, set by ``tcp`` in the
  configuration) in the **work frame** (set by ``work_frame``), in mm and degrees (see `arm.pose.Pose`).
- The work frame has **z up** and its origin on the reference height of the part surface (``z = 0``).
- A **tap depth is positive downwards**: a tap of depth ``d`` at ``(x, y)`` brings the pad apex to
  ``z = -d``, i.e. ``d`` mm below the surface reference. ``d`` may be negative (the lowest point stays
  above the reference). ``max_tap_depth`` bounds ``d``.

Backends: `arm.sim.SimArm` (embedded default) and `arm.ur.UrArm` (Universal Robots through ur-rtde);
`arm.factory.make_arm` picks one from the configuration.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable, Literal, Protocol, runtime_checkable

from .pose import Pose
from .world import WorldContact

if TYPE_CHECKING:
    from .config import ArmConfig
    from .tap import TapMotion

__all__ = ["Arm", "ArmState", "TapEvent", "TapCallback"]


@dataclass(frozen=True)
class TapEvent:
    """One edge of a tap, passed to the tap callbacks.

    Attributes
    ----------
    phase : {"contact", "release"}
        ``"contact"``: the pad is at the approach height above the tap point and starts its stroke down
        (start capturing: the first frame is the rest frame). ``"release"``: the pad is back at the approach
        height, clear of the part (stop capturing).
    time_s : float
        Time on the arm's clock, s (`time.monotonic` on hardware and real-time simulation, simulated time
        in instant simulation).
    pose : Pose
        TCP pose in the work frame at this edge, mm and degrees.
    depth_mm : float
        Depth of the tap below the surface reference, mm (positive = into the part).
    contact : WorldContact or None
        Simulation only: what the pad meets at the bottom of the tap (with this tap's placement error),
        the same object in both edges of one tap; None on real hardware.
    """

    phase: Literal["contact", "release"]
    time_s: float
    pose: Pose
    depth_mm: float
    contact: WorldContact | None = None


TapCallback = Callable[[TapEvent], None]


@dataclass(frozen=True)
class ArmState:
    """Robot and safety state as the controller reports it.

    Attributes
    ----------
    connected : bool
        Whether the arm's connection is open.
    robot_mode : str
        Controller robot mode (``"RUNNING"`` when powered with brakes released; ``"POWER_OFF"``, ``"IDLE"``, ...).
    safety_mode : str
        Controller safety mode (``"NORMAL"``, ``"REDUCED"``, ``"PROTECTIVE_STOP"``, ``"ROBOT_EMERGENCY_STOP"``, ...).
    program_running : bool
        Whether the control program that executes our moves is running on the controller.
    protective_stop : bool
        Whether the controller reports a protective stop.
    emergency_stop : bool
        Whether the controller reports an emergency stop.
    """

    connected: bool
    robot_mode: str
    safety_mode: str
    program_running: bool
    protective_stop: bool = False
    emergency_stop: bool = False

    @property
    def problem(self) -> str | None:
        """Why the arm may not move now, phrased for the user; None when it is ready."""
        if not self.connected:
            return "not connected"
        if self.emergency_stop:
            return "the controller reports an emergency stop; release it on the robot, then reconnect"
        if self.protective_stop:
            return ("the controller reports a protective stop; remove the cause, then recover explicitly "
                    "(recover_protective_stop)")
        if self.safety_mode not in ("NORMAL", "REDUCED"):
            return f"safety mode is {self.safety_mode}"
        if self.robot_mode != "RUNNING":
            return f"robot mode is {self.robot_mode} (power on and release the brakes)"
        if not self.program_running:
            return "the control program is not running on the controller"
        return None

    @property
    def ready(self) -> bool:
        """Whether the arm may move now."""
        return self.problem is None


@runtime_checkable
class Arm(Protocol):
    """What every arm backend offers. Distances in mm, angles in degrees, poses in the work frame.

    Use it as a context manager: entering connects; leaving stops any motion and disconnects, on every
    exit path. Every move is checked against the configured safety limits before anything is sent and is
    refused with `arm.errors.SafetyError` (never clipped); a move the controller refuses or abandons raises
    `arm.errors.ArmFault`; moves are refused while the controller reports a protective or emergency stop or
    the control program is not running. Recovery from a protective stop is the explicit
    `recover_protective_stop` call, never automatic.
    """

    config: ArmConfig

    def connect(self) -> Arm:
        """Open the connection (idempotent); returns the arm."""
        ...

    def disconnect(self) -> None:
        """Stop any motion, close the connection (idempotent)."""
        ...

    def __enter__(self) -> Arm:
        """Connect."""
        ...

    def __exit__(self, *exc_info) -> None:
        """Stop and disconnect."""
        ...

    def pose(self) -> Pose:
        """The current TCP pose in the work frame."""
        ...

    def state(self) -> ArmState:
        """Robot and safety state."""
        ...

    def move_linear(self, target: Pose, *, speed_mm_s: float, acceleration_mm_s2: float) -> None:
        """Move the TCP in a straight line to ``target`` (work frame); returns when it has arrived."""
        ...

    def move_relative(self, dx: float = 0.0, dy: float = 0.0, dz: float = 0.0, *,
                      speed_mm_s: float, acceleration_mm_s2: float) -> None:
        """Move the TCP by ``(dx, dy, dz)`` mm along the work frame's axes, keeping its orientation."""
        ...

    def stop(self) -> None:
        """Decelerate to a stop now."""
        ...

    def tap(self, x: float, y: float, *, depth_mm: float, motion: TapMotion | None = None,
            on_contact: TapCallback | None = None, on_release: TapCallback | None = None) -> TapEvent:
        """Tap at ``(x, y)`` of the work frame down to ``z = -depth_mm``; returns the release event."""
        ...

    def recover_protective_stop(self) -> None:
        """Unlock a protective stop and restart the control program (an explicit operator decision)."""
        ...
