"""Live camera frames through OpenCV's ``VideoCapture``, with warm-up, drop counting and stall detection."""

from __future__ import annotations

import math
import time
from collections.abc import Callable

from tactip.errors import SourceError
from tactip.sources.base import FrameSourceBase

__all__ = ["CameraSource"]


class CameraSource(FrameSourceBase):
    """A live camera (the TacTip's USB webcam), as a `FrameSource`.

    Opens the device, asks for a one-frame buffer (so frames are fresh, not queued) and, when
    ``exposure`` is given, manual exposure (refusals by the driver are ignored: not every camera
    allows it), then discards ``warmup_frames`` while auto-gain and white balance settle.
    Time stamps come from ``time.monotonic()``, 0 at the first delivered frame.

    Dropped frames are counted from gaps in the time stamps beyond 1.5 frame periods (when the frame
    rate is known) or jumps of ``CAP_PROP_POS_FRAMES`` (when the driver reports it), whichever is larger.

    Parameters
    ----------
    device : int or str
        Camera index (0, 1, ...) or device path (``/dev/video0``).
    frame_size : (int, int) or None
        Requested (width, height), px; None keeps the driver's default.
    frame_rate : float or None
        Requested frames per second; None keeps the driver's default.
    exposure : float or None
        Manual exposure in the driver's units (V4L2: 100 us steps); None keeps auto exposure.
    warmup_frames : int
        Frames read and discarded after opening.
    max_failed_reads : int
        Consecutive failed reads after which the camera counts as stopped.
    timeout_s : float
        Time without a frame after which the camera counts as stopped, s.
    grey : bool
        Convert frames to grey (once, on read).
    capture_factory : callable or None
        ``device -> VideoCapture``-like object (``isOpened``, ``read``, ``set``, ``get``, ``release``);
        None uses ``cv2.VideoCapture``. Tests inject fakes here.
    clock : callable
        Monotonic clock, s (injectable for tests).

    Raises
    ------
    SourceError
        When the camera cannot be opened, or stops delivering during warm-up.

    Examples
    --------
    >>> with CameraSource(0, exposure=50) as camera:          # doctest: +SKIP
    ...     frame = camera.read()
    """

    live = True

    def __init__(self, device: int | str = 0, *, frame_size: tuple[int, int] | None = None,
                 frame_rate: float | None = None, exposure: float | None = None, warmup_frames: int = 5,
                 max_failed_reads: int = 10, timeout_s: float = 2.0, grey: bool = False,
                 capture_factory: Callable | None = None, clock: Callable[[], float] = time.monotonic):
        super().__init__(grey=grey)
        if warmup_frames < 0:
            raise SourceError(f"warmup_frames must be >= 0, got {warmup_frames}")
        if max_failed_reads < 1:
            raise SourceError(f"max_failed_reads must be >= 1, got {max_failed_reads}")
        if not timeout_s > 0:
            raise SourceError(f"timeout_s must be > 0, got {timeout_s}")
        self.device = device
        self.name = f"camera {device!r}"
        self.max_failed_reads = int(max_failed_reads)
        self.timeout_s = float(timeout_s)
        self._clock = clock
        self.dropped_frames = 0
        self._start = None
        self._last_time = None
        self._last_position = None
        import cv2

        self._cv2 = cv2
        if capture_factory is None:
            self._capture = _quiet_open(cv2, device)
        else:
            self._capture = capture_factory(device)
        if self._capture is None or not self._capture.isOpened():
            if self._capture is not None:
                self._capture.release()
            self._closed = True
            raise SourceError(f"cannot open {self.name}: no such camera, or it is in use")
        self._configure(frame_size, frame_rate, exposure)
        self._last_good = clock()
        for _ in range(int(warmup_frames)):
            self._grab()
        self._last_time = None  # drops are counted from the first delivered frame

    def _configure(self, frame_size, frame_rate, exposure) -> None:
        """Ask the driver for a one-frame buffer, size, rate and exposure; refusals are ignored."""
        cv2, capture = self._cv2, self._capture
        capture.set(cv2.CAP_PROP_BUFFERSIZE, 1)
        if frame_size is not None:
            capture.set(cv2.CAP_PROP_FRAME_WIDTH, int(frame_size[0]))
            capture.set(cv2.CAP_PROP_FRAME_HEIGHT, int(frame_size[1]))
        if frame_rate is not None:
            capture.set(cv2.CAP_PROP_FPS, float(frame_rate))
        if exposure is not None:
            # manual mode: 1 on V4L2, 0.25 on DirectShow; one of them is accepted or both are refused
            capture.set(cv2.CAP_PROP_AUTO_EXPOSURE, 1) or capture.set(cv2.CAP_PROP_AUTO_EXPOSURE, 0.25)
            capture.set(cv2.CAP_PROP_EXPOSURE, float(exposure))
        width = int(capture.get(cv2.CAP_PROP_FRAME_WIDTH) or 0)
        height = int(capture.get(cv2.CAP_PROP_FRAME_HEIGHT) or 0)
        self.frame_size = (width, height) if width > 0 and height > 0 else tuple(frame_size or (0, 0))
        fps = capture.get(cv2.CAP_PROP_FPS)
        self.frame_rate = float(fps) if fps and math.isfinite(fps) and fps > 0 else frame_rate

    def _grab(self):
        """Read until a frame arrives: (image, time). Raises SourceError after too many failures or too long."""
        failures = 0
        while True:
            ok, image = self._capture.read()
            now = self._clock()
            if ok and image is not None:
                self._last_good = now
                if self.frame_size == (0, 0):
                    self.frame_size = (image.shape[1], image.shape[0])
                return image, now
            failures += 1
            if failures >= self.max_failed_reads or now - self._last_good > self.timeout_s:
                raise SourceError(f"{self.name} stopped delivering frames "
                                  f"({failures} failed reads, {now - self._last_good:.1f} s without a frame)")

    def _read(self):
        image, now = self._grab()
        if self._start is None:
            self._start = now
        if self._last_time is not None and self.frame_rate:
            by_time = round((now - self._last_time) * self.frame_rate) - 1 if (
                now - self._last_time > 1.5 / self.frame_rate) else 0
        else:
            by_time = 0
        position = self._capture.get(self._cv2.CAP_PROP_POS_FRAMES)
        by_position = 0
        if position and position > 0:
            if self._last_position is not None:
                by_position = max(int(position - self._last_position) - 1, 0)
            self._last_position = position
        self.dropped_frames += max(by_time, by_position)
        self._last_time = now
        return image, now - self._start

    def _close(self) -> None:
        self._capture.release()


def _quiet_open(cv2, device):
    """``cv2.VideoCapture(device)`` without OpenCV's warnings when there is no such camera."""
    logging = getattr(getattr(cv2, "utils", None), "logging", None)
    if logging is None:
        return cv2.VideoCapture(device)
    level = logging.getLogLevel()
    logging.setLogLevel(logging.LOG_LEVEL_ERROR)
    try:
        return cv2.VideoCapture(device)
    finally:
        logging.setLogLevel(level)
