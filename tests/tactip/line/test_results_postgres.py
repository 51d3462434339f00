"""The PostgreSQL results backend against a real server (a throwaway cluster, see `services`).

The same writes give the same rows in SQLite and PostgreSQL; several writers at once (processes,
and two simulated stations running `tactip inspect`) store every tap and verdict exactly once,
each row with its station; `tactip results` reads the shared database.
"""

from __future__ import annotations

import multiprocessing
import os
import subprocess
import sys
from collections import Counter

import pytest

from tactip.line.results import ResultsError, ResultsStore, open_results
from tests.tactip.conftest import (printed_inspections, run_cli, small_station_table, stored_inspections,
                                   write_station)


def _inspect(store, gap="g1", nominal=2.0, estimate=2.25, decided=True, station="line-1"):
    i = store.start_inspection(gap, nominal_width=nominal, tolerance=0.25, policy="active",
                               decision_threshold=0.9, station=station, model="m.h5")
    store.record_tap(i, tap=1, depth_mm=1.0, identity_estimate=estimate, location_estimate=1.5, belief=0.4,
                     what_belief=[0.4, 0.6], where_belief=[0.25, 0.75])
    store.record_tap(i, tap=2, depth_mm=4.75, identity_estimate=estimate, belief=0.95,
                     what_belief=[0.05, 0.95], where_belief=[1.0, 0.0])
    return i, store.finish_inspection(i, estimated_width=estimate, estimated_depth=4.7, belief=0.95,
                                      taps=2, decided=decided)


def _comparable(store):
    """Every stored value except times (which differ by when the test ran)."""
    rows = [{k: v for k, v in r.as_dict().items() if k not in ("started_at", "finished_at", "duration_s")}
            for r in store.inspections()]
    taps = [{k: v for k, v in t.items() if k != "at"} for r in store.inspections() for t in store.taps(r.id)]
    return rows, taps


def test_the_same_writes_give_the_same_rows_in_sqlite_and_postgresql(tmp_path, postgres_url):
    stored = {}
    for where in (tmp_path / "r.sqlite", postgres_url):
        with open_results(where) as store:
            verdicts = [_inspect(store, estimate=2.25)[1], _inspect(store, "g2", estimate=2.5)[1],
                        _inspect(store, "g3", estimate=2.0, decided=False, station="line-2")[1]]
            aborted = store.start_inspection("g4", nominal_width=1.0, tolerance=0.1, policy="random")
            store.record_tap(aborted, tap=1, depth_mm=2.0, what_belief=[0.3, 0.7])
            store.abort_inspection(aborted, "protective stop")
            assert verdicts == [True, False, None]
            store.update_station("line-1", state="ready", arm="sim: ready", frame_rate=20.0, model="m.h5")
            store.update_station("line-2", state="inspecting", arm="ur: ready", frame_rate=29.97)
            store.update_station("line-1", state="stopped: protective stop", arm="sim: protective stop",
                                 frame_rate=20.0, model="m.h5")             # one row per station, replaced
            stations = [{k: v for k, v in s.items() if k not in ("updated_at", "heartbeat_at", "host", "pid")}
                        for s in store.stations()]
            stored[str(where)] = (*_comparable(store), stations)
            assert [r.station for r in store.inspections(station="line-2")] == ["line-2"]
            assert [r.gap for r in store.inspections(limit=2)] == ["g3", "g4"]
            assert [t["tap"] for t in store.taps_after(0)] == [1, 2, 1, 2, 1, 2, 1]
    sqlite_rows, postgres_rows = stored.values()
    assert postgres_rows == sqlite_rows
    rows, taps, stations = postgres_rows
    assert stations == [dict(name="line-1", state="stopped: protective stop", arm="sim: protective stop",
                             frame_rate=20.0, model="m.h5"),
                        dict(name="line-2", state="inspecting", arm="ur: ready", frame_rate=29.97, model=None)]
    assert rows[3]["status"] == "aborted" and rows[3]["reason"] == "protective stop" and rows[3]["taps"] == 1
    assert taps[0]["what_belief"] == [0.4, 0.6] and taps[0]["location_estimate"] == 1.5


