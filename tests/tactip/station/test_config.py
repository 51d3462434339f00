"""Station configuration: the samples load, and every kind of mistake names its key."""

import pathlib
import tomllib

import pytest

from tactip.station.config import load_station_config, parse_station_config
from tactip.errors import ConfigError

SAMPLES = pathlib.Path(__file__).resolve().parents[3] / "samples"


def _sim_table():
    return tomllib.loads((SAMPLES / "station_sim.toml").read_text())


def test_sample_sim_station_loads():
    cfg = load_station_config(SAMPLES / "station_sim.toml")
    assert cfg.simulated and len(cfg.gaps) == 20
    assert [g.nominal_width for g in cfg.gaps] == pytest.approx([0.25 * k for k in range(1, 21)])
    depths = cfg.protocol.depths
    assert depths[0] == 0.0 and depths[-1] == pytest.approx(5.5) and len(depths) == 23
    # depth 0 taps 1.5 mm above the surface reference; 5.5 taps 4 mm into the part
    assert cfg.protocol.arm_depth_mm(0.0) == -1.5 and cfg.protocol.arm_depth_mm(5.5) == 4.0
    assert cfg.results.is_absolute() or cfg.results.parts[0] == "samples"


def test_sample_ur_station_loads():
    cfg = load_station_config(SAMPLES / "station_ur.toml")
    assert not cfg.simulated and cfg.arm.host and cfg.sensor.preset == ""


def test_a_named_sensor_describes_the_pad():
    data = _sim_table()
    data["sensor"].update(preset="radial-120", pins=120)
    assert parse_station_config(data, base_dir=SAMPLES).sensor.preset == "radial-120"


@pytest.mark.parametrize("mutate, key", [
    (lambda d: d["perception"].update(decision_threshold=1.5), "perception.decision_threshold"),
    (lambda d: d["perception"].update(policy="psychic"), "perception.policy"),
    (lambda d: d["perception"].update(start_depth=7.0), "perception.start_depth"),
    (lambda d: d["protocol"].update(depth_step=0), "protocol.depth_step"),
    (lambda d: d["protocol"].update(samples="forty"), "protocol.samples"),
    (lambda d: d["protocol"].update(depth_max=9.0), "protocol.depth_max"),
    (lambda d: d["sensor"].update(colour=True), "colour"),
    (lambda d: d["sensor"].update(preset="tactip-9"), "sensor.preset must be one of tactip-127"),
    (lambda d: d["gaps"][3].pop("nominal_width"), "gaps[3].nominal_width"),
    (lambda d: d["gaps"][0].update(tolerance=-1), "gaps[0].tolerance"),
    (lambda d: d["gaps"][1].update(name="g01"), "duplicate gap names: g01"),
    (lambda d: d.pop("gaps"), "[[gaps]]"),
    (lambda d: d["arm"].pop("workspace"), "workspace"),
    (lambda d: d["arm"].update(max_tap_speed=500.0), "max_tap_speed"),
    (lambda d: d.pop("arm"), "[arm]"),
    (lambda d: d.update(extra={}), "extra"),
])
def test_errors_name_the_key(mutate, key):
    data = _sim_table()
    mutate(data)
    with pytest.raises(ConfigError) as err:
        parse_station_config(data, base_dir=SAMPLES)
    assert key in str(err.value)


def test_missing_and_invalid_files(tmp_path):
    with pytest.raises(ConfigError, match="not found"):
        load_station_config(tmp_path / "nope.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[station\nname=1")
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_station_config(bad)


def test_relative_paths_resolve_against_the_file(tmp_path):
    text = (SAMPLES / "station_sim.toml").read_text()
    (tmp_path / "s.toml").write_text(text)
    cfg = load_station_config(tmp_path / "s.toml")
    assert cfg.perception.model == tmp_path / "../station_data/sim/model.h5"


@pytest.mark.parametrize("encode, words", [
    (lambda text: text.encode("latin-1"), ["not UTF-8 text", "Latin-1", "0xe9"]),
    (lambda text: text.encode("utf-16"), ["UTF-16 text"]),
    (lambda text: b"\x00\xff" + text.encode(), ["a binary file"]),
])
def test_files_in_other_encodings_are_named(tmp_path, encode, words):
    text = (SAMPLES / "station_sim.toml").read_text().replace('"sim-line-1"', '"ligne-é"')
    path = tmp_path / "s.toml"
    path.write_bytes(encode(text))
    with pytest.raises(ConfigError) as err:
        load_station_config(path)
    assert all(w in str(err.value) for w in words) and str(path) in str(err.value), str(err.value)


def test_a_byte_order_mark_is_dropped_and_folders_are_named(tmp_path):
    text = (SAMPLES / "station_sim.toml").read_text().replace('"sim-line-1"', '"ligne-é"')
    (tmp_path / "bom.toml").write_bytes(b"\xef\xbb\xbf" + text.encode())
    assert load_station_config(tmp_path / "bom.toml").name == "ligne-é"
    with pytest.raises(ConfigError, match="is a folder, not a TOML file"):
        load_station_config(tmp_path)


@pytest.mark.parametrize("mutate, message", [
    (lambda d: d["protocol"].update(depth_step=1e-7), "55000001 depths"),
    (lambda d: d["protocol"].update(repeats=1000), "taps per collection"),
    (lambda d: d["sensor"].update(pins=5, selected_pins=5), "sensor.pins must be in 7..2000 pins, got 5"),
    (lambda d: d["sim"].update(seed=-1), "sim.seed must be in 0..4294967295, got -1"),
    (lambda d: d["station"].update(data_dir=5), "station.data_dir must be a path string, got 5"),
    (lambda d: d["arm"]["tap"].update(dwell=100000), "[arm.tap] dwell: must be in [0, 10] s, got 100000"),
    (lambda d: d["gaps"][2].update(x=1e30), "gaps[2].x 1e+30 mm lies outside the arm workspace x -20..600 mm"),
    (lambda d: d["gaps"][0].update(true_width=float("inf")), "gaps[0].true_width must be a number"),
    (lambda d: d["sensor"].update(source=10**6), "sensor.source must be in 0..63"),
    (lambda d: d["perception"].update(model=""), "perception.model must be a path string"),
])
def test_ranges_name_the_key_and_the_range(mutate, message):
    data = _sim_table()
    mutate(data)
    with pytest.raises(ConfigError) as err:
        parse_station_config(data, base_dir=SAMPLES)
    assert message in str(err.value)


def test_every_depth_of_the_small_station_is_a_class_of_its_own(tmp_path):
    # The test suite's small station collects 12 depths (0-5.5 mm, 0.5 mm apart). With 11 classes spanning
    # 0-5.5 mm, 5.0 and 5.5 mm shared a class whose depth spread a Gaussian's covariance took for noise.
    import numpy as np

    from perception import Dataset
    from perception.likelihood import fit_class_grid
    from tests.tactip.conftest import small_station_table

    config = parse_station_config(small_station_table(tmp_path), base_dir=tmp_path)
    depths = np.asarray(config.protocol.depths)
    assert len(depths) == 12 and depths[-1] == pytest.approx(5.5)
    taps = np.random.default_rng(0).normal(size=(len(depths), 4, 2))
    dataset = Dataset(taps, depths, np.ones(len(depths)), None, "tactip")
    grid = fit_class_grid(dataset, n_locations=config.perception.locations)
    assert sorted(grid.location_class(depths)) == list(range(len(depths)))
