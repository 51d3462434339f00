"""Universal Robots backend through ur-rtde (``rtde_control``, ``rtde_receive``, ``dashboard_client``).

Connecting (`UrArm.connect`, or entering the context manager):

1. dashboard server (port 29999): reachable, and on PolyScope 5.6+ in Remote Control;
2. RTDE receive interface (port 30004): pose, robot mode, safety mode and status bits;
3. only when the robot is RUNNING with safety NORMAL/REDUCED: RTDE control interface, which uploads the
   ur-rtde control script (port 30003) and waits for it to run, then the TCP offset is set. Otherwise
   the arm is connected for monitoring only (``tactip arm status`` reports why) and moves are refused.

Moves are sent asynchronously (``moveL(..., asynchronous=True)``) and supervised by a watchdog loop at the
RTDE rate: it raises `ArmFault` and stops the arm if the controller reports a protective or emergency
stop or the control program stops, or if the move overruns its trapezoidal-profile duration by more than
a margin. A move the controller refuses (ur-rtde returns False) is an `ArmFault` naming the cause.
Leaving the context manager stops the arm, stops the control script and disconnects, on every exit path.

Units: ur-rtde takes m, m/s, m/s^2 and rotation vectors in rad; this module converts from the interface's
mm, mm/s, mm/s^2 and degrees (`arm.pose.pose_to_ur`).
"""

from __future__ import annotations

import time

from .base import BaseArm
from .config import ArmConfig
from .errors import ArmConnectionError, ArmFault
from .interface import ArmState
from .pose import Pose, pose_from_ur, pose_to_ur
from .profile import trapezoid_duration

__all__ = ["UrArm", "ROBOT_MODES", "SAFETY_MODES"]

ROBOT_MODES = {-1: "NO_CONTROLLER", 0: "DISCONNECTED", 1: "CONFIRM_SAFETY", 2: "BOOTING", 3: "POWER_OFF",
               4: "POWER_ON", 5: "IDLE", 6: "BACKDRIVE", 7: "RUNNING", 8: "UPDATING_FIRMWARE"}
SAFETY_MODES = {1: "NORMAL", 2: "REDUCED", 3: "PROTECTIVE_STOP", 4: "RECOVERY", 5: "SAFEGUARD_STOP",
                6: "SYSTEM_EMERGENCY_STOP", 7: "ROBOT_EMERGENCY_STOP", 8: "VIOLATION", 9: "FAULT",
                10: "VALIDATE_JOINT_ID", 11: "UNDEFINED_SAFETY_MODE", 12: "AUTOMATIC_MODE_SAFEGUARD_STOP",
                13: "SYSTEM_THREE_POSITION_ENABLING_STOP"}
_RECEIVE_VARIABLES = ["timestamp", "actual_TCP_pose", "robot_mode", "safety_mode", "runtime_state",
                      "robot_status_bits", "safety_status_bits"]
_PROTECTIVE_STOP_BIT, _EMERGENCY_STOP_BIT = 2, 7
_ARRIVED_MM = 0.5          # a finished move must end this close to its target
_SETTLED_MM = 0.01         # ... and is settled once the pose read back is this close (UR repeatability)
_STILL_MM = 0.001          # ... and moved less than this since the previous RTDE cycle
_SETTLE_CYCLES = 10        # RTDE cycles to wait for the receive interface to catch up after a move
_RECEIVE_STALL_S = 2.0     # no new RTDE data for this long (s) while waiting on it: the connection has failed


class _FreshPackages:
    """Counts the receive interface's fresh data packages (a new controller timestamp) since it was made.

    Waits after a move are counted in these, the controller's own cycles, so that a loaded computer which
    delays the packages is not mistaken for the arm; `stalled` says no new package came for
    `_RECEIVE_STALL_S` s.
    """

    def __init__(self, receive):
        self._receive = receive
        self._stamp = receive.getTimestamp()
        self._fresh_at = time.monotonic()
        self.count = 0

    def update(self) -> int:
        """Read the receive interface's timestamp: the fresh packages seen so far."""
        stamp = self._receive.getTimestamp()
        if stamp != self._stamp:
            self._stamp, self._fresh_at = stamp, time.monotonic()
            self.count += 1
        return self.count

    @property
    def stalled(self) -> bool:
        """No fresh package for `_RECEIVE_STALL_S` s (wall-clock time)."""
        return time.monotonic() - self._fresh_at > _RECEIVE_STALL_S


