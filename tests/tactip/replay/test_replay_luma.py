"""Replay's reader takes the decoder's luma plane only where it gives today's grey frames (`tactip.replay.luma`)."""

import cv2
import h5py
import numpy as np
import pytest

import tactip.replay.luma as luma_module
from tactip.replay.luma import LumaVideoSource, luma_table
from tactip.replay.video import replay_video
from tactip.sim import Contact, SyntheticTacTip
from tactip.sources import VideoSource

CODECS = [("mp4v", ".mp4"), ("MJPG", ".avi")]


def _write(path, codec: str, *, tint=None, seed: int = 3, frames: int = 12, size=(320, 240)) -> None:
    """A short tap of a 127-pin synthetic TacTip (grey content, written as BGR); `tint` scales B, G, R and adds a
    saturated orange LED patch: a colour recording."""
    sensor = SyntheticTacTip(pins=127, seed=seed, image_size=size)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*codec), 20.0, size, True)
    rng = np.random.default_rng(seed)
    for k in range(frames):
        image = sensor.render(Contact(3.0 * k / frames, 2.0, 0.0)).image
        image = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR) if image.ndim == 2 else image
        if tint is not None:
            image = image * np.asarray(tint, dtype=float) + rng.normal(0.0, 4.0, image.shape)
            image[100:130, 150:220] = (40, 200, 250)
            image = np.clip(image, 0, 255).astype(np.uint8)
        writer.write(image)
    writer.release()


def _frames(source):
    with source:
        return [(frame.index, frame.timestamp_s, frame.image) for frame in source]


@pytest.mark.parametrize("size", [(320, 240), (328, 246)])  # (rows not a multiple of 16 or 32 px: padded planes)
@pytest.mark.parametrize("codec,suffix", CODECS)
def test_luma_frames_equal_grey_of_bgr(tmp_path, codec, suffix, size, capfd):
    video = tmp_path / f"grey{suffix}"
    _write(video, codec, size=size)
    expected = _frames(VideoSource(video, grey=True))
    source = LumaVideoSource(video, decode_threads=1)
    # Grey content: the table reproduces the first frame, the luma plane is read. (Not MJPG at 328 px: swscale's
    # full-range conversion there rounds by pixel position, one level apart, so no table does: the BGR path.)
    assert source.luma or (codec == "MJPG" and size != (320, 240))
    got = _frames(source)
    assert len(got) == len(expected) == 12
    for (index, time_s, image), (index0, time0_s, image0) in zip(got, expected):
        assert index == index0 and time_s == time0_s
        assert image.shape == image0.shape == size[::-1] and image.dtype == np.uint8
        assert np.array_equal(image, image0)  # bit for bit, not only within rounding
    assert "unsupported picture format" not in capfd.readouterr().err.lower()  # OpenCV's per-frame warning silenced


def test_log_level_restored_after_close(tmp_path):
    video = tmp_path / "grey.mp4"
    _write(video, "mp4v", frames=3)
    before = cv2.utils.logging.getLogLevel()
    first, second = LumaVideoSource(video), LumaVideoSource(video)
    assert first.luma and second.luma
    assert cv2.utils.logging.getLogLevel() <= cv2.utils.logging.LOG_LEVEL_ERROR
    first.close()
    assert cv2.utils.logging.getLogLevel() <= cv2.utils.logging.LOG_LEVEL_ERROR  # the other is still open
    second.close()
    assert cv2.utils.logging.getLogLevel() == before


@pytest.mark.parametrize("codec,suffix", CODECS)
def test_colour_recording_falls_back_to_bgr(tmp_path, codec, suffix):
    video = tmp_path / f"colour{suffix}"
    _write(video, codec, tint=(0.8, 1.0, 1.15))
    expected = _frames(VideoSource(video, grey=True))
    source = LumaVideoSource(video)
    assert not source.luma  # its chroma rounds differently: the luma plane is not today's grey
    got = _frames(source)
    assert len(got) == len(expected)
    assert all(np.array_equal(image, image0) for (_, _, image), (_, _, image0) in zip(got, expected))


class _IgnoresConvertRGB:
    """A capture whose backend ignores ``CAP_PROP_CONVERT_RGB``: BGR frames whatever was asked."""

    def __init__(self, path, api, options):
        self._capture = cv2.VideoCapture(path, api)

    def __getattr__(self, name):
        return getattr(self._capture, name)


class _RefusesConvertRGB(_IgnoresConvertRGB):
    """A capture that raises when opened with a property it does not know."""

    def __init__(self, path, api, options):
        raise cv2.error("unsupported property")


