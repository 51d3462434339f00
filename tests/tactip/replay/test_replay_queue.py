"""Replay's reader decodes ahead of the tracking within a bounded memory (`tactip.replay.video._queue_frames`)."""

from tactip.replay.video import _QUEUE_BYTES, _queue_frames


def test_the_queue_holds_64_mb_of_grey_frames_and_never_fewer_than_8():
    assert _queue_frames((640, 480)) == 218                     # the slide bench: the field search's ~150-230 frames
    assert _queue_frames((1920, 1080)) == 32
    for size in [(640, 480), (1920, 1080), (1280, 720), (320, 240)]:
        width, height = size
        assert _queue_frames(size) * width * height <= _QUEUE_BYTES
    assert _queue_frames((8000, 8000)) == 8                     # huge frames: the old queue, no more
    assert _queue_frames((0, 0)) == 8                           # a source that does not know its size
