"""`tactip replay --calibration --model`: a recorded video of one known gap, decided against ground truth.

The video is filmed by the small simulated station of `conftest.sim_station` (its arm, and its
SimulatedCamera: same pin preset and seed as the sensor it was calibrated and trained on): several
taps of one gap at a deep protocol depth, written with OpenCV's 'mp4v' at the camera's 20 fps.
"""

import dataclasses
import functools
import pathlib

import cv2
import h5py
import numpy as np
import pytest

from perception import ModelError, load_model, save_model
from tactip.replay.video import replay_video
from tactip.sim.camera import SimulatedCamera
from tactip.station.station import Station

from tests.tactip.conftest import run_cli

TAPS = 8
DEPTH_MM = 4.5  # protocol depth: deep in the 0-5.5 mm range


class RecordingCamera(SimulatedCamera):
    """The station's simulated camera, keeping every tap's frames (rest before and after included)."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.recorded = []

    def end_tap(self, event):
        """`SimulatedCamera.end_tap`, recording the frames."""
        frames, times = super().end_tap(event)
        self.recorded += frames
        return frames, times


@functools.lru_cache(maxsize=None)
def _film(station_root: str, directory: str, gap_index: int):
    """Film TAPS taps of the station's gap ``gap_index`` to an MP4; returns (path, true width mm)."""
    from tactip.station.config import load_station_config
    from calibration import load_calibration

    root = pathlib.Path(station_root)
    config = load_station_config(root / "station.toml")
    calibration = load_calibration(root / "calibration.h5")
    tap = config.arm.tap
    camera = RecordingCamera(pins=config.sensor.pins, frame_rate=config.sensor.frame_rate,
                             tap_speed_mm_s=tap.speed_mm_s, dwell_s=tap.dwell_s,
                             approach_height_mm=tap.approach_height_mm, noise_sigma=config.sim.noise_sigma,
                             seed=config.sim.seed)
    gap = config.gaps[gap_index]
    with Station(config, calibration=calibration, camera=camera) as station:
        for k in range(TAPS):
            station.tap(gap, DEPTH_MM, seed=1000 + k)
    path = pathlib.Path(directory) / f"taps_{gap.name}.mp4"
    height, width = camera.recorded[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), config.sensor.frame_rate,
                             (width, height), True)
    for frame in camera.recorded:
        writer.write(cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR))
    writer.release()
    return path, float(gap.true_width if gap.true_width is not None else gap.nominal_width)


@pytest.fixture(scope="module")
def film(sim_station, tmp_path_factory):
    return _film(str(sim_station.root), str(tmp_path_factory.mktemp("film")), 2)


@pytest.fixture(scope="module")
def replayed(sim_station, film, tmp_path_factory):
    out = tmp_path_factory.mktemp("decided") / "replay.h5"
    annotated = out.with_name("annotated.mp4")
    code, stdout, stderr = run_cli(["replay", film[0], "--out", out, "--annotate", annotated, "--quiet",
                                    "--calibration", sim_station.root / "calibration.h5",
                                    "--model", sim_station.model])
    assert code == 0, stderr
    return out, annotated


