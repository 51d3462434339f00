"""The dashboard without a browser: capability figures, trends, the live feed, the app's routes and guard.

The browser end to end (a simulated inspection watched in headless Chromium) is in
`test_dashboard_browser.py`.
"""

from __future__ import annotations

import json
import threading
import time
import urllib.error
import urllib.request

import numpy as np
import pytest

from tactip.line.dashboard import DashboardError, DashboardServer, check_bind, gap_trends, make_app
from tactip.line.dashboard.feed import FeedState
from tactip.line.results import open_results, process_capability
from tests.tactip.conftest import run_cli

pytest.importorskip("starlette", reason="the dashboard needs the 'line' extra (pip install -e '.[test]')")


class Client:
    """GET (or another method) against a running `DashboardServer`: (status, body text)."""

    def __init__(self, server):
        self.url = server.url.rstrip("/")

    def get(self, path, params=None, headers=None, method="GET"):
        from urllib.error import HTTPError
        from urllib.parse import urlencode

        query = f"?{urlencode(params)}" if params else ""
        request = urllib.request.Request(self.url + path + query, headers=headers or {}, method=method)
        try:
            with urllib.request.urlopen(request, timeout=20) as response:
                return response.status, response.read().decode()
        except HTTPError as exc:
            return exc.code, exc.read().decode()


TOKEN = "s3cret-0123456789abcdef"


def _verdict(store, gap, width, *, nominal=1.0, tolerance=0.2, decided=True, station="cell-1"):
    i = store.start_inspection(gap, nominal_width=nominal, tolerance=tolerance, policy="active", station=station)
    store.record_tap(i, tap=1, depth_mm=2.0, identity_estimate=width, belief=0.9, what_belief=[0.1, 0.9])
    store.finish_inspection(i, estimated_width=width, estimated_depth=2.0, belief=0.9, taps=1, decided=decided)
    return i


def test_capability_matches_the_definition():
    rng = np.random.default_rng(4)
    widths = rng.normal(1.05, 0.04, size=40)
    c = process_capability(widths, nominal_mm=1.0, tolerance_mm=0.2)
    mu, sigma = widths.mean(), widths.std(ddof=1)
    assert c.n == 40 and c.mean_mm == pytest.approx(mu) and c.sigma_mm == pytest.approx(sigma)
    assert c.cp == pytest.approx(0.4 / (6 * sigma))                              # (USL - LSL) / 6 sigma
    assert c.cpk == pytest.approx((1.2 - mu) / (3 * sigma))                      # the nearer limit is USL
    centred = process_capability(widths - widths.mean() + 1.0, nominal_mm=1.0, tolerance_mm=0.2)
    assert centred.cpk == pytest.approx(centred.cp)                              # centred: Cpk = Cp
    assert process_capability([1.1], nominal_mm=1.0, tolerance_mm=0.2).cp is None
    assert process_capability([1.1, 1.1], nominal_mm=1.0, tolerance_mm=0.2).cpk is None    # no spread
    assert process_capability([], nominal_mm=1.0, tolerance_mm=0.2).n == 0
    with pytest.raises(ValueError, match="tolerance_mm must be > 0"):
        process_capability([1.0, 1.1], nominal_mm=1.0, tolerance_mm=0)


def test_trends_use_the_newest_decided_inspections_of_each_gap(tmp_path):
    with open_results(tmp_path / "r.sqlite") as store:
        widths = [0.95, 1.0, 1.02, 1.1, 0.98, 1.05]
        for w in widths:
            _verdict(store, "door", w)
        _verdict(store, "door", 3.0, decided=False)                # undecided: not a measurement
        aborted = store.start_inspection("door", nominal_width=1.0, tolerance=0.2, policy="active")
        store.abort_inspection(aborted, "protective stop")
        _verdict(store, "hood", 2.1, nominal=2.0, tolerance=0.3)
        rows = store.inspections()
    door, hood = gap_trends(rows, window=4)
    assert door["gap"] == "door" and [p["estimated_width"] for p in door["points"]] == widths[-4:]
    expected = process_capability(widths[-4:], nominal_mm=1.0, tolerance_mm=0.2)
    assert door["capability"] == dict(expected.as_dict(), warning="n = 4 < 25: too few inspections to judge capability")
    assert (hood["nominal_mm"], hood["tolerance_mm"], hood["capability"]["n"]) == (2.0, 0.3, 1)


