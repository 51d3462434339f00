"""Issue 9, data safety: nothing lost, nothing overwritten, no traceback (the real CLI, in subprocesses).

Every case runs ``tactip`` through `faultkit.run_tactip`, which checks that no traceback is printed,
that the command's inputs are byte-identical afterwards and that no temporary file is left; refusals
are checked with `faultkit.assert_refused` (non-zero exit, the message names the problem).

Disk-full cases run on a small tmpfs the test mounts itself when it may (root); otherwise on a fake
full disk: a file-size limit (RLIMIT_FSIZE) makes the write layer fail (EFBIG) at the same place.
`FULL_DISK_MODE` records which ran; ``TACTIP_TEST_NO_MOUNT=1`` forces the fake (to test it as root).
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import resource
import shutil
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from perception import load_dataset, load_model
from tests.tactip.conftest import LOCATIONS, run_cli, small_station_table, write_station
from tests.tactip.faultkit import assert_refused, digest, leftover_temporaries, run_tactip, run_tactip_in_process

FULL_DISK_MODE: dict[str, str] = {}


# -- helpers -----------------------------------------------------------------------------------------

def station_copy(sim_station, root: Path, *, datasets: bool = True, model: bool = True, **sections) -> Path:
    """A copy of the session's small station in ``root`` (its calibration, model and datasets); returns the TOML."""
    root.mkdir(parents=True, exist_ok=True)
    shutil.copy(sim_station.root / "calibration.h5", root / "calibration.h5")
    if model:
        shutil.copy(sim_station.model, root / "model.h5")
    if datasets:
        (root / "datasets").mkdir(exist_ok=True)
        shutil.copy(sim_station.train, root / "datasets" / "train.h5")
        shutil.copy(sim_station.test, root / "datasets" / "test.h5")
    return write_station(root, small_station_table(root, **sections))


@contextlib.contextmanager
def small_filesystem(folder: Path, size_kb: int):
    """Mount a ``size_kb`` tmpfs on ``folder`` (root only); yields True if mounted, False if not permitted."""
    folder.mkdir(parents=True, exist_ok=True)
    mounted = False
    allowed = not os.environ.get("TACTIP_TEST_NO_MOUNT")     # set it to try the fake full disk as root
    if allowed and hasattr(os, "geteuid") and os.geteuid() == 0 and shutil.which("mount"):
        done = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size_kb}k", "tmpfs", str(folder)],
                              capture_output=True)
        mounted = done.returncode == 0
    try:
        yield mounted
    finally:
        if mounted:
            subprocess.run(["umount", "-l", str(folder)], capture_output=True)


def fill(folder: Path, leave_bytes: int) -> Path:
    """Fill the file system of ``folder`` with one file, leaving about ``leave_bytes`` free."""
    stat = os.statvfs(folder)
    free = stat.f_bavail * stat.f_frsize
    filler = folder / "filler.bin"
    with open(filler, "wb") as f:
        f.write(b"\0" * max(0, free - leave_bytes))
    return filler


def file_size_limit(limit_bytes: int):
    """A ``preexec_fn``: regular files may not grow past ``limit_bytes`` (writes fail with EFBIG: a fake full disk)."""
    def limit():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit_bytes, limit_bytes))
    return limit


def disk_full_words(mounted: bool) -> tuple[str, ...]:
    return ("disk full while writing",) if mounted else ("file size limit reached while writing",)


@pytest.fixture(scope="module")
def inspected(sim_station, tmp_path_factory):
    """A copy of the small station after one inspection of g02: its ``results.sqlite`` holds one done row."""
    root = tmp_path_factory.mktemp("inspected")
    toml = station_copy(sim_station, root, datasets=False)
    done = run_tactip("inspect", "--config", toml, "--gap", "g02", "--seed", "1", "--quiet", cwd=root)
    assert done.returncode == 0, done.stderr
    return root / "results.sqlite"


def rows(db: Path) -> list[tuple]:
    with contextlib.closing(sqlite3.connect(f"{db.as_uri()}?mode=ro", uri=True)) as con:
        return con.execute("SELECT id, gap, status, reason, taps, station FROM inspections ORDER BY id").fetchall()


# -- outputs over inputs --------------------------------------------------------------------------------

