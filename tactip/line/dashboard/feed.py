"""The live feed: one thread polls the results store and hands new taps and changed inspections to every page.

Polling the store (every `POLL_S`) works the same for SQLite and PostgreSQL and for a station on
another host: the dashboard needs nothing from the station but its database. Tap row ids are
unique, but concurrent PostgreSQL writers may commit them out of order, so each poll asks again
from `LOOKBACK_IDS` below the highest id seen and drops the ids already sent.
"""

from __future__ import annotations

import asyncio
import threading
from typing import Callable

__all__ = ["LiveFeed", "FeedState", "POLL_S", "LOOKBACK_IDS"]

#: Time between two polls of the store, s: the bulk of a tap's delay to the page.
POLL_S = 0.1
#: How far below the highest tap id seen each poll looks again (ids committed late), rows.
LOOKBACK_IDS = 256
#: Inspections whose status and tap count are compared at each poll (the newest), rows.
WATCHED_INSPECTIONS = 100


class FeedState:
    """What has been sent: the tap ids and the inspections' (status, taps). `poll` returns the news.

    Parameters
    ----------
    store : ResultsStoreBase
        The store to poll; its current contents are taken as already sent (history is read by
        the page itself).
    """

    def __init__(self, store):
        self.cursor = store.last_tap_id()
        # The taps within the look-back are history too: not to be sent again by the first poll.
        self.sent: set[int] = {t["id"] for t in store.taps_after(max(0, self.cursor - LOOKBACK_IDS))}
        self.inspections = {r.id: (r.status, r.taps) for r in store.inspections(limit=WATCHED_INSPECTIONS)}
        self.stations = {s["name"]: _status(s) for s in store.stations()}

    def poll(self, store) -> list[tuple[str, dict]]:
        """News since the last poll, as (event, data): ``station`` (changed status rows) first, then inspection
        by inspection in id order, each as the page must see it: a new or running ``inspection`` row before its
        new ``tap`` rows, a finished one (``done``, ``aborted``) after them.

        So a page always has an inspection's deciding tap before its verdict, and the verdict before the next
        inspection of the station starts, even when one poll catches all of it.
        """
        events = []
        for s in store.stations():  # a heartbeat alone is no news: pages judge silence from their state reads
            if self.stations.get(s["name"]) != _status(s):
                self.stations[s["name"]] = _status(s)
                events.append(("station", s))
        changed = {}
        for r in store.inspections(limit=WATCHED_INSPECTIONS):
            key = (r.status, r.taps)
            if self.inspections.get(r.id) != key:
                self.inspections[r.id] = key
                changed[r.id] = r.as_dict()
        if len(self.inspections) > 4 * WATCHED_INSPECTIONS:
            keep = sorted(self.inspections)[-2 * WATCHED_INSPECTIONS:]
            self.inspections = {k: self.inspections[k] for k in keep}
        # Read after the inspections: every tap of an inspection seen finished is among these.
        taps: dict[int, list[dict]] = {}
        for tap in store.taps_after(max(0, self.cursor - LOOKBACK_IDS)):
            if tap["id"] in self.sent or tap["id"] <= self.cursor - LOOKBACK_IDS:
                continue
            self.sent.add(tap["id"])
            self.cursor = max(self.cursor, tap["id"])
            taps.setdefault(tap["inspection_id"], []).append(tap)
        self.sent = {i for i in self.sent if i > self.cursor - LOOKBACK_IDS}
        for inspection_id in sorted(set(changed) | set(taps)):
            row = changed.get(inspection_id)
            running = row is not None and row["status"] == "running"
            if running:
                events.append(("inspection", row))
            events.extend(("tap", tap) for tap in sorted(taps.get(inspection_id, []), key=lambda t: t["tap"]))
            if row is not None and not running:
                events.append(("inspection", row))
        return events


class LiveFeed:
    """A polling thread fanning out store events to asyncio subscribers (one queue per page).

    Parameters
    ----------
    open_store : callable
        Returns a new read-only store (the thread keeps its own connection). While it fails
        (no database yet, server unreachable) the feed retries every second and reports the
        error in `status`.
    poll_s : float
        Time between polls, s.
    """

    def __init__(self, open_store: Callable, *, poll_s: float = POLL_S):
        self._open_store = open_store
        self.poll_s = float(poll_s)
        self._subscribers: list[tuple[asyncio.AbstractEventLoop, asyncio.Queue]] = []
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.status = "starting"

    def start(self) -> None:
        """Start the polling thread."""
        self._thread = threading.Thread(target=self._run, name="tactip-dashboard-feed", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stop the thread and end every subscriber's stream."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(5)
        with self._lock:
            for loop, queue in self._subscribers:
                loop.call_soon_threadsafe(queue.put_nowait, None)

    def subscribe(self) -> asyncio.Queue:
        """A queue of (event, data) for the calling event loop; None in it means the feed ended."""
        queue: asyncio.Queue = asyncio.Queue(maxsize=10_000)
        with self._lock:
            self._subscribers.append((asyncio.get_running_loop(), queue))
        return queue

    def unsubscribe(self, queue: asyncio.Queue) -> None:
        """Forget a subscriber's queue."""
        with self._lock:
            self._subscribers = [(loop, q) for loop, q in self._subscribers if q is not queue]

    def _publish(self, events) -> None:
        with self._lock:
            subscribers = list(self._subscribers)
        for loop, queue in subscribers:
            for event in events:
                loop.call_soon_threadsafe(_put, queue, event)

    def _run(self) -> None:
        store = state = None
        while not self._stop.is_set():
            try:
                store = store or self._open_store()
                try:
                    state = state or FeedState(store)
                    events = state.poll(store)
                except Exception:
                    if getattr(store, "reopen_to_poll", False):
                        raise
                    # A kept connection (PostgreSQL) that the server dropped: one more try on a new one.
                    _close_quietly(store)
                    store = self._open_store()
                    state = state or FeedState(store)
                    events = state.poll(store)
                if getattr(store, "reopen_to_poll", False):
                    # SQLite: no connection outlives a poll, so a writer's exit (which deletes the -wal and
                    # -shm files under a reader still holding them) can never leave this process reading stale
                    # or "malformed" pages.
                    _close_quietly(store)
                    store = None
                self._set_status("live")
            except Exception as exc:  # the database went away or is not there yet: say so and retry
                self._set_status(f"cannot read the results database: {' '.join(str(exc).split())}")
                if store is not None:
                    _close_quietly(store)
                store = None
                self._stop.wait(1.0)
                continue
            if events:
                self._publish(events)
            self._stop.wait(self.poll_s)
        if store is not None:
            _close_quietly(store)

    def _set_status(self, status: str) -> None:
        """Change `status`, telling every page (a ``status`` event) when it changes."""
        if status != self.status:
            self.status = status
            self._publish([("status", {"feed": status, "live": status == "live"})])


def _status(station: dict) -> dict:
    return {k: v for k, v in station.items() if k != "heartbeat_at"}


def _put(queue: asyncio.Queue, event) -> None:
    try:
        queue.put_nowait(event)
    except asyncio.QueueFull:  # a page that stopped reading: it refetches the state when it reconnects
        pass


def _close_quietly(store) -> None:
    try:
        store.close()
    except Exception:
        pass
