"""The station's cameras behind one protocol, and the factory that opens the configured one.

A camera gives ``rest_frames(n)`` off contact, is told ``begin_tap(event)`` when the arm starts its
stroke and ``end_tap(event)`` when it is back up (returning the tap's frames and their times), and
``close()`` releases it. Two implement it: `LiveCamera` (an OpenCV camera or video read on a thread;
the frames queued between the arm's two callbacks are the tap) and `tactip.sim.camera.SimulatedCamera`
(the synthetic TacTip rendering the simulated arm's true contact).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from tactip.errors import SourceError, TactipError
from tactip.sources import ThreadedReader, open_source
from tactip.station.config import StationConfig

__all__ = ["Camera", "LiveCamera", "make_camera"]


@runtime_checkable
class Camera(Protocol):
    """What the station needs of a camera (see the module docstring)."""

    def rest_frames(self, n: int) -> list[np.ndarray]:
        """``n`` frames off contact."""

    def begin_tap(self, event, *, seed: int | None = None) -> None:
        """The arm starts its stroke down (``seed``: a simulated tap's noise)."""

    def end_tap(self, event) -> tuple[list[np.ndarray], list[float]]:
        """The arm is back up: the tap's frames and their times, s."""

    def close(self) -> None:
        """Release the camera."""


class LiveCamera:
    """A real camera (OpenCV) read on a thread; a tap is the frames between the arm's callbacks.

    Parameters
    ----------
    source : str, int or FrameSource
        Camera index, device path or video file (`tactip.sources.open_source`), or an open source.
    queue_frames : int
        Capacity of the frame queue; a tap must fit in it.
    timeout_s : float
        How long to wait for a frame before the camera counts as stalled, s.
    """

    def __init__(self, source: str | int, *, queue_frames: int = 512, timeout_s: float = 2.0):
        self.timeout_s = float(timeout_s)
        if not hasattr(source, "read"):
            source = open_source(source, grey=True)
        self._reader = ThreadedReader(source, maxsize=queue_frames, when_full="drop")
        self.frame_rate = self._reader.frame_rate
        self._rest = None

    def rest_frames(self, n: int) -> list[np.ndarray]:
        """The next ``n`` frames (after dropping what was queued)."""
        self._reader.drain()
        frames = []
        for _ in range(n):
            frame = self._reader.read(timeout_s=self.timeout_s)
            if frame is None:
                raise SourceError("the camera stream ended while taking rest frames")
            frames.append(frame.image)
        return frames

    def begin_tap(self, event, *, seed: int | None = None) -> None:
        """The stroke starts: the newest queued frame (still off contact) is the tap's rest frame."""
        queued = self._reader.drain()
        if not queued:
            frame = self._reader.read(timeout_s=self.timeout_s)
            if frame is None:
                raise SourceError("the camera stream ended")
            queued = [frame]
        self._rest = queued[-1]

    def end_tap(self, event) -> tuple[list[np.ndarray], list[float]]:
        """The pad is back up: the rest frame and every frame since are the tap."""
        frames = [self._rest, *self._reader.drain()]
        self._rest = None
        return [f.image for f in frames], [f.timestamp_s for f in frames]

    def close(self) -> None:
        """Stop the reader thread and release the camera."""
        self._reader.close()


def make_camera(config: StationConfig) -> Camera:
    """The station's camera from its configuration: the synthetic TacTip on a simulated arm, else a live one.

    Raises
    ------
    TactipError
        ``[sensor] source = "synthetic"`` without the simulated arm.
    """
    if config.arm.backend == "sim" or config.sensor.source == "synthetic":
        if config.arm.backend != "sim":
            raise TactipError("[sensor] source 'synthetic' needs the simulated arm (arm.backend = 'sim')")
        tap = config.arm.tap
        from tactip.sim.camera import SimulatedCamera

        return SimulatedCamera(pins=config.sensor.pins, frame_rate=config.sensor.frame_rate,
                               tap_speed_mm_s=tap.speed_mm_s, dwell_s=tap.dwell_s,
                               approach_height_mm=tap.approach_height_mm, noise_sigma=config.sim.noise_sigma,
                               seed=config.sim.seed, preset=config.sensor.preset)
    return LiveCamera(config.sensor.source)
