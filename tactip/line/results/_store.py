"""What every results backend shares: the rows, the writes and the reads, in portable SQL.

A backend (`tactip.line.results.sqlite`, `tactip.line.results.postgres`) opens its connection, creates the
schema and maps its driver's errors; the SQL below is written once with ``?`` placeholders and runs
on both. Every write is its own transaction (a tap and its count together), committed before the
call returns.
"""

from __future__ import annotations

import errno

import csv
import datetime as _dt
import io
import json
import os
import socket
from dataclasses import dataclass
from typing import Iterable, Sequence

from tactip.errors import TactipError

SCHEMA_VERSION = 1
#: A ``running`` inspection older than this is closed as stale even if its process cannot be checked
#: (another host, or a row from before the ``pid`` column), s.
STALE_AFTER_S = 24 * 3600.0
_HOST = socket.gethostname()

EXPORT_FIELDS = (
    "id", "gap", "nominal_width", "tolerance", "estimated_width", "estimated_depth", "belief",
    "taps", "decided", "passed", "policy", "decision_threshold", "status", "reason",
    "station", "model", "started_at", "finished_at", "duration_s",
)
#: Columns of one tap as `ResultsStoreBase.taps` and `ResultsStoreBase.taps_after` return them.
TAP_FIELDS = ("tap", "depth_mm", "location_estimate", "identity_estimate", "belief", "what_belief",
              "where_belief", "at")
#: Columns of a station's status row (`ResultsStoreBase.update_station`, `ResultsStoreBase.stations`).
STATION_FIELDS = ("name", "state", "arm", "frame_rate", "model", "host", "pid", "updated_at", "heartbeat_at")



class ResultsError(TactipError):
    """The results database cannot be opened or is not a tactip results database."""


def _now() -> str:
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="milliseconds")


@dataclass(frozen=True)
class InspectionRow:
    """One inspection as stored (field names as in `EXPORT_FIELDS`)."""

    id: int
    gap: str
    nominal_width: float
    tolerance: float
    estimated_width: float | None
    estimated_depth: float | None
    belief: float | None
    taps: int
    decided: bool
    passed: bool | None
    policy: str
    decision_threshold: float | None
    status: str
    reason: str | None
    station: str | None
    model: str | None
    started_at: str
    finished_at: str | None
    duration_s: float | None

    def as_dict(self) -> dict:
        """The row as a plain dict (JSON-ready)."""
        return {name: getattr(self, name) for name in EXPORT_FIELDS}


