"""What the dashboard shows, read from a results store: stations, current inspections, verdicts, trends.

Pure reads (no I/O of its own beyond the store's queries); the web app serves `dashboard_state`
as JSON and the page draws it.
"""

from __future__ import annotations

import datetime as _dt
import functools
import re
from typing import Sequence

from tactip.line import OFFLINE_AFTER_S
from tactip.line.results import InspectionRow, ResultsStoreBase, process_capability

__all__ = ["dashboard_state", "gap_trends", "station_status", "gap_key", "HISTORY_ROWS", "OFFLINE_AFTER_S",
           "CAPABILITY_MIN_N"]

#: The newest inspections read for a page (verdicts, trends, stations), rows.
HISTORY_ROWS = 5000
#: Below this many estimates Cp/Cpk carry a warning (their 95 % interval is wider than about +-30 %).
CAPABILITY_MIN_N = 25
# Words of an arm or station state that stop the line (alarms).
_STOPS = ("protective stop", "emergency stop", "safeguard stop", "fault")


def gap_key(name: str) -> tuple:
    """Sort key of a gap (or station) name in natural order: ``g5 < g05b < g20`` (digits by value)."""
    return tuple((0, int(part), part) if part.isdigit() else (1, 0, part.lower())
                 for part in re.split(r"(\d+)", name or "") if part)


def gap_trends(rows: Sequence[InspectionRow], *, window: int = 50) -> list[dict]:
    """Per gap (in natural order of names): the last ``window`` decided estimates against nominal +- tolerance,
    and Cp/Cpk over them, of all stations and of each.

    Parameters
    ----------
    rows : sequence of InspectionRow
        Stored inspections, oldest first; only ``done`` and decided ones count.
    window : int
        How many of each gap's newest decided inspections to use (>= 2 for Cp/Cpk).

    Returns
    -------
    list of dict
        One per gap, sorted by `gap_key`: ``gap``, ``nominal_mm``, ``tolerance_mm`` (of its newest
        inspection), ``points`` (``id``, ``estimated_width``, ``passed``, ``station``, ``finished_at``),
        ``capability`` (`Capability.as_dict` plus ``warning``: a text when ``n`` < `CAPABILITY_MIN_N`, else
        None) and ``by_station`` (per station of those points, by name: ``station`` and its ``capability``).
    """
    by_gap: dict[str, list[InspectionRow]] = {}
    for r in rows:
        if r.status == "done" and r.decided and r.estimated_width is not None:
            by_gap.setdefault(r.gap, []).append(r)
    out = []
    for gap in sorted(by_gap, key=gap_key):
        done = by_gap[gap]
        newest = done[-1]
        # Capability is judged against the newest specification: a changed nominal starts a new series.
        same = [r for r in done if r.nominal_width == newest.nominal_width and r.tolerance == newest.tolerance]
        recent = same[-window:]

        def capability(of):
            c = process_capability([r.estimated_width for r in of], nominal_mm=newest.nominal_width,
                                   tolerance_mm=newest.tolerance).as_dict()
            c["warning"] = (None if c["n"] >= CAPABILITY_MIN_N else
                            f"n = {c['n']} < {CAPABILITY_MIN_N}: too few inspections to judge capability")
            return c

        stations = sorted({r.station or "(unnamed)" for r in recent}, key=gap_key)
        out.append(dict(gap=gap, nominal_mm=newest.nominal_width, tolerance_mm=newest.tolerance,
                        points=[dict(id=r.id, estimated_width=r.estimated_width, passed=r.passed, station=r.station,
                                     finished_at=r.finished_at) for r in recent],
                        capability=capability(recent),
                        by_station=[dict(station=name, capability=capability(
                            [r for r in recent if (r.station or "(unnamed)") == name])) for name in stations]))
    return out


