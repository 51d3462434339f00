"""SIGTERM handled like Ctrl-C: the running work unwinds, closes what it started, and says why.

`terminate_like_ctrl_c` turns SIGTERM into a `Terminated` exception (a `KeyboardInterrupt`, so every
``except KeyboardInterrupt`` and ``finally`` that cleans up after Ctrl-C also runs on SIGTERM); an
inspection then stores itself as aborted with the reason "terminated (SIGTERM)".
"""

from __future__ import annotations

import contextlib
import signal
import threading
from typing import Iterator

__all__ = ["Terminated", "terminate_like_ctrl_c", "interruption_reason"]


class Terminated(KeyboardInterrupt):
    """The process received SIGTERM (``kill PID``, a service manager stopping it)."""


def _raise_terminated(signum, frame):
    raise Terminated(f"terminated by signal {signum}")


@contextlib.contextmanager
def terminate_like_ctrl_c() -> Iterator[None]:
    """Within the block, SIGTERM raises `Terminated` in the main thread (no-op off the main thread)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def interruption_reason(exc: BaseException) -> str:
    """The reason stored for work stopped by ``exc``: "terminated (SIGTERM)", "interrupted (Ctrl-C)", or the error."""
    if isinstance(exc, Terminated):
        return "terminated (SIGTERM)"
    if isinstance(exc, KeyboardInterrupt):
        return "interrupted (Ctrl-C)"
    if isinstance(exc, OSError) and exc.strerror and str(exc).startswith("[Errno"):
        return exc.strerror  # e.g. "disk full while writing 'results.sqlite'"
    return f"{type(exc).__name__}: {exc}"