def test_train_refuses_to_write_the_model_over_its_dataset(sim_station, tmp_path):
    data = tmp_path / "train.h5"
    shutil.copy(sim_station.train, data)
    # Refused while parsing: the output holds collected taps (whoever's input they are).
    result = run_tactip("train", "train.h5", "--out", "train.h5", cwd=tmp_path, inputs=[data])
    assert_refused(result, "train.h5", "collected taps", "destroy")
    os.link(data, tmp_path / "hardlink.h5")       # the same file under another name
    os.symlink(data, tmp_path / "symlink.h5")
    for alias in ("hardlink.h5", "symlink.h5"):                    # variants in-process (no second start)
        result = run_tactip_in_process("train", "train.h5", "--out", alias, cwd=tmp_path, inputs=[data])
        assert_refused(result, alias, "destroy")
    # Another kind of input (a model trained earlier, given as the dataset) is refused as the input.
    model = tmp_path / "model.h5"
    shutil.copy(sim_station.model, model)
    result = run_tactip_in_process("train", "model.h5", "--out", "model.h5", cwd=tmp_path, inputs=[model])
    assert_refused(result, "model.h5", "trained model", "--overwrite")    # ours: replaced only when asked
    result = run_tactip_in_process("train", "model.h5", "--out", "model.h5", "--overwrite", cwd=tmp_path,
                                   inputs=[model])
    assert_refused(result, "model.h5", "input")                           # asked, but it is the input
    assert len(load_dataset(data)) == len(load_dataset(sim_station.train))


def test_results_export_and_plot_refuse_to_write_over_the_database(sim_station, inspected, tmp_path):
    toml = station_copy(sim_station, tmp_path, datasets=False, model=False)
    db = tmp_path / "results.sqlite"
    shutil.copy(inspected, db)
    os.symlink(db, tmp_path / "widths.png")                            # an image name that is the database
    for k, argv in enumerate((("export", "--db", db, "--csv", "--out", db),
                              ("export", "--db", db, "--json", "--out", "results.sqlite"),
                              ("plot", "--db", db, "--out", "widths.png"),
                              ("export", "--config", toml, "--csv", "--out", toml))):
        run = run_tactip if k == 0 else run_tactip_in_process          # the case as a real process
        result = run("results", *argv, cwd=tmp_path, inputs=[db, toml])
        assert_refused(result, "destroy")
    assert rows(db)[0][2] == "done"


def test_validate_refuses_json_or_plot_over_its_model_or_test_set(sim_station, tmp_path):
    model, test = tmp_path / "model.h5", tmp_path / "test.h5"
    shutil.copy(sim_station.model, model)
    shutil.copy(sim_station.test, test)
    os.symlink(test, tmp_path / "curves.png")                         # a plot name that is the test set
    for k, argv in enumerate((("--json", "model.h5"), ("--json", "test.h5"), ("--plot", "curves.png"))):
        run = run_tactip if k == 0 else run_tactip_in_process
        result = run("validate", "model.h5", "test.h5", "--runs", "10", "--quiet", *argv, cwd=tmp_path,
                     inputs=[model, test])
        assert_refused(result, argv[1], "destroy")


def test_an_output_over_collected_taps_or_results_is_refused(sim_station, inspected, tmp_path, capsys):
    """Nothing overwritten: a typo naming a collection or the results database as an output is refused
    before any work (they are not the command's inputs, but hours of collecting or inspecting) unless
    --overwrite is given; in-process (the subprocess case is
    `test_train_refuses_to_write_the_model_over_its_dataset`)."""
    data, db = tmp_path / "test.h5", tmp_path / "results.sqlite"
    shutil.copy(sim_station.test, data)
    shutil.copy(inspected, db)
    before = {p: digest(p) for p in (data, db)}
    video = Path(__file__).resolve().parents[2] / "samples" / "synthetic_tap.mp4"
    for argv, what in ((("train", sim_station.train, "--out", data), "collected taps"),
                       (("replay", video, "--out", data, "--quiet"), "collected taps"),
                       (("calibrate", "--config", sim_station.toml, "--out", data), "collected taps"),
                       (("validate", sim_station.model, sim_station.test, "--json", data), "collected taps"),
                       (("results", "export", "--db", inspected, "--csv", "--out", db), "inspection results")):
        code, _, err = run_cli(argv)
        assert code == 1 and "destroy" in err and what in err and "--overwrite" in err, (argv, err)
        assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert {p: digest(p) for p in (data, db)} == before and not leftover_temporaries(tmp_path)


def test_record_and_calibrate_refuse_outputs_over_their_inputs(sim_station, tmp_path):
    video = tmp_path / "v.mp4"
    shutil.copy(Path(__file__).resolve().parents[2] / "samples" / "synthetic_tap.mp4", video)
    result = run_tactip("record", "v.mp4", "--out", "v.mp4", "--frames", "3", "--overwrite", cwd=tmp_path,
                        inputs=[video])
    assert_refused(result, "v.mp4", "input")
    # An earlier recording (not this command's input) is replaced only when asked.
    earlier = tmp_path / "earlier.mp4"
    shutil.copy(video, earlier)
    result = run_tactip_in_process("record", "synthetic", "--out", earlier, "--frames", "3", cwd=tmp_path,
                                   inputs=[earlier])
    assert_refused(result, "earlier.mp4", "exists", "--overwrite")
    toml = station_copy(sim_station, tmp_path / "station", datasets=False)
    for k, out in enumerate((toml, tmp_path / "station" / "model.h5")):
        run = run_tactip if k == 0 else run_tactip_in_process
        result = run("calibrate", "--config", toml, "--out", out, "--overwrite", cwd=tmp_path, inputs=[toml, out])
        assert_refused(result, out.name, "input")


