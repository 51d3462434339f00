"""What every backend shares: frames, safety checks before every move, relative moves, the tap, clean exits.

A backend subclasses `BaseArm` and implements the controller-facing hooks, all in the robot **base** frame:
``_open``, ``_close``, ``_read_base_pose``, ``_read_state``, ``_move_base``, ``_stop_motion``, ``_recover``;
optionally ``_now``, ``_sleep`` and ``_tap_contact`` (the simulation's world contact). Everything else -
work frame, TCP poses, limits, the tap sequence and its callbacks - lives here once.
"""

from __future__ import annotations

import time

from .config import ArmConfig, SafetyLimits
from .errors import ArmError, ArmFault, SafetyError
from .interface import ArmState, TapCallback, TapEvent
from .pose import Pose
from .safety import check_move, check_point, check_ready
from .tap import Segment, TapMotion, plan_tap
from .world import WorldContact

__all__ = ["BaseArm"]


class BaseArm:
    """Shared behaviour of the arm backends (see `arm.interface.Arm` for the contract).

    Parameters
    ----------
    config : ArmConfig
        Validated ``[arm]`` configuration (frames, limits, tap motion).
    """

    def __init__(self, config: ArmConfig):
        if not isinstance(config, ArmConfig):
            raise TypeError(f"config must be an ArmConfig, got {type(config).__name__}")
        self.config = config
        self.limits = SafetyLimits.from_config(config)
        self._work_frame = config.work_frame
        self._base_to_work = config.work_frame.inverse()
        self._connected = False

    def __repr__(self) -> str:
        state = "connected" if self._connected else "disconnected"
        return f"{type(self).__name__}(backend={self.config.backend!r}, {state})"

    # -- lifecycle ---------------------------------------------------------------------------------

    @property
    def connected(self) -> bool:
        """Whether the connection is open."""
        return self._connected

    def connect(self) -> BaseArm:
        """Open the connection (idempotent); returns the arm."""
        if not self._connected:
            self._open()
            self._connected = True
        return self

    def disconnect(self) -> None:
        """Stop any motion and close the connection (idempotent; never raises for a stop that fails)."""
        if not self._connected:
            return
        try:
            self._stop_quietly()
        finally:
            self._connected = False
            self._close()

    def __enter__(self) -> BaseArm:
        """Connect."""
        return self.connect()

    def __exit__(self, *exc_info) -> None:
        """Stop and disconnect, whatever happened inside the block."""
        self.disconnect()

    # -- reading -----------------------------------------------------------------------------------

    def pose(self) -> Pose:
        """The current TCP pose in the work frame (mm, deg)."""
        self._require_connected()
        return self._base_to_work @ self._read_base_pose()

    def state(self) -> ArmState:
        """Robot and safety state (a disconnected arm reports ``connected=False``)."""
        if not self._connected:
            return ArmState(False, "DISCONNECTED", "UNKNOWN", False)
        return self._read_state()

    # -- moving ------------------------------------------------------------------------------------

    def move_linear(self, target: Pose, *, speed_mm_s: float, acceleration_mm_s2: float) -> None:
        """Move the TCP in a straight line to ``target`` (work frame) at the given speed and acceleration.

        Raises
        ------
        SafetyError
            The move breaks a limit (nothing moved).
        ArmFault
            The arm is not ready, or the controller refused or abandoned the move (the arm is stopped).
        """
        if not isinstance(target, Pose):
            raise TypeError(f"target must be a Pose, got {type(target).__name__}")
        self._run([Segment("move", target, speed_mm_s, acceleration_mm_s2)])

    def move_relative(self, dx: float = 0.0, dy: float = 0.0, dz: float = 0.0, *,
                      speed_mm_s: float, acceleration_mm_s2: float) -> None:
        """Move the TCP by ``(dx, dy, dz)`` mm along the work frame's axes, keeping its orientation."""
        self._require_connected()
        target = self.pose().translated(dx, dy, dz)
        self._run([Segment("move", target, speed_mm_s, acceleration_mm_s2)])

    def stop(self) -> None:
        """Decelerate to a stop now."""
        self._require_connected()
        self._stop_motion()

    def recover_protective_stop(self) -> None:
        """Unlock a protective stop and restart the control program: an explicit operator decision."""
        self._require_connected()
        self._recover()

    def check_tap(self, x: float, y: float, *, depth_mm: float, motion: TapMotion | None = None) -> None:
        """Refuse a tap whose tap point, approach point or depth is outside the limits (no connection needed).

        Raises
        ------
        SafetyError
            Naming the broken limit.
        """
        motion = motion or self.config.tap
        if not -float(depth_mm) < motion.approach_height_mm:
            raise SafetyError(f"depth_mm {depth_mm:g} puts the bottom of the stroke above the approach height "
                             f"({motion.approach_height_mm:g} mm)")
        check_point((x, y, motion.approach_height_mm), self.limits, what="approach point")
        check_point((x, y, -float(depth_mm)), self.limits, what="bottom of the tap")

    def tap(self, x: float, y: float, *, depth_mm: float, motion: TapMotion | None = None,
            on_contact: TapCallback | None = None, on_release: TapCallback | None = None) -> TapEvent:
        """Tap at ``(x, y)`` of the work frame down to ``z = -depth_mm`` (see `arm.tap`).

        Every segment is checked before the first one moves. ``on_contact`` is called when the pad starts
        its stroke down from the approach height, ``on_release`` when it is back there.

        Parameters
        ----------
        x, y : float
            Tap point in the work frame, mm.
        depth_mm : float
            Depth of the bottom of the stroke below the surface reference, mm (positive = into the part).
        motion : TapMotion, optional
            Defaults to the configuration's ``[arm.tap]``.
        on_contact, on_release : callable(TapEvent), optional

        Returns
        -------
        TapEvent
            The ``"release"`` event.
        """
        motion = motion or self.config.tap
        self.check_tap(x, y, depth_mm=depth_mm, motion=motion)
        self._require_connected()
        segments = plan_tap(self.pose(), x, y, depth_mm=depth_mm, motion=motion)
        self._check_segments(segments)
        *positioning, press, release = segments
        self._run(positioning)
        contact = self._tap_contact(press.target)
        start = TapEvent("contact", self._now(), self.pose(), float(depth_mm), contact)
        if on_contact is not None:
            on_contact(start)
        self._run([press])
        self._sleep(motion.dwell_s)
        self._run([release])
        end = TapEvent("release", self._now(), self.pose(), float(depth_mm), contact)
        if on_release is not None:
            on_release(end)
        return end

    # -- internals ---------------------------------------------------------------------------------

    def _require_connected(self) -> None:
        if not self._connected:
            raise ArmFault(f"{type(self).__name__} is not connected; use it as a context manager or call connect()")

    def _check_segments(self, segments: list[Segment]) -> None:
        check_ready(self.state())
        here = self.pose()
        for segment in segments:
            check_move(here, segment.target, speed_mm_s=segment.speed_mm_s,
                       acceleration_mm_s2=segment.acceleration_mm_s2, limits=self.limits)
            here = segment.target

    def _run(self, segments: list[Segment]) -> None:
        """Check then execute segments; on any failure stop the arm and re-raise."""
        self._require_connected()
        self._check_segments(segments)
        for segment in segments:
            check_ready(self.state())
            try:
                self._move_base(self._work_frame @ segment.target, segment.speed_mm_s, segment.acceleration_mm_s2)
            except BaseException:
                self._stop_quietly()
                raise

    def _stop_quietly(self) -> None:
        try:
            self._stop_motion()
        except ArmError:
            pass

    def _now(self) -> float:
        return time.monotonic()

    def _sleep(self, seconds: float) -> None:
        if seconds > 0:
            time.sleep(seconds)

    def _tap_contact(self, bottom: Pose) -> WorldContact | None:
        return None

    # Backend hooks (base frame, mm, deg, mm/s, mm/s^2).
    def _open(self) -> None:
        raise NotImplementedError

    def _close(self) -> None:
        raise NotImplementedError

    def _read_base_pose(self) -> Pose:
        raise NotImplementedError

    def _read_state(self) -> ArmState:
        raise NotImplementedError

    def _move_base(self, target: Pose, speed_mm_s: float, acceleration_mm_s2: float) -> None:
        raise NotImplementedError

    def _stop_motion(self) -> None:
        raise NotImplementedError

    def _recover(self) -> None:
        raise NotImplementedError
