"""Frame sources: camera logic (with a fake capture), video files, image folders, synthetic, threaded reading."""

import threading

import cv2
import numpy as np
import pytest

from tactip.errors import SourceError
from tactip.sources import (CameraSource, Frame, FrameSource, ImageFolderSource, SyntheticSource, ThreadedReader,
                            VideoSource, open_source)
from tactip.sim import Contact


# -- a fake camera ------------------------------------------------------------------------------
class FakeClock:
    """A monotonic clock the fake capture advances."""

    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


class FakeCapture:
    """A ``cv2.VideoCapture`` stand-in: delivers scripted reads, advancing the clock by ``dt`` each read.

    ``script`` items: an int k (a frame whose pixels are k), or None (a failed read).
    """

    def __init__(self, script, clock, *, dt=0.05, fps=20.0, positions=False, refuse=()):
        self.script, self.clock, self.dt = list(script), clock, dt
        self.props = {cv2.CAP_PROP_FRAME_WIDTH: 8.0, cv2.CAP_PROP_FRAME_HEIGHT: 6.0, cv2.CAP_PROP_FPS: fps}
        self.positions, self.refuse = positions, set(refuse)
        self.sets, self.released, self.reads = [], False, 0

    def isOpened(self):
        return True

    def read(self):
        step = self.script.pop(0) if self.script else None
        dt = self.dt(self.reads) if callable(self.dt) else self.dt
        self.clock.now += dt
        self.reads += 1
        if step is None:
            return False, None
        if self.positions:
            self.props[cv2.CAP_PROP_POS_FRAMES] = float(step + 1)  # the driver's own frame counter
        return True, np.full((6, 8, 3), step, np.uint8)

    def set(self, prop, value):
        self.sets.append((prop, value))
        return prop not in self.refuse

    def get(self, prop):
        return self.props.get(prop, 0.0)

    def release(self):
        self.released = True


def camera(script, **options):
    """A CameraSource over a FakeCapture; returns (source, capture)."""
    clock = FakeClock()
    capture_options = {k: options.pop(k) for k in ("dt", "fps", "positions", "refuse") if k in options}
    capture = FakeCapture(script, clock, **capture_options)
    source = CameraSource(0, capture_factory=lambda device: capture, clock=clock, **options)
    return source, capture


@pytest.mark.parametrize("spec", [97, "97", "/dev/video97"])
def test_a_missing_camera_is_a_source_error(spec):
    with pytest.raises(SourceError, match="cannot open camera"):
        open_source(spec)


def test_camera_that_never_opens_is_released():
    class Closed(FakeCapture):
        def isOpened(self):
            return False

    capture = Closed([], FakeClock())
    with pytest.raises(SourceError, match="cannot open camera 3"):
        CameraSource(3, capture_factory=lambda device: capture)
    assert capture.released


def test_camera_discards_warm_up_frames_and_stamps_from_zero():
    source, capture = camera(range(20), warmup_frames=3)
    frames = [source.read() for _ in range(4)]
    assert [int(f.image[0, 0, 0]) for f in frames] == [3, 4, 5, 6]  # frames 0-2 were warm-up
    assert [f.index for f in frames] == [0, 1, 2, 3]
    np.testing.assert_allclose([f.timestamp_s for f in frames], [0.0, 0.05, 0.1, 0.15])
    assert source.frame_size == (8, 6) and source.frame_rate == 20.0 and source.live
    assert source.dropped_frames == 0


def test_camera_asks_for_a_one_frame_buffer_and_manual_exposure_and_ignores_refusals():
    refused = (cv2.CAP_PROP_AUTO_EXPOSURE, cv2.CAP_PROP_EXPOSURE)
    source, capture = camera(range(10), exposure=50.0, warmup_frames=0, refuse=refused)
    props = [prop for prop, _ in capture.sets]
    assert (cv2.CAP_PROP_BUFFERSIZE, 1) in capture.sets
    assert cv2.CAP_PROP_AUTO_EXPOSURE in props and (cv2.CAP_PROP_EXPOSURE, 50.0) in capture.sets
    assert source.read().index == 0  # refusals did not stop the camera


