"""The station commands end to end: calibrate, collect, train, validate, inspect, results; crashes and faults.

The pipeline itself runs once per session in the `sim_station` fixture (conftest); these tests check
that what it wrote is real, inspect with it, and rehearse what goes wrong: a collection killed
midway (in a subprocess), an arm fault mid-inspection, a camera that shows no sensor.
"""

import csv
import io
import json
import shutil
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest

import tactip.station.station
from calibration import collection_plan
from perception import load_dataset, load_model
from tactip.station.config import load_station_config
from tactip.station.procedures import collect_station, sensor_description
from tactip.line.results import ResultsStore
from tactip.sim.camera import SimulatedCamera
from tests.tactip.conftest import (LOCATIONS, SMALL_GAPS, THRESHOLDS, FaultyArm, printed_inspections, run_cli,
                                   sim_arm, small_station_table, stored_inspections, write_station)

EXPORTED = {"gap", "nominal_width", "estimated_width", "belief", "taps", "decided", "passed", "policy", "started_at"}


def test_calibrate_collect_train_validate_wrote_real_files(sim_station):
    config, calibration = sim_station.config, sim_station.calibration
    assert "331 pins (expected 331), 40 selected >= 4 mm apart" in sim_station.runs["calibrate"][1]
    # the datasets hold the plan: 4 gaps x 12 depths x 2 repeats, labelled with the protocol depth and the width
    depths = np.arange(0.0, 5.51, 0.5)
    widths = [config.gap(name).nominal_width for name in SMALL_GAPS]
    assert widths == [0.5, 1.5, 2.5, 3.5]
    sets = {name: load_dataset(getattr(sim_station, name)) for name in ("train", "test")}
    p = config.protocol
    plan = collection_plan(config.gaps, p.depths, repeats=p.repeats, seed=p.seed)
    for name, data in sets.items():
        assert len(data) == len(plan[name]) == 96 and data.taps.shape[1:] == (40, 80)
        assert np.allclose(data.location, np.tile(np.repeat(depths, 2), 4))
        assert np.array_equal(data.identity, np.repeat(widths, 24))
        assert np.array_equal(data.lateral, np.zeros(96))
        assert data.sensor == sensor_description(config, calibration) and data.front_end == "tactip"
        # taps press harder with depth: the deepest taps move the pins most
        peak = np.abs(data.taps).max(axis=(1, 2)).reshape(4, 24)
        assert (peak[:, -1] > 10 * peak[:, 0]).all()
    assert not np.array_equal(sets["train"].taps, sets["test"].taps)      # two independent collections
    # the model loads, with the class grid of the datasets and the fixation the sweep chose
    model = load_model(sim_station.model)
    assert (model.n_locations, model.dims, model.samples, model.front_end) == (LOCATIONS, 80, 40, "tactip")
    assert np.array_equal(model.identities, widths)
    assert model.recommended["fixation_location"] in model.location_centres
    assert model.recommended["decision_threshold"] in THRESHOLDS
    assert f"written to {sim_station.model}" in sim_station.runs["sweep"][1]
    # validate: one entry per threshold, each with the figures
    rows = json.loads(sim_station.validation.read_text())
    assert [(r["policy"], r["threshold"]) for r in rows] == [("active", t) for t in THRESHOLDS]
    for r in rows:
        assert {"mean_taps", "mean_identity_error", "accuracy", "mean_location_error"} <= set(r)
        assert 1 <= r["mean_taps"] <= 20 and 0 <= r["accuracy"] <= 1 and 0 <= r["mean_identity_error"] <= 3


