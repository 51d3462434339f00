"""The station on the simulated arm and camera: taps, their refusals, and the model check."""

import dataclasses

import numpy as np
import pytest

from calibration import collection_plan
from perception import ModelError, fit_model, load_dataset, save_model
from tactip.errors import TactipError
from tactip.station.inspection import load_station_model
from tactip.station.station import Station
from tests.perception.synthetic import gap_dataset
from tests.tactip.conftest import run_cli


@pytest.fixture
def station(sim_station):
    with Station(sim_station.config, calibration=sim_station.calibration) as open_station:
        yield open_station


def with_model(config, path, **protocol):
    """``config`` using the model at ``path`` (and other protocol settings)."""
    return dataclasses.replace(config, perception=dataclasses.replace(config.perception, model=path),
                               protocol=dataclasses.replace(config.protocol, **protocol))


def test_a_deeper_tap_gives_larger_features(station):
    gap = station.config.gap("g06")
    taps = [station.tap(gap, depth, seed=7) for depth in (0.0, 2.0, 3.5, 5.5)]
    for tap, depth in zip(taps, (0.0, 2.0, 3.5, 5.5)):
        assert tap.features.shape == (40, 80) and tap.features.dtype == np.float32
        # protocol depth d presses to reference_height (1.5 mm) - d below the surface
        assert tap.contact.indentation_mm == pytest.approx(depth - 1.5)
        assert tap.contact.gap_name == "g06" and tap.contact.gap_width_mm == 1.5
        assert tap.depth_mm == depth and tap.frames >= 2
    peak = [np.abs(tap.features).max() for tap in taps]
    assert peak[0] < 0.2                                   # depth 0 taps air: only camera noise
    assert peak[0] < peak[1] < peak[2] < peak[3]
    assert peak[3] > 20 * peak[0]


def test_the_lateral_offset_moves_the_tap_across_the_gap(station):
    gap = station.config.gap("g10")
    tap = station.tap(gap, 4.0, lateral_mm=0.4, seed=1)
    assert tap.lateral_mm == 0.4
    assert tap.contact.gap_offset_mm == pytest.approx(0.4) and tap.contact.gap_width_mm == 2.5


@pytest.mark.parametrize("depth", [-0.05, 5.6, 40.0])
def test_a_depth_outside_the_protocol_is_refused_before_the_arm_moves(station, depth):
    gap = station.config.gaps[0]
    station.tap(gap, 1.0, seed=0)
    commands, pose = list(station.arm.commands), station.arm.pose()
    with pytest.raises(TactipError, match="outside the protocol range 0..5.5 mm"):
        station.tap(gap, depth, seed=0)
    assert station.arm.commands == commands and station.arm.pose() == pose


def test_the_same_planned_tap_gives_the_same_features(sim_station, station):
    config = sim_station.config
    p = config.protocol
    plan = collection_plan(config.gaps, p.depths, repeats=p.repeats, seed=p.seed)["train"]
    collected = load_dataset(sim_station.train)       # tapped by worker processes, in plan order
    for planned in (plan[0], plan[17], plan[-1]):
        features = station.tap(planned.gap, planned.depth_mm, lateral_mm=planned.lateral_mm, seed=planned.seed).features
        assert np.array_equal(features, collected.taps[planned.index])
        again = station.tap(planned.gap, planned.depth_mm, lateral_mm=planned.lateral_mm, seed=planned.seed).features
        assert np.array_equal(again, features)
    other = station.tap(plan[-1].gap, plan[-1].depth_mm, seed=plan[-1].seed + 1).features
    assert not np.array_equal(other, features)            # the seed draws the camera noise


def test_a_tap_needs_a_calibration(sim_station):
    with Station(sim_station.config) as station:
        commands = list(station.arm.commands)
        with pytest.raises(TactipError, match="run 'tactip calibrate' first"):
            station.tap(sim_station.config.gaps[0], 3.0)
        assert station.arm.commands == commands


def test_leaving_the_station_disconnects_the_arm_even_on_error(sim_station):
    station = Station(sim_station.config, calibration=sim_station.calibration)
    with pytest.raises(RuntimeError):
        with station:
            assert station.arm.connected
            raise RuntimeError("boom")
    assert not station.arm.connected
    station.close()                                       # twice is fine


def test_the_station_model_loads(sim_station):
    model = load_station_model(sim_station.config, sim_station.calibration)
    assert (model.front_end, model.samples, model.dims) == ("tactip", 40, 80)


