"""The station's results store: one SQLite file, one row per inspection and one per tap.

The embedded default backend (`tactip.line.results.postgres` is the one for a line of stations).
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
stations
    one row per station, replaced as it works: ``name``, ``state`` (ready, inspecting, stopped[: reason]),
    ``arm`` (``BACKEND: ready`` or what stops it), ``frame_rate`` (camera, frames/s), ``model``,
    ``host``, ``pid``, ``updated_at``, ``heartbeat_at`` (its last sign of life: written every few seconds
    while it works; added to older databases by the first writer that opens them).
"""

from __future__ import annotations

import contextlib
import errno
import functools
import os
import sqlite3
from pathlib import Path

from tactip._output import write_error
from tactip.line.results._store import SCHEMA_VERSION, ResultsError, ResultsStoreBase

__all__ = ["ResultsStore"]

# Columns added after the first schema (nullable; added to older databases when a writer opens them).
_ADDED_COLUMNS = {"inspections": {"pid": "INTEGER", "host": "TEXT"}, "stations": {"heartbeat_at": "TEXT"}}

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
CREATE TABLE IF NOT EXISTS stations (
    name TEXT PRIMARY KEY,
    state TEXT NOT NULL,
    arm TEXT,
    frame_rate REAL,
    model TEXT,
    host TEXT,
    pid INTEGER,
    updated_at TEXT NOT NULL,
    heartbeat_at TEXT
);
"""


@functools.lru_cache(maxsize=1)
def _our_columns() -> dict[str, frozenset]:
    """The columns of each table of our schema (read off `_SCHEMA` built in memory)."""
    with contextlib.closing(sqlite3.connect(":memory:")) as db:
        db.executescript(_SCHEMA)
        tables = [r[0] for r in db.execute("SELECT name FROM sqlite_master WHERE type='table'")]
        return {t: frozenset(r[1] for r in db.execute(f"PRAGMA table_info({t})")) for t in tables
                if t != "sqlite_sequence"}


class ResultsStore(ResultsStoreBase):
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
    ...     _ = store.finish_inspection(i, estimated_width=1.0, estimated_depth=2.0, belief=0.95,
    ...                                 taps=1, decided=True)
    ...     store.inspections()[0].passed
    True
    """

    #: A reader that polls must open the file anew for each poll (`tactip.line.dashboard.feed`): when the last
    #: writer process exits, SQLite deletes the -wal and -shm files, and a connection kept open across that
    #: (with every other connection of its process, which share its -shm mapping) goes on reading a stale
    #: index: old rows, or "database disk image is malformed".
    reopen_to_poll = True

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
                for table, added in _ADDED_COLUMNS.items():
                    columns = {row[1] for row in self._db.execute(f"PRAGMA table_info({table})")}
                    for name, kind in added.items():
                        if name not in columns:
                            with contextlib.suppress(sqlite3.OperationalError):  # added by a concurrent writer
                                self._db.execute(f"ALTER TABLE {table} ADD COLUMN {name} {kind}")
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
        # SQLite reads the header, never open(): closing any descriptor of the file drops every POSIX lock this
        # process holds on it, its connections' too; a writer process exiting then takes itself for the last one
        # and deletes the -wal and -shm under them (a dashboard read "database disk image is malformed").
        if path.stat().st_size:
            try:
                with contextlib.closing(_connect_read_only(path)) as db:
                    tables = {r[0] for r in db.execute("SELECT name FROM sqlite_master WHERE type='table'")}
                    schema = None
                    if "meta" in tables:
                        with contextlib.suppress(sqlite3.Error):      # a foreign 'meta' may have other columns
                            row = db.execute("SELECT value FROM meta WHERE key='schema'").fetchone()
                            schema = row and row[0]
                    columns = {t: {r[1] for r in db.execute(f"PRAGMA table_info({t})")}
                               for t in tables & set(_our_columns())}
            except sqlite3.Error as exc:
                if "not a database" in str(exc):
                    raise ResultsError(f"{path} is not a tactip results database (not an SQLite file); it was left "
                                       f"unchanged") from None
                raise self._error(exc, "reading") from None
            # A database whose creation was cut short (disk full) holds some of our tables, each with our
            # columns (older versions lack the added ones), and no schema row yet.
            stamped = schema is not None and str(schema).startswith("tactip-results/")
            foreign = [t for t, have in columns.items() if not _our_columns()[t] - set(_ADDED_COLUMNS.get(t, ())) <= have]
            ours = stamped or (tables <= {*_our_columns(), "sqlite_sequence"} and not foreign)
            if tables - {"sqlite_sequence"} and not ours:
                names = ", ".join(sorted(foreign or (tables - {"sqlite_sequence"}))[:5])
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

    def _make_room(self) -> bool:
        """On a full disk: checkpoint the write-ahead log into the database and truncate it, so that the last
        word of an inspection (its row closed as aborted) finds room in it again."""
        try:
            busy, _, _ = self._db.execute("PRAGMA wal_checkpoint(TRUNCATE)").fetchone()
        except sqlite3.Error:
            return False
        return not busy

    def _write(self, sql: str, params=()) -> list[tuple]:
        self._refuse_if_read_only()
        try:
            return self._db.execute(sql, params).fetchall()
        except sqlite3.Error as exc:
            raise self._error(exc, "writing") from None

    def _query(self, sql: str, params=()) -> list[tuple]:
        try:
            return self._db.execute(sql, params).fetchall()
        except sqlite3.Error as exc:
            raise self._error(exc, "reading") from None

    @contextlib.contextmanager
    def _transaction(self):
        # BEGIN IMMEDIATE takes the write lock at once: a concurrent writer waits (busy_timeout)
        # instead of failing half-way through the transaction.
        self._write("BEGIN IMMEDIATE")
        try:
            yield
            self._write("COMMIT")
        except BaseException:
            with contextlib.suppress(sqlite3.Error):
                self._db.execute("ROLLBACK")
            raise

    def close(self) -> None:
        """Close the database connection."""
        self._db.close()


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


def _disk_full(path: str) -> bool:
    try:
        stat = os.statvfs(os.path.dirname(os.path.abspath(path)))
    except OSError:
        return False
    return stat.f_bavail * stat.f_frsize < 64 * 1024