@pytest.mark.parametrize("fake", [_IgnoresConvertRGB, _RefusesConvertRGB])
def test_fallback_when_the_property_is_unsupported(tmp_path, monkeypatch, fake):
    video = tmp_path / "grey.mp4"
    _write(video, "mp4v", frames=6)
    expected = _frames(VideoSource(video, grey=True))
    before = cv2.utils.logging.getLogLevel()
    real = cv2.VideoCapture
    opened = []

    def capture(*args):
        if len(args) == 3 and cv2.CAP_PROP_CONVERT_RGB in list(args[2])[::2]:
            opened.append(fake)
            return fake(*args)
        return real(*args)

    monkeypatch.setattr(cv2, "VideoCapture", capture)
    source = LumaVideoSource(video)
    assert opened and not source.luma
    got = _frames(source)
    assert all(np.array_equal(image, image0) for (_, _, image), (_, _, image0) in zip(got, expected))
    assert len(got) == len(expected) == 6
    assert cv2.utils.logging.getLogLevel() == before


def test_luma_table_maps_limited_range_exactly():
    levels = np.arange(16, 236, dtype=np.uint8)
    luma = np.tile(levels, (4, 1))
    grey = np.clip(np.round((luma.astype(float) - 16) * 255 / 219), 0, 255).astype(np.uint8)
    table = luma_table(luma, grey)
    assert table is not None and np.array_equal(cv2.LUT(luma, table), grey)
    assert table[0] == 0 and table[255] == 255  # beyond the values seen: the fit, clipped
    assert 0 <= int(table[100]) - round((100 - 16) * 255 / 219) <= 0
    # half the values unseen: interpolated between their neighbours, within one grey level of the formula
    sparse = luma[:, ::2]
    table = luma_table(sparse, grey[:, ::2])
    formula = np.clip(np.round((np.arange(256) - 16) * 255 / 219), 0, 255)
    assert np.abs(table.astype(int) - formula).max() <= 1


def test_luma_table_refuses_what_it_cannot_reproduce():
    rng = np.random.default_rng(0)
    luma = rng.integers(0, 256, (30, 40), dtype=np.uint8)
    assert luma_table(luma, rng.integers(0, 256, (30, 40), dtype=np.uint8)) is None   # grey unrelated to luma
    assert luma_table(luma, luma[:, :20]) is None                                      # another shape
    assert luma_table(luma, luma.astype(np.uint16)) is None                            # another depth
    assert luma_table(np.full((5, 5), 7, np.uint8), np.full((5, 5), 7, np.uint8)) is None  # one level: no map
    few = np.tile(np.arange(100, 115, dtype=np.uint8), (3, 1))
    assert luma_table(few, few) is None and luma_table(few[:, :-1], few[:, :-1]) is None  # 15, 14 levels: too few
    assert luma_table(np.tile(np.arange(100, 116, dtype=np.uint8), (3, 1)),
                      np.tile(np.arange(100, 116, dtype=np.uint8), (3, 1))) is not None  # 16 levels
    assert np.array_equal(luma_table(luma, luma), np.arange(256))                       # grey is luma


@pytest.mark.parametrize("threads", [1, 2])  # (one: luma mapped on the tracking thread; two: on the reader's)
def test_replay_the_same_with_and_without_the_luma_plane(tmp_path, monkeypatch, threads):
    video = tmp_path / "tap.mp4"
    _write(video, "mp4v", frames=16)
    deferred = []
    defer = LumaVideoSource.defer_table
    monkeypatch.setattr(LumaVideoSource, "defer_table", lambda self: deferred.append(1) or defer(self))
    tables = []

    def spied(luma, grey):
        tables.append(luma_table(luma, grey))
        return tables[-1]

    monkeypatch.setattr(luma_module, "luma_table", spied)
    replay_video(video, tmp_path / "luma.h5", decode_threads=threads)
    assert len(tables) == 1 and tables[0] is not None  # replay read the luma plane
    assert len(deferred) == (threads == 1)
    monkeypatch.setattr(luma_module, "luma_table", lambda luma, grey: None)  # the BGR path throughout
    replay_video(video, tmp_path / "bgr.h5", decode_threads=threads)
    with h5py.File(tmp_path / "luma.h5") as a, h5py.File(tmp_path / "bgr.h5") as b:
        for name in ("positions", "lost", "retired", "blank"):
            assert np.array_equal(a[name][:], b[name][:], equal_nan=name == "positions")


@pytest.mark.parametrize("codec,suffix", CODECS)
def test_deferred_table_maps_every_frame_to_grey(tmp_path, codec, suffix):
    video = tmp_path / f"grey{suffix}"
    _write(video, codec, frames=6)
    expected = _frames(VideoSource(video, grey=True))
    source = LumaVideoSource(video)
    table = source.defer_table()  # replay maps on its tracking thread
    got = _frames(source)
    assert table is not None and len(got) == len(expected) == 6
    raw_differs = False
    for (_, _, image), (_, _, image0) in zip(got, expected):
        raw_differs |= not np.array_equal(image, image0)
        assert np.array_equal(cv2.LUT(image, table), image0)  # the first frame too: it is luma as the others
    # (mp4v's limited range, MJPG's one level of offset from swscale here: the raw luma is not the grey)
    assert raw_differs == (not np.array_equal(table, np.arange(256)))
    colour = tmp_path / f"colour{suffix}"
    _write(colour, codec, tint=(0.8, 1.0, 1.15), frames=3)
    with LumaVideoSource(colour) as fallback:
        assert fallback.defer_table() is None  # BGR converted by the source: nothing to map


