"""SIGTERM and SIGHUP handled like Ctrl-C: the running work unwinds, closes what it started, and says why.

`terminate_like_ctrl_c` turns SIGTERM (``kill PID``, a service manager) and SIGHUP (the terminal or the
SSH session closed) into a `Terminated` exception (a `KeyboardInterrupt`, so every
``except KeyboardInterrupt`` and ``finally`` that cleans up after Ctrl-C also runs: temporary files are
removed); an inspection then stores itself as aborted with the reason "terminated (SIGTERM)" or
"terminated (SIGHUP)". A SIGHUP already ignored (``nohup tactip ...``) stays ignored.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from typing import Iterator

__all__ = ["Terminated", "terminate_like_ctrl_c", "interruption_reason"]

# The signals that stop the work like Ctrl-C (SIGHUP does not exist on Windows).
_SIGNALS = tuple(s for s in (getattr(signal, "SIGTERM", None), getattr(signal, "SIGHUP", None)) if s is not None)


class Terminated(KeyboardInterrupt):
    """The process received SIGTERM or SIGHUP; ``signum`` says which."""

    def __init__(self, signum: int = signal.SIGTERM):
        super().__init__(f"terminated by signal {signum}")
        self.signum = int(signum)

    @property
    def signal_name(self) -> str:
        """``"SIGTERM"`` or ``"SIGHUP"``."""
        return signal.Signals(self.signum).name


def _raise_terminated(signum, frame):
    raise Terminated(signum)


@contextlib.contextmanager
def terminate_like_ctrl_c() -> Iterator[None]:
    """Within the block, SIGTERM and SIGHUP raise `Terminated` in the main thread (no-op off the main thread)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {}
    for signum in _SIGNALS:
        if signal.getsignal(signum) is signal.SIG_IGN:
            continue  # nohup: the user asked to outlive the terminal
        previous[signum] = signal.signal(signum, _raise_terminated)
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


def interruption_reason(exc: BaseException) -> str:
    """The reason stored for work stopped by ``exc``: "terminated (SIGTERM)", "interrupted (Ctrl-C)", or the error."""
    if isinstance(exc, Terminated):
        return f"terminated ({exc.signal_name})"
    if isinstance(exc, KeyboardInterrupt):
        return "interrupted (Ctrl-C)"
    if isinstance(exc, OSError) and exc.strerror and str(exc).startswith("[Errno"):
        return exc.strerror  # e.g. "disk full while writing 'results.sqlite'"
    return f"{type(exc).__name__}: {exc}"
