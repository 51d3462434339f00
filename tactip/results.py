"""The station's results store: one SQLite file, one row per inspection and one per tap.

Every write is committed at once (WAL journal), so a crash, a fault or Ctrl-C loses nothing
already stored. An inspection row is created when the inspection starts (``status='running'``),
each tap is added as it is taken, and the row is closed as ``done`` or ``aborted`` (with the reason).

Tables
------
inspections
    ``id``, ``gap``, ``nominal_width`` (mm), ``tolerance`` (mm), ``estimated_width`` (mm),
    ``estimated_depth`` (mm), ``belief`` (posterior of the decided width, 0-1), ``taps``,
    ``decided`` (0/1), ``passed`` (0/1, NULL when undecided or aborted), ``policy``,
    ``decision_threshold``, ``status`` (running/done/aborted), ``reason``, ``station``, ``model``,
    ``started_at`` / ``finished_at`` (ISO 8601 UTC), ``duration_s``.
taps
    ``inspection_id``, ``tap`` (1-based), ``depth_mm`` (commanded depth of the tap),
    ``location_estimate`` (mm), ``identity_estimate`` (mm), ``belief``, ``what_belief`` and
    ``where_belief`` (JSON lists: the marginal beliefs after the tap), ``at`` (ISO time).
"""

from __future__ import annotations

import csv
import datetime as _dt
import io
import json
import sqlite3
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Sequence

from .errors import TactipError

__all__ = ["ResultsStore", "InspectionRow", "EXPORT_FIELDS", "ResultsError", "plot_inspections"]

SCHEMA_VERSION = 1

EXPORT_FIELDS = (
    "id", "gap", "nominal_width", "tolerance", "estimated_width", "estimated_depth", "belief",
    "taps", "decided", "passed", "policy", "decision_threshold", "status", "reason",
    "station", "model", "started_at", "finished_at", "duration_s",
)

