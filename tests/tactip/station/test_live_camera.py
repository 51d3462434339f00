"""The live camera's tap capture: the rest frame before the stroke, then every frame until release."""

import time

import numpy as np
import pytest

from tactip.errors import SourceError
from tactip.sources import Frame
from tactip.station.camera import LiveCamera


class FakeCamera:
    """A live source delivering numbered frames every ``period_s`` until told to stop."""

    live = True
    frame_size = (8, 6)
    frame_rate = 200.0

    def __init__(self, period_s=0.005, stall_after=None):
        self.period_s, self.stall_after = period_s, stall_after
        self.index = 0

    def read(self):
        stalled = self.stall_after is not None and self.index >= self.stall_after
        time.sleep(0.5 if stalled else self.period_s)     # a stalled camera: far slower than the timeout
        frame = Frame(self.index, time.monotonic(), np.full((6, 8), self.index % 256, np.uint8))
        self.index += 1
        return frame

    def seek(self, index):
        raise SourceError("live")

    def close(self):
        pass


def test_a_tap_is_the_rest_frame_then_every_frame_until_release():
    camera = LiveCamera(FakeCamera(), timeout_s=1.0)
    try:
        time.sleep(0.05)                      # frames queue up before the tap: not part of it
        camera.begin_tap(event=None)
        time.sleep(0.1)                       # the stroke, dwell and release: about 20 frames
        frames, times = camera.end_tap(event=None)
    finally:
        camera.close()
    values = [int(f[0, 0]) for f in frames]
    assert len(frames) >= 10
    assert values == list(range(values[0], values[0] + len(values)))   # consecutive: nothing lost or repeated
    assert np.all(np.diff(times) > 0)
    assert values[0] >= 5                     # the rest frame is the newest before the stroke, not the first queued


def test_rest_frames_are_fresh_frames():
    camera = LiveCamera(FakeCamera(), timeout_s=1.0)
    try:
        time.sleep(0.03)
        first = camera.rest_frames(3)
        assert [int(f[0, 0]) for f in first] == list(range(int(first[0][0, 0]), int(first[0][0, 0]) + 3))
    finally:
        camera.close()


def test_a_camera_that_stops_delivering_is_an_error():
    camera = LiveCamera(FakeCamera(stall_after=2), timeout_s=0.2)
    try:
        time.sleep(0.05)
        camera.begin_tap(event=None)          # the two frames it gave
        with pytest.raises(SourceError, match="no frame within"):
            camera.rest_frames(1)
    finally:
        camera.close()
