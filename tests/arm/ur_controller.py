"""The emulated UR controller's state: RTDE variable types, the uploaded script's register handshake, motion.

Used by `tests.arm.ur_emulator`, which serves it over TCP. See that module for the protocol summary.
"""

from __future__ import annotations

import re
import threading
import time
from dataclasses import dataclass, field

import numpy as np

# RTDE types of output variables; registers are matched by pattern below.
OUTPUT_TYPES = {
    "timestamp": "DOUBLE", "robot_mode": "INT32", "safety_mode": "INT32", "safety_status": "INT32",
    "runtime_state": "UINT32", "robot_status_bits": "UINT32", "safety_status_bits": "UINT32",
    "speed_scaling": "DOUBLE", "target_speed_fraction": "DOUBLE", "actual_execution_time": "DOUBLE",
    "actual_momentum": "DOUBLE", "actual_main_voltage": "DOUBLE", "actual_robot_voltage": "DOUBLE",
    "actual_robot_current": "DOUBLE", "standard_analog_input0": "DOUBLE", "standard_analog_input1": "DOUBLE",
    "standard_analog_output0": "DOUBLE", "standard_analog_output1": "DOUBLE", "payload": "DOUBLE",
    "actual_digital_input_bits": "UINT64", "actual_digital_output_bits": "UINT64",
    "joint_mode": "VECTOR6INT32", "actual_tool_accelerometer": "VECTOR3D", "payload_cog": "VECTOR3D",
}
VECTOR6_OUTPUTS = ("target_q", "target_qd", "target_qdd", "target_current", "target_moment", "actual_q",
                   "actual_qd", "actual_current", "joint_control_output", "actual_TCP_pose", "actual_TCP_speed",
                   "actual_TCP_force", "target_TCP_pose", "target_TCP_speed", "joint_temperatures",
                   "actual_joint_voltage", "ft_raw_wrench", "payload_inertia")
FORMATS = {"DOUBLE": "d", "INT32": "i", "UINT32": "I", "UINT64": "Q", "VECTOR6D": "6d", "VECTOR3D": "3d",
           "VECTOR6INT32": "6i", "BOOL": "?", "UINT8": "B"}
ROBOT_MODES = {"POWER_OFF": 3, "IDLE": 5, "RUNNING": 7}
SAFETY_MODES = {"NORMAL": 1, "PROTECTIVE_STOP": 3, "ROBOT_EMERGENCY_STOP": 7}
SAFETY_BITS = {"NORMAL": 1 << 0, "PROTECTIVE_STOP": 1 << 2, "ROBOT_EMERGENCY_STOP": (1 << 6) | (1 << 7)}
STOPPED, PLAYING, PAUSED = 1, 2, 4       # runtime states


def value_count(fmt: str) -> int:
    """How many values a struct format of one variable holds ("6d" -> 6)."""
    return int(fmt[:-1]) if len(fmt) > 1 else 1


def output_type(name: str) -> str:
    """The RTDE type of an output variable, or NOT_FOUND."""
    if name in OUTPUT_TYPES:
        return OUTPUT_TYPES[name]
    if name in VECTOR6_OUTPUTS:
        return "VECTOR6D"
    if re.fullmatch(r"output_int_register_\d+", name):
        return "INT32"
    if re.fullmatch(r"output_double_register_\d+", name):
        return "DOUBLE"
    return "NOT_FOUND"


def input_type(name: str) -> str:
    """The RTDE type of an input variable, or NOT_FOUND."""
    if re.fullmatch(r"input_int_register_\d+", name):
        return "INT32"
    if re.fullmatch(r"input_double_register_\d+", name):
        return "DOUBLE"
    return {"external_force_torque": "VECTOR6D", "speed_slider_mask": "UINT32",
            "speed_slider_fraction": "DOUBLE", "standard_digital_output_mask": "UINT8",
            "standard_digital_output": "UINT8"}.get(name, "NOT_FOUND")


@dataclass
class Options:
    """How the emulated controller behaves."""

    polyscope: str = "5.11.1.108318"
    remote_control: bool = True
    run_uploaded_script: bool = True
    robot_mode: str = "RUNNING"
    time_scale: float = 20.0
    tcp: list = field(default_factory=lambda: [0.4, -0.15, 0.05, np.pi, 0.0, 0.0])