def station_status(rows: Sequence[InspectionRow], *, heartbeats: Sequence[dict] = (),
                   now: _dt.datetime | None = None, offline_after_s: float = OFFLINE_AFTER_S) -> list[dict]:
    """Per station: inspecting (which gap) or idle, its model, counts and last activity, arm and camera, its
    last verdict, and its alarms (protective stop, aborted inspection, offline).

    Parameters
    ----------
    rows : sequence of InspectionRow
        Stored inspections, oldest first.
    heartbeats : sequence of dict
        The stations' own status rows (`ResultsStoreBase.stations`): ``state``, ``arm``,
        ``frame_rate`` (frames/s), ``updated_at``, ``heartbeat_at``; a station that wrote one but
        inspected nothing is listed too.
    now : datetime, optional
        For ``idle_s`` and ``silent_s`` (default the current UTC time).
    offline_after_s : float
        A station that should be working (its state not ``stopped``, or an inspection ``running``) and
        has given no sign of life for longer than this is ``offline``, s.

    Returns
    -------
    list of dict
        By name: ``name``, ``state`` (inspecting, idle), ``gap``, counts (``inspections``, ``passed``,
        ``failed``, ``undecided``, ``aborted``), ``model``, ``last_activity``, ``idle_s``, ``station_state``,
        ``arm``, ``frame_rate``, ``heartbeat_at``, ``silent_s`` (s since its last sign of life), ``offline``,
        ``last`` (its newest finished inspection as a dict, or None) and ``alarms`` (texts; empty when fine).
    """
    now = now or _dt.datetime.now(_dt.timezone.utc)
    stations: dict[str, dict] = {}
    newest: dict[str, InspectionRow] = {}
    finished: dict[str, InspectionRow] = {}
    for r in rows:
        name = r.station or "(unnamed)"
        s = stations.setdefault(name, dict(name=name, inspections=0, passed=0, failed=0, undecided=0, aborted=0))
        s["inspections"] += 1
        if r.status == "aborted":
            s["aborted"] += 1
        elif r.status == "done":
            s[{True: "passed", False: "failed", None: "undecided"}[r.passed]] += 1
        if r.status != "running":
            finished[name] = r
        newest[name] = r
        s.update(model=r.model, last_inspection=r.id, last_activity=r.finished_at or r.started_at,
                 state="inspecting" if r.status == "running" else "idle",
                 gap=r.gap if r.status == "running" else None)
    for beat in heartbeats:
        s = stations.setdefault(beat["name"], dict(name=beat["name"], inspections=0, passed=0, failed=0, undecided=0,
                                                   aborted=0, model=beat["model"], last_inspection=None,
                                                   last_activity=beat["updated_at"], state="idle", gap=None))
        s.update(station_state=beat["state"], arm=beat["arm"], frame_rate=beat["frame_rate"],
                 heartbeat_at=beat.get("heartbeat_at") or beat["updated_at"])
        if beat["model"]:
            s["model"] = beat["model"]
        if s["state"] != "inspecting" and beat["updated_at"] > s["last_activity"]:
            s["last_activity"] = beat["updated_at"]
    for name, s in stations.items():
        for key in ("station_state", "arm", "frame_rate", "heartbeat_at"):
            s.setdefault(key, None)
        last = _dt.datetime.fromisoformat(s["last_activity"])
        s["idle_s"] = None if s["state"] == "inspecting" else max(0.0, (now - last).total_seconds())
        signs = [t for t in (s["heartbeat_at"], s["last_activity"]) if t]
        s["silent_s"] = max(0.0, (now - max(_dt.datetime.fromisoformat(t) for t in signs)).total_seconds())
        working = s["state"] == "inspecting" or (s["station_state"] is not None
                                                 and not s["station_state"].startswith("stopped"))
        s["offline"] = bool(working and s["silent_s"] > offline_after_s)
        s["last"] = finished[name].as_dict() if name in finished else None
        s["alarms"] = _alarms(s, newest.get(name))
    return sorted(stations.values(), key=lambda s: gap_key(s["name"]))


def _alarms(s: dict, newest: InspectionRow | None) -> list[str]:
    """What an operator must see about station ``s`` at once: offline, an arm stop, an aborted inspection."""
    alarms = []
    if s["offline"]:
        alarms.append(f"offline: no heartbeat for {s['silent_s']:.0f} s")
    for text in (s["station_state"], s["arm"]):
        if text and any(stop in text.lower() for stop in _STOPS):
            alarms.append(text)
            break
    if newest is not None and newest.status == "aborted":
        alarms.append(f"inspection {newest.id} ({newest.gap}) aborted: {newest.reason or 'no reason stored'}")
    return alarms


def dashboard_state(store: ResultsStoreBase, *, verdicts: int = 20, window: int = 50,
                    station_info: dict | None = None, offline_after_s: float = OFFLINE_AFTER_S) -> dict:
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
    offline_after_s : float
        A working station silent for longer than this is offline (`station_status`), s.

    Returns
    -------
    dict
        ``stations``, ``current`` (per station its newest inspection, its taps in ``tap_rows``),
        ``verdicts`` (newest first), ``gaps`` (trends and capability), ``width_classes_mm``
        (of the newest model, when it can be read), ``last_tap_id``, ``station_info``, ``window``,
        ``alarms`` (``station``, ``text``: every station's alarms, by station), ``offline_after_s``.
    """
    rows = store.inspections(limit=HISTORY_ROWS)
    stations = station_status(rows, heartbeats=store.stations(), offline_after_s=offline_after_s)
    current = []
    for s in stations:
        row = next((r for r in reversed(rows) if (r.station or "(unnamed)") == s["name"]), None)
        if row is not None:
            current.append(dict(row.as_dict(), tap_rows=store.taps(row.id)))
    finished = [r.as_dict() for r in reversed(rows) if r.status != "running"][:verdicts]
    model = next((r.model for r in reversed(rows) if r.model), None)
    return dict(stations=stations, current=current, verdicts=finished, gaps=gap_trends(rows, window=window),
                width_classes_mm=width_classes(model), last_tap_id=store.last_tap_id(),
                station_info=station_info, window=window, offline_after_s=offline_after_s,
                alarms=[dict(station=s["name"], text=text) for s in stations for text in s["alarms"]])


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
