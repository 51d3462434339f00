"""After a move, the UR backend waits on the receive interface in its own packages, not in wall-clock time.

The control interface reports a move done; the receive interface (its own RTDE connection) may deliver
its next package later on a loaded computer. Fakes of the two ur-rtde interfaces on an injected clock
(`arm.ur.time`) show the three cases: packages that arrive late but right (the move succeeds), fresh
packages that show the arm short of its target (a fault), and packages that stop coming (a fault that
says so).
"""
from types import SimpleNamespace

import pytest

import arm.ur as ur
from arm.errors import ArmFault
from arm.pose import Pose, pose_to_ur
from arm.ur import UrArm

from tests.arm.conftest import make_config

CONFIG = make_config(backend="ur", host="127.0.0.1")
START, TARGET = Pose(400.0, -150.0, 50.0, 180.0, 0.0, 0.0), Pose(400.0, -150.0, 40.0, 180.0, 0.0, 0.0)


class Clock:
    """`time.monotonic` and `time.sleep` on a clock that only `sleep` advances (s)."""

    def __init__(self):
        self.now = 0.0

    def monotonic(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        self.now += seconds


class Receive:
    """A receive interface whose packages stop for ``silent_s`` after the move (then show ``arrived``)."""

    def __init__(self, clock, *, silent_s: float, arrived: Pose, period_s: float):
        self.clock, self.silent_s, self.arrived, self.period_s = clock, silent_s, arrived, period_s

    def _fresh(self) -> bool:
        return self.clock.now >= self.silent_s

    def getTimestamp(self):
        return 1000.0 + (self.clock.now // self.period_s * self.period_s if self._fresh() else 0.0)

    def getActualTCPPose(self):
        return pose_to_ur(self.arrived if self._fresh() else START)

    isConnected = staticmethod(lambda: True)
    getSafetyStatusBits = staticmethod(lambda: 1)
    getRobotMode = staticmethod(lambda: 7)                   # RUNNING
    getSafetyMode = staticmethod(lambda: 1)                  # NORMAL
    isProtectiveStopped = isEmergencyStopped = staticmethod(lambda: False)


def control_that_finishes_at_once():
    progress = SimpleNamespace(isAsyncOperationRunning=lambda: False)
    return SimpleNamespace(moveL=lambda *args: True, isConnected=lambda: True, isProgramRunning=lambda: True,
                           getAsyncOperationProgressEx=lambda: progress)


def move_with(monkeypatch, *, silent_s: float, arrived: Pose):
    clock = Clock()
    monkeypatch.setattr(ur, "time", clock)
    arm = UrArm(CONFIG)
    receive = Receive(clock, silent_s=silent_s, arrived=arrived, period_s=1.0 / arm.frequency_hz)
    arm._receive, arm._control = receive, control_that_finishes_at_once()
    arm._move_base(TARGET, 10.0, 100.0)
    return clock


def test_packages_that_arrive_late_but_right_end_the_move(monkeypatch):
    # 0.2 s without a package is 100 RTDE cycles at 500 Hz: a wall-clock wait of 10 cycles gave up.
    clock = move_with(monkeypatch, silent_s=0.2, arrived=TARGET)
    assert clock.now >= 0.2


def test_fresh_packages_short_of_the_target_are_a_fault(monkeypatch):
    with pytest.raises(ArmFault, match="short of the target"):
        move_with(monkeypatch, silent_s=0.0, arrived=Pose(400.0, -150.0, 42.0, 180.0, 0.0, 0.0))


def test_packages_that_stop_coming_are_a_fault_that_says_so(monkeypatch):
    with pytest.raises(ArmFault, match="stopped arriving"):
        move_with(monkeypatch, silent_s=1e9, arrived=TARGET)