class Controller:
    """The controller's state, the uploaded script's handshake and the motion, under one lock."""

    def __init__(self, options: Options):
        self.options = options
        self.lock = threading.RLock()
        self.tcp = np.array(options.tcp, dtype=float)
        self.target = self.tcp.copy()
        self.robot_mode = options.robot_mode
        self.safety = "NORMAL"
        self.runtime = STOPPED
        self.in_int, self.in_double = [0] * 48, [0.0] * 48
        self.out_int, self.out_double = [0] * 48, [0.0] * 48
        self.executing = False
        self.motion = None            # (start, target, speed m/s, t0, duration s, sync)
        self.op_id = self.changes = 0
        self.watchdog_hz = 0.0
        self.last_input = time.monotonic()
        self.stop_during_next_move = False
        self.pending_stop_at = None
        self.log: list[dict] = []
        self.start = time.monotonic()

    # -- state seen through RTDE --------------------------------------------------------------------

    def value(self, name: str):
        """The current value of an RTDE output variable."""
        if name == "timestamp":
            return time.monotonic() - self.start
        if name in ("actual_TCP_pose", "target_TCP_pose"):
            return tuple(self.tcp if name == "actual_TCP_pose" else self.target)
        if name == "robot_mode":
            return ROBOT_MODES[self.robot_mode]
        if name in ("safety_mode", "safety_status"):
            return SAFETY_MODES[self.safety]
        if name == "runtime_state":
            return self.runtime
        if name == "robot_status_bits":
            return (ROBOT_MODES[self.robot_mode] >= 4) | ((self.runtime == PLAYING) << 1)
        if name == "safety_status_bits":
            return SAFETY_BITS[self.safety]
        if name.startswith("output_int_register_"):
            return self.out_int[int(name.rsplit("_", 1)[1])]
        if name.startswith("output_double_register_"):
            return self.out_double[int(name.rsplit("_", 1)[1])]
        kind = output_type(name)
        size = {"VECTOR6D": 6, "VECTOR3D": 3, "VECTOR6INT32": 6}.get(kind)
        return (0,) * size if size else (1.0 if name == "speed_scaling" else 0)

    # -- the uploaded script ------------------------------------------------------------------------

    def start_program(self) -> None:
        """The uploaded control script starts: ready for a command."""
        self.runtime, self.executing = PLAYING, False
        self.out_int[0], self.watchdog_hz = 1, 0.0

    def stop_program(self, runtime: int = STOPPED) -> None:
        """The control program ends (or pauses); the arm stops where it is."""
        self.runtime, self.motion = runtime, None
        self._async_status(running=False)

    def apply_inputs(self, values: dict) -> None:
        """An input data package arrived: update registers, then run one step of the script's loop."""
        self.last_input = time.monotonic()
        for name, value in values.items():
            index = int(name.rsplit("_", 1)[1]) if name[-1].isdigit() else None
            if name.startswith("input_int_register_"):
                self.in_int[index] = value
            elif name.startswith("input_double_register_"):
                self.in_double[index] = value
        if self.runtime != PLAYING:
            return
        cmd = self.in_int[0]
        if cmd == 0:
            self.executing = False
            self.out_int[0] = 1
        elif not self.executing:
            self.executing = True
            self._process(cmd)

    def _process(self, cmd: int) -> None:
        entry = {"cmd": cmd, "t": time.monotonic() - self.start}
        done = True
        if cmd == 3:                                              # moveL
            pose, speed, accel = self.in_double[0:6], self.in_double[6], self.in_double[7]
            entry.update(pose=list(pose), speed=speed, acceleration=accel, asynchronous=self.in_int[1])
            self._start_motion(np.array(pose), speed, sync=not self.in_int[1])
            done = bool(self.in_int[1])
        elif cmd == 33:                                           # stopL
            entry.update(acceleration=self.in_double[0], asynchronous=self.in_int[1])
            self.motion = None
            self.target = self.tcp.copy()
            self._async_status(running=False)
        elif cmd == 35:                                           # set watchdog
            self.watchdog_hz = entry["min_frequency"] = self.in_double[0]
        elif cmd == 29:                                           # set TCP
            entry["tcp"] = list(self.in_double[0:6])
        elif cmd == 255:                                          # stop script
            self.log.append(entry)
            self.stop_program()
            return
        self.log.append(entry)
        if done:
            self.out_int[0] = 2

    def _start_motion(self, target: np.ndarray, speed: float, *, sync: bool) -> None:
        distance = float(np.linalg.norm(target[:3] - self.tcp[:3]))
        duration = distance / max(speed, 1e-9) / self.options.time_scale
        now = time.monotonic()
        self.motion = (self.tcp.copy(), target, now, duration, sync)
        self.target = target.copy()
        self._async_status(running=not sync)
        if self.stop_during_next_move:
            self.stop_during_next_move = False
            self.pending_stop_at = now + duration / 2

    def _async_status(self, *, running: bool) -> None:
        if running:
            self.op_id = (self.op_id + 1) % 128
        self.changes = (self.changes + 1) % 256
        self.out_int[2] = (self.op_id << 24) | (self.changes << 16) | (int(running) << 15)

    def step(self) -> None:
        """Advance the motion and the timed faults to now."""
        now = time.monotonic()
        if self.pending_stop_at is not None and now >= self.pending_stop_at:
            # The arm halts where the move had taken it at the stop's own moment, however late this step runs
            # (a loaded machine can run the first step after the whole move's duration).
            self._advance(self.pending_stop_at)
            self.pending_stop_at = None
            self.protective_stop()
        if self.watchdog_hz > 0 and self.runtime == PLAYING and now - self.last_input > 1.0 / self.watchdog_hz:
            self.log.append({"cmd": "watchdog expired", "t": now - self.start})
            self.stop_program()
        self._advance(now)

    def _advance(self, now: float) -> None:
        """Move the tool along the current motion to where it is at monotonic time ``now`` (s)."""
        if self.motion is None:
            return
        start, target, t0, duration, sync = self.motion
        fraction = 1.0 if duration <= 0 else min((now - t0) / duration, 1.0)
        self.tcp[:3] = start[:3] + fraction * (target[:3] - start[:3])
        if fraction >= 1.0:
            self.tcp = target.copy()
            self.motion = None
            self._async_status(running=False)
            if sync and self.runtime == PLAYING:
                self.out_int[0] = 2

    # -- faults -------------------------------------------------------------------------------------

    def protective_stop(self) -> None:
        """A protective stop: the arm halts and the program pauses."""
        self.safety = "PROTECTIVE_STOP"
        self.stop_program(PAUSED)
        self.target = self.tcp.copy()

    def unlock_protective_stop(self) -> bool:
        """Dashboard ``unlock protective stop``: back to normal, the program stopped."""
        if self.safety != "PROTECTIVE_STOP":
            return False
        self.safety = "NORMAL"
        self.runtime = STOPPED
        return True
