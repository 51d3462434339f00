"""One way to run independent pieces of work: in turn here, or through a map-like callable given.

Perception and the reproductions do no distribution themselves (they import no engine): a caller that
has one (`tactip.cluster`: Dask distributed) passes ``map_fn(function, items) -> results in order``,
and every experiment gives the same results either way, since each piece carries its own seed.
"""

from __future__ import annotations

from typing import Callable, Iterable

__all__ = ["map_pieces"]


def map_pieces(function: Callable, items: Iterable, *, map_fn: Callable | None = None,
               progress: Callable | None = None) -> list:
    """``[function(item) for item in items]``, here in turn or through ``map_fn``.

    Parameters
    ----------
    function : callable
        One piece of work; with ``map_fn`` it may run in another process (a module-level function,
        or a ``functools.partial`` of one, travels cheapest).
    items : iterable
    map_fn : callable, optional
        ``map_fn(function, items)``, returning the results in the items' order (e.g.
        `tactip.cluster.cluster_map`); it shows its own progress. Default: here, in turn.
    progress : callable, optional
        Wraps the items when they run here (e.g. ``tqdm``).

    Returns
    -------
    list
    """
    items = list(items)
    if map_fn is not None:
        return list(map_fn(function, items))
    return [function(item) for item in (progress or (lambda x: x))(items)]