def test_a_postgresql_reader_cannot_write_and_the_password_is_never_shown(postgres_url, postgres_cluster):
    with open_results(postgres_url) as store:
        _inspect(store)
    with open_results(postgres_url, read_only=True) as reader:
        assert len(reader.inspections()) == 1
        with pytest.raises(ResultsError, match="read-only"):
            reader.start_inspection("g1", nominal_width=1.0, tolerance=0.1, policy="active")
    # An empty database holds no results yet: a reader says so and creates nothing.
    empty = postgres_cluster.create_database("empty_one")
    with pytest.raises(ResultsError, match="holds no tactip results yet"):
        open_results(empty, read_only=True)
    # Nothing listens there: one line, the URL without its password.
    with pytest.raises(ResultsError, match=r"cannot connect to the results database "
                                           r"postgresql://tactip:\*\*\*@127\.0\.0\.1:1/x") as caught:
        open_results("postgresql://tactip:s3cret@127.0.0.1:1/x", read_only=True)
    assert "s3cret" not in str(caught.value)


def test_stale_rows_are_closed_in_postgresql_too(postgres_url, monkeypatch):
    with open_results(postgres_url) as store:
        mine = store.start_inspection("g1", nominal_width=1.0, tolerance=0.1, policy="active", station="line-1")
        monkeypatch.setattr(os, "getpid", lambda: 2**22 + 11)        # a process that does not exist
        dead = store.start_inspection("g2", nominal_width=1.0, tolerance=0.1, policy="active", station="line-1")
        other = store.start_inspection("g3", nominal_width=1.0, tolerance=0.1, policy="active", station="line-2")
        monkeypatch.undo()
        assert store.close_stale_inspections("line-1") == [dead]
        rows = {r.id: r for r in store.inspections()}
    assert rows[dead].status == "aborted" and "stale" in rows[dead].reason
    assert rows[mine].status == "running" and rows[other].status == "running"


def _writer(url: str, station: str, inspections: int, taps: int, start) -> None:
    start.wait()                                      # all writers begin together
    with open_results(url) as store:
        for k in range(inspections):
            i = store.start_inspection(f"g{k}", nominal_width=1.0, tolerance=0.2, policy="active", station=station)
            for tap in range(1, taps + 1):
                store.record_tap(i, tap=tap, depth_mm=0.1 * tap, identity_estimate=1.0 + 0.001 * k,
                                 belief=tap / taps, what_belief=[tap / taps, 1 - tap / taps])
            store.finish_inspection(i, estimated_width=1.0 + 0.001 * k, estimated_depth=0.5, belief=1.0,
                                    taps=taps, decided=True)


@pytest.mark.parametrize("backend", ["postgresql", "sqlite"])
def test_concurrent_writers_store_every_tap_once(backend, postgres_url, tmp_path):
    """Four processes at once, 10 inspections x 12 taps each: all 480 taps and 40 verdicts, once each."""
    url = postgres_url if backend == "postgresql" else str(tmp_path / "line.sqlite")
    with open_results(url):                           # the schema exists before the race (as after a first run)
        pass
    ctx = multiprocessing.get_context("fork")  # nothing is connected yet in this process
    start = ctx.Event()
    writers = [ctx.Process(target=_writer, args=(url, f"cell-{n}", 10, 12, start)) for n in range(4)]
    for w in writers:
        w.start()
    start.set()
    for w in writers:
        w.join(120)
    assert [w.exitcode for w in writers] == [0, 0, 0, 0]
    with open_results(url, read_only=True) as store:
        rows = store.inspections()
        taps = store.taps_after(0, limit=10_000)
    assert Counter(r.station for r in rows) == {f"cell-{n}": 10 for n in range(4)}
    assert all(r.status == "done" and r.passed is True and r.taps == 12 for r in rows)
    keys = [(t["inspection_id"], t["tap"]) for t in taps]
    assert len(keys) == len(set(keys)) == 4 * 10 * 12                   # none lost, none duplicated
    by_inspection = Counter(t["inspection_id"] for t in taps)
    assert all(by_inspection[r.id] == 12 for r in rows)
    assert all(t["station"] == next(r.station for r in rows if r.id == t["inspection_id"]) for t in taps[:50])


# -- two simulated stations on one line --------------------------------------------------------------


