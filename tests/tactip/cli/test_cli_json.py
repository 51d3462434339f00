"""Issue 22: a CLI a script can gate on. ``--json [FILE|-]`` the same in every command that reports (JSON alone
on standard output, or in FILE), ``inspect --fail-on``'s exit status, ``-q``/``-v`` on every command."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path
from types import SimpleNamespace

import pytest

from tactip.cli.inspect import EXIT_VERDICT, exit_status
from tactip.line.results import ResultsStore
from tests.tactip.conftest import run_cli, small_station_table, write_station

SAMPLES = Path(__file__).resolve().parents[3] / "samples"
FRAME = SAMPLES / "synthetic_frame.png"


@pytest.fixture(scope="module")
def inspected(sim_station, tmp_path_factory):
    """The small station inspected over two gaps with ``--json -``: (code, out, err, results database)."""
    root = tmp_path_factory.mktemp("json-inspected")
    results = root / "results.sqlite"
    toml = write_station(root, small_station_table(sim_station.root, station={"results": str(results)}))
    code, out, err = run_cli(["inspect", "--config", toml, "--gap", "g02", "--gap", "g14", "--seed", "0",
                              "--json", "--fail-on", "undecided"])
    return SimpleNamespace(code=code, out=out, err=err, db=results, toml=toml, root=root)


def test_inspect_json_is_alone_on_stdout_and_matches_the_stored_verdicts(inspected):
    verdicts = json.loads(inspected.out)                         # nothing but the JSON on standard output
    assert "g02: width" in inspected.err and "2 gap(s) in" in inspected.err   # the human lines went to stderr
    with ResultsStore(inspected.db) as store:
        rows = {r.id: r for r in store.inspections()}
    assert [v["gap"] for v in verdicts] == ["g02", "g14"]
    for v in verdicts:
        row = rows[v["result_id"]]
        assert v["gap"] == row.gap and v["taps"] == row.taps and v["estimated_width_mm"] == pytest.approx(
            row.estimated_width)
        assert v["verdict"] == {True: "PASS", False: "FAIL", None: "UNDECIDED"}[row.passed]


def test_inspect_fail_on_sets_the_exit_status_from_the_verdicts(inspected):
    verdicts = [v["verdict"] for v in json.loads(inspected.out)]
    gated = any(v in ("FAIL", "UNDECIDED") for v in verdicts)
    assert inspected.code == (EXIT_VERDICT if gated else 0), (verdicts, inspected.err)


@pytest.mark.parametrize("verdicts, fail_on, expected", [
    (["PASS", "PASS"], None, 0), (["FAIL", "UNDECIDED"], None, 0),
    (["PASS", "UNDECIDED"], "fail", 0), (["PASS", "FAIL"], "fail", EXIT_VERDICT),
    (["PASS", "UNDECIDED"], "undecided", EXIT_VERDICT), (["FAIL"], "undecided", EXIT_VERDICT),
    (["PASS"], "undecided", 0), ([], "undecided", 0)])
def test_the_exit_status_of_each_verdict_and_fail_on(verdicts, fail_on, expected):
    assert exit_status([SimpleNamespace(verdict=v) for v in verdicts], fail_on) == expected


def test_inspect_json_to_a_file_keeps_the_human_lines_on_stdout(sim_station, tmp_path):
    results = tmp_path / "results.sqlite"
    toml = write_station(tmp_path, small_station_table(sim_station.root, station={"results": str(results)}))
    code, out, err = run_cli(["inspect", "--config", toml, "--gap", "g06", "--seed", "1", "--json",
                              tmp_path / "out" / "verdicts.json", "--fail-on", "fail"])
    verdicts = json.loads((tmp_path / "out" / "verdicts.json").read_text())       # its folder was created
    assert [v["gap"] for v in verdicts] == ["g06"] and "g06: width" in out
    assert code == (EXIT_VERDICT if verdicts[0]["verdict"] == "FAIL" else 0), err


def test_results_list_and_export_json_to_stdout_or_a_file(inspected, tmp_path):
    code, out, err = run_cli(["results", "list", "--db", inspected.db, "--json"])
    listed = json.loads(out)
    assert code == 0 and [r["gap"] for r in listed] == ["g02", "g14"], err
    for argv in (["--json", tmp_path / "a.json"], ["--json", "--out", tmp_path / "b.json"]):
        code, out, err = run_cli(["results", "export", "--db", inspected.db, *argv])
        assert code == 0 and out == "", err
    assert json.loads((tmp_path / "a.json").read_text()) == json.loads((tmp_path / "b.json").read_text()) == listed
    code, out, err = run_cli(["results", "export", "--db", inspected.db, "--json", "-"])
    assert code == 0 and json.loads(out) == listed
    code, _, err = run_cli(["results", "export", "--db", inspected.db, "--json", tmp_path / "c.json",
                            "--out", tmp_path / "d.json"])
    assert code == 1 and "--json FILE or --json --out FILE" in err


def test_detect_json_to_stdout_alone_or_to_a_file_beside_the_summary(tmp_path):
    code, out, err = run_cli(["detect", FRAME, "--json"])
    found = json.loads(out)
    assert code == 0 and found["count"] == 331 and len(found["pins"]) == 331, err
    code, out, err = run_cli(["detect", FRAME, "--json", tmp_path / "pins.json"])
    assert code == 0 and "331 pins in" in out
    assert json.loads((tmp_path / "pins.json").read_text()) == found


def test_json_never_replaces_an_existing_file_that_is_not_json(tmp_path, capsys):
    # --json takes an optional value: 'detect --json FRAME.png OTHER.png' must not write over the frame
    from tactip.cli import main

    frame = tmp_path / "frame.png"
    shutil.copy(FRAME, frame)
    before = frame.read_bytes()
    with pytest.raises(SystemExit) as refused:
        main(["detect", "--json", str(frame), str(FRAME)])
    assert refused.value.code == 2 and "not a .json file" in capsys.readouterr().err
    assert frame.read_bytes() == before
    (tmp_path / "old.json").write_text("{}")                     # a .json file of one's own is replaced as asked
    code, _, err = run_cli(["detect", FRAME, "--json", tmp_path / "old.json"])
    assert code == 0 and json.loads((tmp_path / "old.json").read_text())["count"] == 331, err


def test_validate_json_to_stdout_is_alone_there(sim_station):
    code, out, err = run_cli(["validate", sim_station.model, sim_station.test, "--runs", "20", "--thresholds", "0.9",
                              "--json", "-"])
    rows = json.loads(out)
    assert code == 0 and rows and {"policy", "threshold"} <= set(rows[0]), err
    assert "test:" in err                                            # the table went to standard error


def test_arm_status_json(tmp_path):
    code, out, err = run_cli(["arm", "status", "--config", SAMPLES / "arm_sim.toml", "--json"])
    status = json.loads(out)
    assert code == 0 and status["ready"] is True and status["backend"] == "sim", err
    assert set(status["pose"]) == {"x_mm", "y_mm", "z_mm", "roll_deg", "pitch_deg", "yaw_deg"}
    code, out, err = run_cli(["arm", "status", "--config", SAMPLES / "arm_sim.toml", "--json", tmp_path / "s.json"])
    assert code == 0 and "backend" in out and json.loads((tmp_path / "s.json").read_text()) == status


def test_json_into_a_fifo_is_streamed(tmp_path):
    """A FIFO named as the JSON file receives the JSON and stays a FIFO (a reader thread drains it)."""
    import threading

    fifo = tmp_path / "pins.fifo"
    os.mkfifo(fifo)
    got = []
    reader = threading.Thread(target=lambda: got.append(open(fifo).read()))
    reader.start()
    code, _, err = run_cli(["detect", FRAME, "--json", fifo])
    reader.join(timeout=60)
    assert code == 0 and json.loads(got[0])["count"] == 331, err
    assert fifo.is_fifo()


def test_quiet_and_verbose_on_every_command_and_before_it(tmp_path):
    before = run_cli(["-q", "detect", FRAME, "--json"])
    after = run_cli(["detect", FRAME, "--json", "-q"])
    assert before[0] == after[0] == 0 and json.loads(before[1]) == json.loads(after[1])
    code, _, err = run_cli(["results", "list", "-q", "--db", tmp_path / "missing.sqlite"])
    assert code == 1 and "Traceback" not in err and len(err.strip().splitlines()) == 1
    code, _, err = run_cli(["-v", "results", "list", "--db", tmp_path / "missing.sqlite"])
    assert code == 1 and "Traceback (most recent call last)" in err                # -v: the traceback too
    assert err.strip().splitlines()[-1].startswith("tactip results: error:")


def test_reproduce_json_to_stdout(tmp_path, monkeypatch):
    """The paper's rows as JSON alone on standard output (the report goes to standard error)."""
    import tactip.reproduce

    report = SimpleNamespace(text=lambda: "report text", json_rows=lambda: [{"figure": "1", "value": 0.5}], rows=[1])
    monkeypatch.setattr(tactip.reproduce, "reproduce", lambda *a, **k: report)
    code, out, err = run_cli(["reproduce", "004", "--quick", "--json", "--no-figures"])
    assert code == 0 and json.loads(out) == [{"figure": "1", "value": 0.5}] and "report text" in err
    shutil.rmtree(tmp_path, ignore_errors=True)
