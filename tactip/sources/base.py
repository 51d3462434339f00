"""The streaming interface every frame source implements: `Frame`, `FrameSource`, `FrameSourceBase`."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from tactip.errors import SourceError

__all__ = ["Frame", "FrameSource", "FrameSourceBase"]


@dataclass(frozen=True, eq=False)
class Frame:
    """One frame from a source.

    Attributes
    ----------
    index : int
        Position in the stream, from 0 (for live sources: frames delivered so far, warm-up excluded).
    timestamp_s : float
        Time of the frame within the stream, s (0 at the first frame; monotonic for live sources).
    image : (H, W) or (H, W, 3) uint8 ndarray
        Grey or BGR, as the source delivers it (grey when the source was opened with ``grey=True``).
    """

    index: int
    timestamp_s: float
    image: np.ndarray


@runtime_checkable
class FrameSource(Protocol):
    """What the pipeline reads frames from: cameras, videos, image folders, the synthetic sensor.

    Attributes
    ----------
    frame_size : (int, int)
        (width, height), px.
    frame_rate : float or None
        Frames per second; None when unknown.
    live : bool
        A live source (camera) refuses `seek`.
    """

    frame_size: tuple[int, int]
    frame_rate: float | None
    live: bool

    def read(self) -> Frame | None:
        """The next frame, or None at the end of the stream."""

    def seek(self, index: int) -> None:
        """Make the next `read` return frame ``index``."""

    def close(self) -> None:
        """Release the device or file; further reads fail."""


class FrameSourceBase:
    """Shared behaviour: context manager, iteration, grey conversion, closed and live checks.

    Subclasses implement ``_read() -> (image, timestamp_s) | None`` and, if not live, ``_seek(index)``,
    and set ``frame_size``, ``frame_rate`` and ``name`` (used in error messages).
    """

    live = False
    frame_size: tuple[int, int] = (0, 0)
    frame_rate: float | None = None
    name = "source"

    def __init__(self, *, grey: bool = False):
        self.grey = bool(grey)
        self._index = 0
        self._closed = False

    def read(self) -> Frame | None:
        """The next frame, or None at the end of the stream.

        Raises
        ------
        SourceError
            The source is closed or cannot deliver (see the subclass).
        """
        if self._closed:
            raise SourceError(f"{self.name} is closed")
        item = self._read()
        if item is None:
            return None
        image, timestamp_s = item
        if self.grey and image.ndim == 3:
            import cv2

            image = cv2.cvtColor(image, cv2.COLOR_BGRA2GRAY if image.shape[2] == 4 else cv2.COLOR_BGR2GRAY)
        frame = Frame(self._index, float(timestamp_s), image)
        self._index += 1
        return frame

    def seek(self, index: int) -> None:
        """Make the next `read` return frame ``index`` (0-based).

        Raises
        ------
        SourceError
            On a live source, a closed source, or a negative index.
        """
        if self.live:
            raise SourceError(f"{self.name} is live and cannot seek")
        if self._closed:
            raise SourceError(f"{self.name} is closed")
        if int(index) != index or index < 0:
            raise SourceError(f"seek index must be a non-negative integer, got {index!r}")
        self._seek(int(index))
        self._index = int(index)

    def close(self) -> None:
        """Release the underlying device or file (idempotent)."""
        if not self._closed:
            self._closed = True
            self._close()

    def _read(self):  # pragma: no cover - abstract
        raise NotImplementedError

    def _seek(self, index: int) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def _close(self) -> None:
        """Release resources; the default has none."""

    def __iter__(self) -> Iterator[Frame]:
        while (frame := self.read()) is not None:
            yield frame

    def __enter__(self):
        return self

    def __exit__(self, *exc_info):
        self.close()

    def __repr__(self) -> str:
        return (f"{type(self).__name__}({self.name!r}, frame_size={self.frame_size}, "
                f"frame_rate={self.frame_rate}, grey={self.grey})")