class UrArm(BaseArm):
    """A Universal Robots arm (CB3 or e-Series) through ur-rtde.

    Parameters
    ----------
    config : ArmConfig
        ``backend = "ur"``, ``host``, frames, limits, tap motion, ``rtde_frequency``.
    move_timeout_margin_s : float
        Time a move may take beyond its trapezoidal-profile duration (x 1.5) before the watchdog stops it, s.
    program_start_timeout_s : float
        How long `recover_protective_stop` waits for the control program to run again, s.
    """

    def __init__(self, config: ArmConfig, *, move_timeout_margin_s: float = 2.0,
                 program_start_timeout_s: float = 5.0):
        super().__init__(config)
        try:
            import dashboard_client
            import rtde_control
            import rtde_receive
        except ImportError as exc:
            raise ArmConnectionError(f"the UR backend needs the ur-rtde package ({exc}); pip install ur-rtde") from None
        self._rtde_control, self._rtde_receive, self._dashboard_client = rtde_control, rtde_receive, dashboard_client
        self.host = config.host
        self.frequency_hz = config.rtde_frequency_hz
        self.move_timeout_margin_s = float(move_timeout_margin_s)
        self.program_start_timeout_s = float(program_start_timeout_s)
        self._dashboard = self._receive = self._control = None

    # -- connection --------------------------------------------------------------------------------

    def _open(self) -> None:
        try:
            self._open_dashboard()
            self._open_receive()
            if self._robot_mode() == "RUNNING" and self._safety_mode() in ("NORMAL", "REDUCED"):
                self._open_control()
        except BaseException:
            self._close()
            raise

    def _open_dashboard(self) -> None:
        dashboard = self._dashboard_client.DashboardClient(self.host)
        try:
            dashboard.connect()
        except RuntimeError as exc:
            raise ArmConnectionError(f"cannot reach the UR controller at {self.host} (dashboard server, port "
                                     f"29999): {exc} Check the address, the cable and that the robot is on.") from None
        if not dashboard.isConnected():
            raise ArmConnectionError(f"cannot reach the UR controller at {self.host} (dashboard server, port 29999)")
        self._dashboard = dashboard
        version = _version_tuple(dashboard.polyscopeVersion())
        if version >= (5, 6) and not dashboard.isInRemoteControl():
            raise ArmConnectionError(f"the UR controller at {self.host} is in Local Control: switch the teach "
                                     f"pendant to Remote Control, then connect again")

    def _open_receive(self) -> None:
        try:
            self._receive = self._rtde_receive.RTDEReceiveInterface(self.host, self.frequency_hz, _RECEIVE_VARIABLES)
        except RuntimeError as exc:
            raise ArmConnectionError(f"cannot open RTDE on the UR controller at {self.host} (port 30004): "
                                     f"{exc}") from None

    def _open_control(self) -> None:
        flags = self._rtde_control.RTDEControlInterface.FLAG_UPLOAD_SCRIPT
        try:
            self._control = self._rtde_control.RTDEControlInterface(self.host, self.frequency_hz, flags)
        except RuntimeError as exc:
            raise ArmConnectionError(f"cannot start the ur-rtde control script on the UR controller at "
                                     f"{self.host}: {exc}") from None
        self._set_tcp()

    def _set_tcp(self) -> None:
        if not self._control.setTcp(pose_to_ur(self.config.tcp)):
            raise ArmFault(f"the controller refused the TCP offset {self.config.tcp}: {self._cause()}")

    def _close(self) -> None:
        # Stop the control script, then drop the interfaces: ur-rtde's destructors disconnect (each waits
        # 0.5 s; an explicit disconnect() would be repeated by the destructor and double that).
        control, dashboard = self._control, self._dashboard
        self._control = self._receive = self._dashboard = None
        if control is not None:
            _quietly(lambda: control.isConnected() and control.isProgramRunning() and control.stopScript())
        del control
        if dashboard is not None:
            _quietly(dashboard.disconnect)

    # -- reading -----------------------------------------------------------------------------------

    def _robot_mode(self) -> str:
        code = self._receive.getRobotMode()
        return ROBOT_MODES.get(code, f"UNKNOWN({code})")

    def _safety_mode(self) -> str:
        code = self._receive.getSafetyMode()
        return SAFETY_MODES.get(code, f"UNKNOWN({code})")

    def _read_base_pose(self) -> Pose:
        return pose_from_ur(self._receive.getActualTCPPose())

    def _read_state(self) -> ArmState:
        receive, control = self._receive, self._control
        connected = receive.isConnected() and (control is None or control.isConnected())
        bits = receive.getSafetyStatusBits()
        return ArmState(
            connected=connected, robot_mode=self._robot_mode(), safety_mode=self._safety_mode(),
            program_running=control is not None and control.isProgramRunning(),
            protective_stop=bool(bits >> _PROTECTIVE_STOP_BIT & 1) or receive.isProtectiveStopped(),
            emergency_stop=bool(bits >> _EMERGENCY_STOP_BIT & 1) or receive.isEmergencyStopped())

    def _cause(self) -> str:
        problem = self._root_cause(self._read_state())
        return problem or "the controller gave no reason (check the pendant's log)"

    def _root_cause(self, state: ArmState) -> str | None:
        """The state's problem once the receive interface has caught up with the control one.

        A protective or emergency stop also halts the control program, and the control interface sees
        the program stop a few RTDE cycles before the receive interface reports the safety bits: when
        the program has stopped, wait up to `_SETTLE_CYCLES` fresh packages of the receive interface for the stop that caused it.
        """
        fresh = _FreshPackages(self._receive)
        while (state.connected and not state.program_running and not (state.protective_stop or state.emergency_stop)
               and fresh.update() < _SETTLE_CYCLES and not fresh.stalled):
            time.sleep(1.0 / self.frequency_hz)
            state = self._read_state()
        return state.problem

    # -- moving ------------------------------------------------------------------------------------

    def _move_base(self, target: Pose, speed_mm_s: float, acceleration_mm_s2: float) -> None:
        control = self._control
        where = self._describe(target)
        start = self._read_base_pose()
        expected_s = trapezoid_duration(start.distance_to(target), speed_mm_s, acceleration_mm_s2)
        allowed_s = 1.5 * expected_s + self.move_timeout_margin_s
        deadline = time.monotonic() + allowed_s
        if not control.moveL(pose_to_ur(target), speed_mm_s / 1000.0, acceleration_mm_s2 / 1000.0, True):
            raise ArmFault(f"the controller rejected the move to {where}: {self._cause()}")
        period = 1.0 / self.frequency_hz
        while control.getAsyncOperationProgressEx().isAsyncOperationRunning():
            problem = self._read_state().problem
            if problem is not None:
                problem = self._root_cause(self._read_state())
                raise ArmFault(f"the move to {where} was interrupted: {problem}; the arm stopped at "
                               f"{self._describe(self._read_base_pose())}")
            if time.monotonic() > deadline:
                raise ArmFault(f"the move to {where} did not finish within {allowed_s:.1f} s (expected "
                               f"{expected_s:.2f} s); the arm was stopped")
            time.sleep(period)
        # The receive interface has its own RTDE connection and may lag the control one by a few cycles:
        # wait for the pose it reports to settle on the target, so pose() after a move reads where it ended.
        # The wait is counted in the receive interface's fresh packages (the controller's cycles), not in
        # this computer's time: a loaded computer that delays the packages is not an arm that stopped short.
        fresh = _FreshPackages(self._receive)
        previous = None
        while True:
            late = fresh.update() >= _SETTLE_CYCLES          # read first: the pose read next is at least as new
            problem, arrived = self._read_state().problem, self._read_base_pose()
            still = previous is not None and arrived.distance_to(previous) <= _STILL_MM
            if problem is None and (arrived.distance_to(target) <= _ARRIVED_MM if late
                                    else still and arrived.distance_to(target) <= _SETTLED_MM):
                return
            previous = arrived
            if problem is not None or late:
                if problem is not None:
                    problem = self._root_cause(self._read_state())
                raise ArmFault(f"the move to {where} ended at {self._describe(arrived)}: "
                               f"{problem or 'short of the target'}")
            if fresh.stalled:
                raise ArmFault(f"the move to {where} finished, but the controller's RTDE data (port 30004) "
                               f"stopped arriving for {_RECEIVE_STALL_S:.0f} s: check the network")
            time.sleep(period)

    def _stop_motion(self) -> None:
        control = self._control
        if control is not None and control.isConnected() and control.isProgramRunning():
            deceleration = min(max(2 * self.config.max_acceleration_mm_s2 / 1000.0, 0.5), 5.0)
            control.stopL(deceleration)

    def _recover(self) -> None:
        state = self._read_state()
        if state.emergency_stop:
            raise ArmFault("an emergency stop cannot be recovered from software: release it on the robot, "
                           "then power on and connect again")
        if state.protective_stop:
            try:
                self._dashboard.unlockProtectiveStop()
            except RuntimeError as exc:
                raise ArmFault(f"the controller refused to unlock the protective stop ({exc}); UR allows it "
                               f"5 s after the stop - inspect the cause and try again") from None
            self._wait_for(lambda: not self._read_state().protective_stop, "the protective stop to clear")
        if self._control is None:
            self._open_control()
        elif not self._control.isProgramRunning():
            if not self._control.reuploadScript():
                raise ArmFault("could not upload the ur-rtde control script again")
            self._wait_for(self._control.isProgramRunning, "the control program to run")
            self._set_tcp()

    def _wait_for(self, condition, what: str) -> None:
        deadline = time.monotonic() + self.program_start_timeout_s
        while not condition():
            if time.monotonic() > deadline:
                raise ArmFault(f"timed out after {self.program_start_timeout_s:g} s waiting for {what}: "
                               f"{self._cause()}")
            time.sleep(1.0 / self.frequency_hz)

    def _describe(self, base_pose: Pose) -> str:
        pose = self._base_to_work @ base_pose
        return f"({pose.x:.2f}, {pose.y:.2f}, {pose.z:.2f}) mm (work frame)"


def _version_tuple(text: str) -> tuple[int, ...]:
    parts = []
    for part in str(text).strip().split("."):
        if not part.isdigit():
            break
        parts.append(int(part))
    return tuple(parts)


def _quietly(action) -> None:
    try:
        action()
    except Exception:  # noqa: BLE001 - best-effort shutdown must reach every step
        pass
