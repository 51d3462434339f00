"""The line's figures: taps written per second into each backend, and the dashboard's tap-to-feed delay.

1. Store throughput: W writer processes (stations) each record I inspections of T taps at once
   into one database, SQLite and PostgreSQL (a throwaway cluster, as the tests make one); taps/s
   and a check that every tap is stored once.
2. Live delay: a dashboard server (`tactip serve`'s app) on the same database, one reader of its
   event stream; for each tap, the time from its storing (the tap's ``at``) to its event reaching
   the reader. The browser adds its own draw time (the browser test measures the whole path:
   ``out/test-artefacts/dashboard/latency.json``). The issue's bar is 0.5 s.

    python bench/bench_dashboard.py [--writers W] [--inspections I] [--taps T]
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import multiprocessing
import sys
import tempfile
import threading
import time
import urllib.request
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.tactip.services: the throwaway cluster


def _writer(url, station, inspections, taps, start, pause_s):
    from tactip.line.results import open_results

    start.wait()
    with open_results(url) as store:
        for k in range(inspections):
            i = store.start_inspection(f"g{k % 4}", nominal_width=1.0, tolerance=0.2, policy="active", station=station)
            for tap in range(1, taps + 1):
                store.record_tap(i, tap=tap, depth_mm=1.0, identity_estimate=1.0, belief=tap / taps,
                                 what_belief=[0.05] * 20)
                if pause_s:
                    time.sleep(pause_s)
            store.finish_inspection(i, estimated_width=1.0, estimated_depth=1.0, belief=1.0, taps=taps, decided=True)


def run_writers(url, writers, inspections, taps, *, pause_s=0.0) -> float:
    """Run the writer processes at once; returns the wall time, s."""
    ctx = multiprocessing.get_context("fork")
    start = ctx.Event()
    procs = [ctx.Process(target=_writer, args=(url, f"cell-{n}", inspections, taps, start, pause_s))
             for n in range(writers)]
    for p in procs:
        p.start()
    t0 = time.perf_counter()
    start.set()
    for p in procs:
        p.join()
    assert all(p.exitcode == 0 for p in procs)
    return time.perf_counter() - t0


def feed_delays(url, writers, inspections, taps) -> list[float]:
    """Stored-to-event delay of every tap (s), through a dashboard server and its event stream."""
    from tactip.line.dashboard import DashboardServer, make_app
    from tactip.line.results import open_results

    delays, total = [], writers * inspections * taps
    ready = threading.Event()

    def listen(base):
        with urllib.request.urlopen(base + "api/events", timeout=60) as stream:
            name = None
            for line in stream:
                now = time.time()
                line = line.decode().rstrip("\n")
                if line.startswith("event: "):
                    name = line[7:]
                    ready.set()
                elif line.startswith("data: ") and name == "tap":
                    at = dt.datetime.fromisoformat(json.loads(line[6:])["at"]).timestamp()
                    delays.append(now - at)
                    if len(delays) == total:
                        return

    with open_results(url):
        pass
    app = make_app(lambda: open_results(url, read_only=True))
    with DashboardServer(app, port=0) as server:
        reader = threading.Thread(target=listen, args=(server.url,), daemon=True)
        reader.start()
        ready.wait(10)
        run_writers(url, writers, inspections, taps, pause_s=0.02)     # about a station's tap rate, and more
        reader.join(30)
    return delays


def main() -> None:
    """Run the benchmark and print its figures."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--writers", type=int, default=2, help="stations writing at once")
    parser.add_argument("--inspections", type=int, default=20, help="inspections per station")
    parser.add_argument("--taps", type=int, default=10, help="taps per inspection")
    args = parser.parse_args()
    from tactip.line.results import open_results
    from tests.tactip.services import PostgresCluster, find_postgres_bin

    backends = {}
    folder = Path(tempfile.mkdtemp(prefix="bench-dashboard-"))
    backends["sqlite"] = lambda name: str(folder / f"{name}.sqlite")
    cluster = None
    bin_dir = find_postgres_bin()
    if bin_dir is not None:
        cluster = PostgresCluster(bin_dir)
        backends["postgresql"] = cluster.create_database
    else:
        print("PostgreSQL is not installed: only SQLite (make services installs it)")
    try:
        total = args.writers * args.inspections * args.taps
        print(f"{args.writers} stations x {args.inspections} inspections x {args.taps} taps = {total} taps")
        for name, make in backends.items():
            url = make("throughput")
            with open_results(url):
                pass
            wall = run_writers(url, args.writers, args.inspections, args.taps)
            with open_results(url, read_only=True) as store:
                stored = store.taps_after(0, limit=10 * total)
            keys = {(t["inspection_id"], t["tap"]) for t in stored}
            print(f"{name:>10}: {total / wall:7.0f} taps/s stored ({wall:.2f} s); {len(stored)} stored, "
                  f"{len(keys)} distinct (expected {total})")
            delays = np.array(feed_delays(make("feed"), args.writers, args.inspections, args.taps)) * 1000
            print(f"{'':>10}  stored -> dashboard event: median {np.median(delays):.0f} ms, "
                  f"95% {np.percentile(delays, 95):.0f} ms, max {delays.max():.0f} ms over {delays.size} taps "
                  f"(bar 500 ms: {'met' if delays.max() < 500 else 'NOT met'})")
    finally:
        if cluster is not None:
            cluster.stop()


if __name__ == "__main__":
    main()