def test_a_model_of_other_dims_is_refused(sim_station, tmp_path):
    path = tmp_path / "other.h5"
    save_model(path, fit_model(gap_dataset(samples=10, dims=8), n_locations=3))
    with pytest.raises(ModelError) as info:
        load_station_model(with_model(sim_station.config, path), sim_station.calibration)
    message = str(info.value)
    assert "trained for tactip taps of 10 samples x 8 dims" in message
    assert "this station makes tactip taps of 40 x 80 (40 pins)" in message


def test_a_taxel_model_is_refused(sim_station, tmp_path):
    assert run_cli(["simulate", "taxel", "--sensor", "fingertip", "--out", tmp_path, "--locations", "4",
                    "--quiet"])[0] == 0
    assert run_cli(["train", tmp_path / "train.h5", "--out", tmp_path / "taxel.h5", "--locations", "4"])[0] == 0
    with pytest.raises(ModelError, match=r"trained for taxel taps .* this station makes tactip taps"):
        load_station_model(with_model(sim_station.config, tmp_path / "taxel.h5"), sim_station.calibration)


def test_a_model_for_other_pins_or_samples_is_refused(sim_station):
    config, calibration = sim_station.config, sim_station.calibration
    fewer = dataclasses.replace(calibration, selected_pins=calibration.selected_pins[:20])
    with pytest.raises(ModelError, match=r"makes tactip taps of 40 x 40 \(20 pins\)"):
        load_station_model(config, fewer)
    with pytest.raises(ModelError, match=r"makes tactip taps of 30 x 80 \(40 pins\)"):
        load_station_model(with_model(config, config.perception.model, samples=30), calibration)


def test_a_missing_model_is_refused(sim_station, tmp_path):
    with pytest.raises(ModelError, match="no model at .*tactip train"):
        load_station_model(with_model(sim_station.config, tmp_path / "none.h5"), sim_station.calibration)


def test_a_model_for_another_tactip_with_the_same_shapes_is_refused(sim_station):
    # 40 feature pins of a 532-pin pad make taps of the same shape as this 331-pin station's.
    other = dataclasses.replace(sim_station.calibration, expected_pins=532)
    with pytest.raises(ModelError, match=r"trained on another sensor: pins 331 \(this station: 532\)"):
        load_station_model(sim_station.config, other)


@pytest.mark.parametrize("blank_at", [0, 4])
def test_a_blank_frame_in_a_tap_is_marked_and_the_pins_recovered(station, blank_at, monkeypatch):
    # LEDs off or a dropped USB frame: a black frame as the rest frame or mid-tap.
    gap = station.config.gap("g06")
    clean = station.tap(gap, 4.0, seed=3)
    end_tap = station.camera.end_tap

    def with_a_blank_frame(event):
        frames, times = end_tap(event)
        frames = list(frames)
        frames[blank_at] = np.zeros_like(frames[blank_at])
        return frames, times

    monkeypatch.setattr(station.camera, "end_tap", with_a_blank_frame)
    tap = station.tap(gap, 4.0, seed=3)
    assert tap.features.shape == clean.features.shape and np.isfinite(tap.features).all()
    # The blank frame is filled in from its neighbours in time: only the samples round it differ, and
    # there by less than the tap itself changes across them (a linear fill between the true neighbours;
    # mid-rise at contact onset the pins under the plate accelerate, so the line misses the curve by up
    # to a sixth of the peak on them); the rest of the tap is the same.
    peak = np.abs(clean.features).max()
    difference = np.abs(tap.features - clean.features)
    assert peak > 1.0 and difference.mean() < 0.01 * peak
    changed = np.flatnonzero(difference.max(axis=1) > 0.02 * peak)  # beyond the noise of a new rest frame
    assert len(changed) == 0 or np.array_equal(changed, np.arange(changed[0], changed[-1] + 1))
    assert len(changed) <= 0.25 * len(difference)
    if len(changed):
        around = clean.features[max(changed[0] - 1, 0):changed[-1] + 2]
        assert np.all(difference[changed] <= np.ptp(around, axis=0) + 1e-6)
    else:
        assert difference.max() <= 0.02 * peak


def test_a_tap_of_blank_frames_is_refused_in_one_line(station, monkeypatch):
    monkeypatch.setattr(station.camera, "end_tap", lambda event: ([np.zeros((480, 640), np.uint8)] * 5, list(range(5))))
    with pytest.raises(TactipError, match="no frame of the tap shows the pins"):
        station.tap(station.config.gap("g06"), 4.0, seed=3)