def test_capability_per_gap_and_station_sorted_by_gap_with_a_warning_below_25(tmp_path):
    rng = np.random.default_rng(7)
    with open_results(tmp_path / "r.sqlite") as store:
        widths = {("g20", "cell-1"): rng.normal(1.0, 0.05, 30), ("g05", "cell-1"): rng.normal(1.0, 0.05, 3),
                  ("g05", "cell-2"): rng.normal(1.1, 0.05, 3), ("g5b", "cell-1"): rng.normal(1.0, 0.05, 2)}
        for (gap, station), ws in widths.items():
            for w in ws:
                _verdict(store, gap, float(w), station=station)
        rows = store.inspections()
    trends = gap_trends(rows, window=50)
    assert [g["gap"] for g in trends] == ["g05", "g5b", "g20"]                      # natural order, not text
    g20, g05 = trends[2], trends[0]
    assert g20["capability"]["n"] == 30 and g20["capability"]["warning"] is None
    assert g05["capability"]["n"] == 6 and "n = 6 < 25" in g05["capability"]["warning"]
    assert [s["station"] for s in g05["by_station"]] == ["cell-1", "cell-2"]
    own = process_capability(widths[("g05", "cell-2")], nominal_mm=1.0, tolerance_mm=0.2)
    assert g05["by_station"][1]["capability"]["cpk"] == pytest.approx(own.cpk)


def test_a_working_station_without_heartbeat_is_offline_and_alarms_clear_when_it_is_back(tmp_path):
    import datetime as dt

    from tactip.line.dashboard import station_status

    with open_results(tmp_path / "r.sqlite") as store:
        store.update_station("cell-1", state="ready", arm="sim: ready")
        killed = store.start_inspection("g01", nominal_width=1.0, tolerance=0.2, policy="active", station="cell-1")
        store.heartbeat("cell-1")
        store.update_station("cell-2", state="stopped", arm="sim: ready")        # stopped: silence is fine
        store.update_station("cell-3", state="stopped: ArmError: protective stop", arm="ur: protective stop")
        aborted = store.start_inspection("g02", nominal_width=1.0, tolerance=0.2, policy="active", station="cell-3")
        store.abort_inspection(aborted, "ArmError: protective stop")
        rows, beats = store.inspections(), store.stations()
    beat = dt.datetime.fromisoformat(next(b for b in beats if b["name"] == "cell-1")["heartbeat_at"])
    soon, later = (station_status(rows, heartbeats=beats, now=beat + dt.timedelta(seconds=s), offline_after_s=10)
                   for s in (9, 11))
    assert [s["offline"] for s in soon] == [False, False, False] and soon[0]["alarms"] == []
    assert [s["offline"] for s in later] == [True, False, False]
    assert later[0]["alarms"] == ["offline: no heartbeat for 11 s"] and later[0]["state"] == "inspecting"
    assert later[2]["alarms"] == ["stopped: ArmError: protective stop",
                                  f"inspection {aborted} (g02) aborted: ArmError: protective stop"]
    with open_results(tmp_path / "r.sqlite") as store:                           # both are back
        store.abort_inspection(killed, "stale: process ended without closing the inspection (killed?)")
        store.update_station("cell-1", state="ready", arm="sim: ready")
        store.start_inspection("g01", nominal_width=1.0, tolerance=0.2, policy="active", station="cell-1")
        store.update_station("cell-3", state="inspecting", arm="ur: ready")
        store.start_inspection("g02", nominal_width=1.0, tolerance=0.2, policy="active", station="cell-3")
        rows, beats = store.inspections(), store.stations()
    back = station_status(rows, heartbeats=beats, offline_after_s=10)
    assert [s["alarms"] for s in back] == [[], [], []] and [s["offline"] for s in back] == [False] * 3