def test_camera_counts_drops_from_time_gaps():
    gaps = {3: 0.2, 6: 0.11}  # before the 4th delivered frame 3 periods are missing, before the 7th 1
    source, _ = camera(range(20), warmup_frames=0, dt=lambda k: gaps.get(k, 0.05))
    frames = [source.read() for _ in range(10)]
    assert source.dropped_frames == 3 + 1
    assert np.all(np.diff([f.timestamp_s for f in frames]) > 0)


def test_camera_counts_drops_from_frame_position_jumps():
    source, _ = camera([0, 1, 2, 6, 7, 9, 10], warmup_frames=0, positions=True, fps=0.0)
    for _ in range(7):
        source.read()
    assert source.frame_rate is None
    assert source.dropped_frames == 3 + 1


def test_camera_that_stops_delivering_raises():
    source, _ = camera([0, 1, 2] + [None] * 20, warmup_frames=0, max_failed_reads=5)
    assert source.read().index == 0 and source.read().index == 1 and source.read().index == 2
    with pytest.raises(SourceError, match="stopped delivering"):
        source.read()


def test_camera_that_stalls_raises_after_the_timeout():
    source, capture = camera([0] + [None] * 100, warmup_frames=0, max_failed_reads=1000, timeout_s=1.0,
                             dt=0.3)
    source.read()
    with pytest.raises(SourceError, match="stopped delivering"):
        source.read()
    assert capture.reads < 10  # gave up after about 1 s, not after 1000 reads


def test_camera_stops_delivering_during_warm_up():
    with pytest.raises(SourceError, match="stopped delivering"):
        camera([None] * 20, warmup_frames=5, max_failed_reads=3)


def test_camera_is_live_converts_to_grey_and_closes():
    source, capture = camera(range(10), warmup_frames=0, grey=True)
    with source:
        frame = source.read()
        assert frame.image.shape == (6, 8) and frame.image.dtype == np.uint8
        with pytest.raises(SourceError, match="live"):
            source.seek(0)
    assert capture.released
    with pytest.raises(SourceError, match="closed"):
        source.read()


def test_a_failed_read_is_retried():
    source, _ = camera([0, None, None, 1], warmup_frames=0, max_failed_reads=3)
    assert [int(f.image[0, 0, 0]) for f in (source.read(), source.read())] == [0, 1]