class ResultsStoreBase:
    """The backend-independent part of a results store (see `tactip.line.results`).

    Subclasses set ``self.path`` (shown in messages), ``self.read_only`` and implement
    ``_query`` (a read returning rows), ``_write`` (one statement, autocommitted),
    ``_transaction`` (a context in which several ``_write`` commit together) and ``close``.
    """

    path: str
    read_only: bool
    #: Whether a reader polling the store should open it anew for each poll (SQLite) rather than keep
    #: one connection (PostgreSQL, reconnected only when the server drops it).
    reopen_to_poll = False

    # -- backend hooks -----------------------------------------------------------------------
    def _query(self, sql: str, params=()) -> list[tuple]:  # pragma: no cover - abstract
        raise NotImplementedError

    def _write(self, sql: str, params=()) -> list[tuple]:  # pragma: no cover - abstract
        raise NotImplementedError

    def _transaction(self):  # pragma: no cover - abstract
        raise NotImplementedError

    def close(self) -> None:  # pragma: no cover - abstract
        """Close the database connection."""
        raise NotImplementedError

    def _refuse_if_read_only(self) -> None:
        if self.read_only:
            raise ResultsError(f"{self.path} was opened read-only (for reading results)")

    # -- writing -----------------------------------------------------------------------------
    def close_stale_inspections(self, station: str | None, *, max_age_s: float = STALE_AFTER_S) -> list[int]:
        """Close as aborted the ``running`` rows of ``station`` whose process is gone; returns their ids.

        A row is stale when it was started on this host by a process that no longer exists, or
        (another host, or no process recorded) when it started more than ``max_age_s`` ago. Rows of
        live processes (concurrent inspections) and of other stations are left alone.
        """
        which = "station IS NULL" if station is None else "station = ?"
        rows = self._query(f"SELECT id, pid, host, started_at FROM inspections WHERE status='running' AND {which}",
                           () if station is None else (station,))
        now = _dt.datetime.now(_dt.timezone.utc)
        closed = []
        for inspection_id, pid, host, started in rows:
            if pid is not None and host == _HOST:
                if _process_alive(int(pid)):
                    continue
                reason = f"stale: process {pid} ended without closing the inspection (killed?)"
            else:
                age = (now - _dt.datetime.fromisoformat(started)).total_seconds()
                if age < max_age_s:
                    continue
                reason = f"stale: still running after {age / 3600:.0f} h"
            self._write("UPDATE inspections SET status='aborted', reason=?, finished_at=? WHERE id=? AND "
                        "status='running'", (reason, _now(), inspection_id))
            closed.append(int(inspection_id))
        return closed

    def start_inspection(self, gap: str, *, nominal_width: float, tolerance: float, policy: str,
                         decision_threshold: float | None = None, station: str | None = None,
                         model: str | None = None) -> int:
        """Open an inspection row (status ``running``) and return its id."""
        self._refuse_if_read_only()
        rows = self._write(
            "INSERT INTO inspections (gap, nominal_width, tolerance, policy, decision_threshold,"
            " station, model, started_at, pid, host) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?) RETURNING id",
            (gap, float(nominal_width), float(tolerance), policy,
             None if decision_threshold is None else float(decision_threshold), station, model, _now(),
             os.getpid(), _HOST),
        )
        return int(rows[0][0])

    def record_tap(self, inspection_id: int, *, tap: int, depth_mm: float,
                   location_estimate: float | None = None, identity_estimate: float | None = None,
                   belief: float | None = None, what_belief: Sequence[float] | None = None,
                   where_belief: Sequence[float] | None = None) -> None:
        """Store one tap of an inspection, with the beliefs after it, and bump the tap count.

        Both land in one transaction: after a crash the count always matches the stored taps.
        """
        self._refuse_if_read_only()
        with self._transaction():
            self._write(
                "INSERT INTO taps (inspection_id, tap, depth_mm, location_estimate, identity_estimate,"
                " belief, what_belief, where_belief, at) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                (inspection_id, int(tap), float(depth_mm), _opt(location_estimate), _opt(identity_estimate),
                 _opt(belief), _json_list(what_belief), _json_list(where_belief), _now()),
            )
            self._write("UPDATE inspections SET taps = ? WHERE id = ?", (int(tap), inspection_id))

    def finish_inspection(self, inspection_id: int, *, estimated_width: float | None,
                          estimated_depth: float | None, belief: float | None, taps: int,
                          decided: bool) -> bool | None:
        """Close an inspection as ``done``; returns pass (True/False), or None when undecided.

        Pass means a decided width within ``tolerance`` of ``nominal_width`` (mm).
        """
        self._refuse_if_read_only()
        nominal, tolerance, started = self._query(
            "SELECT nominal_width, tolerance, started_at FROM inspections WHERE id = ?", (inspection_id,))[0]
        passed = None
        if decided and estimated_width is not None:
            passed = bool(abs(float(estimated_width) - nominal) <= tolerance + 1e-9)
        finished = _now()
        self._write(
            "UPDATE inspections SET estimated_width=?, estimated_depth=?, belief=?, taps=?, decided=?,"
            " passed=?, status='done', finished_at=?, duration_s=? WHERE id=?",
            (_opt(estimated_width), _opt(estimated_depth), _opt(belief), int(taps), int(bool(decided)),
             None if passed is None else int(passed), finished, _seconds(started, finished), inspection_id),
        )
        return passed

    def abort_inspection(self, inspection_id: int, reason: str) -> None:
        """Close an inspection as ``aborted`` with the reason (taps stored so far are kept)."""
        self._refuse_if_read_only()
        started = self._query("SELECT started_at FROM inspections WHERE id = ?", (inspection_id,))[0][0]
        finished = _now()
        update = ("UPDATE inspections SET status='aborted', reason=?, finished_at=?, duration_s=? WHERE id=?",
                  (reason, finished, _seconds(started, finished), inspection_id))
        try:
            self._write(*update)
        except OSError as exc:
            if exc.errno != errno.ENOSPC or not self._make_room():
                raise
            self._write(*update)     # the row says why it stopped, on a full disk too

    def _make_room(self) -> bool:
        """Free what the backend can of its own files on a full disk; whether a write may be tried again."""
        return False

    def update_station(self, name: str, *, state: str, arm: str | None = None, frame_rate: float | None = None,
                       model: str | None = None) -> None:
        """Store the status of station ``name`` (one row per station, replaced at each call).

        Parameters
        ----------
        name : str
            The station (``[station] name``).
        state : str
            ``ready``, ``inspecting``, ``stopped`` or ``stopped: REASON``.
        arm : str, optional
            The arm as its controller reports it: ``"BACKEND: ready"`` or ``"BACKEND: PROBLEM"``.
        frame_rate : float, optional
            The camera's frame rate, frames/s.
        model : str, optional
            The perception model file in use.
        """
        self._refuse_if_read_only()
        now = _now()
        self._write(
            f"INSERT INTO stations ({', '.join(STATION_FIELDS)}) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?) ON CONFLICT (name) "
            f"DO UPDATE SET {', '.join(f'{k} = excluded.{k}' for k in STATION_FIELDS[1:])}",
            (name, state, arm, _opt(frame_rate), model, _HOST, os.getpid(), now, now),
        )

    def heartbeat(self, name: str) -> None:
        """Say that station ``name`` is alive now (its row's ``heartbeat_at``); a working station calls it
        every `HEARTBEAT_S` (`tactip.station.heartbeat.Heartbeat`), and a dashboard shows a station that
        stopped beating while it should be working as offline."""
        self._refuse_if_read_only()
        self._write("UPDATE stations SET heartbeat_at = ? WHERE name = ?", (_now(), name))

    # -- reading -----------------------------------------------------------------------------
    def stations(self) -> list[dict]:
        """The stations' status rows (keys `STATION_FIELDS`), by name; [] for a database from before them."""
        for fields in (STATION_FIELDS, STATION_FIELDS[:-1]):  # a database from before heartbeats, read-only
            try:
                rows = self._query(f"SELECT {', '.join(fields)} FROM stations ORDER BY name")
            except ResultsError:
                continue
            out = [dict(zip(fields, r)) for r in rows]
            for row in out:  # a status row of a version before heartbeats: its update was its last sign of life
                row["heartbeat_at"] = row.get("heartbeat_at") or row["updated_at"]
            return out
        return []  # no stations table: written by an earlier version, opened read-only

    def inspections(self, *, limit: int | None = None, station: str | None = None) -> list[InspectionRow]:
        """Stored inspections, oldest first (the newest ``limit`` when given; of one ``station`` if given)."""
        where, params = ("", ()) if station is None else (" WHERE station = ?", (station,))
        if limit is not None and limit <= 0:
            return []
        if limit is None:
            rows = self._query(f"SELECT {', '.join(EXPORT_FIELDS)} FROM inspections{where} ORDER BY id", params)
        else:
            rows = self._query(f"SELECT {', '.join(EXPORT_FIELDS)} FROM inspections{where} ORDER BY id DESC "
                               f"LIMIT ?", (*params, int(limit)))[::-1]
        return [_row(r) for r in rows]

    def taps(self, inspection_id: int) -> list[dict]:
        """The taps of one inspection, in order, with their beliefs decoded (keys `TAP_FIELDS`)."""
        rows = self._query(f"SELECT {', '.join(TAP_FIELDS)} FROM taps WHERE inspection_id = ? ORDER BY tap",
                           (inspection_id,))
        return [_tap(dict(zip(TAP_FIELDS, r))) for r in rows]

    def taps_after(self, row_id: int, *, limit: int = 1000) -> list[dict]:
        """Taps stored with a row id above ``row_id``, in id order: the live feed of a dashboard.

        Each dict holds `TAP_FIELDS` plus ``id`` (the tap row's id), ``inspection_id``, ``gap``
        and ``station``. Row ids are unique but, with concurrent writers on PostgreSQL, not always
        committed in order: a reader that must miss none asks again a little below its last id.
        """
        fields = ", ".join(f"t.{name}" for name in TAP_FIELDS)
        rows = self._query(f"SELECT t.id, t.inspection_id, i.gap, i.station, {fields} FROM taps t JOIN inspections i "
                           f"ON i.id = t.inspection_id WHERE t.id > ? ORDER BY t.id LIMIT ?",
                           (int(row_id), int(limit)))
        return [_tap(dict(zip(("id", "inspection_id", "gap", "station", *TAP_FIELDS), r))) for r in rows]

    def last_tap_id(self) -> int:
        """The highest tap row id stored (0 when there is none)."""
        return int(self._query("SELECT COALESCE(MAX(id), 0) FROM taps")[0][0])

    def export_csv(self, rows: Iterable[InspectionRow] | None = None) -> str:
        """All inspections (or ``rows``) as CSV text with the `EXPORT_FIELDS` header."""
        buf = io.StringIO()
        writer = csv.DictWriter(buf, fieldnames=EXPORT_FIELDS, lineterminator="\n")
        writer.writeheader()
        for row in self.inspections() if rows is None else rows:
            writer.writerow({k: ("" if v is None else v) for k, v in row.as_dict().items()})
        return buf.getvalue()

    def export_json(self, rows: Iterable[InspectionRow] | None = None) -> str:
        """All inspections (or ``rows``) as a JSON list of objects."""
        return json.dumps([r.as_dict() for r in (self.inspections() if rows is None else rows)], indent=2)

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.path!r})"


def _process_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # exists, another user's (PermissionError), or cannot tell
        return True
    return True


def _opt(value) -> float | None:
    return None if value is None else float(value)


def _json_list(values) -> str | None:
    return None if values is None else json.dumps([round(float(v), 6) for v in values])


def _seconds(start_iso: str, end_iso: str) -> float:
    return (_dt.datetime.fromisoformat(end_iso) - _dt.datetime.fromisoformat(start_iso)).total_seconds()


def _row(values: tuple) -> InspectionRow:
    d = dict(zip(EXPORT_FIELDS, values))
    d["id"] = int(d["id"])
    d["decided"] = bool(d["decided"])
    d["passed"] = None if d["passed"] is None else bool(d["passed"])
    return InspectionRow(**d)


def _tap(d: dict) -> dict:
    for key in ("what_belief", "where_belief"):
        d[key] = None if d[key] is None else json.loads(d[key])
    for key in ("id", "inspection_id"):
        if key in d:
            d[key] = int(d[key])
    return d