def test_heartbeats_come_from_an_inspecting_station_and_old_databases_gain_the_column(tmp_path):
    import sqlite3
    import time

    from tactip.station.heartbeat import Heartbeat

    db = tmp_path / "old.sqlite"
    with open_results(db) as store:
        store.update_station("cell-1", state="ready")
    with sqlite3.connect(db) as con:                                              # a database from before heartbeats
        con.execute("ALTER TABLE stations DROP COLUMN heartbeat_at")
    with open_results(db, read_only=True) as reader:                              # read as is, not changed
        (old,) = reader.stations()
    assert old["heartbeat_at"] == old["updated_at"]
    with open_results(db) as store:                                               # a writer adds the column
        first = store.stations()[0]["heartbeat_at"]
    with Heartbeat(lambda: open_results(db), "cell-1", period_s=0.05) as beating:
        deadline = time.monotonic() + 20
        while beating.beats < 3 and time.monotonic() < deadline:
            time.sleep(0.02)
    with open_results(db, read_only=True) as reader:
        (row,) = reader.stations()
    assert beating.beats >= 3 and row["heartbeat_at"] > first and row["updated_at"] == old["updated_at"]


def test_the_feed_misses_no_tap_committed_out_of_id_order(postgres_url):
    """Two stations' transactions: the later id commits first; the feed still delivers both, once each."""
    import psycopg

    with open_results(postgres_url) as store:
        i = store.start_inspection("g1", nominal_width=1.0, tolerance=0.1, policy="active", station="cell-1")
    reader = open_results(postgres_url, read_only=True)
    feed = FeedState(reader)
    insert = ("INSERT INTO tactip.taps (inspection_id, tap, depth_mm, at) VALUES (%s, %s, 1.0, 'now') RETURNING id")
    with psycopg.connect(postgres_url) as slow, psycopg.connect(postgres_url, autocommit=True) as fast:
        early = slow.execute(insert, (i, 1)).fetchone()[0]            # takes its id, not committed yet
        late = fast.execute(insert, (i, 2)).fetchone()[0]             # a later id, committed at once
        assert late > early
        first = [data["id"] for kind, data in feed.poll(reader) if kind == "tap"]
        slow.commit()
    second = [data["id"] for kind, data in feed.poll(reader) if kind == "tap"]
    third = [data["id"] for kind, data in feed.poll(reader) if kind == "tap"]
    reader.close()
    assert (first, second, third) == ([late], [early], [])


_WRITER = """
import sys
from tactip.line.results import open_results
with open_results(sys.argv[1]) as store:
    i = store.start_inspection(sys.argv[2], nominal_width=1.0, tolerance=0.2, policy="active", station="cell-1")
    for k in (1, 2):
        store.record_tap(i, tap=k, depth_mm=2.0, identity_estimate=1.0, belief=0.5 * k)
    store.finish_inspection(i, estimated_width=1.0, estimated_depth=2.0, belief=0.99, taps=2, decided=True)
"""


def test_the_feed_follows_station_runs_in_separate_processes_on_sqlite(tmp_path):
    """Each writer process exits (SQLite deletes the -wal and -shm): the feed still sees every run, stays live."""
    import asyncio
    import os
    import subprocess
    import sys

    from tactip.line.dashboard import LiveFeed

    db = tmp_path / "r.sqlite"
    with open_results(db) as store:
        _verdict(store, "g00", 1.0)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))

    async def watch():
        feed = LiveFeed(lambda: open_results(db, read_only=True), poll_s=0.02)
        queue = feed.subscribe()
        feed.start()
        seen, statuses = [], []
        try:
            for gap in ("g01", "g02", "g03"):
                await asyncio.to_thread(subprocess.run, [sys.executable, "-c", _WRITER, str(db), gap], check=True,
                                        env=env)
                deadline = asyncio.get_running_loop().time() + 20
                while not any(d.get("gap") == gap and d.get("status") == "done" for k, d in seen if k == "inspection"):
                    kind, data = await asyncio.wait_for(queue.get(), deadline - asyncio.get_running_loop().time())
                    (statuses if kind == "status" else seen).append((kind, data) if kind != "status" else data["feed"])
        finally:
            feed.stop()
        return seen, statuses, feed.status

    seen, statuses, status = asyncio.run(watch())
    done = [d["gap"] for k, d in seen if k == "inspection" and d["status"] == "done"]
    assert done == ["g01", "g02", "g03"]
    for gap in done:                                                      # both taps, each before the verdict
        mine = [(k, d.get("tap")) for k, d in seen if d.get("gap") == gap and (k == "tap" or d["status"] == "done")]
        assert mine == [("tap", 1), ("tap", 2), ("inspection", None)]
    assert status == "live" and all(s == "live" for s in statuses)