# -- video files --------------------------------------------------------------------------------
def write_video(path, count=12, size=(160, 120), fps=20.0, fourcc="mp4v"):
    """A video whose frame i is uniformly grey at 15 i + 20; returns the levels."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*fourcc), fps, size, isColor=False)
    assert writer.isOpened()
    levels = [15 * i + 20 for i in range(count)]
    for level in levels:
        writer.write(np.full(size[::-1], level, np.uint8))
    writer.release()
    return levels


@pytest.mark.parametrize("name, fourcc", [("clip.mp4", "mp4v"), ("clip.avi", "MJPG")])
def test_video_frames_in_order_with_time_stamps(tmp_path, name, fourcc):
    levels = write_video(tmp_path / name, fourcc=fourcc)
    with open_source(tmp_path / name) as video:
        assert isinstance(video, VideoSource) and isinstance(video, FrameSource)
        assert video.frame_size == (160, 120) and video.frame_rate == pytest.approx(20.0) and not video.live
        frames = list(video)
    assert [f.index for f in frames] == list(range(12))
    np.testing.assert_allclose([f.timestamp_s for f in frames], np.arange(12) / 20.0)
    np.testing.assert_allclose([f.image.mean() for f in frames], levels, atol=3.0)


def test_video_seek_and_grey(tmp_path):
    levels = write_video(tmp_path / "clip.mp4")
    with VideoSource(tmp_path / "clip.mp4", grey=True) as video:
        video.read()
        video.seek(7)
        frame = video.read()
    assert frame.index == 7 and frame.timestamp_s == pytest.approx(0.35)
    assert frame.image.ndim == 2 and abs(frame.image.mean() - levels[7]) < 3.0


def test_video_on_one_decoder_thread_reads_the_same_frames(tmp_path):
    # Replay decodes on one thread fewer than the cores; the frames must not depend on it.
    write_video(tmp_path / "clip.mp4")
    with open_source(tmp_path / "clip.mp4", grey=True) as default, \
            open_source(tmp_path / "clip.mp4", grey=True, decode_threads=1) as single:
        assert single._capture.get(cv2.CAP_PROP_N_THREADS) == 1
        pairs = list(zip(default, single, strict=True))
    assert len(pairs) == 12 and all(np.array_equal(a.image, b.image) for a, b in pairs)
    with pytest.raises(ValueError, match="decode_threads"):
        VideoSource(tmp_path / "clip.mp4", decode_threads=0)
    cv2.imwrite(str(tmp_path / "frame.png"), np.zeros((8, 8), np.uint8))
    with open_source(tmp_path / "frame.png", decode_threads=1) as image:  # no decoder: the option is dropped
        assert image.read().image.shape[:2] == (8, 8)


def test_missing_video_names_the_path(tmp_path):
    with pytest.raises(SourceError, match="missing.mp4"):
        VideoSource(tmp_path / "missing.mp4")


@pytest.mark.parametrize("content", [b"", np.random.default_rng(0).bytes(20000)])
def test_corrupt_video_names_the_path(tmp_path, content):
    path = tmp_path / "corrupt.mp4"
    path.write_bytes(content)
    with pytest.raises(SourceError, match="corrupt.mp4"):
        open_source(path)


# -- image folders ------------------------------------------------------------------------------
def test_image_folder_in_natural_order(tmp_path):
    for i in (1, 2, 10, 11):
        cv2.imwrite(str(tmp_path / f"frame_{i}.png"), np.full((30, 40), 10 * i, np.uint8))
    cv2.imwrite(str(tmp_path / "frame_3.jpg"), np.full((30, 40, 3), 30, np.uint8))
    (tmp_path / "notes.txt").write_text("not an image")
    with open_source(tmp_path, frame_rate=10.0) as folder:
        assert isinstance(folder, ImageFolderSource) and len(folder) == 5
        assert folder.frame_size == (40, 30) and folder.frame_rate == 10.0
        frames = list(folder)
    assert [int(f.image.mean()) for f in frames] == [10, 20, 30, 100, 110]
    assert frames[0].image.ndim == 2 and frames[2].image.ndim == 3  # as they come
    np.testing.assert_allclose([f.timestamp_s for f in frames], np.arange(5) / 10.0)


def test_image_folder_seek_grey_and_single_file(tmp_path):
    for i in range(4):
        cv2.imwrite(str(tmp_path / f"{i}.bmp"), np.full((30, 40, 3), 50 * i, np.uint8))
    with ImageFolderSource(tmp_path, grey=True) as folder:
        folder.seek(2)
        frame = folder.read()
        assert frame.index == 2 and frame.image.shape == (30, 40) and int(frame.image.mean()) == 100
        assert folder.read().index == 3 and folder.read() is None
    with open_source(tmp_path / "1.bmp") as single:
        assert [f.index for f in single] == [0]


def test_empty_or_missing_folder_and_unreadable_image(tmp_path):
    with pytest.raises(SourceError, match="holds no images"):
        ImageFolderSource(tmp_path)
    with pytest.raises(SourceError, match="nowhere"):
        ImageFolderSource(tmp_path / "nowhere")
    (tmp_path / "0.png").write_bytes(b"not a png")
    with pytest.raises(SourceError, match="0.png"):
        ImageFolderSource(tmp_path)


def test_unknown_spec_names_it_and_the_choices():
    with pytest.raises(SourceError, match=r"'no/such/thing'.*synthetic"):
        open_source("no/such/thing")


# -- synthetic ----------------------------------------------------------------------------------
def test_synthetic_source_taps_with_ground_truth():
    taps = [Contact(2.0, 2.0), Contact(5.0, 2.0)]
    with open_source("synthetic:127", taps=taps, rest_s=0.5) as source:
        assert isinstance(source, SyntheticSource) and source.sensor.n_pins == 127
        assert source.frame_rate == 20.0 and source.frame_size == (640, 480)
        frames, depths, moved = [], [], []
        for frame in source:
            frames.append(frame)
            depths.append(source.truth.contact.indentation_mm)
            moved.append(np.abs(source.truth.centres - source.sensor.rest_centres).max())
    assert len(frames) == source.frame_count == 61  # 0.5 + 2 x (0.75 + 0.5) s at 20 fps, both ends
    assert frames[0].image.shape == (480, 640)
    depths = np.array(depths)
    assert depths[:11].max() == 0.0 and depths[25:36].max() == 0.0 and depths[50:].max() == 0.0  # rests
    assert depths[10:26].max() == pytest.approx(2.0) and depths[35:51].max() == pytest.approx(5.0)
    assert np.argmax(moved) in range(40, 46)  # the deepest frames are in the second tap's plateau


def test_synthetic_source_seek_keeps_the_script():
    source = SyntheticSource(pins=127, taps=[Contact(4.0)])
    source.seek(15)
    frame = source.read()
    assert frame.index == 15 and frame.timestamp_s == 0.75
    assert source.truth.contact == source.contact_at(0.75) and source.truth.contact.indentation_mm == 4.0


# -- threaded reading ---------------------------------------------------------------------------
class CountingSource:
    """A FrameSource of ``count`` tiny frames; raises ``error`` at frame ``fail_at``."""

    frame_size, frame_rate, live = (4, 3), 30.0, True

    def __init__(self, count, *, fail_at=None, error=None):
        self.count, self.fail_at, self.error = count, fail_at, error
        self.next, self.closed = 0, False

    def read(self):
        if self.next == self.fail_at:
            raise self.error
        if self.next >= self.count:
            return None
        self.next += 1
        return Frame(self.next - 1, (self.next - 1) / 30.0, np.zeros((3, 4), np.uint8))

    def seek(self, index):
        raise SourceError("live")

    def close(self):
        self.closed = True


def test_threaded_reader_preserves_order_when_blocking():
    source = CountingSource(200)
    with ThreadedReader(source, maxsize=3, when_full="block") as reader:
        indices = [f.index for f in reader]
    assert indices == list(range(200)) and reader.dropped_frames == 0
    assert source.closed and not reader.running


def test_threaded_reader_drops_the_oldest_when_full():
    source = CountingSource(50)
    reader = ThreadedReader(source, maxsize=4, when_full="drop")
    reader._thread.join(5.0)  # let the worker run to the end without reading
    indices = [f.index for f in reader]
    reader.close()
    assert indices == sorted(indices) and indices[-1] == 49  # newest kept, in order
    assert len(indices) + reader.dropped_frames == 50 and reader.dropped_frames > 0


def test_threaded_reader_reraises_worker_errors_on_the_main_thread():
    error = SourceError("camera 0 stopped delivering frames")
    source = CountingSource(100, fail_at=3, error=error)
    with ThreadedReader(source, when_full="block") as reader:
        assert [reader.read().index for _ in range(3)] == [0, 1, 2]
        with pytest.raises(SourceError, match="stopped delivering") as raised:
            reader.read()
    assert raised.value is error and not reader.running


def test_threaded_reader_close_joins_a_blocked_worker():
    source = CountingSource(10_000)
    reader = ThreadedReader(source, maxsize=2, when_full="block")
    while reader._queue.qsize() < 2:  # the worker is now blocked on the full queue
        threading.Event().wait(0.01)
    reader.close()
    assert not reader.running and source.closed
    with pytest.raises(SourceError, match="closed"):
        reader.read()
    with pytest.raises(SourceError, match="seek"):
        reader.seek(0)


def test_threaded_reader_over_a_real_source(tmp_path):
    write_video(tmp_path / "clip.mp4", count=8)
    with ThreadedReader(open_source(tmp_path / "clip.mp4", grey=True), when_full="block") as reader:
        frames = list(reader)
    assert [f.index for f in frames] == list(range(8)) and frames[0].image.ndim == 2


def test_docstring_examples_run():
    import doctest

    import tactip.sources
    import tactip.sim.source
    import tactip.sources.threaded

    for module in (tactip.sources, tactip.sim.source, tactip.sources.threaded):
        assert doctest.testmod(module).failed == 0