def test_replay_refuses_outputs_over_the_video_or_each_other(tmp_path):
    video = tmp_path / "v.mp4"
    shutil.copy(Path(__file__).resolve().parents[2] / "samples" / "synthetic_tap.mp4", video)
    for k, argv in enumerate((("--out", "o.h5", "--annotate", "v.mp4"), ("--out", "v.mp4"),
                              ("--out", "o.h5", "--annotate", "o.h5"))):
        run = run_tactip if k == 0 else run_tactip_in_process           # the case as a real process
        result = run("replay", "v.mp4", *argv, "--quiet", cwd=tmp_path, inputs=[video])
        assert_refused(result, "v.mp4" if "v.mp4" in argv else "same file")
    assert not (tmp_path / "o.h5").exists()


# -- full disk ----------------------------------------------------------------------------------------

def test_collect_on_a_full_disk_keeps_only_complete_taps_and_resumes(sim_station, tmp_path):
    from tactip.station.config import load_station_config

    # One gap, one repeat: 12 taps per set, so that the resume stays quick.
    toml = station_copy(sim_station, tmp_path / "station", datasets=False, model=False, gaps=("g02",), repeats=1)
    depths = np.asarray(load_station_config(toml).protocol.depths)
    out = tmp_path / "small"
    with small_filesystem(out, 128) as mounted:
        FULL_DISK_MODE["collect"] = "tmpfs 128 kB" if mounted else "RLIMIT_FSIZE 128 kB (no mount permission)"
        extra = {} if mounted else {"preexec_fn": file_size_limit(128 * 1024)}
        result = run_tactip("collect", "--config", toml, "--out", out, "--workers", "1", "--quiet",
                            cwd=tmp_path, inputs=[toml, tmp_path / "station" / "calibration.h5"], **extra)
        assert_refused(result, *disk_full_words(mounted), "train.h5")
        assert result.returncode == 1                                      # not a segfault (139)
        assert not leftover_temporaries(out)
        if mounted:
            stored = load_dataset(out / "train.h5")
            assert 0 < len(stored) < len(depths)
            # Every stored tap is a whole tap at its planned depth: nothing zero, nothing partial.
            assert np.array_equal(stored.location, depths[:len(stored)]) and (stored.identity == 0.5).all()
            assert np.abs(stored.taps).reshape(len(stored), -1).any(axis=1).all()   # no all-zero tap
        else:
            # A size limit leaves the file shorter than its header: refused by readers, repaired by the rerun.
            with pytest.raises(Exception, match="cut short by a failed write"):
                load_dataset(out / "train.h5")
        # The resume after the full disk: space again (a bigger file system, or no limit).
        if mounted:
            subprocess.run(["mount", "-o", "remount,size=8m", str(out)], check=True)
        again = run_tactip("collect", "--config", toml, "--out", out, "--workers", "1", "--quiet", cwd=tmp_path,
                           timeout=300)
        assert again.returncode == 0, again.stderr
        for name in ("train.h5", "test.h5"):
            whole = load_dataset(out / name)
            assert np.array_equal(whole.location, depths)                  # every planned tap, once, in order
            assert np.abs(whole.taps).reshape(len(whole), -1).any(axis=1).all()
        if mounted:
            resumed = load_dataset(out / "train.h5")
            assert np.array_equal(resumed.taps[:len(stored)], stored.taps)   # the taps kept were not touched


def test_replay_on_a_full_disk_reports_it_and_leaves_nothing(tmp_path):
    video = tmp_path / "v.mp4"
    shutil.copy(Path(__file__).resolve().parents[2] / "samples" / "synthetic_tap.mp4", video)
    out = tmp_path / "small"
    with small_filesystem(out, 96) as mounted:
        FULL_DISK_MODE["replay"] = "tmpfs 96 kB" if mounted else "RLIMIT_FSIZE 96 kB"
        extra = {} if mounted else {"preexec_fn": file_size_limit(96 * 1024)}
        result = run_tactip("replay", video, "--out", out / "o.h5", "--quiet", cwd=tmp_path, inputs=[video], **extra)
        assert_refused(result, *disk_full_words(mounted), "o.h5")
        assert result.returncode == 1
        assert not (out / "o.h5").exists() and not leftover_temporaries(out)