def test_a_kept_reader_stays_right_while_stores_open_and_close_beside_it(tmp_path):
    """Opening a store in the process used to read the file's header with open(); its close dropped the kept
    reader's locks, the next writer to exit deleted the -wal and -shm under it, and it read stale rows."""
    import os
    import subprocess
    import sys

    db = tmp_path / "r.sqlite"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    subprocess.run([sys.executable, "-c", _WRITER, str(db), "g00"], check=True, env=env)
    with open_results(db, read_only=True) as kept:
        for k in range(1, 4):
            subprocess.run([sys.executable, "-c", _WRITER, str(db), f"g0{k}"], check=True, env=env)
            with open_results(db, read_only=True) as fresh:
                assert len(fresh.inspections()) == k + 1
            assert [r.gap for r in kept.inspections()] == [f"g0{j}" for j in range(k + 1)]


def test_the_feed_sends_a_deciding_tap_before_the_next_inspection(tmp_path):
    """One poll catching an inspection's last tap, its verdict and the next inspection's start sends them in
    that order (it used to send the next 'running' first, and the page dropped the last tap as late)."""
    db = tmp_path / "r.sqlite"
    with open_results(db) as store:
        first = store.start_inspection("g05", nominal_width=1.0, tolerance=0.2, policy="active", station="cell-1")
        store.record_tap(first, tap=1, depth_mm=2.0, identity_estimate=1.0, belief=0.4)
        with open_results(db, read_only=True) as reader:
            feed = FeedState(reader)
        store.record_tap(first, tap=2, depth_mm=2.0, identity_estimate=1.0, belief=0.99)
        store.finish_inspection(first, estimated_width=1.0, estimated_depth=2.0, belief=0.99, taps=2, decided=True)
        second = store.start_inspection("g06", nominal_width=1.0, tolerance=0.2, policy="active", station="cell-1")
        store.record_tap(second, tap=1, depth_mm=2.0, identity_estimate=1.1, belief=0.3)
    with open_results(db, read_only=True) as reader:
        events = [(k, d.get("inspection_id", d.get("id")), d.get("tap", d.get("status"))) for k, d in feed.poll(reader)]
    assert events == [("tap", first, 2), ("inspection", first, "done"), ("inspection", second, "running"),
                      ("tap", second, 1)]


def test_the_state_shows_the_history_with_the_station_stopped(tmp_path):
    db = tmp_path / "r.sqlite"
    with open_results(db) as store:
        for w in (1.0, 1.1, 0.9):
            _verdict(store, "door", w)
        running = store.start_inspection("hood", nominal_width=2.0, tolerance=0.2, policy="active", station="cell-2")
        store.record_tap(running, tap=1, depth_mm=3.0, identity_estimate=2.1, belief=0.4, what_belief=[0.4, 0.6])
        store.update_station("cell-2", state="inspecting", arm="ur: ready", frame_rate=29.97, model="m.h5")
        store.update_station("cell-3", state="stopped: protective stop", arm="ur: protective stop")
    app = make_app(lambda: open_results(db, read_only=True), results_name=str(db))
    with DashboardServer(app, port=0) as server:
        client = Client(server)
        page = client.get("/")
        state = json.loads(client.get("/api/state", params={"window": 2})[1])
        assert client.get("/api/state", params={"window": 1})[0] == 400
        assert client.get("/api/state", method="POST")[0] == 405                # read-only: GET only
    assert page[0] == 200 and "EventSource" in page[1]
    assert [v["estimated_width"] for v in state["verdicts"]] == [0.9, 1.1, 1.0]   # newest first, no running row
    assert [(s["name"], s["state"], s["gap"], s["arm"], s["frame_rate"]) for s in state["stations"]] == [
        ("cell-1", "idle", None, None, None), ("cell-2", "inspecting", "hood", "ur: ready", 29.97),
        ("cell-3", "idle", None, "ur: protective stop", None)]                 # a status row, no inspections yet
    assert state["stations"][2]["station_state"] == "stopped: protective stop"
    cell2 = next(c for c in state["current"] if c["station"] == "cell-2")
    assert cell2["tap_rows"][0]["what_belief"] == [0.4, 0.6] and state["results"] == str(db)
    capability = dict(state["gaps"][0]["capability"])
    assert capability.pop("warning").startswith("n = 2 < 25")
    assert capability == process_capability([1.1, 0.9], nominal_mm=1.0, tolerance_mm=0.2).as_dict()


