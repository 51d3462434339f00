"""Shared fixtures of the arm tests: a small simulated station."""

import pytest

from arm.config import ArmConfig, SimSettings
from arm.pose import Pose
from arm.world import Gap


def make_config(**overrides) -> ArmConfig:
    """A sim configuration with a tilted, offset work frame (so frame bugs show), overridable per test."""
    values = dict(
        backend="sim",
        workspace_min_mm=(-20.0, -20.0, -8.0),
        workspace_max_mm=(120.0, 40.0, 40.0),
        max_tap_depth_mm=6.0,
        tcp=Pose(0.0, 0.0, 60.0),
        work_frame=Pose(400.0, -150.0, 20.0, 0.0, 0.0, 30.0),
        sim=SimSettings(gaps=(Gap("narrow", 30.0, 0.0, 0.5), Gap("wide", 60.0, 0.0, 3.0)), seed=3,
                        home=Pose(0.0, 0.0, 30.0, 180.0, 0.0, 0.0)),
    )
    values.update(overrides)
    return ArmConfig(**values)


@pytest.fixture
def config() -> ArmConfig:
    """The default test configuration."""
    return make_config()