def test_record_and_annotated_replay_on_a_full_disk_report_it(tmp_path):
    """OpenCV's video writer says nothing when the disk fills: the video must not be kept, cut short, as done."""
    video = tmp_path / "v.mp4"
    shutil.copy(Path(__file__).resolve().parents[2] / "samples" / "synthetic_tap.mp4", video)
    out = tmp_path / "small"
    with small_filesystem(out, 96) as mounted:
        FULL_DISK_MODE["record, replay --annotate"] = "tmpfs 96 kB" if mounted else "RLIMIT_FSIZE 600 kB"
        # The fake limit lets replay's 0.5 MB HDF5 output through and stops its 2 MB annotated video.
        extra = {} if mounted else {"preexec_fn": file_size_limit(600 * 1024)}
        recorded = run_tactip("record", video, "--out", out / "r.mp4", "--quiet", cwd=tmp_path, inputs=[video],
                              **({} if mounted else {"preexec_fn": file_size_limit(96 * 1024)}))
        assert_refused(recorded, *disk_full_words(mounted), "r.mp4")
        replayed = run_tactip("replay", video, "--out", tmp_path / "o.h5", "--annotate", out / "a.mp4", "--quiet",
                              cwd=tmp_path, inputs=[video], **extra)
        assert_refused(replayed, *disk_full_words(mounted), "a.mp4")
        assert not (out / "r.mp4").exists() and not (out / "a.mp4").exists() and not (tmp_path / "o.h5").exists()
        assert not leftover_temporaries(out)


def test_simulate_on_a_full_disk_reports_it_without_crashing(tmp_path):
    """HDF5 meeting a full disk at close crashed the process (segfault, a traceback from h5py's cleanup)."""
    out = tmp_path / "small"
    with small_filesystem(out, 300) as mounted:
        FULL_DISK_MODE["simulate taxel"] = "tmpfs 300 kB" if mounted else "RLIMIT_FSIZE 300 kB"
        extra = {} if mounted else {"preexec_fn": file_size_limit(300 * 1024)}
        result = run_tactip("simulate", "taxel", "--out", out, "--locations", "300", "--quiet", cwd=tmp_path, **extra)
        assert_refused(result, *disk_full_words(mounted), "train.h5")
        assert result.returncode == 1 and not (out / "train.h5").exists() and not leftover_temporaries(out)


def test_an_output_in_a_read_only_folder_is_refused_before_any_work(sim_station, inspected, tmp_path, capsys):
    """Every output flag checks its folder can be written while parsing: no work is done and then lost."""
    from tactip.cli import main

    root = tmp_path / "ro"
    with small_filesystem(root, 64) as mounted:
        if mounted:
            subprocess.run(["mount", "-o", "remount,ro", str(root)], check=True)
            words = "read-only file system"
        elif os.geteuid() == 0:
            pytest.skip("root without mount permission: file modes cannot make a folder read-only")
        else:
            root.chmod(0o555)
            words = "permission denied"
        image = Path(__file__).resolve().parents[2] / "samples" / "synthetic_frame.png"
        try:
            for argv in (["train", sim_station.train, "--out", root / "m.h5"],
                         ["validate", sim_station.model, sim_station.test, "--json", root / "v.json"],
                         ["validate", sim_station.model, sim_station.test, "--plot", root / "v.png"],
                         ["results", "export", "--db", inspected, "--csv", "--out", root / "r.csv"],
                         ["results", "plot", "--db", inspected, "--out", root / "r.png"],
                         ["detect", image, "--annotate", root / "d.png"],
                         ["record", "synthetic", "--out", root / "r.mp4"],
                         ["calibrate", "--config", sim_station.toml, "--out", root / "sub" / "cal.h5"]):
                with pytest.raises(SystemExit) as exit_:
                    main([str(a) for a in argv])
                err = capsys.readouterr().err
                assert exit_.value.code == 2 and words in err and "cannot write" in err, (argv, err)
        finally:
            if not mounted:
                root.chmod(0o755)


def test_results_export_on_a_full_disk_keeps_the_old_file(inspected, tmp_path):
    db = tmp_path / "results.sqlite"
    shutil.copy(inspected, db)
    with contextlib.closing(sqlite3.connect(db)) as con:                 # 100 inspections: a 50 kB export
        columns = "gap, nominal_width, tolerance, estimated_width, belief, taps, decided, passed, policy, " \
                  "status, station, started_at"
        for _ in range(99):
            con.execute(f"INSERT INTO inspections ({columns}) SELECT {columns} FROM inspections WHERE id = 1")
        con.commit()
    out = tmp_path / "small"
    with small_filesystem(out, 64) as mounted:
        # The fake limit must let SQLite make its 32 kB -shm file beside the database.
        FULL_DISK_MODE["results export"] = "tmpfs 64 kB" if mounted else "RLIMIT_FSIZE 40 kB"
        old = out / "old.json"
        old.write_text('["the export of yesterday"]\n')
        if mounted:
            fill(out, 512)
        extra = {} if mounted else {"preexec_fn": file_size_limit(40 * 1024)}
        result = run_tactip("results", "export", "--db", db, "--json", "--out", old, cwd=tmp_path,
                            inputs=[db, old], **extra)
        assert_refused(result, *disk_full_words(mounted), "old.json")
        assert old.read_text() == '["the export of yesterday"]\n'


