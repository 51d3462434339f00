"""The SQLite results store: rows written as they happen, pass/fail, abort, export, bad files."""

import csv
import io
import json
import os
import sqlite3

import pytest

from tactip.line.results import EXPORT_FIELDS, ResultsError, ResultsStore
from tactip.line.results.sqlite import _SCHEMA


def _inspect(store, gap="g1", nominal=2.0, estimate=2.25, decided=True, tolerance=0.25):
    i = store.start_inspection(gap, nominal_width=nominal, tolerance=tolerance, policy="active",
                               decision_threshold=0.9)
    store.record_tap(i, tap=1, depth_mm=1.0, identity_estimate=estimate, belief=0.4,
                     what_belief=[0.4, 0.6], where_belief=[1.0])
    store.record_tap(i, tap=2, depth_mm=4.75, identity_estimate=estimate, belief=0.95,
                     what_belief=[0.05, 0.95], where_belief=[1.0])
    return i, store.finish_inspection(i, estimated_width=estimate, estimated_depth=4.7, belief=0.95,
                                      taps=2, decided=decided)


def test_pass_fail_and_undecided(tmp_path):
    with ResultsStore(tmp_path / "r.sqlite") as store:
        assert _inspect(store, estimate=2.25)[1] is True        # on the tolerance edge: pass
        assert _inspect(store, estimate=2.5)[1] is False
        assert _inspect(store, estimate=2.0, decided=False)[1] is None
        rows = store.inspections()
    assert [r.passed for r in rows] == [True, False, None]
    assert all(r.status == "done" and r.taps == 2 for r in rows)


def test_rows_are_on_disk_while_running(tmp_path):
    path = tmp_path / "r.sqlite"
    store = ResultsStore(path)
    i = store.start_inspection("g7", nominal_width=1.0, tolerance=0.1, policy="random")
    store.record_tap(i, tap=1, depth_mm=3.0, what_belief=[0.5, 0.5])
    # A second connection (another process, or after a crash) sees both rows already.
    other = sqlite3.connect(path)
    assert other.execute("SELECT status, taps FROM inspections").fetchall() == [("running", 1)]
    assert other.execute("SELECT COUNT(*) FROM taps").fetchone()[0] == 1
    store.close()


def test_abort_keeps_taps_and_reason(tmp_path):
    with ResultsStore(tmp_path / "r.sqlite") as store:
        i = store.start_inspection("g2", nominal_width=1.0, tolerance=0.1, policy="active")
        store.record_tap(i, tap=1, depth_mm=2.0, belief=0.3, what_belief=[0.3, 0.7])
        store.abort_inspection(i, "protective stop")
        row = store.inspections()[0]
        taps = store.taps(i)
    assert (row.status, row.reason, row.passed, row.decided) == ("aborted", "protective stop", None, False)
    assert taps[0]["what_belief"] == [0.3, 0.7] and taps[0]["depth_mm"] == 2.0


def test_export_csv_and_json_have_the_fields(tmp_path):
    with ResultsStore(tmp_path / "r.sqlite") as store:
        _inspect(store)
        text_csv, text_json = store.export_csv(), store.export_json()
    rows = list(csv.DictReader(io.StringIO(text_csv)))
    assert tuple(rows[0]) == EXPORT_FIELDS
    for key in ("gap", "nominal_width", "estimated_width", "belief", "taps", "decided", "passed", "policy", "started_at"):
        assert key in json.loads(text_json)[0]
    assert float(rows[0]["estimated_width"]) == 2.25 and rows[0]["passed"] == "True"


def test_not_a_database_is_a_clear_error(tmp_path):
    bad = tmp_path / "notes.sqlite"
    bad.write_bytes(b"this is not sqlite" * 100)
    with pytest.raises(ResultsError, match="not a tactip results database"):
        ResultsStore(bad)


# -- issue 9: foreign files untouched, read-only readers, stale rows ----------------------------------