def _reference_table(luma, grey):
    """`luma_table` as it was (session 17): means by weighted bincount, checked by looking the table up."""
    values, flat = luma.ravel(), grey.ravel().astype(np.float64)
    count = np.bincount(values, minlength=256)
    seen = np.flatnonzero(count)
    if len(seen) < 16:
        return None
    mean = np.bincount(values, weights=flat, minlength=256)[seen] / count[seen]
    slope, intercept = np.polyfit(seen.astype(np.float64), mean, 1, w=np.sqrt(count[seen]))
    levels = np.arange(256, dtype=np.float64)
    table = np.interp(levels, seen, mean)
    outside = (levels < seen[0]) | (levels > seen[-1])
    table[outside] = slope * levels[outside] + intercept
    table = np.clip(np.round(table), 0, 255).astype(np.uint8)
    return table if np.array_equal(cv2.LUT(luma, table), grey) else None


@pytest.mark.parametrize("exact_below", [2 ** 24, 1])  # cv2.calcHist's float32 counts; np.bincount's, for the largest
def test_luma_table_from_the_joint_histogram_is_the_reference(monkeypatch, exact_below):
    monkeypatch.setattr(luma_module, "_EXACT_FLOAT32", exact_below)
    rng = np.random.default_rng(7)
    made = refused = 0
    for trial in range(60):
        height, width = int(rng.integers(8, 120)), int(rng.integers(8, 160))
        luma = rng.integers(int(rng.integers(0, 40)), int(rng.integers(60, 256)), (height, width), dtype=np.uint8)
        shift = rng.uniform(-0.5, 0.5, 256)  # each luma value's own rounding
        grey = np.clip(np.round((luma - 16.0) * 255 / 219 + shift[luma]), 0, 255).astype(np.uint8)
        if trial % 3 == 1:  # one pixel off its luma's grey (chroma): no table reproduces the frame
            y, x = rng.integers(height), rng.integers(width)
            grey[y, x] = grey[y, x] + 1 if grey[y, x] < 255 else 254
        if trial % 5 == 4:
            luma = luma[:, ::2]  # (a strided view)
            grey = grey[:, ::2].copy()
        expected, table = _reference_table(luma, grey), luma_table(luma, grey)
        assert (table is None) == (expected is None)
        if expected is not None:
            assert np.array_equal(table, expected) and np.array_equal(cv2.LUT(luma, table), grey)
        made, refused = made + (expected is not None), refused + (expected is None)
    assert made >= 20 and refused >= 15  # both outcomes exercised


@pytest.mark.parametrize("codec,suffix", CODECS)
def test_open_grey_takes_over_the_sources_capture(tmp_path, monkeypatch, codec, suffix):
    video = tmp_path / f"grey{suffix}"
    _write(video, codec, frames=5)
    expected = _frames(VideoSource(video, grey=True))
    real, opened = cv2.VideoCapture, []
    monkeypatch.setattr(cv2, "VideoCapture", lambda *args: opened.append(args[0]) or real(*args))
    source = luma_module.open_grey(video, 1)
    assert isinstance(source, LumaVideoSource) and source.luma
    assert len(opened) == 2  # the source's BGR capture and the luma one: the first frame decoded once by each
    table = source.defer_table()
    got = _frames(source)
    assert len(got) == len(expected) == 5
    for (index, time_s, image), (index0, time0_s, image0) in zip(got, expected):
        assert index == index0 and time_s == time0_s and np.array_equal(cv2.LUT(image, table), image0)


def test_adopt_takes_fresh_grey_video_sources_only(tmp_path):
    video = tmp_path / "colour.mp4"
    _write(video, "mp4v", tint=(0.8, 1.0, 1.15), frames=4)
    expected = _frames(VideoSource(video, grey=True))
    original = VideoSource(video, grey=True)
    source = LumaVideoSource.adopt(original)
    assert not source.luma  # a colour recording: the BGR path, on the adopted capture
    original.close()  # closed already: the capture is the new source's, still open
    got = _frames(source)
    assert all(np.array_equal(image, image0) for (_, _, image), (_, _, image0) in zip(got, expected))
    assert len(got) == len(expected) == 4
    read_from = VideoSource(video, grey=True)
    read_from.read()
    for refused in (read_from, VideoSource(video), source):  # read from; BGR; closed
        with pytest.raises(ValueError):
            LumaVideoSource.adopt(refused)
    read_from.close()