_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS inspections (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    gap TEXT NOT NULL,
    nominal_width REAL NOT NULL,
    tolerance REAL NOT NULL,
    estimated_width REAL,
    estimated_depth REAL,
    belief REAL,
    taps INTEGER NOT NULL DEFAULT 0,
    decided INTEGER NOT NULL DEFAULT 0,
    passed INTEGER,
    policy TEXT NOT NULL,
    decision_threshold REAL,
    status TEXT NOT NULL DEFAULT 'running',
    reason TEXT,
    station TEXT,
    model TEXT,
    started_at TEXT NOT NULL,
    finished_at TEXT,
    duration_s REAL
);
CREATE TABLE IF NOT EXISTS taps (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    inspection_id INTEGER NOT NULL REFERENCES inspections(id),
    tap INTEGER NOT NULL,
    depth_mm REAL NOT NULL,
    location_estimate REAL,
    identity_estimate REAL,
    belief REAL,
    what_belief TEXT,
    where_belief TEXT,
    at TEXT NOT NULL
);
CREATE INDEX IF NOT EXISTS taps_by_inspection ON taps(inspection_id, tap);
"""


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


class ResultsStore:
    """An SQLite results database; every write is committed immediately.

    Parameters
    ----------
    path : str or Path
        Database file; created (with its folder) if missing. ``":memory:"`` for tests.

    Examples
    --------
    >>> with ResultsStore(":memory:") as store:
    ...     i = store.start_inspection("g1", nominal_width=1.0, tolerance=0.25, policy="active")
    ...     store.record_tap(i, tap=1, depth_mm=2.0, identity_estimate=1.0, belief=0.5)
    ...     store.finish_inspection(i, estimated_width=1.0, estimated_depth=2.0, belief=0.95,
    ...                             taps=1, decided=True)
    ...     store.inspections()[0].passed
    True
    """

    def __init__(self, path: str | Path):
        self.path = str(path)
        if self.path != ":memory:":
            Path(self.path).parent.mkdir(parents=True, exist_ok=True)
        try:
            self._db = sqlite3.connect(self.path, isolation_level=None)  # autocommit: each write lands
            self._db.execute("PRAGMA journal_mode=WAL")
            self._db.executescript(_SCHEMA)
            version = self._db.execute("SELECT value FROM meta WHERE key='schema'").fetchone()
        except sqlite3.DatabaseError as exc:
            raise ResultsError(f"{self.path} is not a tactip results database ({exc})") from None
        if version is None:
            self._db.execute("INSERT INTO meta VALUES ('schema', ?)", (f"tactip-results/{SCHEMA_VERSION}",))
        elif version[0] != f"tactip-results/{SCHEMA_VERSION}":
            raise ResultsError(f"{self.path} holds results schema {version[0]!r}; "
                               f"this version reads tactip-results/{SCHEMA_VERSION}")

    # -- writing -----------------------------------------------------------------------------
    def start_inspection(self, gap: str, *, nominal_width: float, tolerance: float, policy: str,
                         decision_threshold: float | None = None, station: str | None = None,
                         model: str | None = None) -> int:
        """Open an inspection row (status ``running``) and return its id."""
        cur = self._db.execute(
            "INSERT INTO inspections (gap, nominal_width, tolerance, policy, decision_threshold,"
            " station, model, started_at) VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
            (gap, float(nominal_width), float(tolerance), policy,
             None if decision_threshold is None else float(decision_threshold), station, model, _now()),
        )
        return int(cur.lastrowid)

    def record_tap(self, inspection_id: int, *, tap: int, depth_mm: float,
                   location_estimate: float | None = None, identity_estimate: float | None = None,
                   belief: float | None = None, what_belief: Sequence[float] | None = None,
                   where_belief: Sequence[float] | None = None) -> None:
        """Store one tap of an inspection, with the beliefs after it, and bump the tap count."""
        self._db.execute("BEGIN")
        try:
            self._db.execute(
                "INSERT INTO taps (inspection_id, tap, depth_mm, location_estimate, identity_estimate,"
                " belief, what_belief, where_belief, at) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                (inspection_id, int(tap), float(depth_mm), _opt(location_estimate), _opt(identity_estimate),
                 _opt(belief), _json_list(what_belief), _json_list(where_belief), _now()),
            )
            self._db.execute("UPDATE inspections SET taps = ? WHERE id = ?", (int(tap), inspection_id))
            self._db.execute("COMMIT")
        except BaseException:
            self._db.execute("ROLLBACK")
            raise

    def finish_inspection(self, inspection_id: int, *, estimated_width: float | None,
                          estimated_depth: float | None, belief: float | None, taps: int,
                          decided: bool) -> bool | None:
        """Close an inspection as ``done``; returns pass (True/False), or None when undecided.

        Pass means a decided width within ``tolerance`` of ``nominal_width`` (mm).
        """
        nominal, tolerance, started = self._db.execute(
            "SELECT nominal_width, tolerance, started_at FROM inspections WHERE id = ?", (inspection_id,)
        ).fetchone()
        passed = None
        if decided and estimated_width is not None:
            passed = bool(abs(float(estimated_width) - nominal) <= tolerance + 1e-9)
        finished = _now()
        self._db.execute(
            "UPDATE inspections SET estimated_width=?, estimated_depth=?, belief=?, taps=?, decided=?,"
            " passed=?, status='done', finished_at=?, duration_s=? WHERE id=?",
            (_opt(estimated_width), _opt(estimated_depth), _opt(belief), int(taps), int(bool(decided)),
             None if passed is None else int(passed), finished, _seconds(started, finished), inspection_id),
        )
        return passed

    def abort_inspection(self, inspection_id: int, reason: str) -> None:
        """Close an inspection as ``aborted`` with the reason (taps stored so far are kept)."""
        started = self._db.execute("SELECT started_at FROM inspections WHERE id = ?",
                                   (inspection_id,)).fetchone()[0]
        finished = _now()
        self._db.execute(
            "UPDATE inspections SET status='aborted', reason=?, finished_at=?, duration_s=? WHERE id=?",
            (reason, finished, _seconds(started, finished), inspection_id),
        )

    # -- reading -----------------------------------------------------------------------------
    def inspections(self, *, limit: int | None = None) -> list[InspectionRow]:
        """Stored inspections, oldest first (the newest ``limit`` when given)."""
        query = f"SELECT {', '.join(EXPORT_FIELDS)} FROM inspections ORDER BY id"
        rows = self._db.execute(query).fetchall()
        if limit is not None:
            rows = rows[-limit:] if limit > 0 else []
        return [_row(r) for r in rows]

    def taps(self, inspection_id: int) -> list[dict]:
        """The taps of one inspection, in order, with their beliefs decoded."""
        cur = self._db.execute(
            "SELECT tap, depth_mm, location_estimate, identity_estimate, belief, what_belief,"
            " where_belief, at FROM taps WHERE inspection_id = ? ORDER BY tap", (inspection_id,))
        names = [d[0] for d in cur.description]
        out = []
        for r in cur.fetchall():
            d = dict(zip(names, r))
            for key in ("what_belief", "where_belief"):
                d[key] = None if d[key] is None else json.loads(d[key])
            out.append(d)
        return out

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

    def close(self) -> None:
        """Close the database connection."""
        self._db.close()

    def __enter__(self) -> "ResultsStore":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"ResultsStore({self.path!r})"


def _opt(value) -> float | None:
    return None if value is None else float(value)


def _json_list(values) -> str | None:
    return None if values is None else json.dumps([round(float(v), 6) for v in values])


def _seconds(start_iso: str, end_iso: str) -> float:
    return (_dt.datetime.fromisoformat(end_iso) - _dt.datetime.fromisoformat(start_iso)).total_seconds()


def _row(values: tuple) -> InspectionRow:
    d = dict(zip(EXPORT_FIELDS, values))
    d["decided"] = bool(d["decided"])
    d["passed"] = None if d["passed"] is None else bool(d["passed"])
    return InspectionRow(**d)


def plot_inspections(rows: Sequence[InspectionRow], path) -> None:
    """Estimated against nominal width of each finished inspection, with its tolerance band.

    Pass, fail and undecided verdicts get their own marker; aborted and running inspections are
    left out (they have no estimate). Written with matplotlib (Agg) to ``path`` (format from the
    suffix, e.g. ``.png``).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    done = [r for r in rows if r.status == "done" and r.estimated_width is not None]
    if not done:
        raise ResultsError("no finished inspections to plot")
    nominal = np.array([r.nominal_width for r in done])
    estimate = np.array([r.estimated_width for r in done])
    tolerance = np.array([r.tolerance for r in done])
    fig, ax = plt.subplots(figsize=(6, 5), layout="constrained")
    low, high = min(nominal.min(), estimate.min()), max(nominal.max(), estimate.max())
    pad = 0.05 * (high - low or 1.0)
    ax.plot([low - pad, high + pad], [low - pad, high + pad], color="0.6", lw=1, zorder=0)
    ax.errorbar(nominal, nominal, yerr=tolerance, fmt="none", ecolor="0.8", elinewidth=6, zorder=1,
                label="nominal ± tolerance")
    for verdict, marker, colour in ((True, "o", "tab:green"), (False, "x", "tab:red"), (None, "s", "tab:orange")):
        chosen = np.array([r.passed is verdict for r in done])
        if chosen.any():
            label = {True: "pass", False: "fail", None: "undecided"}[verdict]
            ax.scatter(nominal[chosen], estimate[chosen], marker=marker, color=colour, zorder=2,
                       label=f"{label} ({int(chosen.sum())})")
    error = np.abs(estimate - nominal)
    ax.set_xlabel("nominal width (mm)")
    ax.set_ylabel("estimated width (mm)")
    ax.set_title(f"{len(done)} inspections: mean |estimate - nominal| {error.mean():.2f} mm, "
                 f"mean {np.mean([r.taps for r in done]):.1f} taps", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left")
    fig.savefig(path, dpi=120)
    plt.close(fig)
