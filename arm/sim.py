"""The simulated arm: the same interface and safety checks as the UR backend, a trapezoidal-velocity motion
model (real-time or instant) and a simulated plate with gaps (`arm.world.PlateWorld`) for the taps.

It is the embedded default: the demo and the tests run on it. Each tap reports, in its `TapEvent`, the
`WorldContact` at the bottom of the stroke (the pad's indentation and the nearest gap's width and lateral
offset, with this tap's placement error) so that the station can render the tap's frames.

Faults can be injected to rehearse error handling: `SimArm.trigger_protective_stop`,
`SimArm.trigger_emergency_stop`, `SimArm.stop_program`.

Example
-------
>>> from arm.config import ArmConfig, SimSettings
>>> from arm.world import Gap
>>> config = ArmConfig("sim", (-10, -10, -8), (100, 40, 30), max_tap_depth_mm=6.0,
...                    sim=SimSettings(gaps=(Gap("g1", 30.0, 0.0, 1.25),)))
>>> with SimArm(config) as arm:
...     event = arm.tap(30.0, 0.0, depth_mm=2.0)
>>> event.contact.gap_name, event.contact.indentation_mm
('g1', 2.0)
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from .base import BaseArm
from .config import ArmConfig
from .errors import ArmFault
from .interface import ArmState
from .pose import Pose
from .profile import trapezoid_duration, trapezoid_fraction
from .world import PlateWorld, WorldContact

__all__ = ["SimArm", "SimCommand"]


@dataclass(frozen=True)
class SimCommand:
    """One move the simulated controller accepted: target TCP pose in the base frame, speed, acceleration."""

    target_base: Pose
    speed_mm_s: float
    acceleration_mm_s2: float
    duration_s: float


class SimArm(BaseArm):
    """A simulated arm over a simulated plate (see the module docstring).

    Parameters
    ----------
    config : ArmConfig
        Frames, limits, tap motion and ``[arm.sim]`` settings.
    world : PlateWorld, optional
        The plate; defaults to ``config.sim.make_world()``.
    realtime : bool, optional
        Whether moves take their real duration; defaults to ``config.sim.realtime``.
    home : Pose, optional
        Initial TCP pose in the work frame; defaults to ``config.sim.home``, else above the centre of the
        workspace at its top with the pad pointing down (roll 180 deg).
    """

    def __init__(self, config: ArmConfig, *, world: PlateWorld | None = None, realtime: bool | None = None,
                 home: Pose | None = None):
        super().__init__(config)
        self.world = world if world is not None else config.sim.make_world()
        self.realtime = config.sim.realtime if realtime is None else bool(realtime)
        if home is None:
            home = config.sim.home
        if home is None:
            low, high = np.array(config.workspace_min_mm), np.array(config.workspace_max_mm)
            centre = (low + high) / 2
            home = Pose(centre[0], centre[1], high[2], 180.0, 0.0, 0.0)
        self.home = home
        self.commands: list[SimCommand] = []
        self._clock_s = 0.0
        self._base_pose = config.work_frame @ home
        self._lock = threading.Lock()
        self._stop_event = threading.Event()
        self._motion = None              # (start base pose, target base pose, start time, profile) while moving
        self._protective_stop = False
        self._emergency_stop = False
        self._program_running = True
        self._stop_during_next_move = False

    # -- fault injection ---------------------------------------------------------------------------

    def trigger_protective_stop(self, *, during_next_move: bool = False) -> None:
        """Simulate a protective stop now, or half-way through the next move."""
        if during_next_move:
            self._stop_during_next_move = True
        else:
            self._protective_stop = True
            self._stop_event.set()

    def trigger_emergency_stop(self) -> None:
        """Simulate an emergency stop (not recoverable by `recover_protective_stop`)."""
        self._emergency_stop = True
        self._program_running = False
        self._stop_event.set()

    def stop_program(self) -> None:
        """Simulate the control program stopping on the controller."""
        self._program_running = False

    # -- backend hooks -----------------------------------------------------------------------------

    def _open(self) -> None:
        self._stop_event.clear()

    def _close(self) -> None:
        pass

    def _now(self) -> float:
        return time.monotonic() if self.realtime else self._clock_s

    def _sleep(self, seconds: float) -> None:
        if self.realtime:
            super()._sleep(seconds)
        else:
            self._clock_s += max(float(seconds), 0.0)

    def _read_base_pose(self) -> Pose:
        with self._lock:
            motion = self._motion
        if motion is None:
            return self._base_pose
        return self._interpolate(motion, time.monotonic() - motion[2])

    def _read_state(self) -> ArmState:
        if self._emergency_stop:
            safety = "ROBOT_EMERGENCY_STOP"
        elif self._protective_stop:
            safety = "PROTECTIVE_STOP"
        else:
            safety = "NORMAL"
        return ArmState(True, "RUNNING", safety, self._program_running,
                        protective_stop=self._protective_stop, emergency_stop=self._emergency_stop)

    def _move_base(self, target: Pose, speed_mm_s: float, acceleration_mm_s2: float) -> None:
        start = self._base_pose
        distance = start.distance_to(target)
        duration = trapezoid_duration(distance, speed_mm_s, acceleration_mm_s2)
        self.commands.append(SimCommand(target, float(speed_mm_s), float(acceleration_mm_s2), duration))
        motion = (start, target, time.monotonic(), (distance, float(speed_mm_s), float(acceleration_mm_s2)))
        if self._stop_during_next_move:
            self._stop_during_next_move = False
            self._protective_stop = True
            self._base_pose = self._interpolate(motion, duration / 2)
            self._clock_s += duration / 2
            raise ArmFault(f"protective stop during the move to {self._work_xyz(target)}; the arm stopped at "
                           f"{self._work_xyz(self._base_pose)}")
        if not self.realtime:
            self._base_pose = target
            self._clock_s += duration
            return
        self._stop_event.clear()
        with self._lock:
            self._motion = motion
        stopped = self._stop_event.wait(duration)
        with self._lock:
            self._motion = None
            self._base_pose = self._interpolate(motion, time.monotonic() - motion[2]) if stopped else target
        if stopped:
            raise ArmFault(f"the move to {self._work_xyz(target)} was stopped at {self._work_xyz(self._base_pose)}")

    def _stop_motion(self) -> None:
        self._stop_event.set()

    def _recover(self) -> None:
        if self._emergency_stop:
            raise ArmFault("an emergency stop cannot be recovered from software; release it on the robot")
        self._protective_stop = False
        self._program_running = True
        self._stop_event.clear()

    def _tap_contact(self, bottom: Pose) -> WorldContact:
        return self.world.contact(bottom)

    def _work_xyz(self, base_pose: Pose) -> str:
        pose = self._base_to_work @ base_pose
        return f"({pose.x:.2f}, {pose.y:.2f}, {pose.z:.2f}) mm (work frame)"

    @staticmethod
    def _interpolate(motion, elapsed_s: float) -> Pose:
        start, target, _t0, (distance, speed, accel) = motion
        s = float(trapezoid_fraction(elapsed_s, distance, speed, accel)) if distance > 0 else 1.0
        position = start.position + s * (target.position - start.position)
        rotations = Rotation.concatenate([start.rotation, target.rotation])
        angles = Slerp([0.0, 1.0], rotations)([s]).as_euler("xyz", degrees=True)[0]
        return Pose(*position.tolist(), *angles.tolist())