def test_inspect_on_a_full_disk_reports_it_and_keeps_the_stored_rows(sim_station, inspected, tmp_path):
    small = tmp_path / "small"
    with small_filesystem(small, 400) as mounted:
        if not mounted:
            pytest.skip("needs a small file system (root): SQLite's own writes are not size-limited the same way")
        FULL_DISK_MODE["inspect"] = "tmpfs 400 kB"
        toml = station_copy(sim_station, tmp_path / "station", datasets=False,
                            station={"results": str(small / "results.sqlite")})
        shutil.copy(inspected, small / "results.sqlite")                 # an earlier inspection, stored
        before = rows(small / "results.sqlite")
        assert [r[2] for r in before] == ["done"]
        filler = fill(small, 40 * 1024)
        result = run_tactip("inspect", "--config", toml, "--seed", "2", "--quiet", cwd=tmp_path, inputs=[toml])
        assert_refused(result, "disk full while writing", "results.sqlite")
        filler.unlink()
        after = rows(small / "results.sqlite")
        assert after[:len(before)] == before                               # nothing stored before is lost
        for row in after[len(before):]:                                    # new rows say why they stopped
            assert row[2] == "aborted" and "disk full" in row[3], row


# -- half-prepared, bad or mixed inputs ------------------------------------------------------------------

def _sim_is(config, monkeypatch):
    """``tactip inspect --sim`` runs the station ``config`` (the small one: its preparation takes seconds)."""
    import tactip.station.config

    monkeypatch.setattr(tactip.station.config, "simulated_station_config", lambda data_dir: config)


