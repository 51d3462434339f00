"""The [arm] table: samples load, defaults apply, and each missing or bad key is named in the error."""

import pathlib

import pytest

from arm.config import ArmConfig, arm_config_from_table, load_arm_config
from arm.errors import ArmConfigError
from arm.pose import Pose

SAMPLES = pathlib.Path(__file__).resolve().parents[2] / "samples"


def minimal(**extra):
    table = {"backend": "sim", "workspace": [[-10, -10, -8], [100, 40, 30]], "max_tap_depth": 6.0}
    table.update(extra)
    return table


@pytest.mark.parametrize("name", ["arm_sim.toml", "arm_ur.toml"])
def test_samples_load(name):
    config = load_arm_config(SAMPLES / name)
    assert config.backend in ("sim", "ur")
    assert config.max_tap_speed_mm_s <= 20.0
    assert config.tap.speed_mm_s <= config.max_tap_speed_mm_s


def test_sample_values_are_parsed_into_frames_and_gaps():
    config = load_arm_config(SAMPLES / "arm_sim.toml")
    assert config.work_frame == Pose(400.0, -150.0, 20.0)
    assert config.tcp.z == 60.0
    assert config.workspace_min_mm == (-20.0, -20.0, -8.0)
    assert [g.width_mm for g in config.sim.gaps] == [0.25, 1.0, 2.5, 5.0]
    assert config.sim.home.roll == 180.0


def test_defaults():
    config = arm_config_from_table(minimal())
    assert (config.max_speed_mm_s, config.max_acceleration_mm_s2, config.max_tap_speed_mm_s) == (50.0, 500.0, 20.0)
    assert config.tcp == Pose(0, 0, 0) and config.work_frame == Pose(0, 0, 0)


@pytest.mark.parametrize("key", ["backend", "workspace", "max_tap_depth"])
def test_missing_key_is_named(key):
    table = minimal()
    del table[key]
    with pytest.raises(ArmConfigError, match=f"missing the key '{key}'"):
        arm_config_from_table(table)


@pytest.mark.parametrize("table, message", [
    (minimal(backend="kuka"), "backend 'kuka' is unknown; choose from sim, ur"),
    (minimal(backend="ur"), "missing the key 'host'"),
    (minimal(max_speed=0), r"max_speed must be in \(0, 250\] mm/s, got 0"),
    (minimal(max_speed=1000.0), "max_speed must be in"),
    (minimal(max_acceleration=-1), "max_acceleration must be in"),
    (minimal(max_tap_depth=25), "max_tap_depth must be in"),
    (minimal(max_tap_speed=30, max_speed=25), "max_tap_speed .* must not exceed max_speed"),
    (minimal(max_speed="fast"), "max_speed must be a number"),
    (minimal(workspace=[[0, 0, 0], [10, 10]]), "workspace must be 3 finite numbers"),
    (minimal(workspace=[[0, 0, 0], [10, -1, 10]]), "workspace: the min corner must be below .*axis y"),
    (minimal(work_frame=[0, 0, 0]), "work_frame must be 6 finite numbers"),
    (minimal(tcp=[0, 0, 0, 0, 0, "x"]), "tcp must be 6"),
    (minimal(max_sped=10), "unknown key 'max_sped'"),
    (minimal(tap={"speed": 30}), r"\[arm.tap\] speed \(30.0\) must not exceed \[arm\] max_tap_speed"),
    (minimal(tap={"dwell": -1}), r"\[arm.tap\] dwell: must be"),
    (minimal(tap={"approach_height": 50}), "approach_height .* above the workspace top"),
    (minimal(tap={"sped": 1}), r"\[arm.tap\] has unknown key 'sped'"),
    (minimal(sim={"gaps": [{"name": "a", "x": 0, "y": 0}]}), r"gaps\[0\] is missing the key 'width'"),
    (minimal(sim={"gaps": [{"name": "a", "x": 0, "y": 0, "width": -1}]}), r"gaps\[0\] width must be in \(0, 100\] mm, got -1"),
    (minimal(sim={"placement_noise": -0.1}), "placement_noise must be in"),
    (minimal(sim={"realtime": "yes"}), "realtime must be true or false"),
])
def test_bad_values_are_named(table, message):
    with pytest.raises(ArmConfigError, match=message):
        arm_config_from_table(table)


def test_file_errors(tmp_path):
    with pytest.raises(OSError):
        load_arm_config(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[arm\nbackend = 1")
    with pytest.raises(ArmConfigError, match="not valid TOML"):
        load_arm_config(bad)
    other = tmp_path / "other.toml"
    other.write_text("[camera]\nindex = 0\n")
    with pytest.raises(ArmConfigError, match=r"no \[arm\] table"):
        load_arm_config(other)


def test_config_is_frozen_and_validated_when_built_directly():
    config = ArmConfig("sim", (0, 0, -1), (10, 10, 10), max_tap_depth_mm=1.0)
    with pytest.raises(AttributeError):
        config.max_speed_mm_s = 1000.0
    with pytest.raises(ArmConfigError, match="max_tap_depth"):
        ArmConfig("sim", (0, 0, -1), (10, 10, 10), max_tap_depth_mm=0.0)
