"""The station's heartbeat: a thread that writes "alive" to the results store every few seconds while it works.

A dashboard cannot tell a station that is thinking from one that was killed (SIGKILL, power cut): both leave
an inspection ``running``. So while `tactip.station.inspection.inspect_station` works, a `Heartbeat` stamps
the station's status row every `HEARTBEAT_S` (`ResultsStoreBase.heartbeat`); a station that should be working
and has not beaten for longer than the dashboard's ``offline_after_s`` is shown offline.

The thread has its own connection (an SQLite connection belongs to one thread; PostgreSQL's would serialise
with the taps). A failed beat is retried at the next one: the inspection's own writes report store errors.
"""

from __future__ import annotations

import threading
from typing import Callable

from tactip.line.results import HEARTBEAT_S, ResultsStoreBase

__all__ = ["Heartbeat"]


class Heartbeat:
    """Beat for station ``name`` every ``period_s`` in a background thread (``with`` starts and stops it).

    Parameters
    ----------
    open_store : callable
        Returns a new writable results store for the thread (`tactip.line.results.open_results`).
    name : str
        The station (``[station] name``).
    period_s : float
        Time between two beats, s.

    Examples
    --------
    >>> with Heartbeat(lambda: open_results("results.sqlite"), "cell-1"):   # doctest: +SKIP
    ...     inspect()
    """

    def __init__(self, open_store: Callable[[], ResultsStoreBase], name: str, *, period_s: float = HEARTBEAT_S):
        if not period_s > 0:
            raise ValueError(f"period_s must be > 0, got {period_s!r}")
        self._open_store, self.name, self.period_s = open_store, name, float(period_s)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.beats = 0

    def __repr__(self) -> str:
        return f"Heartbeat({self.name!r}, period_s={self.period_s:g})"

    def start(self) -> "Heartbeat":
        """Start beating (the first beat at once)."""
        self._thread = threading.Thread(target=self._run, name=f"tactip-heartbeat-{self.name}", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop beating and wait for the thread."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(10)

    def _run(self) -> None:
        store = None
        try:
            while not self._stop.is_set():
                try:
                    store = store or self._open_store()
                    store.heartbeat(self.name)
                    self.beats += 1
                except Exception:  # the store is busy or gone: the inspection's own writes say why
                    if store is not None:
                        _close_quietly(store)
                    store = None
                self._stop.wait(self.period_s)
        finally:
            if store is not None:
                _close_quietly(store)

    def __enter__(self) -> "Heartbeat":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()


def _close_quietly(store) -> None:
    try:
        store.close()
    except Exception:
        pass
