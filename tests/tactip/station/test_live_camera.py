"""The live camera's tap capture: the rest frame before the stroke, then every frame until release.

No test here depends on how fast the machine runs: the fake camera delivers exactly the frames a test
lets through, stamped by a fake clock, and the tests wait (with a generous bound) until the reader has
queued them; only the stalled camera's timeout is a time.
"""

import threading
import time

import numpy as np
import pytest

from tactip.errors import SourceError
from tactip.sources import Frame
from tactip.station.camera import LiveCamera


class FakeCamera:
    """A live source of numbered frames on a fake clock (``period_s`` apart), delivering ``allowed`` frames
    (None: any number) and then waiting for `let_through` or `close`."""

    live = True
    frame_size = (8, 6)
    frame_rate = 200.0

    def __init__(self, period_s=0.005, allowed=None):
        self.period_s, self.allowed = period_s, allowed
        self.index = 0
        self._closed = False
        self._more = threading.Condition()

    def let_through(self, n):
        """Deliver ``n`` more frames."""
        with self._more:
            self.allowed += n
            self._more.notify_all()

    def read(self):
        with self._more:
            self._more.wait_for(lambda: self._closed or self.allowed is None or self.index < self.allowed)
            if self._closed:
                return None
            frame = Frame(self.index, self.index * self.period_s, np.full((6, 8), self.index % 256, np.uint8))
            self.index += 1
            return frame

    def seek(self, index):
        raise SourceError("live")

    def close(self):
        with self._more:
            self._closed = True
            self._more.notify_all()


def queued(camera, n, bound_s=30.0):
    """Wait until the live camera's reader has queued ``n`` frames (the bound only catches a hang)."""
    deadline = time.monotonic() + bound_s
    while camera._reader._queue.qsize() != n:
        assert time.monotonic() < deadline, f"the reader queued {camera._reader._queue.qsize()} frames, not {n}"
        time.sleep(0.001)


def test_a_tap_is_the_rest_frame_then_every_frame_until_release():
    fake = FakeCamera(allowed=5)
    camera = LiveCamera(fake, timeout_s=5.0)
    try:
        queued(camera, 5)                     # frames queue up before the tap: not part of it
        camera.begin_tap(event=None)
        fake.let_through(20)                  # the stroke, dwell and release
        queued(camera, 20)
        frames, times = camera.end_tap(event=None)
    finally:
        camera.close()
    values = [int(f[0, 0]) for f in frames]
    assert values == list(range(4, 25))       # the newest frame before the stroke, then every frame: none lost
    assert times == pytest.approx(0.005 * np.arange(4, 25))


def test_rest_frames_are_fresh_frames():
    fake = FakeCamera(allowed=3)
    camera = LiveCamera(fake, timeout_s=5.0)
    try:
        queued(camera, 3)                     # stale frames, queued before the call
        # Once they are dropped, three fresh ones arrive.
        fresh = threading.Thread(target=lambda: (queued(camera, 0), fake.let_through(3)), daemon=True)
        fresh.start()
        first = camera.rest_frames(3)
        fresh.join()
        assert [int(f[0, 0]) for f in first] == [3, 4, 5]
    finally:
        camera.close()


def test_a_camera_that_stops_delivering_is_an_error():
    camera = LiveCamera(FakeCamera(allowed=2), timeout_s=0.2)   # then nothing more
    try:
        queued(camera, 2)
        camera.begin_tap(event=None)          # the two frames it gave
        with pytest.raises(SourceError, match="no frame within"):
            camera.rest_frames(1)
    finally:
        camera.close()
