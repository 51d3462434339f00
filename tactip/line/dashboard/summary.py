"""What the dashboard shows, read from a results store: stations, current inspections, verdicts, trends.

Pure reads (no I/O of its own beyond the store's queries); the web app serves `dashboard_state`
as JSON and the page draws it.
"""

from __future__ import annotations

import datetime as _dt
import functools
from typing import Sequence

from tactip.line.results import InspectionRow, ResultsStoreBase, process_capability

__all__ = ["dashboard_state", "gap_trends", "station_status", "HISTORY_ROWS"]

#: The newest inspections read for a page (verdicts, trends, stations), rows.
HISTORY_ROWS = 5000


def gap_trends(rows: Sequence[InspectionRow], *, window: int = 50) -> list[dict]:
    """Per gap: the last ``window`` decided estimates against nominal +- tolerance, and Cp/Cpk over them.

    Parameters
    ----------
    rows : sequence of InspectionRow
        Stored inspections, oldest first; only ``done`` and decided ones count.
    window : int
        How many of each gap's newest decided inspections to use (>= 2 for Cp/Cpk).

    Returns
    -------
    list of dict
        One per gap (by name, in order of first appearance): ``gap``, ``nominal_mm``,
        ``tolerance_mm`` (of its newest inspection), ``points`` (``id``, ``estimated_width``,
        ``passed``, ``station``, ``finished_at``) and ``capability`` (`Capability.as_dict`).
    """
    by_gap: dict[str, list[InspectionRow]] = {}
    for r in rows:
        if r.status == "done" and r.decided and r.estimated_width is not None:
            by_gap.setdefault(r.gap, []).append(r)
    out = []
    for gap, done in by_gap.items():
        newest = done[-1]
        # Capability is judged against the newest specification: a changed nominal starts a new series.
        same = [r for r in done if r.nominal_width == newest.nominal_width and r.tolerance == newest.tolerance]
        recent = same[-window:]
        capability = process_capability([r.estimated_width for r in recent], nominal_mm=newest.nominal_width,
                                        tolerance_mm=newest.tolerance)
        out.append(dict(gap=gap, nominal_mm=newest.nominal_width, tolerance_mm=newest.tolerance,
                        points=[dict(id=r.id, estimated_width=r.estimated_width, passed=r.passed, station=r.station,
                                     finished_at=r.finished_at) for r in recent],
                        capability=capability.as_dict()))
    return out


def station_status(rows: Sequence[InspectionRow], *, heartbeats: Sequence[dict] = (),
                   now: _dt.datetime | None = None) -> list[dict]:
    """Per station: inspecting (which gap) or idle, its model, counts and last activity, arm and camera.

    Parameters
    ----------
    rows : sequence of InspectionRow
        Stored inspections, oldest first.
    heartbeats : sequence of dict
        The stations' own status rows (`ResultsStoreBase.stations`): ``state``, ``arm``,
        ``frame_rate`` (frames/s), ``updated_at``; a station that wrote one but inspected nothing
        is listed too.
    now : datetime, optional
        For ``idle_s`` (default the current UTC time).
    """
    now = now or _dt.datetime.now(_dt.timezone.utc)
    stations: dict[str, dict] = {}
    for r in rows:
        name = r.station or "(unnamed)"
        s = stations.setdefault(name, dict(name=name, inspections=0, passed=0, failed=0, undecided=0, aborted=0))
        s["inspections"] += 1
        if r.status == "aborted":
            s["aborted"] += 1
        elif r.status == "done":
            s[{True: "passed", False: "failed", None: "undecided"}[r.passed]] += 1
        s.update(model=r.model, last_inspection=r.id, last_activity=r.finished_at or r.started_at,
                 state="inspecting" if r.status == "running" else "idle",
                 gap=r.gap if r.status == "running" else None)
    for beat in heartbeats:
        s = stations.setdefault(beat["name"], dict(name=beat["name"], inspections=0, passed=0, failed=0, undecided=0,
                                                   aborted=0, model=beat["model"], last_inspection=None,
                                                   last_activity=beat["updated_at"], state="idle", gap=None))
        s.update(station_state=beat["state"], arm=beat["arm"], frame_rate=beat["frame_rate"],
                 heartbeat_at=beat["updated_at"])
        if beat["model"]:
            s["model"] = beat["model"]
        if s["state"] != "inspecting" and beat["updated_at"] > s["last_activity"]:
            s["last_activity"] = beat["updated_at"]
    for s in stations.values():
        last = _dt.datetime.fromisoformat(s["last_activity"])
        s["idle_s"] = None if s["state"] == "inspecting" else max(0.0, (now - last).total_seconds())
        for key in ("station_state", "arm", "frame_rate", "heartbeat_at"):
            s.setdefault(key, None)
    return sorted(stations.values(), key=lambda s: s["name"])


def dashboard_state(store: ResultsStoreBase, *, verdicts: int = 20, window: int = 50,
                    station_info: dict | None = None) -> dict:
    """Everything the page draws, as JSON-ready data.

    Parameters
    ----------
    store : ResultsStoreBase
        An open (read-only) results store.
    verdicts : int
        How many of the newest finished inspections to list.
    window : int
        Inspections per gap for the trend charts and Cp/Cpk (see `gap_trends`).
    station_info : dict, optional
        What the configuration says of the station (arm, camera frame rate, model), shown as is.

    Returns
    -------
    dict
        ``stations``, ``current`` (per station its newest inspection, its taps in ``tap_rows``),
        ``verdicts`` (newest first), ``gaps`` (trends and capability), ``width_classes_mm``
        (of the newest model, when it can be read), ``last_tap_id``, ``station_info``, ``window``.
    """
    rows = store.inspections(limit=HISTORY_ROWS)
    stations = station_status(rows, heartbeats=store.stations())
    current = []
    for s in stations:
        row = next((r for r in reversed(rows) if (r.station or "(unnamed)") == s["name"]), None)
        if row is not None:
            current.append(dict(row.as_dict(), tap_rows=store.taps(row.id)))
    finished = [r.as_dict() for r in reversed(rows) if r.status != "running"][:verdicts]
    model = next((r.model for r in reversed(rows) if r.model), None)
    return dict(stations=stations, current=current, verdicts=finished, gaps=gap_trends(rows, window=window),
                width_classes_mm=width_classes(model), last_tap_id=store.last_tap_id(),
                station_info=station_info, window=window)


@functools.lru_cache(maxsize=8)
def width_classes(model_path: str | None) -> list[float] | None:
    """The width classes (mm) of the model at ``model_path``: the bars of the belief chart; None if unreadable."""
    if not model_path:
        return None
    try:
        from perception import load_model

        return [round(float(w), 4) for w in load_model(model_path).identities]
    except Exception:  # another host's path, a model being rewritten: the chart labels bars by index
        return None