def test_two_simulated_stations_inspecting_at_once_store_every_tap_and_verdict_once(
        sim_station, postgres_url, tmp_path):
    """Two `tactip inspect` processes, one database: what each printed is what is stored, once.

    (One station into SQLite, checked the same way: `test_cli_station.test_inspect_then_export_the_results`.)
    """
    results, gaps = postgres_url, ("g02", "g14")
    names = ["cell-1", "cell-2"]
    tomls = [write_station(tmp_path, small_station_table(sim_station.root, station={"name": name, "results": results}),
                           name=f"{name}.toml") for name in names]
    runs = [subprocess.Popen([sys.executable, "-m", "tactip.cli", "inspect", "--config", str(toml),
                              "--seed", str(n + 3), *(f"--gap={g}" for g in gaps)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            for n, toml in enumerate(tomls)]
    outputs = [run.communicate(timeout=240) for run in runs]
    assert [run.returncode for run in runs] == [0, 0], [err for _, err in outputs]
    with open_results(results, read_only=True) as store:
        rows = store.inspections()
        assert Counter(r.station for r in rows) == {name: len(gaps) for name in names}
        assert all(r.status == "done" for r in rows)
        for name, (out, _) in zip(names, outputs):
            printed_taps, printed_verdicts = printed_inspections(out)
            stored_taps, stored_verdicts = stored_inspections(store, name)
            assert set(printed_verdicts) == set(gaps) and len(printed_taps) >= len(gaps)
            assert stored_taps == printed_taps                       # every tap, once, with its values
            assert stored_verdicts == printed_verdicts
        assert [(s["name"], s["state"], s["arm"], s["frame_rate"], s["model"]) for s in store.stations()] == \
            [(name, "stopped", "sim: ready", sim_station.config.sensor.frame_rate, str(sim_station.model))
             for name in names]
    # tactip results reads the shared database, all of it or one station's rows
    code, out, err = run_cli(["results", "list", "--db", results, "--station", "cell-2"])
    assert code == 0, err
    assert out.count("cell-2") == len(gaps) and "cell-1" not in out
    code, out, err = run_cli(["results", "list", "--config", tomls[0]])
    assert code == 0 and out.count("cell-1") == out.count("cell-2") == len(gaps)


def test_sqlite_stays_the_default_and_refuses_other_urls(tmp_path):
    import tomllib

    from tactip.station.config import SIM_PRESET, ConfigError, parse_station_config

    table = tomllib.loads(SIM_PRESET.read_text())
    del table["station"]["results"], table["station"]["data_dir"]
    assert parse_station_config(table, base_dir=tmp_path).results == tmp_path / "station_data" / "results.sqlite"
    table["station"]["results"] = "postgresql://u@db.plant:5432/line"
    assert parse_station_config(table, base_dir=tmp_path).results == "postgresql://u@db.plant:5432/line"
    table["station"]["results"] = "mysql://u@db/line"
    with pytest.raises(ConfigError, match="station.results must be a file path or a postgresql:// URL"):
        parse_station_config(table, base_dir=tmp_path)
    assert isinstance(open_results(tmp_path / "r.sqlite"), ResultsStore)


def test_a_postgresql_database_from_before_heartbeats_is_read_and_gains_the_column(postgres_url):
    import psycopg

    with open_results(postgres_url) as store:
        store.update_station("line-1", state="ready")
    with psycopg.connect(postgres_url, autocommit=True) as db:                    # as an older version made it
        db.execute("ALTER TABLE tactip.stations DROP COLUMN heartbeat_at")
    with open_results(postgres_url, read_only=True) as reader:                    # read as is, not changed
        (old,) = reader.stations()
    assert old["heartbeat_at"] == old["updated_at"]
    with open_results(postgres_url) as store:                                     # the next writer adds it
        store.heartbeat("line-1")
        (row,) = store.stations()
    assert row["heartbeat_at"] > old["updated_at"] and row["updated_at"] == old["updated_at"]


def test_a_foreign_tactip_schema_is_refused_before_anything_is_written(postgres_url):
    import psycopg

    with psycopg.connect(postgres_url, autocommit=True) as db:                    # someone else's 'tactip' schema
        db.execute("CREATE SCHEMA tactip")
        db.execute("CREATE TABLE tactip.inspections (id INT PRIMARY KEY, owner TEXT)")
        db.execute("CREATE TABLE tactip.meta (key TEXT PRIMARY KEY, value TEXT)")
        db.execute("INSERT INTO tactip.inspections VALUES (1, 'them')")

    def schema():
        with psycopg.connect(postgres_url, autocommit=True) as db:
            columns = db.execute("SELECT table_name, column_name FROM information_schema.columns "
                                 "WHERE table_schema = 'tactip' ORDER BY 1, 2").fetchall()
            return columns, db.execute("SELECT * FROM tactip.inspections").fetchall(), \
                db.execute("SELECT * FROM tactip.meta").fetchall()

    before = schema()
    with pytest.raises(ResultsError, match="other tables .*inspections.*left unchanged"):
        open_results(postgres_url)
    assert schema() == before                                                     # no table, column or row added
    code, _, err = run_cli(["results", "list", "--db", postgres_url])
    assert code == 1 and ("left unchanged" in err or "no tactip results" in err), err   # a reader: refused too
