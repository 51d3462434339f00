"""Read a live source on a background thread so slow processing never stalls the camera."""

from __future__ import annotations

import queue
import threading

from tactip.errors import SourceError
from tactip.sources.base import Frame, FrameSource

__all__ = ["ThreadedReader"]

_END = object()  # end-of-stream marker in the queue


class ThreadedReader:
    """Decode frames on a thread into a bounded queue; read them from the main thread.

    The worker reads ``source`` until the end of the stream, an error or `close`. When the queue is
    full it drops the oldest frame (``when_full="drop"``, counted in `dropped_frames`: for live
    cameras, fresh frames matter more than complete ones) or waits (``when_full="block"``: for files,
    where every frame counts). An error in the worker is re-raised by `read` on the main thread.
    `close` stops the worker and always joins it; the source is closed too unless
    ``close_source=False``. Implements the `FrameSource` interface (without `seek`).

    Parameters
    ----------
    source : FrameSource
    maxsize : int
        Queue capacity, frames.
    when_full : {"drop", "block"}
    close_source : bool
    join_timeout_s : float
        How long `close` waits for a worker stuck in a blocking read, s.

    Examples
    --------
    >>> from tactip.sources import SyntheticSource
    >>> with ThreadedReader(SyntheticSource(pins=127), when_full="block") as reader:
    ...     count = sum(1 for _ in reader)
    """

    live: bool

    def __init__(self, source: FrameSource, *, maxsize: int = 4, when_full: str = "drop",
                 close_source: bool = True, join_timeout_s: float = 5.0):
        if maxsize < 1:
            raise SourceError(f"maxsize must be >= 1, got {maxsize}")
        if when_full not in ("drop", "block"):
            raise SourceError(f"when_full must be 'drop' or 'block', got {when_full!r}")
        self.source = source
        self.frame_size = source.frame_size
        self.frame_rate = source.frame_rate
        self.live = source.live
        self.when_full = when_full
        self.close_source = close_source
        self.join_timeout_s = join_timeout_s
        self.dropped_frames = 0
        self._queue: queue.Queue = queue.Queue(maxsize=maxsize)
        self._stop = threading.Event()
        self._error: BaseException | None = None
        self._finished = False
        self._thread = threading.Thread(target=self._work, name="tactip-frame-reader", daemon=True)
        self._thread.start()

    def _work(self) -> None:
        """Worker: read frames into the queue until the end, an error or a stop request."""
        try:
            while not self._stop.is_set():
                frame = self.source.read()
                if frame is None:
                    break
                self._put(frame)
        except BaseException as exc:  # re-raised on the main thread by read()
            self._error = exc
        finally:
            self._put(_END, final=True)

    def _put(self, item, *, final: bool = False) -> None:
        """Enqueue; when full, drop the oldest frame or wait. The end marker waits until closed."""
        while final or not self._stop.is_set():
            try:
                self._queue.put(item, timeout=0.05 if self.when_full == "block" else 0)
                return
            except queue.Full:
                if self._stop.is_set():
                    return  # closing: nobody reads any more
                if self.when_full == "drop":
                    try:
                        self._queue.get_nowait()
                        self.dropped_frames += 1
                    except queue.Empty:
                        pass

    def read(self, timeout_s: float | None = None) -> Frame | None:
        """The next frame, or None at the end of the stream.

        Raises
        ------
        SourceError
            When no frame arrives within ``timeout_s`` (None waits indefinitely) or the reader is closed.
        Exception
            Whatever the worker raised while reading the source.
        """
        if self._finished:
            if self._error is not None:
                raise self._error
            return None
        if self._stop.is_set():
            raise SourceError("threaded reader is closed")
        try:
            item = self._queue.get(timeout=timeout_s)
        except queue.Empty:
            raise SourceError(f"no frame within {timeout_s} s") from None
        if item is _END:
            self._finished = True
            if self._error is not None:
                raise self._error
            return None
        return item

    def drain(self) -> list[Frame]:
        """All frames queued now, oldest first, without waiting (worker errors are re-raised).

        The station drains at the start of a tap (keeping the newest frame as the rest frame) and
        again at its end (the frames of the tap).
        """
        frames = []
        while True:
            try:
                item = self._queue.get_nowait()
            except queue.Empty:
                break
            if item is _END:
                self._finished = True
                if self._error is not None:
                    raise self._error
                break
            frames.append(item)
        return frames

    def seek(self, index: int) -> None:
        """Not supported: frames are already in flight."""
        raise SourceError("a threaded reader cannot seek; seek the source before wrapping it")

    def close(self) -> None:
        """Stop the worker, join it, and close the source (unless ``close_source=False``)."""
        self._stop.set()
        try:
            while True:  # unblock a worker waiting on a full queue
                self._queue.get_nowait()
        except queue.Empty:
            pass
        finally:
            self._thread.join(self.join_timeout_s)
            if self.close_source:
                self.source.close()

    @property
    def running(self) -> bool:
        """Whether the worker thread is alive."""
        return self._thread.is_alive()

    def __iter__(self):
        while (frame := self.read()) is not None:
            yield frame

    def __enter__(self):
        return self

    def __exit__(self, *exc_info):
        self.close()

    def __repr__(self) -> str:
        return f"ThreadedReader({self.source!r}, maxsize={self._queue.maxsize}, when_full={self.when_full!r})"