def test_inspect_then_export_the_results(sim_station, tmp_path):
    results = tmp_path / "results.sqlite"
    toml = write_station(tmp_path, small_station_table(sim_station.root, station={"results": str(results)}))
    code, out, err = run_cli(["inspect", "--config", toml, "--seed", "0"])
    assert code == 0, err
    assert "4 gap(s) in" in out and f"results: {results}" in out
    with ResultsStore(results) as store:
        rows = store.inspections()
        # every tap and verdict printed is stored, once (the line's bar for one station on SQLite)
        printed_taps, printed_verdicts = printed_inspections(out)
        assert set(printed_verdicts) == set(SMALL_GAPS) and len(printed_taps) >= len(SMALL_GAPS)
        assert stored_inspections(store) == (printed_taps, printed_verdicts)
        assert [r.gap for r in rows] == list(SMALL_GAPS) and {r.status for r in rows} == {"done"}
        for r in rows:
            taps = store.taps(r.id)
            assert 1 <= r.taps == len(taps) <= 20 and taps[-1]["identity_estimate"] == r.estimated_width
            assert all(0.0 <= t["depth_mm"] <= 5.5 for t in taps)
        # the verdicts are right (each gap is at its nominal width) and so are the depth estimates
        assert sum(r.passed is True for r in rows) >= 3
        assert np.mean([abs(r.estimated_width - r.nominal_width) for r in rows]) <= 0.25    # chance: 1.25 mm
        taps = [t for r in rows for t in store.taps(r.id)]
        assert np.mean([abs(t["location_estimate"] - t["depth_mm"]) for t in taps]) <= 0.5  # a class width

    code, out, _ = run_cli(["results", "export", "--db", results, "--json"])
    exported = json.loads(out)
    assert code == 0 and len(exported) == 4 and EXPORTED <= set(exported[0])
    assert [e["estimated_width"] for e in exported] == [r.estimated_width for r in rows]
    assert [e["passed"] for e in exported] == [r.passed for r in rows]
    code, _, err = run_cli(["results", "export", "--db", results, "--csv", "--out", tmp_path / "results.csv"])
    table = list(csv.DictReader(io.StringIO((tmp_path / "results.csv").read_text())))
    assert code == 0 and len(table) == 4 and EXPORTED <= set(table[0])
    assert [float(t["estimated_width"]) for t in table] == [r.estimated_width for r in rows]
    assert [t["gap"] for t in table] == list(SMALL_GAPS)
    code, out, _ = run_cli(["results", "list", "--db", results])
    assert code == 0 and all(name in out for name in SMALL_GAPS)


def test_inspect_sim_keeps_everything_in_its_data_dir(sim_station, tmp_path, monkeypatch):
    data = tmp_path / "data"
    data.mkdir()
    shutil.copy(sim_station.root / "calibration.h5", data)    # the small station's sensor is the preset's sensor
    # The packaged station's likelihood, on the small station's taps and with its recommended settings.
    from perception import load_dataset, load_model, save_model, train_model

    model = train_model(load_dataset(sim_station.train), kind="gaussian", n_locations=int(LOCATIONS))
    save_model(data / "model.h5", model.with_recommended(**load_model(sim_station.model).recommended))
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(["inspect", "--sim", "--data-dir", "data", "--gap", "g14", "--start-depth", "5",
                              "--quiet"])
    assert code == 0, err
    assert "No trained model" not in out and "1 gap(s) in" in out
    assert [p.name for p in tmp_path.iterdir()] == ["data"]
    with ResultsStore(data / "results.sqlite") as store:
        (row,) = store.inspections()
    assert row.gap == "g14" and row.station == "sim-line-1" and row.model == str((data / "model.h5").resolve())


# -- a collection killed midway ------------------------------------------------------------------

@pytest.fixture(scope="module")
def small_collection(sim_station, tmp_path_factory):
    """2 gaps x 6 depths on the shared calibration, and its uninterrupted collection."""
    root = tmp_path_factory.mktemp("resume")
    table = small_station_table(root, gaps=("g02", "g10"), depth_step=1.1, repeats=1,
                                sensor={"calibration": str(sim_station.root / "calibration.h5")})
    toml = write_station(root, table)
    reference = collect_station(load_station_config(toml), root / "reference", workers=1, progress=False,
                                log=lambda _: None)
    return toml, {name: load_dataset(path) for name, path in reference.items()}


def stored_taps(path) -> int | None:
    """Taps in a dataset another process is writing (None while it cannot be read)."""
    try:
        with h5py.File(path, "r", locking=False) as f:
            return f["taps"].shape[0]
    except (OSError, KeyError):
        return None