def test_no_database_yet_is_said_on_the_page(tmp_path):
    app = make_app(lambda: open_results(tmp_path / "none.sqlite", read_only=True))
    with DashboardServer(app, port=0) as server:
        state = json.loads(Client(server).get("/api/state")[1])
    assert "no results database" in state["error"] and state["verdicts"] == []
    assert not (tmp_path / "none.sqlite").exists()


def test_a_token_guards_every_route(tmp_path):
    app = make_app(lambda: open_results(tmp_path / "r.sqlite", read_only=True), token=TOKEN)
    with DashboardServer(app, port=0) as server:
        client = Client(server)
        for path in ("/", "/api/state", "/api/events", "/healthz"):
            assert client.get(path)[0] == 401
            assert client.get(path, params={"token": "wrong"})[0] == 401
            if path != "/api/events":                                       # a stream does not end by itself
                assert client.get(path, params={"token": TOKEN})[0] == 200
                assert client.get(path, headers={"Authorization": f"Bearer {TOKEN}"})[0] == 200
    check_bind("127.0.0.1", None), check_bind("localhost", None), check_bind("::1", None)
    check_bind("0.0.0.0", TOKEN)
    with pytest.raises(DashboardError, match="--host 0.0.0.0 is reachable from other machines: give --token"):
        check_bind("0.0.0.0", None)
    code, _, err = run_cli(["serve", "--db", tmp_path / "r.sqlite", "--host", "192.168.1.5"])
    assert code == 1 and err.count("\n") == 1 and "give --token" in err
    with pytest.raises(DashboardError, match="at least 16 characters, got 1"):
        check_bind("0.0.0.0", "x")
    with pytest.raises(ValueError, match="at least 16 characters"):
        make_app(lambda: None, token="short-token")
    code, _, err = run_cli(["serve", "--db", tmp_path / "r.sqlite", "--token", "x"])
    assert code == 1 and err.count("\n") == 1 and "at least 16 characters" in err


def test_a_wrong_host_header_is_refused(tmp_path):
    """DNS rebinding: a page of evil.example resolving its name to 127.0.0.1 sends Host: evil.example."""
    db = tmp_path / "r.sqlite"
    with open_results(db) as store:
        _verdict(store, "door", 1.0)
    with DashboardServer(make_app(lambda: open_results(db, read_only=True)), port=0) as server:
        client = Client(server)
        for host in (f"127.0.0.1:{server.port}", f"localhost:{server.port}", "localhost"):
            assert client.get("/api/state", headers={"Host": host})[0] == 200
        for host in ("evil.example.com", f"evil.example.com:{server.port}", "127.0.0.1.evil.example", "10.0.0.1"):
            code, text = client.get("/api/state", headers={"Host": host})
            assert code == 421 and "--allow-host" in text and "door" not in text
    with DashboardServer(make_app(lambda: open_results(db, read_only=True)), port=0,
                         allow_hosts=["station3.plant"]) as server:
        assert Client(server).get("/healthz", headers={"Host": "Station3.plant:80"})[0] == 200
        assert Client(server).get("/healthz", headers={"Host": "evil.example.com"})[0] == 421