def test_decided_width_is_the_true_width(sim_station, film, replayed):
    out, _ = replayed
    _, true_width = film
    model = load_model(sim_station.model)
    with h5py.File(out) as h5:
        bounds = h5["tap_bounds"][:]
        valid = h5["tap_valid"][:]
        group = h5["decisions"]
        attrs = dict(group.attrs)
        what = group["what_belief"][:]
        belief = group["belief"][:]
        used = group["used"][:]
        identities = group["identities"][:]
        assert list(h5["selected_pins"][:]) == list(sim_station.calibration.selected_pins)
    assert len(bounds) == TAPS and valid.all()
    assert what.shape == (TAPS, model.n_identities) and belief.shape == (TAPS,) and used.shape == (TAPS,)
    assert np.allclose(identities, model.identities)
    # The decided width is the true width (the nearest class to it).
    nearest = model.identities[np.abs(model.identities - true_width).argmin()]
    assert attrs["identity_estimate"] == pytest.approx(nearest)
    assert attrs["decided"] and 0 <= attrs["decided_at_tap"] < TAPS
    assert attrs["belief"] > attrs["decision_threshold"] == pytest.approx(
        model.recommended.get("decision_threshold", 0.9))
    # Taps up to the decision entered the belief (rows sum to 1), later ones are NaN.
    decided = attrs["decided_at_tap"]
    assert used[:decided + 1].all() and not used[decided + 1:].any()
    assert np.allclose(what[used].sum(axis=1), 1.0) and np.isnan(what[~used]).all()
    assert np.allclose(belief[used], what[used].max(axis=1))
    assert attrs["model"] == str(sim_station.model)


def test_cli_prints_taps_and_decision(sim_station, film, tmp_path):
    out = tmp_path / "replay.h5"
    code, stdout, stderr = run_cli(["replay", film[0], "--out", out, "--calibration",
                                    sim_station.root / "calibration.h5", "--model", sim_station.model,
                                    "--decision-threshold", "1.0"])
    assert code == 0, stderr
    # A threshold of 1 is never crossed: every valid tap enters the belief and nothing is decided.
    with h5py.File(out) as h5:
        attrs = dict(h5["decisions"].attrs)
        assert h5["decisions/used"][:].all()
    assert not attrs["decided"] and attrs["decided_at_tap"] == -1 and attrs["decision_threshold"] == 1.0
    assert stdout.count("  tap ") == TAPS and "Undecided: best" in stdout


def test_annotated_video_shows_the_width(replayed):
    _, annotated = replayed
    capture = cv2.VideoCapture(str(annotated))
    frames = []
    ok, frame = capture.read()
    while ok:
        frames.append(frame)
        ok, frame = capture.read()
    capture.release()
    # The width line is drawn at the top in yellow on tap frames only; rest frames have none.
    top = np.stack(frames)[:, 8:28, 10:300]
    yellow = ((top[..., 1] > 180) & (top[..., 2] > 180) & (top[..., 0] < 100)).sum(axis=(1, 2))
    assert yellow[0] == 0 and yellow.max() > 50


def _variant(sim_station, path, **changes):
    model = load_model(sim_station.model)
    save_model(path, dataclasses.replace(model, **changes))
    return path


def test_model_of_another_shape_or_sensor_is_refused(sim_station, film, tmp_path):
    model = load_model(sim_station.model)
    cut = 60
    other_shape = _variant(sim_station, tmp_path / "shape.h5", log_probability=model.log_probability[:cut],
                           bin_lower=model.bin_lower[:cut], bin_width=model.bin_width[:cut],
                           dim_names=model.dim_names[:cut])
    other_sensor = _variant(sim_station, tmp_path / "sensor.h5", sensor={**model.sensor, "pins": 532})
    for path, words in ((other_shape, ["60 dims", "40 x 80"]), (other_sensor, ["pins 532", "331"])):
        out = tmp_path / "replay.h5"
        code, stdout, stderr = run_cli(["replay", film[0], "--out", out, "--calibration",
                                        sim_station.root / "calibration.h5", "--model", path])
        assert code == 1 and not out.exists()
        assert len(stderr.strip().splitlines()) == 1 and all(w in stderr for w in words), stderr
    with pytest.raises(ModelError, match="60 dims"):
        replay_video(film[0], tmp_path / "r.h5", calibration=sim_station.calibration, model=load_model(other_shape))


def test_model_needs_calibration(sim_station, film, tmp_path):
    code, _, stderr = run_cli(["replay", film[0], "--out", tmp_path / "r.h5", "--model", sim_station.model])
    assert code == 1 and "calibration" in stderr and len(stderr.strip().splitlines()) == 1