def test_an_interrupted_preparation_leaves_no_half_prepared_model(sim_station, tmp_path, monkeypatch, capsys):
    """inspect --sim's first preparation, interrupted in the fixation sweep, then resumed by the next
    ``inspect --sim`` (in-process, on the small station: the packaged one's preparation takes minutes)."""
    import calibration
    from tactip.cli import main
    from tactip.station.config import load_station_config
    from tactip.station.procedures import model_is_prepared

    toml = station_copy(sim_station, tmp_path, model=False)
    config = load_station_config(toml)
    _sim_is(config, monkeypatch)

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    prepare = calibration.prepare_station_model
    monkeypatch.setattr(calibration, "prepare_station_model", interrupted)
    assert main(["inspect", "--sim", "--gap", "g02", "--quiet"]) == 130         # Ctrl-C in the sweep
    assert "Stopped." in capsys.readouterr().err
    assert not config.perception.model.exists() and not model_is_prepared(config.perception.model)
    assert not leftover_temporaries(tmp_path) and not (tmp_path / "results.sqlite").exists()
    monkeypatch.setattr(calibration, "prepare_station_model",
                        lambda *a, **k: prepare(*a, **{**k, "runs": 100}))
    assert main(["inspect", "--sim", "--gap", "g02", "--seed", "1", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "No trained model" in out and "model ready" in out and "1 gap(s)" in out
    assert model_is_prepared(config.perception.model)


def test_a_half_prepared_model_is_prepared_again_or_warned_about(sim_station, tmp_path, monkeypatch, capsys):
    from perception import save_model
    from tactip.cli import main
    from tactip.station.config import load_station_config
    from tactip.station.procedures import model_is_prepared

    bare = load_model(sim_station.model)
    bare = type(bare)(**{**bare.__dict__, "recommended": {}})
    save_model(tmp_path / "model.h5", bare)
    assert not model_is_prepared(tmp_path / "model.h5") and model_is_prepared(sim_station.model)
    toml = station_copy(sim_station, tmp_path / "station", datasets=False)
    shutil.copy(tmp_path / "model.h5", tmp_path / "station" / "model.h5")
    # A station of one's own: inspected with the model as it is, and warned about (in-process, as below).
    before = digest(tmp_path / "station" / "model.h5")
    code, out, err = run_cli(["inspect", "--config", toml, "--gap", "g02", "--seed", "1"])
    assert code == 0, err
    assert "no recommended decision_threshold or fixation_location" in out
    assert digest(tmp_path / "station" / "model.h5") == before
    # inspect --sim (a model left by a version that trained in place): its preparation is resumed first.
    _sim_is(load_station_config(toml), monkeypatch)
    import tactip.station.procedures

    def prepare(config, **kwargs):
        shutil.copy(sim_station.model, config.perception.model)                # as the preparation ends
        return config.perception.model

    monkeypatch.setattr(tactip.station.procedures, "prepare_model", prepare)
    assert main(["inspect", "--sim", "--gap", "g02", "--seed", "1", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "has no recommended settings (an earlier preparation was interrupted): resuming" in out
    assert "no recommended" not in out.split("model ready")[1]                  # inspected with the prepared model
    assert model_is_prepared(tmp_path / "station" / "model.h5")


# The case (threshold 0 stored by a bad sweep) runs as a real process, the others in-process.
@pytest.mark.parametrize("key, value, command, words, real", [
    ("decision_threshold", 0.0, "inspect", ("decision_threshold", "(0, 1]"), True),
    ("decision_threshold", float("nan"), "validate", ("decision_threshold",), False),
    ("decision_threshold", 1.5, "replay", ("decision_threshold",), False),
    ("fixation_location", 40.0, "inspect", ("fixation_location", "range"), False),
])
def test_a_model_with_bad_recommended_settings_is_refused(sim_station, tmp_path, key, value, command, words, real):
    toml = station_copy(sim_station, tmp_path, datasets=False)
    model = tmp_path / "model.h5"
    with h5py.File(model, "r+") as f:
        settings = json.loads(f.attrs["recommended"])
        f.attrs["recommended"] = json.dumps({**settings, key: value})
    video = Path(__file__).resolve().parents[2] / "samples" / "synthetic_tap.mp4"
    argv = {"inspect": ("inspect", "--config", toml, "--quiet"),
            "validate": ("validate", model, sim_station.test, "--runs", "10", "--quiet"),
            "replay": ("replay", video, "--out", "o.h5", "--calibration", tmp_path / "calibration.h5", "--model",
                       model, "--quiet")}[command]
    result = (run_tactip if real else run_tactip_in_process)(*argv, cwd=tmp_path, inputs=[model, toml])
    assert_refused(result, "model.h5", *words)
    assert not (tmp_path / "results.sqlite").exists() or rows(tmp_path / "results.sqlite") == []
    assert not (tmp_path / "o.h5").exists()


def test_a_model_with_nan_likelihoods_is_refused_and_train_refuses_inf_epsilon(sim_station, tmp_path):
    model = tmp_path / "model.h5"
    shutil.copy(sim_station.model, model)
    with h5py.File(model, "r+") as f:
        f["log_probability"][0, 0, 0] = np.nan
    result = run_tactip("validate", model, sim_station.test, "--runs", "10", "--quiet", cwd=tmp_path,
                        inputs=[model, sim_station.test])
    assert_refused(result, "model.h5", "log_probability", "nan")
    # Replay refuses it as well, before reading the video (in-process: the same loader, no second start).
    video = Path(__file__).resolve().parents[2] / "samples" / "synthetic_tap.mp4"
    code, _, err = run_cli(["replay", video, "--out", tmp_path / "o.h5", "--calibration",
                            sim_station.root / "calibration.h5", "--model", model, "--quiet"])
    assert code == 1 and "log_probability holds 1 NaN" in err and "Traceback" not in err, err
    assert not (tmp_path / "o.h5").exists() and not leftover_temporaries(tmp_path)
    result = run_tactip("train", sim_station.train, "--out", "inf.h5", "--epsilon", "inf", cwd=tmp_path,
                        inputs=[sim_station.train])
    assert_refused(result, "--epsilon", "finite")
    assert not (tmp_path / "inf.h5").exists()


def test_taps_stored_as_bytes_are_refused_naming_the_dataset(sim_station, tmp_path):
    data = tmp_path / "bytes.h5"
    shutil.copy(sim_station.train, data)
    with h5py.File(data, "r+") as f:
        shape = f["taps"].shape
        del f["taps"]
        f.create_dataset("taps", data=np.full(shape[:1], b"x" * 8, dtype="S8"))
    result = run_tactip("train", data, "--out", "m.h5", cwd=tmp_path, inputs=[data])
    assert_refused(result, "bytes.h5", "taps", "not numbers")


def test_a_partly_written_tap_is_never_read(sim_station, tmp_path):
    """A tap whose arrays grew but whose data never reached the disk (the full-disk failure) is not counted."""
    data = tmp_path / "train.h5"
    shutil.copy(sim_station.train, data)
    with h5py.File(data, "r+") as f:
        n = f.attrs["complete_taps"]
        for name in ("taps", "location", "identity"):
            f[name].resize(n + 3, axis=0)                                  # three zero taps, not counted
    result = run_tactip("train", data, "--out", "m.h5", "--locations", LOCATIONS, cwd=tmp_path, inputs=[data])
    assert result.returncode == 0, result.stderr
    assert f"{n} taps" in result.stdout
    assert np.array_equal(load_model(tmp_path / "m.h5").log_probability, load_model(sim_station.model).log_probability)


# The case (another seed) runs as a real process, the others in-process.
@pytest.mark.parametrize("section, change, word, real", [
    ("protocol", {"seed": 7}, "seed", True),
    ("protocol", {"repeats": 1}, "repeats", False),
    ("protocol", {"lateral_jitter_mm": 0.3}, "lateral_jitter_mm", False),
])
def test_a_resumed_collection_with_another_protocol_is_refused(sim_station, tmp_path, section, change, word, real):
    toml = station_copy(sim_station, tmp_path, model=False, **{section: change})
    datasets = tmp_path / "datasets"
    with h5py.File(datasets / "train.h5", "r+") as f:                   # an interrupted collection
        f.attrs["complete_taps"] = 5
    with h5py.File(datasets / "test.h5", "r+") as f:
        f.attrs["complete_taps"] = 0
    before = {p: digest(p) for p in datasets.iterdir()}
    result = (run_tactip if real else run_tactip_in_process)("collect", "--config", toml, "--out", datasets,
                                                             "--workers", "1", "--quiet", cwd=tmp_path, inputs=[toml])
    assert_refused(result, "train.h5", word)
    assert {p: digest(p) for p in datasets.iterdir()} == before


# -- the results database ----------------------------------------------------------------------------

def test_results_refuse_another_sqlite_database_unchanged(sim_station, tmp_path):
    other = tmp_path / "other.sqlite"
    with contextlib.closing(sqlite3.connect(other)) as con:
        con.execute("CREATE TABLE invoices (id INTEGER PRIMARY KEY, amount REAL)")
        con.execute("INSERT INTO invoices (amount) VALUES (12.5)")
        con.commit()
    toml = station_copy(sim_station, tmp_path / "station", datasets=False, station={"results": str(other)})
    for run, argv in ((run_tactip_in_process, ("results", "list", "--db", other)),
                      (run_tactip_in_process, ("results", "export", "--db", other, "--csv")),
                      (run_tactip, ("inspect", "--config", toml, "--gap", "g02", "--quiet"))):
        result = run(*argv, cwd=tmp_path, inputs=[other])
        assert_refused(result, "other.sqlite", "another SQLite database", "invoices")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["other.sqlite", "station"]   # no -wal, no -shm


def test_results_list_refuses_a_limit_below_one(inspected, tmp_path):
    db = tmp_path / "results.sqlite"
    shutil.copy(inspected, db)
    for run, limit in ((run_tactip, "-1"), (run_tactip_in_process, "0")):
        result = run("results", "list", "--db", db, "--limit", limit, cwd=tmp_path, inputs=[db])
        assert_refused(result, "--limit")
        assert "(no inspections)" not in result.stdout


def test_a_read_only_data_folder_is_reported_as_permission_denied(sim_station, inspected, tmp_path):
    """Root ignores file modes: as root the folder is a tmpfs remounted read-only, otherwise chmod 555."""
    root = tmp_path / "ro"
    with small_filesystem(root, 8192) as mounted:
        if not mounted and os.geteuid() == 0:
            pytest.skip("root without mount permission: file modes cannot make a folder read-only")
        toml = station_copy(sim_station, root / "station", datasets=True)
        station = root / "station"
        shutil.copy(inspected, station / "results.sqlite")
        if mounted:
            subprocess.run(["mount", "-o", "remount,ro", str(root)], check=True)
        else:
            for path in [station, *station.rglob("*")]:
                path.chmod(0o555 if path.is_dir() else 0o444)
        try:
            inputs = [station / "results.sqlite", station / "datasets"]
            listed = run_tactip_in_process("results", "list", "--db", station / "results.sqlite", cwd=tmp_path,
                                           inputs=inputs)
            assert listed.returncode == 0, listed.stderr                   # reading needs no write access
            assert "g02" in listed.stdout
            # The cases (a results database, an HDF5 dataset) as real processes; train in-process.
            for run, argv, words in ((run_tactip, ("inspect", "--config", toml, "--gap", "g02", "--quiet"),
                                      ("permission denied", "results")),
                                     (run_tactip, ("collect", "--config", toml, "--out", station / "datasets",
                                                   "--quiet", "--workers", "1"),
                                      ("permission denied", "train.h5")),
                                     (run_tactip_in_process, ("train", station / "datasets" / "train.h5", "--out",
                                                              station / "m.h5"), ("m.h5",))):
                result = run(*argv, cwd=tmp_path, inputs=inputs)
                assert_refused(result, *words)
                assert "not a results database" not in result.stderr and "not an HDF5 file" not in result.stderr
        finally:
            if not mounted:
                for path in [station, *station.rglob("*")]:
                    path.chmod(0o755 if path.is_dir() else 0o644)


def _sighup_as_a_terminal_leaves_it() -> None:
    """In the child: SIGHUP at its default action, whatever pytest inherited (``nohup make test`` ignores it).

    tactip keeps a SIGHUP that its parent ignored ignored (as ``nohup tactip ...`` asks), so without this
    the hang-up test would only hold when the suite itself was started from a terminal.
    """
    if hasattr(signal, "SIGHUP"):
        signal.signal(signal.SIGHUP, signal.SIG_DFL)


def _start_inspect(toml: Path, cwd: Path) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "tactip.cli", "inspect", "--config", str(toml), "--seed", "1",
                             "--quiet"], cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            stdin=subprocess.DEVNULL, preexec_fn=_sighup_as_a_terminal_leaves_it)


def _wait_for_a_tap(db: Path, process: subprocess.Popen, timeout_s: float = 60) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and process.poll() is None:
        if db.exists():
            with contextlib.suppress(sqlite3.Error):
                if any(r[2] == "running" and r[4] >= 1 for r in rows(db)):
                    return
        time.sleep(0.05)
    pytest.fail("the inspection never reached its first tap")


@pytest.mark.parametrize("signum, said", [(signal.SIGTERM, "Stopped (terminated)"),
                                           (signal.SIGHUP, "Stopped (SIGHUP: the terminal closed)")])
def test_sigterm_or_a_hang_up_during_inspect_stores_the_inspection_as_aborted(sim_station, tmp_path, signum, said):
    """SIGTERM (kill, a service manager) and SIGHUP (the terminal or SSH session closed) act as Ctrl-C."""
    toml = station_copy(sim_station, tmp_path, datasets=False)
    db = tmp_path / "results.sqlite"
    process = _start_inspect(toml, tmp_path)
    _wait_for_a_tap(db, process)
    process.send_signal(signum)
    out, err = process.communicate(timeout=60)
    assert "Traceback" not in err, err
    assert process.returncode == 128 + signum and said in err
    statuses = [(r[2], r[3]) for r in rows(db)]
    name = signal.Signals(signum).name
    assert statuses[-1] == ("aborted", f"terminated ({name})") and "running" not in [s for s, _ in statuses]
    assert not leftover_temporaries(tmp_path)


def test_stale_running_rows_are_closed_but_live_ones_are_not(sim_station, tmp_path):
    toml = station_copy(sim_station, tmp_path, datasets=False)
    db = tmp_path / "results.sqlite"
    killed = _start_inspect(toml, tmp_path)                              # SIGKILL: no chance to close its row
    _wait_for_a_tap(db, killed)
    killed.kill()
    killed.communicate(timeout=30)
    # A concurrent inspection (this test's own live process) and another station's row stay running.
    import socket

    with contextlib.closing(sqlite3.connect(db)) as con:
        for station, pid in (("sim-line-1", os.getpid()), ("another-line", 2**22 + 7)):
            con.execute("INSERT INTO inspections (gap, nominal_width, tolerance, policy, station, started_at, pid, "
                        "host) VALUES ('g02', 0.5, 0.1, 'active', ?, ?, ?, ?)",
                        (station, "2099-01-01T00:00:00+00:00", pid, socket.gethostname()))
        con.commit()
    before = rows(db)
    assert [r[2] for r in before].count("running") == 3
    result = run_tactip("inspect", "--config", toml, "--gap", "g02", "--seed", "1", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "closed 1 inspection(s) left 'running'" in result.stdout
    after = {r[0]: r for r in rows(db)}
    assert after[before[0][0]][2] == "aborted" and "stale" in after[before[0][0]][3]
    assert after[before[1][0]][2] == "running" and after[before[2][0]][2] == "running"


# -- broken pipes --------------------------------------------------------------------------------------

def test_only_a_broken_stdout_is_the_quiet_broken_pipe(sim_station, inspected, tmp_path, monkeypatch, capsys):
    db = tmp_path / "results.sqlite"
    shutil.copy(inspected, db)
    # Piped into a reader that has gone: quiet, exit 1, no traceback.
    process = subprocess.Popen([sys.executable, "-m", "tactip.cli", "results", "export", "--db", str(db), "--json"],
                               cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL)
    process.stdout.close()
    err = process.stderr.read().decode()
    process.wait(timeout=60)
    assert process.returncode == 1 and err == ""
    # A broken pipe elsewhere (a worker pool, a robot socket) is an error with a message.
    import tactip.cli.train
    from tactip.cli import main

    def broken(args):
        raise BrokenPipeError(errno.EPIPE, "Broken pipe")

    monkeypatch.setattr(tactip.cli.train, "run", broken)
    assert main(["train", str(sim_station.train), "--out", str(tmp_path / "m.h5")]) == 1
    assert "broken pipe" in capsys.readouterr().err.lower()



def test_temporaries_of_killed_writers_are_removed_by_the_next_write(sim_station, tmp_path):
    """SIGKILL or a power cut leaves ``.NAME.PID.part*``; the next write of NAME removes it, not a live writer's."""
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    stale = tmp_path / f".m.{dead.pid}.part.h5"
    live = tmp_path / f".m.{os.getpid()}.part.h5"                          # this test's process: alive
    other = tmp_path / f".m2.{dead.pid}.part.h5"                           # another output's: not ours to remove
    for path in (stale, live, other):
        path.write_bytes(b"half a model")
    result = subprocess.run([sys.executable, "-m", "tactip.cli", "train", str(sim_station.train), "--out",
                             str(tmp_path / "m.h5"), "--locations", str(LOCATIONS)], capture_output=True, text=True,
                            cwd=tmp_path, stdin=subprocess.DEVNULL, timeout=120)
    assert result.returncode == 0, result.stderr
    assert not stale.exists() and live.exists() and other.exists()
    assert load_model(tmp_path / "m.h5").n_classes == load_model(sim_station.model).n_classes