@pytest.mark.parametrize("stop", [signal.SIGKILL, signal.SIGINT], ids=["SIGKILL", "SIGINT"])
def test_a_killed_collection_resumes_to_the_uninterrupted_dataset(small_collection, tmp_path, stop):
    toml, reference = small_collection
    out = tmp_path / "datasets"
    argv = [sys.executable, "-m", "tactip.cli", "collect", "--config", str(toml), "--out", str(out),
            "--workers", "1", "--quiet"]
    process = subprocess.Popen(argv, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while (stored_taps(out / "train.h5") or 0) < 3:
            assert process.poll() is None, "the collection ended before it could be stopped"
            assert time.monotonic() < deadline, "no taps stored within 60 s"
            time.sleep(0.01)
        process.send_signal(stop)
        _, err = process.communicate(timeout=30)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    if stop == signal.SIGINT:
        assert process.returncode == 130 and err.strip().splitlines()[-1] == "Stopped." and "Traceback" not in err
    else:
        assert process.returncode == -signal.SIGKILL
    partial = stored_taps(out / "train.h5") + (stored_taps(out / "test.h5") or 0)
    assert 3 <= partial < 24                                           # stopped partway
    rerun = subprocess.run(argv, cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert rerun.returncode == 0, rerun.stderr
    for name, expected in reference.items():
        resumed = load_dataset(out / f"{name}.h5")
        for field in ("taps", "location", "identity", "lateral"):
            assert np.array_equal(getattr(resumed, field), getattr(expected, field)), (name, field)


def test_a_collection_on_a_process_pool_stores_the_uninterrupted_dataset(small_collection, tmp_path):
    """The simulated station's pool of spawned processes (``workers=2``; the suite's own collections tap
    in the test's process, ``TACTIP_SIM_WORKERS``) stores the taps of the collection taken here."""
    toml, reference = small_collection
    pooled = collect_station(load_station_config(toml), tmp_path / "pooled", workers=2, progress=False,
                             log=lambda _: None)
    for name, expected in reference.items():
        stored = load_dataset(pooled[name])
        assert len(stored) == 12
        for field in ("taps", "location", "identity", "lateral"):
            assert np.array_equal(getattr(stored, field), getattr(expected, field)), (name, field)


# -- faults ---------------------------------------------------------------------------------------

def test_inspect_exits_1_with_one_line_on_an_arm_fault(sim_station, tmp_path, monkeypatch):
    results = tmp_path / "results.sqlite"
    table = small_station_table(sim_station.root, station={"results": str(results)},
                                perception={"decision_threshold": 1.0, "max_taps": 3})
    toml = write_station(tmp_path, table)
    station_class = tactip.station.station.Station
    arms = []

    def station_with_a_faulty_arm(config, *, calibration=None, **_):
        arms.append(sim_arm(config, FaultyArm, fault_tap=5))      # the second gap's second tap
        return station_class(config, calibration=calibration, arm=arms[-1])

    monkeypatch.setattr(tactip.station.station, "Station", station_with_a_faulty_arm)
    code, out, err = run_cli(["inspect", "--config", toml, "--start-depth", "4", "--quiet"])
    assert code == 1
    assert err.count("\n") == 1 and err.startswith("tactip inspect: error: protective stop during the move to")
    assert "g02: width" in out and "g06" not in out
    with ResultsStore(results) as store:
        assert [(r.gap, r.status, r.taps) for r in store.inspections()] == [("g02", "done", 3), ("g06", "aborted", 1)]
        (station,) = store.stations()                                # its status row says why it stopped
    assert station["state"].startswith("stopped: ArmFault: protective stop during the move to")
    assert station["arm"].startswith("sim: the controller reports a protective stop")
    assert not arms[0].connected


class GreyCamera:
    """A camera that sees no sensor: uniform grey frames."""

    live = False

    def rest_frames(self, n):
        return [np.full((480, 640), 128, np.uint8)] * n

    def close(self):
        pass


@pytest.mark.parametrize("camera, pins, message", [
    (GreyCamera, 331, "tactip calibrate: error: no sensor in view: "),
    (lambda: SimulatedCamera(pins=331), 532, "tactip calibrate: error: pin detection cannot be tuned to 532 pins"),
], ids=["no-sensor", "wrong-count"])
def test_calibrate_refuses_with_one_line(tmp_path, monkeypatch, camera, pins, message):
    toml = write_station(tmp_path, small_station_table(tmp_path, sensor={"pins": pins}))
    monkeypatch.setattr(tactip.station.station, "make_camera", lambda config: camera())
    code, out, err = run_cli(["calibrate", "--config", toml])
    assert code == 1 and err.count("\n") == 1 and err.startswith(message)
    assert not (tmp_path / "calibration.h5").exists()


def test_collect_without_calibration_refuses_with_one_line(tmp_path):
    toml = write_station(tmp_path, small_station_table(tmp_path))
    code, _, err = run_cli(["collect", "--config", toml, "--out", tmp_path / "datasets", "--workers", "1"])
    assert code == 1 and err.count("\n") == 1
    assert err.startswith("tactip collect: error: no calibration file at") and "run 'tactip calibrate' first" in err
