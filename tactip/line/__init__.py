"""The line: the results stores (SQLite, PostgreSQL) and the live dashboard that reads them.

- `tactip.line.results`: one row per inspection and per tap, written as they happen;
- `tactip.line.dashboard`: the read-only live page (`tactip serve`).
"""

__all__ = ["HEARTBEAT_S", "OFFLINE_AFTER_S"]

#: How often a working station writes its heartbeat to the results store, s.
HEARTBEAT_S = 2.0
#: A working station silent for longer than this is shown offline by the dashboard, s: a few missed beats.
OFFLINE_AFTER_S = 5 * HEARTBEAT_S