def test_a_connection_that_sends_no_request_is_closed(tmp_path):
    import socket

    app = make_app(lambda: open_results(tmp_path / "r.sqlite", read_only=True))
    with DashboardServer(app, port=0, header_timeout_s=0.3) as server:
        with socket.create_connection(("127.0.0.1", server.port), timeout=20) as idle, \
                socket.create_connection(("127.0.0.1", server.port), timeout=20) as slow:
            slow.sendall(b"GET /healthz HTTP/1.1\r\nHost: 127.0.0.1\r\n")      # never finishes its head
            assert idle.recv(100) == b"" and slow.recv(100) == b""             # closed by the server, in time
        assert Client(server).get("/healthz")[0] == 200


def test_a_flood_of_half_open_connections_starves_no_client(tmp_path):
    """400 half-open connections to a server limited to 256 open files: a request with the token is still
    answered within 2 s, and the console gets no 'Too many open files'."""
    from tests.tactip.line.flood import served_under_a_half_open_flood

    db = tmp_path / "r.sqlite"
    with open_results(db) as store:
        _verdict(store, "door", 1.0)
    with served_under_a_half_open_flood(db, TOKEN) as url:
        request = urllib.request.Request(url + "api/state", headers={"Authorization": f"Bearer {TOKEN}"})
        with urllib.request.urlopen(request, timeout=2) as response:          # the bar: within 2 s
            assert response.status == 200 and json.loads(response.read())["verdicts"][0]["gap"] == "door"


def test_taps_and_verdicts_stream_as_server_sent_events(tmp_path):
    db = tmp_path / "r.sqlite"
    with open_results(db) as store:
        _verdict(store, "hood", 2.0)                                 # history: not streamed again
    events = []

    def listen(url):
        with urllib.request.urlopen(url + "api/events", timeout=20) as stream:
            name = None
            for line in stream:
                line = line.decode().rstrip("\n")
                if line.startswith("event: "):
                    name = line[7:]
                elif line.startswith("data: "):
                    events.append((name, json.loads(line[6:])))
                    kinds = [k for k, data in events]
                    if "tap" in kinds and any(k == "inspection" and data["status"] == "done" for k, data in events):
                        return

    app = make_app(lambda: open_results(db, read_only=True))
    with DashboardServer(app, port=0) as server:
        listener = threading.Thread(target=listen, args=(server.url,), daemon=True)
        listener.start()
        while not events:                                           # the stream said hello
            time.sleep(0.02)
        with open_results(db) as store:
            store.update_station("cell-1", state="ready", arm="sim: ready", frame_rate=20.0)
            i = _verdict(store, "door", 1.05)
        listener.join(20)
    # The feed's own status ("starting" -> "live" when its first poll ends after the page subscribed, as on a busy
    # machine) may come between: it is not what the store streamed.
    assert all(data["live"] for name, data in events if name == "status"), events
    events = [(name, data) for name, data in events if name != "status"]
    kinds = [name for name, _ in events]
    assert kinds[:2] == ["hello", "station"] and kinds.count("tap") == 1
    assert kinds.index("tap") < len(kinds) - 1 and kinds[-1] == "inspection"     # the tap before the verdict
    assert events[1][1]["arm"] == "sim: ready" and events[1][1]["state"] == "ready"
    tap = events[kinds.index("tap")][1]
    assert (tap["inspection_id"], tap["tap"], tap["gap"], tap["station"], tap["what_belief"]) == \
        (i, 1, "door", "cell-1", [0.1, 0.9])
    last = [data for name, data in events if name == "inspection"][-1]
    assert (last["id"], last["status"], last["passed"]) == (i, "done", True)


def test_serve_help_names_the_guard(capsys):
    from tactip.cli import main

    with pytest.raises(SystemExit) as done:
        main(["serve", "--help"])
    text = capsys.readouterr().out
    assert done.value.code == 0 and "--token" in text and "127.0.0.1" in text and "read-only" in text