def test_another_sqlite_database_is_refused_unchanged(tmp_path):
    path = tmp_path / "other.sqlite"
    with sqlite3.connect(path) as con:
        con.execute("CREATE TABLE invoices (id INTEGER PRIMARY KEY)")
    before = path.read_bytes()
    for read_only in (False, True):
        with pytest.raises(ResultsError, match="another SQLite database .*invoices"):
            ResultsStore(path, read_only=read_only)
    assert path.read_bytes() == before and sorted(p.name for p in tmp_path.iterdir()) == ["other.sqlite"]
    (tmp_path / "notes.txt").write_text("not a database")
    with pytest.raises(ResultsError, match="not an SQLite file"):
        ResultsStore(tmp_path / "notes.txt")


def test_a_foreign_database_with_tables_named_as_ours_is_refused_unchanged(tmp_path):
    """Issue 22: an SQLite file with its own 'inspections' (and 'meta') tables was given columns and tables
    before it failed on 'no such column: started_at'. Table names are not enough: the columns must be ours."""
    path = tmp_path / "plant.sqlite"
    with sqlite3.connect(path) as con:
        con.execute("CREATE TABLE inspections (id INTEGER PRIMARY KEY, part TEXT, verdict TEXT)")
        con.execute("CREATE TABLE meta (name TEXT)")
    before = path.read_bytes()
    for read_only in (False, True):
        with pytest.raises(ResultsError, match="another SQLite database .*inspections"):
            ResultsStore(path, read_only=read_only)
    assert path.read_bytes() == before and sorted(p.name for p in tmp_path.iterdir()) == ["plant.sqlite"]
    # Our own database cut short after its first table (disk full while creating it) is still ours.
    ours = tmp_path / "cut.sqlite"
    with sqlite3.connect(ours) as con:
        con.executescript(_SCHEMA.split(";")[0] + ";" + _SCHEMA.split(";")[1] + ";")
    with ResultsStore(ours) as store:
        _inspect(store)
        assert len(store.inspections()) == 1


def test_a_reader_changes_nothing(tmp_path):
    path = tmp_path / "r.sqlite"
    with ResultsStore(path) as store:
        _inspect(store)
    before = path.read_bytes()
    with ResultsStore(path, read_only=True) as store:
        assert len(store.inspections()) == 1
        with pytest.raises(ResultsError, match="read-only"):
            store.start_inspection("g1", nominal_width=1.0, tolerance=0.1, policy="active")
    assert path.read_bytes() == before


def test_stale_running_rows_of_dead_processes_are_closed(tmp_path, monkeypatch):
    with ResultsStore(tmp_path / "r.sqlite") as store:
        mine = store.start_inspection("g1", nominal_width=1.0, tolerance=0.1, policy="active", station="line-1")
        monkeypatch.setattr(os, "getpid", lambda: 2**22 + 11)        # a process that does not exist
        dead = store.start_inspection("g2", nominal_width=1.0, tolerance=0.1, policy="active", station="line-1")
        other = store.start_inspection("g3", nominal_width=1.0, tolerance=0.1, policy="active", station="line-2")
        monkeypatch.undo()
        assert store.close_stale_inspections("line-1") == [dead]
        rows = {r.id: r for r in store.inspections()}
    assert rows[dead].status == "aborted" and "stale" in rows[dead].reason
    assert rows[mine].status == "running" and rows[other].status == "running"    # alive, or another station


def test_a_database_from_before_the_station_rows_still_reads(tmp_path):
    path = tmp_path / "r.sqlite"
    with ResultsStore(path) as store:
        _inspect(store)
    with sqlite3.connect(path) as con:                          # as an earlier version left it
        con.execute("DROP TABLE stations")
    with ResultsStore(path, read_only=True) as store:
        assert store.stations() == [] and len(store.inspections()) == 1
    with ResultsStore(path) as store:                           # a writer adds the table
        store.update_station("line-1", state="ready", arm="sim: ready", frame_rate=20.0)
        assert [(s["name"], s["state"]) for s in store.stations()] == [("line-1", "ready")]
