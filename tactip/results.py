"""The station's results store: one SQLite file, one row per inspection and one per tap.

Every write is committed at once (WAL journal), so a crash, a fault or Ctrl-C loses nothing
already stored. An inspection row is created when the inspection starts (``status='running'``),
each tap is added as it is taken, and the row is closed as ``done`` or ``aborted`` (with the reason).
A row left ``running`` by a process that died (SIGKILL, power cut) is closed as aborted by the next
inspection of its station (`ResultsStore.close_stale_inspections`); concurrent inspections, whose
processes are alive, are left alone.

An existing file is checked before anything is written to it: another SQLite database (or any
other file) is refused unchanged. Readers (``tactip results``) open the file read-only, so they
work in a read-only folder. Write errors are named for what they are ("disk full while writing X").

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

import contextlib
import csv
import datetime as _dt
import errno
import functools
import io
import json
import os
import socket
import sqlite3
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Sequence

from ._output import write_error
from .errors import TactipError

__all__ = ["ResultsStore", "InspectionRow", "EXPORT_FIELDS", "ResultsError", "plot_inspections"]

SCHEMA_VERSION = 1
#: A ``running`` inspection older than this is closed as stale even if its process cannot be checked
#: (another host, or a row from before the ``pid`` column), s.
STALE_AFTER_S = 24 * 3600.0
_HOST = socket.gethostname()
_SQLITE_MAGIC = b"SQLite format 3\x00"
# Columns added after the first schema (nullable; added to older databases when a writer opens them).
_ADDED_COLUMNS = {"pid": "INTEGER", "host": "TEXT"}

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

    def __init__(self, path: str | Path, *, read_only: bool = False):
        self.path = str(path)
        self.read_only = bool(read_only)
        memory = self.path == ":memory:"
        if not memory:
            self._check_before_opening(Path(self.path))
        try:
            if memory:
                self._db = sqlite3.connect(self.path, isolation_level=None)
            elif read_only:
                self._db = _connect_read_only(Path(self.path))
            else:
                self._db = sqlite3.connect(self.path, isolation_level=None)  # autocommit: each write lands
            if read_only:
                tables = {r[0] for r in self._db.execute("SELECT name FROM sqlite_master WHERE type='table'")}
                if not {"meta", "inspections", "taps"} <= tables:
                    raise ResultsError(f"{self.path} holds no inspections yet (its creation was cut short)")
                version = self._db.execute("SELECT value FROM meta WHERE key='schema'").fetchone()
                version = version or (f"tactip-results/{SCHEMA_VERSION}",)  # cut short before the schema row
            else:
                self._db.execute("PRAGMA busy_timeout=10000")  # concurrent inspections share the file
                self._db.execute("PRAGMA journal_mode=WAL")
                self._db.executescript(_SCHEMA)
                columns = {row[1] for row in self._db.execute("PRAGMA table_info(inspections)")}
                for name, kind in _ADDED_COLUMNS.items():
                    if name not in columns:
                        with contextlib.suppress(sqlite3.OperationalError):  # added by a concurrent writer
                            self._db.execute(f"ALTER TABLE inspections ADD COLUMN {name} {kind}")
                version = self._db.execute("SELECT value FROM meta WHERE key='schema'").fetchone()
                if version is None:
                    self._db.execute("INSERT OR IGNORE INTO meta VALUES ('schema', ?)",
                                     (f"tactip-results/{SCHEMA_VERSION}",))
                    version = (f"tactip-results/{SCHEMA_VERSION}",)
        except sqlite3.Error as exc:
            raise self._error(exc, "opening") from None
        if version is None:
            raise ResultsError(f"{self.path} is not a tactip results database (no schema)")
        if version[0] != f"tactip-results/{SCHEMA_VERSION}":
            raise ResultsError(f"{self.path} holds results schema {version[0]!r}; "
                               f"this version reads tactip-results/{SCHEMA_VERSION}")

    def _check_before_opening(self, path: Path) -> None:
        """Refuse, without changing it, a file that is not ours; name permission problems as such."""
        if path.is_dir():
            raise ResultsError(f"{path} is a folder, not a results database")
        if not path.exists():
            if self.read_only:
                raise ResultsError(f"no results database at {path} (nothing inspected yet?)")
            try:
                path.parent.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise OSError(exc.errno, f"cannot create the results folder {str(path.parent)!r} "
                                         f"({exc.strerror})") from None
            if not os.access(path.parent, os.W_OK):
                raise PermissionError(errno.EACCES, f"permission denied writing the results database {str(path)!r} "
                                                    f"(its folder is read-only)")
            return
        if not os.access(path, os.R_OK):
            raise PermissionError(errno.EACCES, f"permission denied reading {str(path)!r}")
        with open(path, "rb") as f:
            head = f.read(len(_SQLITE_MAGIC))
        if head and head != _SQLITE_MAGIC:
            raise ResultsError(f"{path} is not a tactip results database (not an SQLite file); it was left unchanged")
        if head:
            try:
                with contextlib.closing(_connect_read_only(path)) as db:
                    tables = {r[0] for r in db.execute("SELECT name FROM sqlite_master WHERE type='table'")}
                    schema = None
                    if "meta" in tables:
                        row = db.execute("SELECT value FROM meta WHERE key='schema'").fetchone()
                        schema = row and row[0]
            except sqlite3.Error as exc:
                raise self._error(exc, "reading") from None
            # A database whose creation was cut short (disk full) holds some of our tables and no schema yet.
            ours = (schema is not None and str(schema).startswith("tactip-results/")) or \
                tables <= {"meta", "inspections", "taps", "sqlite_sequence"}
            if tables - {"sqlite_sequence"} and not ours:
                names = ", ".join(sorted(tables - {"sqlite_sequence"})[:5])
                raise ResultsError(f"{path} is another SQLite database (tables {names}), not tactip results; "
                                   f"it was left unchanged: choose another results file")
        if not self.read_only:
            for where, what in ((path, "the results database"), (path.parent, "the results folder")):
                if not os.access(where, os.W_OK):
                    raise PermissionError(errno.EACCES, f"permission denied writing {what} {str(where)!r}")

    def _error(self, exc: sqlite3.Error, doing: str) -> Exception:
        """An SQLite error as the user should read it: disk full, permission, or not a results database."""
        text = str(exc).lower()
        if "disk is full" in text or "disk i/o" in text and _disk_full(self.path):
            return write_error(OSError(errno.ENOSPC, str(exc)), self.path)
        if "readonly" in text or "read-only" in text or "permission" in text:
            return PermissionError(errno.EACCES, f"permission denied {doing} {self.path!r} ({exc})")
        if "locked" in text or "busy" in text:
            return ResultsError(f"{self.path} is locked by another process ({exc})")
        if "not a database" in text or "malformed" in text or "unable to open" in text:
            return ResultsError(f"{self.path} is not a tactip results database ({exc})")
        return ResultsError(f"{self.path}: {exc}")

    def _write(self, sql: str, params=()) -> sqlite3.Cursor:
        if self.read_only:
            raise ResultsError(f"{self.path} was opened read-only (for reading results)")
        try:
            return self._db.execute(sql, params)
        except sqlite3.Error as exc:
            raise self._error(exc, "writing") from None

    def close_stale_inspections(self, station: str | None, *, max_age_s: float = STALE_AFTER_S) -> list[int]:
        """Close as aborted the ``running`` rows of ``station`` whose process is gone; returns their ids.

        A row is stale when it was started on this host by a process that no longer exists, or
        (another host, or no process recorded) when it started more than ``max_age_s`` ago. Rows of
        live processes (concurrent inspections) and of other stations are left alone.
        """
        rows = self._db.execute("SELECT id, pid, host, started_at FROM inspections WHERE status='running' AND "
                                "station IS ?", (station,)).fetchall()
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

    # -- writing -----------------------------------------------------------------------------
    def start_inspection(self, gap: str, *, nominal_width: float, tolerance: float, policy: str,
                         decision_threshold: float | None = None, station: str | None = None,
                         model: str | None = None) -> int:
        """Open an inspection row (status ``running``) and return its id."""
        cur = self._write(
            "INSERT INTO inspections (gap, nominal_width, tolerance, policy, decision_threshold,"
            " station, model, started_at, pid, host) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
            (gap, float(nominal_width), float(tolerance), policy,
             None if decision_threshold is None else float(decision_threshold), station, model, _now(),
             os.getpid(), _HOST),
        )
        return int(cur.lastrowid)

    def record_tap(self, inspection_id: int, *, tap: int, depth_mm: float,
                   location_estimate: float | None = None, identity_estimate: float | None = None,
                   belief: float | None = None, what_belief: Sequence[float] | None = None,
                   where_belief: Sequence[float] | None = None) -> None:
        """Store one tap of an inspection, with the beliefs after it, and bump the tap count."""
        self._write("BEGIN")
        try:
            self._write(
                "INSERT INTO taps (inspection_id, tap, depth_mm, location_estimate, identity_estimate,"
                " belief, what_belief, where_belief, at) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                (inspection_id, int(tap), float(depth_mm), _opt(location_estimate), _opt(identity_estimate),
                 _opt(belief), _json_list(what_belief), _json_list(where_belief), _now()),
            )
            self._write("UPDATE inspections SET taps = ? WHERE id = ?", (int(tap), inspection_id))
            self._write("COMMIT")
        except BaseException:
            with contextlib.suppress(sqlite3.Error):
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
        self._write(
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
        self._write(
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


def _connect_read_only(path: Path) -> sqlite3.Connection:
    """A read-only connection that changes nothing; in a read-only folder (no -shm file possible), immutable."""
    uri = Path(os.path.abspath(path)).as_uri()
    try:
        db = sqlite3.connect(f"{uri}?mode=ro", uri=True, isolation_level=None)
        db.execute("SELECT count(*) FROM sqlite_master").fetchone()
        return db
    except sqlite3.OperationalError:
        if os.access(path.parent, os.W_OK):
            raise
    db = sqlite3.connect(f"{uri}?immutable=1", uri=True, isolation_level=None)
    db.execute("SELECT count(*) FROM sqlite_master").fetchone()
    return db


def _process_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, another user's
        return True
    except OSError:
        return True
    return True


def _disk_full(path: str) -> bool:
    try:
        stat = os.statvfs(os.path.dirname(os.path.abspath(path)))
    except OSError:
        return False
    return stat.f_bavail * stat.f_frsize < 64 * 1024


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


def plot_inspections(rows: Sequence[InspectionRow], path, *, inputs=()) -> None:
    """Estimated against nominal width of each finished inspection, with its tolerance band.

    Pass, fail and undecided verdicts get their own marker; aborted and running inspections are
    left out (they have no estimate). Written with matplotlib (Agg) to ``path`` (format from the
    suffix, e.g. ``.png``), atomically; ``path`` must not be one of ``inputs`` (the database).
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
    from ._output import atomic_output

    try:
        with atomic_output(path, inputs=inputs) as tmp:
            fig.savefig(tmp, dpi=120, format=Path(path).suffix.lstrip(".") or "png")
    finally:
        plt.close(fig)