@pytest.mark.parametrize("sigint", ["default", "ignored"])
def test_tactip_serve_serves_until_ctrl_c_even_with_a_page_listening(tmp_path, sigint):
    # "ignored": started as a background job by a script (SIGINT ignored from the start), where
    # uvicorn's re-raised SIGINT does nothing: still "Stopped." and exit 130.
    import signal
    import subprocess
    import sys

    db = tmp_path / "r.sqlite"
    with open_results(db) as store:
        _verdict(store, "door", 1.05)
    start = signal.SIG_IGN if sigint == "ignored" else signal.SIG_DFL
    serve = subprocess.Popen([sys.executable, "-m", "tactip.cli", "serve", "--db", str(db), "--port", "0"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             preexec_fn=lambda: signal.signal(signal.SIGINT, start))
    try:
        first = serve.stdout.readline()                              # "dashboard of DB on http://127.0.0.1:PORT/ ..."
        assert first.startswith(f"dashboard of {db} on http://127.0.0.1:"), first + serve.stderr.read()
        url = first.split(" on ")[1].split()[0]
        state = json.loads(urllib.request.urlopen(url + "api/state", timeout=20).read())
        assert [v["gap"] for v in state["verdicts"]] == ["door"]
        stream = urllib.request.urlopen(url + "api/events", timeout=20)  # an open event stream...
        assert stream.readline().startswith(b"event: hello")
        serve.send_signal(signal.SIGINT)                             # ...does not hold Ctrl-C up
        out, err = serve.communicate(timeout=20)
        stream.close()
    finally:
        if serve.poll() is None:
            serve.kill()
    assert serve.returncode == 130 and err == "Stopped.\n"




def test_token_without_a_value_is_generated_and_printed(tmp_path):
    import subprocess
    import sys

    db = tmp_path / "r.sqlite"
    with open_results(db) as store:
        _verdict(store, "door", 1.0)
    serve = subprocess.Popen([sys.executable, "-m", "tactip.cli", "serve", "--db", str(db), "--port", "0", "--token"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        address, said = serve.stdout.readline(), serve.stdout.readline()
        token = said.split()[1]
        assert said.startswith("token: ") and len(token) >= 16 and f"?token={token}" in address
        url = address.split(" on ")[1].split("?")[0]
        with urllib.request.urlopen(f"{url}healthz?token={token}", timeout=20) as response:
            assert response.status == 200
        with pytest.raises(urllib.error.HTTPError, match="401"):
            urllib.request.urlopen(f"{url}healthz", timeout=20)
    finally:
        serve.terminate()
        serve.communicate(timeout=20)


def test_the_feed_reconnects_when_postgresql_drops_it(postgres_url):
    """A restarted or failed-over server drops the feed's connection: it reconnects within the same poll,
    stays live, and misses nothing written meanwhile."""
    import asyncio

    import psycopg

    from tactip.line.dashboard import LiveFeed

    with open_results(postgres_url) as store:
        _verdict(store, "g01", 1.0)

    async def watch():
        feed = LiveFeed(lambda: open_results(postgres_url, read_only=True), poll_s=0.02)
        queue = feed.subscribe()
        feed.start()
        seen = []
        try:
            loop = asyncio.get_running_loop()
            deadline = loop.time() + 20
            while feed.status != "live" and loop.time() < deadline:
                await asyncio.sleep(0.02)
            with psycopg.connect(postgres_url, autocommit=True) as admin:   # drop every reader connection
                admin.execute("SELECT pg_terminate_backend(pid) FROM pg_stat_activity WHERE pid <> pg_backend_pid() "
                              "AND datname = current_database()")
            with open_results(postgres_url) as store:
                _verdict(store, "g02", 1.1)
            while not any(k == "inspection" and d["gap"] == "g02" and d["status"] == "done" for k, d in seen):
                seen.append(await asyncio.wait_for(queue.get(), deadline - loop.time()))
        finally:
            feed.stop()
        return seen, feed.status

    seen, status = asyncio.run(watch())
    assert [d["tap"] for k, d in seen if k == "tap" and d["gap"] == "g02"] == [1]
    assert status == "live" and all(d["feed"] == "live" for k, d in seen if k == "status")   # never not live
