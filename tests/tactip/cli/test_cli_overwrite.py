"""Issue 22: a file the project wrote (model, calibration, collected taps, replay, results database, station
TOML) is replaced only with --overwrite, whatever the command; a new path or a foreign file is written as
before, and a stream (``-``) is never refused."""

from __future__ import annotations

import shutil
from pathlib import Path

import h5py
import pytest

from tactip._output import project_file, refuse_replacing_project_files
from tactip.errors import TactipError
from tests.tactip.conftest import run_cli
from tests.tactip.faultkit import digest, leftover_temporaries

SAMPLES = Path(__file__).resolve().parents[3] / "samples"


@pytest.fixture()
def station_files(sim_station, tmp_path):
    """Copies of the small station's files in ``tmp_path``: model, calibration, taps, TOML, results DB."""
    from tactip.line.results import open_results

    for name, source in (("model.h5", sim_station.model), ("calibration.h5", sim_station.root / "calibration.h5"),
                         ("train.h5", sim_station.train), ("test.h5", sim_station.test),
                         ("station.toml", sim_station.toml)):
        shutil.copy(source, tmp_path / name)
    with open_results(tmp_path / "results.sqlite"):
        pass                                                           # our schema, no rows
    return tmp_path


def test_each_kind_of_project_file_is_recognised_by_its_content(station_files, tmp_path):
    kinds = {name: project_file(station_files / name) for name in
             ("model.h5", "calibration.h5", "train.h5", "station.toml", "results.sqlite")}
    assert "tactip-model/1" in kinds["model.h5"] and "tactip-calibration/1" in kinds["calibration.h5"]
    assert kinds["train.h5"].startswith("collected taps") and "[station]" in kinds["station.toml"]
    assert kinds["results.sqlite"].startswith("inspection results")
    # Foreign files: an HDF5 without our marker, a TOML without a station table, text, a missing path.
    with h5py.File(tmp_path / "foreign.h5", "w") as f:
        f.attrs["schema"] = "someone-else/1"
    (tmp_path / "pyproject.toml").write_text('[project]\nname = "x"\n')
    (tmp_path / "notes.txt").write_text("station = 1\n")
    for name in ("foreign.h5", "pyproject.toml", "notes.txt", "missing.h5"):
        assert project_file(tmp_path / name) is None, name
    # A copy named anything is still ours: recognised by content, not by name.
    shutil.copy(station_files / "model.h5", tmp_path / "curves.json")
    assert "tactip-model/1" in project_file(tmp_path / "curves.json")


def test_the_issue_cases_are_refused_without_overwrite_and_leave_the_file(station_files):
    root = station_files
    cases = [
        (["results", "export", "--db", root / "results.sqlite", "--csv", "--out", root / "model.h5"], "model.h5"),
        (["results", "export", "--db", root / "results.sqlite", "--json", "--out", root / "calibration.h5"],
         "calibration.h5"),
        (["results", "list", "--db", root / "results.sqlite", "--json", root / "train.h5"], "train.h5"),
        (["train", root / "train.h5", "--out", root / "calibration.h5"], "calibration.h5"),
        (["train", root / "train.h5", "--out", root / "station.toml"], "station.toml"),
        (["validate", root / "model.h5", root / "test.h5", "--runs", "10", "--json", root / "calibration.h5"],
         "calibration.h5"),
        (["detect", SAMPLES / "synthetic_frame.png", "--json", root / "model.h5"], "model.h5"),
        (["replay", SAMPLES / "synthetic_tap.mp4", "--out", root / "train.h5"], "train.h5"),
        (["calibrate", "--config", root / "station.toml"], "calibration.h5"),            # the station's own
        (["reproduce", "004", "--quick", "--json", root / "results.sqlite"], "results.sqlite"),
    ]
    before = {p: digest(p) for p in root.iterdir()}
    for argv, name in cases:
        code, out, err = run_cli(argv)
        assert code == 1, (argv, out, err)
        assert name in err and "--overwrite" in err and "Traceback" not in err, (argv, err)
        assert len(err.strip().splitlines()) == 1, err
    assert {p: digest(p) for p in root.iterdir()} == before and not leftover_temporaries(root)


def test_with_overwrite_the_file_is_replaced(station_files):
    root = station_files
    code, _, err = run_cli(["results", "export", "--db", root / "results.sqlite", "--csv", "--out", root / "model.h5",
                            "--overwrite"])
    assert code == 0, err
    assert (root / "model.h5").read_text().startswith("id,")                   # now the CSV asked for
    code, _, err = run_cli(["train", root / "train.h5", "--out", root / "station.toml", "--overwrite", "-q"])
    assert code == 0, err
    assert "tactip-model/1" in project_file(root / "station.toml")


def test_a_foreign_file_a_new_path_and_a_stream_are_written_as_before(station_files, tmp_path):
    root = station_files
    (root / "old.csv").write_text("someone's notes\n")
    for out in (root / "old.csv", root / "new" / "sub" / "fresh.csv"):          # missing folders are created
        code, _, err = run_cli(["results", "export", "--db", root / "results.sqlite", "--csv", "--out", out])
        assert code == 0, err
        assert out.read_text().startswith("id,")
    code, out, err = run_cli(["results", "export", "--db", root / "results.sqlite", "--json", "-"])
    assert code == 0 and out.strip() == "[]", err


def test_the_helper_refuses_only_without_overwrite(station_files):
    with pytest.raises(TactipError, match=r"model\.h5.*trained model.*--overwrite"):
        refuse_replacing_project_files([station_files / "model.h5"], overwrite=False)
    refuse_replacing_project_files([station_files / "model.h5"], overwrite=True)
    refuse_replacing_project_files([None, "-", station_files / "missing.h5"], overwrite=False)


def test_every_command_that_writes_a_file_has_overwrite_and_the_common_flags():
    from tactip.cli import COMMANDS, _leaf_parsers, build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    for name in COMMANDS:
        for leaf in _leaf_parsers(sub.choices[name]):
            options = set(leaf._option_string_actions)
            assert {"-q", "--quiet", "-v", "--verbose"} <= options, leaf.prog
            writes = any(getattr(a.type, "__name__", "") in ("output_file", "creatable_file", "image_file",
                                                             "json_target") for a in leaf._actions)
            assert not writes or "--overwrite" in options, leaf.prog
