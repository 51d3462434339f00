"""Progress bars: tqdm on a terminal, plain lines at most one per few seconds anywhere else.

A tqdm bar redraws itself with carriage returns up to ten times a second: on a terminal that is one
line, in a log file or a CI job it is thousands. `progress_bar` makes every bar of the project: on a
terminal it is tqdm as usual; when its stream (standard error) is not a terminal, it writes a whole line
(``collect:  40%|####      | 160/400 [00:20<00:30, 8.0tap/s]``) at most once per `PLAIN_INTERVAL_S`,
and the last one when it ends.
"""

from __future__ import annotations

import sys

__all__ = ["progress_bar", "PLAIN_INTERVAL_S"]

#: Shortest time between two plain progress lines, s.
PLAIN_INTERVAL_S = 5.0


def progress_bar(iterable=None, **options):
    """A tqdm progress bar; plain lines, at most one per `PLAIN_INTERVAL_S`, when not on a terminal.

    Parameters
    ----------
    iterable : iterable, optional
        Wrapped, as ``tqdm(iterable)``.
    **options
        tqdm's options (``total``, ``desc``, ``unit``, ``disable``, ``leave``, ``file`` ...).

    Returns
    -------
    tqdm.tqdm
        Usable as tqdm is: iterate over it, or ``update`` it inside ``with``.
    """
    from tqdm import tqdm

    stream = options.get("file") or sys.stderr
    if not _is_terminal(stream):
        options.update(file=_Lines(stream), mininterval=max(options.get("mininterval", 0.0), PLAIN_INTERVAL_S),
                       maxinterval=max(options.get("maxinterval", 0.0), 10 * PLAIN_INTERVAL_S), miniters=1,
                       dynamic_ncols=False, ncols=options.get("ncols", 80), ascii=True, leave=True)
    return tqdm(iterable, **options)


def _is_terminal(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError, OSError):
        return False


class _Lines:
    """A stream for tqdm that turns its redraws (``\\r`` + bar) into whole lines and drops its blank-outs."""

    def __init__(self, stream):
        self._stream = stream

    def write(self, text: str) -> None:
        for piece in text.replace("\r", "\n").split("\n"):
            if piece.strip():
                self._stream.write(piece.rstrip() + "\n")

    def flush(self) -> None:
        flush = getattr(self._stream, "flush", None)
        if flush is not None:
            flush()
