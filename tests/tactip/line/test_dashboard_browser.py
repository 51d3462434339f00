"""The dashboard end to end in headless Chromium (Debian's, driven by Playwright).

Issue 23's bars, each in the browser: station runs in a row on SQLite, the deciding tap and the held verdict,
a station killed with SIGKILL shown offline, a protective stop shown red, a DNS-rebinding Host refused, a
half-open flood not starving a client, and the layout at 1920x1080, 1366x768 and 390x844 (screenshots in
``out/test-artefacts/dashboard/``). Waits poll with deadlines; no rate is asserted.

A line's PostgreSQL database holds a history; the page shows it with the station stopped; then a
simulated station inspects (``tactip inspect`` in its own process) and the page shows each tap as it
is stored, the verdict, and the trend and Cp/Cpk updated. The delay from a tap's storing to its row
on the page is measured in the browser for every tap and written, with a screenshot, to the test's
artefacts (``out/test-artefacts/dashboard/``); the figures are reported, not asserted (no timed tests).
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from tactip.line.results import open_results, process_capability
from tests.tactip.conftest import small_station_table, write_station
from tests.tactip.services import SKIP_CHROMIUM, artefacts_dir, find_chromium

REBIND_HOST = "rebind.example.test"
TOKEN = "s3cret-0123456789abcdef"
CHROMIUM_FLAGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
                  "--disable-sync", "--no-first-run", "--disable-dev-shm-usage",
                  # DNS rebinding without DNS: the browser resolves a stranger's name to the dashboard's address.
                  f"--host-resolver-rules=MAP {REBIND_HOST} 127.0.0.1"]
HISTORY_WIDTHS_MM = [0.45, 0.52, 0.50, 0.61, 0.48, 0.55, 0.40, 0.50]       # g02: nominal 0.50 +- 0.25 mm


@pytest.fixture(scope="module")
def browser():
    """Headless Chromium (skips, saying why, where it is not installed)."""
    chromium = find_chromium()
    if chromium is None:
        pytest.skip(SKIP_CHROMIUM)
    sync_api = pytest.importorskip("playwright.sync_api", reason="Playwright is not installed (pip install -e '.[test]')")
    with sync_api.sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium, args=CHROMIUM_FLAGS, headless=True)
        yield browser
        browser.close()


def test_a_simulated_inspection_shows_live_in_the_browser(browser, sim_station, postgres_url, tmp_path):
    from tactip.line.dashboard import DashboardServer, make_app

    gap = next(g for g in sim_station.config.gaps if g.name == "g02")
    with open_results(postgres_url) as store:                          # yesterday's shift on this line
        for w in HISTORY_WIDTHS_MM:
            i = store.start_inspection("g02", nominal_width=gap.nominal_width, tolerance=gap.tolerance,
                                       policy="active", station="cell-1", model=str(sim_station.model))
            store.record_tap(i, tap=1, depth_mm=3.0, identity_estimate=w, belief=0.95)
            store.finish_inspection(i, estimated_width=w, estimated_depth=3.0, belief=0.95, taps=1, decided=True)
    history = process_capability(HISTORY_WIDTHS_MM, nominal_mm=gap.nominal_width, tolerance_mm=gap.tolerance)
    toml = write_station(tmp_path, small_station_table(sim_station.root,
                                                       station={"name": "cell-1", "results": postgres_url}))
    artefacts = artefacts_dir("dashboard")

    app = make_app(lambda: open_results(postgres_url, read_only=True), results_name=postgres_url)
    with DashboardServer(app, port=0) as server:
        page = browser.new_page(viewport={"width": 1280, "height": 1000})
        errors = []
        page.on("pageerror", lambda exc: errors.append(str(exc)))
        page.goto(server.url)
        page.wait_for_selector("body[data-loaded='1']")
        page.wait_for_selector("#live.on")
        # The station is stopped: the history alone is on the page.
        assert page.locator("#verdicts tbody tr").count() == len(HISTORY_WIDTHS_MM)
        row = page.locator("#capability tr.gap-row[data-gap='g02']")
        assert row.locator("td.n").inner_text() == str(len(HISTORY_WIDTHS_MM))
        assert row.locator("td.cp").inner_text() == f"{history.cp:.2f}"
        assert row.locator("td.cpk").inner_text() == f"{history.cpk:.2f}"
        assert page.locator(".trend[data-gap='g02'] circle.point").count() == len(HISTORY_WIDTHS_MM)

        # The station inspects g02 (its own process, writing to the line's database).
        run = subprocess.run([sys.executable, "-m", "tactip.cli", "inspect", "--config", str(toml), "--gap", "g02",
                              "--seed", "5", "--quiet"], capture_output=True, text=True, timeout=240)
        assert run.returncode == 0, run.stderr
        with open_results(postgres_url, read_only=True) as store:
            live = store.inspections()[-1]
            stored_taps = store.taps(live.id)
        verdict = f"#verdicts tr[data-inspection='{live.id}']"
        page.wait_for_selector(verdict, timeout=20_000)
        card = page.locator(f".card[data-inspection='{live.id}']")
        page.wait_for_function(f"document.querySelectorAll(\".card[data-inspection='{live.id}'] .tap-table tbody tr\")"
                               f".length === {len(stored_taps)}", timeout=20_000)
        expected = {True: "PASS", False: "FAIL", None: "UNDECIDED"}[live.passed]
        assert page.locator(f"{verdict} .verdict").inner_text() == expected
        station = page.locator("#stations tr[data-station='cell-1']")     # its status row: arm, camera
        page.wait_for_function("document.querySelector(\"#stations tr[data-station='cell-1'] .state\")"
                               ".textContent === 'stopped'", timeout=20_000)
        assert station.locator(".arm").inner_text() == "sim: ready"
        assert station.locator(".rate").inner_text() == f"{sim_station.config.sensor.frame_rate:.1f}"
        assert card.locator(".current-verdict .verdict").inner_text() == expected
        shown = [[c.inner_text() for c in r.locator("td").all()][:4] for r in card.locator(".tap-table tbody tr").all()]
        assert shown == [[str(t["tap"]), f"{t['depth_mm']:.2f}", f"{t['identity_estimate']:.2f}", f"{t['belief']:.3f}"]
                         for t in stored_taps]
        assert card.locator("svg.belief rect").count() == len(stored_taps[-1]["what_belief"])
        # The trend and Cp/Cpk take the new verdict in (when it was decided).
        n = len(HISTORY_WIDTHS_MM) + int(live.decided)
        page.wait_for_function(f"document.querySelectorAll(\".trend[data-gap='g02'] circle.point\").length === {n}",
                               timeout=20_000)
        after = process_capability(HISTORY_WIDTHS_MM + [live.estimated_width] * live.decided,
                                   nominal_mm=gap.nominal_width, tolerance_mm=gap.tolerance)
        assert row.locator("td.cpk").inner_text() == f"{after.cpk:.2f}"
        drawn = card.locator("tr[data-latency-ms]").evaluate_all(
            "rows => rows.map(r => [Number(r.dataset.latencyMs), r.dataset.via])")
        latencies_ms = [ms for ms, _ in drawn]
        via = {path: sum(v == path for _, v in drawn) for path in ("feed", "snapshot")}
        page.screenshot(path=str(artefacts / "dashboard-postgres.png"), full_page=True)
        page.close()
    assert errors == []
    # Every tap appeared while the page watched (through the feed, or a refresh that happened to read it
    # first), and its delay from storing to drawing is recorded.
    assert len(latencies_ms) == len(stored_taps)
    figures = dict(taps=len(latencies_ms), via=via, latency_ms_median=float(np.median(latencies_ms)),
                   latency_ms_max=float(np.max(latencies_ms)), latency_ms=latencies_ms, bar_ms=500,
                   verdict=expected, inspection=live.id)
    (artefacts / "latency.json").write_text(json.dumps(figures, indent=2) + "\n")
    print(f"\ntap to page: median {figures['latency_ms_median']:.0f} ms, max {figures['latency_ms_max']:.0f} ms "
          f"over {len(latencies_ms)} taps ({via['feed']} by the feed; bar 500 ms); screenshot {artefacts / 'dashboard-postgres.png'}")


# -- issue 23 ----------------------------------------------------------------------------------------

@pytest.fixture
def sqlite_station(sim_station, tmp_path):
    """The small simulated station writing to an SQLite file of its own: (station TOML, results path)."""
    results = tmp_path / "results.sqlite"
    toml = write_station(tmp_path, small_station_table(sim_station.root, station={"name": "cell-1",
                                                                                    "results": str(results)}))
    return toml, results


def _inspect(toml, *args, wait=True):
    argv = [sys.executable, "-m", "tactip.cli", "inspect", "--config", str(toml), "--quiet", *args]
    if not wait:
        return subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    run = subprocess.run(argv, capture_output=True, text=True, timeout=240)
    assert run.returncode == 0, run.stderr
    return run


def _open(browser, server, size=(1366, 768), query=""):
    page = browser.new_page(viewport={"width": size[0], "height": size[1]})
    errors = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    page.goto(server.url + query)
    page.wait_for_selector("body[data-loaded='1']")
    page.wait_for_selector("#live.on")
    return page, errors


def _tile(page, station="cell-1"):
    return page.locator(f"#tiles .tile[data-station='{station}']")


def test_three_station_runs_in_a_row_on_sqlite_each_show_their_verdict(browser, sqlite_station):
    """Bar: each of three separate inspect processes puts its verdict on the page within 3 s, still there
    5 s later, the badge live throughout and "malformed" never on the page."""
    from tactip.line.dashboard import DashboardServer, make_app

    toml, results = sqlite_station
    _inspect(toml, "--gap", "g02", "--seed", "1")                     # the database exists before serving
    app = make_app(lambda: open_results(results, read_only=True), results_name=str(results))
    with DashboardServer(app, port=0) as server:
        page, errors = _open(browser, server)
        for k, gap in enumerate(("g06", "g10", "g14")):
            _inspect(toml, "--gap", gap, "--seed", str(k + 2))
            with open_results(results, read_only=True) as store:
                run = store.inspections()[-1]
            expected = {True: "PASS", False: "FAIL", None: "UNDECIDED"}[run.passed]
            tile = f"#tiles .tile[data-station='cell-1'][data-inspection='{run.id}']"
            page.wait_for_selector(tile, timeout=3_000)                  # the bar: within 3 s
            assert page.locator(f"{tile} .tverdict").inner_text() == expected
            page.wait_for_selector(f"#verdicts tr[data-inspection='{run.id}']", timeout=3_000)
            page.wait_for_timeout(5_000)                                 # the bar: still there 5 s later
            assert page.locator(f"{tile} .tverdict").inner_text() == expected
            assert page.locator(f".card[data-inspection='{run.id}'] .current-verdict").inner_text() == expected
            assert page.locator("body[data-live='1']").count() == 1, page.locator("#live").inner_text()
            assert "malformed" not in page.content()
        page.close()
    assert errors == []


def test_the_deciding_tap_is_kept_and_the_verdict_held_until_the_next_inspection_is_under_way(browser, tmp_path):
    """An inspection decided on one tap, finished and followed by the next within one poll of the feed: its
    card shows the tap and the verdict, and stays (held) while the next one starts, then gives way to it."""
    from tactip.line.dashboard import DashboardServer, make_app

    db = tmp_path / "r.sqlite"
    with open_results(db) as store:
        store.update_station("cell-1", state="ready", arm="sim: ready")
    app = make_app(lambda: open_results(db, read_only=True), poll_s=1.0)   # one poll catches all that follows
    with DashboardServer(app, port=0) as server:
        page, errors = _open(browser, server)
        with open_results(db) as store:
            first = store.start_inspection("g05", nominal_width=1.0, tolerance=0.2, policy="active", station="cell-1")
            store.record_tap(first, tap=1, depth_mm=2.0, identity_estimate=1.05, belief=0.97, what_belief=[0.03, 0.97])
            store.finish_inspection(first, estimated_width=1.05, estimated_depth=2.0, belief=0.97, taps=1, decided=True)
            second = store.start_inspection("g06", nominal_width=2.0, tolerance=0.2, policy="active", station="cell-1")
            store.record_tap(second, tap=1, depth_mm=2.0, identity_estimate=1.5, belief=0.4, what_belief=[0.6, 0.4])
        held = f".card.held[data-inspection='{first}']"
        page.wait_for_selector(held, timeout=10_000)
        assert page.locator(f"{held} .tap-table tbody tr").count() == 1      # the deciding tap
        assert page.locator(f"{held} .tap-table tbody tr td").nth(2).inner_text() == "1.05"
        assert page.locator(f"{held} .current-verdict").inner_text() == "PASS"
        assert "next: g06" in page.locator(f"{held} .next").inner_text()
        assert _tile(page).get_attribute("data-inspection") == str(first)
        assert _tile(page).locator(".tverdict").inner_text() == "PASS"
        assert page.locator(f".card[data-inspection='{second}']:not(.held)").count() == 1   # the next, under it
        page.wait_for_selector(f".card[data-inspection='{first}']", state="detached", timeout=15_000)  # then alone
        assert page.locator(f".card[data-inspection='{second}'] .tap-table tbody tr").count() == 1
        assert _tile(page).locator(".tverdict").inner_text() == "PASS"      # the tile keeps the last verdict
        page.close()
    assert errors == []


def test_a_station_killed_mid_inspection_shows_offline_and_clears_when_back(browser, sqlite_station):
    """Bar: a station killed with SIGKILL while it inspects shows "offline" (red tile, banner) within 30 s."""
    import os
    import signal
    import time

    from tactip.line.dashboard import DashboardServer, make_app

    toml, results = sqlite_station
    _inspect(toml, "--gap", "g02", "--seed", "1")
    app = make_app(lambda: open_results(results, read_only=True))          # the default --offline-after
    with DashboardServer(app, port=0) as server:
        page, errors = _open(browser, server)
        station = _inspect(toml, "--seed", "3", wait=False)               # all four gaps
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:                                  # until it is at work
            with open_results(results, read_only=True) as store:
                if any(r.status == "running" for r in store.inspections()):
                    break
            time.sleep(0.05)
        os.kill(station.pid, signal.SIGKILL)
        killed = time.monotonic()
        station.wait(20)
        page.wait_for_function("document.querySelector(\"#tiles .tile[data-station='cell-1'] .tverdict\")"
                               ".textContent === 'OFFLINE'", timeout=30_000)    # the bar: within 30 s
        shown_after_s = time.monotonic() - killed
        print(f"\nkilled station shown offline after {shown_after_s:.1f} s (bar 30 s; --offline-after 10 s)")
        (artefacts_dir("dashboard") / "offline.json").write_text(json.dumps(dict(shown_after_s=shown_after_s)) + "\n")
        assert "alarm" in _tile(page).get_attribute("class")
        assert _tile(page).evaluate("e => getComputedStyle(e).backgroundColor") == "rgb(183, 28, 28)"
        assert "cell-1: offline: no heartbeat" in page.locator("#alarms").inner_text()
        assert page.locator(".card[data-station='cell-1'] .current-verdict").last.inner_text() == "OFFLINE"
        page.screenshot(path=str(artefacts_dir("dashboard") / "offline-1366x768.png"))
        _inspect(toml, "--gap", "g06", "--seed", "4")                      # back: the alarm clears
        page.wait_for_function("!document.querySelector(\"#tiles .tile[data-station='cell-1']\")"
                               ".classList.contains('alarm')", timeout=15_000)
        assert page.locator("#alarms.on").count() == 0
        page.close()
    assert errors == []


def test_a_protective_stop_shows_red_and_clears_when_the_station_is_back(browser, tmp_path):
    from tactip.line.dashboard import DashboardServer, make_app

    db = tmp_path / "r.sqlite"
    with open_results(db) as store:
        store.update_station("cell-2", state="ready", arm="ur: ready")
        done = store.start_inspection("g01", nominal_width=1.0, tolerance=0.2, policy="active", station="cell-2")
        store.finish_inspection(done, estimated_width=1.0, estimated_depth=2.0, belief=0.97, taps=1, decided=True)
    app = make_app(lambda: open_results(db, read_only=True))
    with DashboardServer(app, port=0) as server:
        page, errors = _open(browser, server)
        assert _tile(page, "cell-2").locator(".tverdict").inner_text() == "PASS"
        with open_results(db) as store:                                    # the arm stops mid-inspection
            stopped = store.start_inspection("g02", nominal_width=1.0, tolerance=0.2, policy="active", station="cell-2")
            store.abort_inspection(stopped, "ArmError: protective stop")
            store.update_station("cell-2", state="stopped: ArmError: protective stop", arm="ur: protective stop")
        page.wait_for_selector("#alarms.on", timeout=10_000)
        banner = page.locator("#alarms").inner_text()
        assert "cell-2: stopped: ArmError: protective stop" in banner and f"inspection {stopped} (g02) aborted" in banner
        assert page.locator("#alarms").evaluate("e => getComputedStyle(e).backgroundColor") == "rgb(183, 28, 28)"
        tile = _tile(page, "cell-2")
        page.wait_for_function("document.querySelector(\"#tiles .tile[data-station='cell-2']\").classList.contains('alarm')",
                               timeout=10_000)
        assert tile.locator(".tverdict").inner_text() == "ABORTED"
        assert tile.evaluate("e => getComputedStyle(e).backgroundColor") == "rgb(183, 28, 28)"
        with open_results(db) as store:                                    # recovered, inspecting again
            store.update_station("cell-2", state="inspecting", arm="ur: ready")
            store.start_inspection("g02", nominal_width=1.0, tolerance=0.2, policy="active", station="cell-2")
        page.wait_for_selector("#alarms:not(.on)", state="attached", timeout=10_000)
        assert "alarm" not in tile.get_attribute("class")
        page.close()
    assert errors == []


def test_a_dns_rebinding_host_is_refused_in_the_browser(browser, tmp_path):
    """The browser resolves a stranger's name to the dashboard's loopback address (DNS rebinding): the
    dashboard refuses that Host (421), while the page by its own address works."""
    from tactip.line.dashboard import DashboardServer, make_app

    db = tmp_path / "r.sqlite"
    with open_results(db) as store:
        done = store.start_inspection("g01", nominal_width=1.0, tolerance=0.2, policy="active", station="cell-1")
        store.finish_inspection(done, estimated_width=1.0, estimated_depth=2.0, belief=0.97, taps=1, decided=True)
    app = make_app(lambda: open_results(db, read_only=True))
    with DashboardServer(app, port=0) as server:
        page = browser.new_page()
        for path in ("/", "/api/state"):
            response = page.goto(f"http://{REBIND_HOST}:{server.port}{path}")
            assert response.status == 421 and "g01" not in page.content()
        assert page.goto(f"{server.url}api/state").status == 200 and "g01" in page.content()
        page.close()


def test_a_half_open_flood_does_not_starve_a_client(browser, tmp_path):
    """Bar: 400 half-open connections to `tactip serve` at ulimit -n 256; a request with the token answers
    within 2 s, and the page loads and goes live."""
    import time
    import urllib.request

    from tests.tactip.line.flood import served_under_a_half_open_flood

    db = tmp_path / "r.sqlite"
    with open_results(db) as store:
        done = store.start_inspection("g01", nominal_width=1.0, tolerance=0.2, policy="active", station="cell-1")
        store.finish_inspection(done, estimated_width=1.0, estimated_depth=2.0, belief=0.97, taps=1, decided=True)
    with served_under_a_half_open_flood(db, TOKEN) as url:
        request = urllib.request.Request(url + "api/state", headers={"Authorization": f"Bearer {TOKEN}"})
        started = time.monotonic()
        with urllib.request.urlopen(request, timeout=2) as response:              # the bar: within 2 s
            assert json.loads(response.read())["verdicts"][0]["gap"] == "g01"
        print(f"\ntokened request under a 400-connection half-open flood answered in "
              f"{1000 * (time.monotonic() - started):.0f} ms (bar 2 s)")
        page = browser.new_page(viewport={"width": 1366, "height": 768})
        page.goto(f"{url}?token={TOKEN}")
        page.wait_for_selector("#tiles .tile[data-station='cell-1']", timeout=10_000)
        page.close()


def test_the_layout_at_a_glance_on_a_desktop_a_laptop_and_a_phone(browser, tmp_path):
    """Tiles, alarms, the current inspection and SPC above the fold at 1366x768; a 390 px phone without a
    sideways scroll and with the verdicts in view; hover values on the trend; screenshots of all three."""
    from tactip.line.dashboard import DashboardServer, make_app

    rng = np.random.default_rng(11)
    db = tmp_path / "r.sqlite"
    with open_results(db) as store:
        for k in range(30):
            for station, gap in (("cell-1", "g20"), ("cell-2", "g05"), ("cell-1", "g05")):
                i = store.start_inspection(gap, nominal_width=0.5, tolerance=0.25, policy="active", station=station)
                w = float(rng.normal(0.52, 0.06))
                for t in (1, 2):
                    store.record_tap(i, tap=t, depth_mm=1.5, identity_estimate=w, belief=0.45 * t,
                                     what_belief=[0.05, 0.2, 0.5, 0.2, 0.05])
                store.finish_inspection(i, estimated_width=w, estimated_depth=1.5, belief=0.9, taps=2, decided=True)
        store.update_station("cell-1", state="inspecting", arm="sim: ready", frame_rate=20.0)
        running = store.start_inspection("g20", nominal_width=0.5, tolerance=0.25, policy="active", station="cell-1")
        store.record_tap(running, tap=1, depth_mm=1.5, identity_estimate=0.5, belief=0.4,
                         what_belief=[0.05, 0.2, 0.5, 0.2, 0.05])
        store.update_station("cell-3", state="stopped: ArmError: protective stop", arm="ur: protective stop")
    artefacts = artefacts_dir("dashboard")
    app = make_app(lambda: open_results(db, read_only=True))
    with DashboardServer(app, port=0) as server:
        for width, height in ((1920, 1080), (1366, 768), (390, 844)):
            page, errors = _open(browser, server, size=(width, height))
            page.wait_for_selector("#alarms.on")
            page.screenshot(path=str(artefacts / f"dashboard-{width}x{height}.png"))
            assert page.evaluate("document.documentElement.scrollWidth") <= width      # nothing cut off sideways
            assert [t.get_attribute("data-station") for t in page.locator("#tiles .tile").all()] == \
                ["cell-1", "cell-2", "cell-3"]
            verdict = page.locator("#tiles .tile[data-station='cell-2'] .tverdict")
            assert float(verdict.evaluate("e => parseFloat(getComputedStyle(e).fontSize)")) >= 40   # readable at 2 m
            if width >= 1366:                                                 # above the fold
                for selector in ("#alarms", "#tiles .tile[data-station='cell-3']", f".card[data-inspection='{running}']",
                                 "#capability tr.gap-row[data-gap='g05']", ".trend[data-gap='g05'] svg"):
                    box = page.locator(selector).first.bounding_box()
                    assert box is not None and box["y"] < height, (width, selector, box)
            else:                                                             # the phone: the verdicts in view
                cell = page.locator("#verdicts tbody tr").first.locator(".verdict").bounding_box()
                assert cell["x"] + cell["width"] <= width
            # Cp/Cpk per gap and per station, sorted by gap, with the warning below n = 25.
            gaps = page.locator("#capability tr.gap-row").evaluate_all("rows => rows.map(r => r.dataset.gap)")
            assert gaps == ["g05", "g20"]
            g05 = [r.get_attribute("data-station") for r in page.locator("#capability tr[data-gap='g05']").all()]
            assert g05 == ["all", "cell-1", "cell-2"]
            assert page.locator("#capability tr[data-gap='g05'][data-station='all'] .warn").count() == 0      # n = 60
            assert page.locator("#capability tr[data-gap='g20'][data-station='cell-1'] .n").inner_text() == "30"
            page.close()
            assert errors == []
        # The trend: a time axis, and a point's values on hover.
        page, errors = _open(browser, server, size=(1366, 768))
        ticks = page.locator(".trend[data-gap='g20'] text.tick").evaluate_all("els => els.map(e => e.textContent)")
        assert len(ticks) >= 2 and all(":" in t for t in ticks), ticks              # clock times
        point = page.locator(".trend[data-gap='g20'] circle.point").last
        point.hover()
        page.wait_for_selector("#tip", state="visible")
        with open_results(db, read_only=True) as store:
            newest = [r for r in store.inspections() if r.gap == "g20" and r.status == "done"][-1]
        tip = page.locator("#tip").inner_text()
        assert f"#{newest.id}" in tip and f"{newest.estimated_width:.3f} mm" in tip and "cell-1" in tip
        page.screenshot(path=str(artefacts / "dashboard-hover-1366x768.png"))
        page.close()
        assert errors == []


def test_the_badge_never_says_live_over_an_unreadable_store(browser, tmp_path):
    from tactip.line.dashboard import DashboardServer, make_app

    db = tmp_path / "r.sqlite"
    with open_results(db) as store:
        store.update_station("cell-1", state="ready", arm="sim: ready")
    app = make_app(lambda: open_results(db, read_only=True))
    with DashboardServer(app, port=0) as server:
        page, errors = _open(browser, server)
        db.rename(tmp_path / "away.sqlite")                                 # the store cannot be read
        page.wait_for_selector("#live.error", timeout=10_000)
        assert page.locator("body[data-live='0']").count() == 1
        assert "not live: cannot read the results database" in page.locator("#live").inner_text()
        (tmp_path / "away.sqlite").rename(db)                               # back
        page.wait_for_selector("#live.on", timeout=10_000)
        assert page.locator("#live").inner_text() == "live"
        page.close()
    assert errors == []
