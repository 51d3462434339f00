"""The station's results store: one row per inspection and one per tap, written as they happen.

Two backends behind one interface (`ResultsStoreBase`): SQLite, the embedded default (one file on
the station's disk, `ResultsStore`), and PostgreSQL, for a line of stations writing to one database
the plant runs (`PostgresResultsStore`). `open_results` picks the backend from the location: a
``postgresql://`` (or ``postgres://``) URL, else a file path. Both hold the same tables (columns in
`tactip.line.results.sqlite`), commit every tap with its count in one transaction, and mark each row
with its station.

Examples
--------
>>> from tactip.line.results import open_results
>>> with open_results(":memory:") as store:
...     i = store.start_inspection("g1", nominal_width=1.0, tolerance=0.25, policy="active", station="line-1")
...     store.record_tap(i, tap=1, depth_mm=2.0, identity_estimate=1.0, belief=0.5)
...     store.finish_inspection(i, estimated_width=1.0, estimated_depth=2.0, belief=0.95, taps=1, decided=True)
True
"""

from __future__ import annotations

from pathlib import Path

from tactip.line import HEARTBEAT_S
from tactip.line.results._store import (EXPORT_FIELDS, STATION_FIELDS, TAP_FIELDS, InspectionRow, ResultsError,
                                        ResultsStoreBase)
from tactip.line.results.capability import process_capability
from tactip.line.results.plot import plot_inspections
from tactip.line.results.sqlite import ResultsStore

__all__ = ["ResultsStore", "ResultsStoreBase", "PostgresResultsStore", "InspectionRow", "EXPORT_FIELDS",
           "TAP_FIELDS", "STATION_FIELDS", "ResultsError", "plot_inspections", "open_results", "is_database_url",
           "describe_location", "process_capability", "HEARTBEAT_S"]

_URL_SCHEMES = ("postgresql://", "postgres://")


def is_database_url(location) -> bool:
    """Whether ``location`` names a PostgreSQL database (a ``postgresql://`` URL) rather than a file."""
    return isinstance(location, str) and location.lower().startswith(_URL_SCHEMES)


def describe_location(location) -> str:
    """``location`` as it may be printed: a database URL without its password."""
    if not is_database_url(location):
        return str(location)
    from tactip.line.results.postgres import redact_url

    return redact_url(location)


def open_results(location: str | Path, *, read_only: bool = False) -> ResultsStoreBase:
    """The results store at ``location``: a PostgreSQL URL or an SQLite file path.

    Parameters
    ----------
    location : str or Path
        ``postgresql://user@host:port/db`` (the PostgreSQL backend, psycopg 3 from the ``line``
        extra) or a file path (SQLite, created when missing unless ``read_only``).
    read_only : bool
        Open for reading only (``tactip results``, the dashboard); every write is refused.

    Returns
    -------
    ResultsStoreBase
        A `ResultsStore` (SQLite) or a `PostgresResultsStore`; close it (or use ``with``).
    """
    if is_database_url(location):
        from tactip.line.results.postgres import PostgresResultsStore

        return PostgresResultsStore(str(location), read_only=read_only)
    return ResultsStore(location, read_only=read_only)


def __getattr__(name):  # PostgresResultsStore without importing psycopg for SQLite users
    if name == "PostgresResultsStore":
        from tactip.line.results.postgres import PostgresResultsStore

        return PostgresResultsStore
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
