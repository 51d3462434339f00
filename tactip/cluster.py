"""Work spread over Dask distributed: an embedded local cluster, or a real one at a scheduler's address.

An archive of recordings, a fixation sweep or a reproduction's seeds are independent pieces of work.
They run on Dask distributed (the well-kept standard engine for Python; no home-made pool):

- `open_client`: a context manager yielding a ``distributed.Client``, on an embedded local cluster
  (one single-threaded worker process per core by default, bound to 127.0.0.1, no dashboard) or
  connected to the scheduler at ``tcp://HOST:PORT`` (``dask scheduler`` and ``dask worker``,
  started by hand or by a cluster manager), closed on the way out;
- `cluster_map`: a map-like callable ``map_fn(function, items) -> list`` that runs on a client, in
  order, with a progress bar: what `perception.fixation_sweep` and `tactip.reproduce.reproduce` take,
  so that perception never imports Dask.

Workers of a real cluster must be able to import ``tactip`` (the same version) and to read and write
the same paths as the machine that submits (a shared file system).

Example
-------
>>> with open_client(workers=2) as client:                        # doctest: +SKIP
...     squares = cluster_map(client)(pow, [(1, 2), (3, 2)])
"""

from __future__ import annotations

import contextlib
import os
from typing import Callable, Iterable, Iterator

from tactip.errors import TactipError

__all__ = ["open_client", "cluster_map", "default_workers", "LOOPBACK_ONLY"]

#: Seconds to wait for a scheduler named by its address, and then for one of its workers, before giving up.
CONNECT_TIMEOUT_S = 10.0

#: An embedded cluster listens on the loopback only: no dashboard, and the scheduler's own HTTP server
#: (health checks, which it always starts, by default on port 8787 of its host) on a free loopback port.
#: Worker processes reach the scheduler over TCP on 127.0.0.1; worker threads in process.
LOOPBACK_ONLY = dict(dashboard_address=None, scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})


def default_workers() -> int:
    """Workers of the embedded cluster by default: one per core this process may run on."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


@contextlib.contextmanager
def open_client(scheduler: str | None = None, *, workers: int | None = None, processes: bool = True,
                threads_per_worker: int = 1) -> Iterator:
    """A Dask ``Client``: on an embedded local cluster, or on the scheduler at ``scheduler``.

    Parameters
    ----------
    scheduler : str, optional
        ``tcp://HOST:PORT`` of a running ``dask scheduler``; default an embedded local cluster.
    workers : int, optional
        Workers of the embedded cluster (default `default_workers`, one per core); not with `scheduler`.
    processes : bool
        Embedded workers as processes (default: OpenCV's thread pool and the GIL are per process) or
        as threads of this process (tests).
    threads_per_worker : int
        Tasks each embedded worker runs at once (default 1: a replay already uses two threads).

    Yields
    ------
    distributed.Client

    Raises
    ------
    ValueError
        `workers` below 1, or given with `scheduler`.
    TactipError
        The scheduler cannot be reached, or has no worker, within `CONNECT_TIMEOUT_S`.
    """
    from distributed import Client, LocalCluster

    if scheduler is not None and workers is not None:
        raise ValueError("workers sets the embedded cluster's size; a cluster at a scheduler has its own workers")
    if workers is not None and (int(workers) != workers or workers < 1):
        raise ValueError(f"workers must be a positive integer, got {workers}")
    if scheduler is None:
        with LocalCluster(n_workers=int(workers or default_workers()), threads_per_worker=int(threads_per_worker),
                          processes=processes, silence_logs=40, **LOOPBACK_ONLY,
                          **(dict(host="127.0.0.1") if processes else {})) as cluster, Client(cluster) as client:
            yield client
        return
    try:
        client = Client(scheduler, timeout=CONNECT_TIMEOUT_S)
    except (OSError, TimeoutError, ValueError) as exc:
        raise TactipError(f"cannot reach the Dask scheduler at {scheduler} ({type(exc).__name__}: "
                          f"{str(exc).splitlines()[0] if str(exc) else 'no answer'}); start one with "
                          f"'dask scheduler' and give its tcp://HOST:PORT") from None
    with client:
        try:  # tasks sent to a cluster without workers would wait for ever
            client.wait_for_workers(1, timeout=CONNECT_TIMEOUT_S)
        except TimeoutError:
            raise TactipError(f"the Dask scheduler at {scheduler} has no workers (none joined within "
                              f"{CONNECT_TIMEOUT_S:g} s); start them with 'dask worker {scheduler}'") from None
        yield client


def cluster_map(client, *, progress: Callable | None = None) -> Callable[[Callable, Iterable], list]:
    """A map-like callable running each item on ``client``'s workers: ``map_fn(function, items) -> list``.

    The results come back in the items' order, whatever order the workers finish in; an error of
    any item is raised (after the others are cancelled), as the builtin ``map`` would. The function
    and items are sent to the workers (pickled), so a module-level function is cheapest.

    Parameters
    ----------
    client : distributed.Client
    progress : callable, optional
        Called as ``progress(total=N)`` to make a bar with ``update(1)`` and ``close()`` (e.g. a
        ``functools.partial`` of ``tqdm``); ticks once per finished item.

    Returns
    -------
    callable
        ``map_fn(function, items) -> list`` of ``function(item)`` for each item.
    """
    def map_fn(function: Callable, items: Iterable) -> list:
        from distributed import as_completed

        items = list(items)
        if not items:
            return []
        # The function (often a partial holding a whole environment) goes to the cluster once, not per item.
        shared = client.scatter(function, broadcast=True, hash=False)
        futures = client.map(_apply, items, function=shared, pure=False)
        bar = progress(total=len(items)) if progress is not None else None
        try:
            for future in as_completed(futures):
                future.result()  # raises the item's error here, at once
                if bar is not None:
                    bar.update(1)
            return client.gather(futures)
        finally:
            if bar is not None:
                bar.close()
            client.cancel([f for f in futures if not f.done()])
            client.cancel([shared])

    return map_fn


def _apply(item, function):
    """``function(item)`` on a worker (`cluster_map`'s task; the function arrives as scattered data)."""
    return function(item)
