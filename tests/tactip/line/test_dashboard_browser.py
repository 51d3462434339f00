"""The dashboard end to end in headless Chromium (Debian's, driven by Playwright).

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

CHROMIUM_FLAGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
                  "--disable-sync", "--no-first-run", "--disable-dev-shm-usage"]
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
        row = page.locator("#capability tr[data-gap='g02']")
        assert row.locator("td").nth(3).inner_text() == str(len(HISTORY_WIDTHS_MM))
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
        page.screenshot(path=str(artefacts / "dashboard.png"), full_page=True)
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
          f"over {len(latencies_ms)} taps ({via['feed']} by the feed; bar 500 ms); screenshot {artefacts / 'dashboard.png'}")
