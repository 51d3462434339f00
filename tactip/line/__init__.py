"""The line: the results stores (SQLite, PostgreSQL) and the live dashboard that reads them.

- `tactip.line.results`: one row per inspection and per tap, written as they happen;
- `tactip.line.dashboard`: the read-only live page (`tactip serve`).
"""

__all__: list[str] = []
