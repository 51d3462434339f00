"""Grey frames of a video file from the decoder's luma plane, without a colour conversion (replay's reader).

OpenCV's FFmpeg backend converts every decoded frame to BGR (swscale, with bicubic chroma upsampling),
and a grey source then converts BGR to grey (`cv2.cvtColor`): on replay's slide bench (640 x 480,
mp4v or MJPG, one decoder thread) that is ~0.25 of the decode thread's ~0.87 ms/frame of CPU, which
on mp4v is replay's critical path. With ``cv2.CAP_PROP_CONVERT_RGB`` off (a documented property,
given when the capture is opened) the backend returns the frame "in its original format": for planar
YUV (yuv420p, yuvj420p, yuv422p ...) a (H, W) uint8 image that is the luma plane Y. That grey differs
from grey-of-BGR by the colour range alone (mp4v stores limited-range Y, 16-235: grey ~ (Y - 16)
255 / 219), so a 256-entry table (`cv2.LUT`; `look_up`, the same pixels two at a time) maps one to the other.

OpenCV says of this mode, when the capture opens, that multiplanar formats "have not been tested"
(and warns on every frame that it treats the format as 8UC1), so the path proves itself on each
video before it is used: the first frame is decoded both ways, the table is read off the pair, and
the luma path is taken only when the table reproduces the first frame's grey-of-BGR exactly, pixel
for pixel; otherwise (another backend, a colour recording whose chroma rounds differently, a packed or
10-bit pixel format whose first plane is not luma, an OpenCV that refuses the property) the source
reads BGR and converts, as `tactip.sources.VideoSource` does. On the slide bench's videos (grey
content, both codecs) every pixel of all 795 frames equals today's grey; on a tinted colour recording
with a saturated LED the first frame disagrees by up to 6 grey levels and the fallback is taken. Grey
content at 320x240 to 1920x1080 px takes the luma path in mp4v at every size tried; in MJPG at 320x240,
640x480 and 1280x720 only (at 328x246, 800x600 or 1920x1080 swscale's full-range conversion rounds by
pixel position, one level apart, and no table reproduces it: the BGR path).
OpenCV's warnings are silenced (log level ERROR) while such a capture is open. Replay maps luma to grey
on its tracking thread (`LumaVideoSource.defer_table`), where it costs less than on the decoder's (`mapped`).
Opening costs ~1 ms of decoding and 0.4 ms for the table (its joint histogram, `cv2.calcHist`), on replay's
serial start: `open_grey` takes over the capture `open_source` opened instead of opening it again.

Not used: FFmpeg's grey-only decoding (``AV_CODEC_FLAG_GRAY``, ``flags;gray``), which would skip the chroma
planes. OpenCV's FFmpeg backend (``cap_ffmpeg_impl.hpp``, 4.x) gives ``OPENCV_FFMPEG_CAPTURE_OPTIONS`` to
``avformat_open_input`` alone and opens the decoder with ``avcodec_open2(context, codec, NULL)``: of that
dictionary the decoder sees only ``video_codec``, ``avdiscard`` and the HW-acceleration keys, never
``flags``; the installed 5.0 behaves alike (below). And the FFmpeg inside opencv-python (``--enable-openssl --enable-libvpx --enable-shared
--enable-pic``) is built without ``--enable-gray``, so its MPEG-4 decoder ignores the flag even when given
(``CONFIG_GRAY`` 0). Measured: with ``flags;gray`` (or ``flags;+gray``) a colour recording still decodes in
colour (B - R 83.0 grey levels on average, as without) in the same CPU time, mp4v and MJPG.
"""

from __future__ import annotations

import sys
import threading

import numpy as np

from tactip.sources.files import VideoSource

__all__ = ["LumaVideoSource", "luma_table", "open_grey", "mapped", "look_up", "pair_table"]

_quiet_lock = threading.Lock()
_quiet_count = 0
_quiet_before = None


def _quiet(enter: bool) -> None:
    """OpenCV's log level at ERROR while any luma capture is open (it warns on each frame); restored after the last."""
    import cv2

    global _quiet_count, _quiet_before
    with _quiet_lock:
        if enter:
            if _quiet_count == 0:
                _quiet_before = cv2.utils.logging.getLogLevel()
                cv2.utils.logging.setLogLevel(min(_quiet_before, cv2.utils.logging.LOG_LEVEL_ERROR))
            _quiet_count += 1
        else:
            _quiet_count -= 1
            if _quiet_count == 0:
                cv2.utils.logging.setLogLevel(_quiet_before)


def luma_table(luma: np.ndarray, grey: np.ndarray) -> np.ndarray | None:
    """The 256-entry table that maps a frame's luma plane to its grey-of-BGR, or None when none does exactly.

    Parameters
    ----------
    luma, grey : (H, W) uint8 ndarray
        One frame decoded both ways: the luma plane (``CAP_PROP_CONVERT_RGB`` off) and
        ``cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)``.

    Returns
    -------
    (256,) uint8 ndarray or None
        Each luma value seen maps to its grey (the mean over its pixels, rounded); values not seen
        in this frame are interpolated between the nearest seen ones (a linear fit beyond them,
        clipped to 0-255). None when shapes or dtypes differ or when the table does not
        reproduce `grey` pixel for pixel (chroma or a pixel format that is not planar YUV), or when
        the frame shows fewer than 16 luma levels (too few to map the others).
    """
    if luma.shape != grey.shape or luma.dtype != np.uint8 or grey.dtype != np.uint8 or luma.ndim != 2:
        return None
    joint = _joint_histogram(luma, grey)
    count = joint.sum(axis=1)
    seen = np.flatnonzero(count)
    if len(seen) < _LEVELS:
        return None
    mean = joint[seen] @ np.arange(256.0) / count[seen]
    slope, intercept = np.polyfit(seen.astype(np.float64), mean, 1, w=np.sqrt(count[seen]))
    levels = np.arange(256, dtype=np.float64)
    table = np.interp(levels, seen, mean)
    outside = (levels < seen[0]) | (levels > seen[-1])
    table[outside] = slope * levels[outside] + intercept
    table = np.clip(np.round(table), 0, 255).astype(np.uint8)
    # Every pixel of each luma value seen has the table's grey: cv2.LUT(luma, table) equals `grey` pixel for pixel.
    return table if np.array_equal(joint[seen, table[seen]], count[seen]) else None


def _joint_histogram(luma: np.ndarray, grey: np.ndarray) -> np.ndarray:
    """(256, 256) float64 counts of the pixels with luma i and grey j: each luma value's count and mean grey are in
    its row, and the entries off a table's say whether it reproduces the grey. `cv2.calcHist` (0.3 ms for 640 x 480
    px against 0.5 for `np.bincount` of the pairs; float32 counts, exact below 2**24 pixels)."""
    if luma.size < _EXACT_FLOAT32:
        import cv2

        return cv2.calcHist([luma, grey], [0, 1], None, [256, 256], [0, 256, 0, 256]).astype(np.float64)
    pairs = luma.astype(np.uint16) << 8 | grey
    return np.bincount(pairs.ravel(), minlength=65536).reshape(256, 256).astype(np.float64)


_EXACT_FLOAT32 = 2 ** 24  # pixels: below, any count in float32 is exact (`cv2.calcHist`'s counts)

# Fewest luma levels a first frame must show for its table to be trusted on the levels it does not show (a dark or
# blank first frame: the BGR path). Slide bench, tables read off 30-100 levels of 16 frames (mp4v, MJPG) against
# the table of all 152-167 levels: within one grey level on every level, interpolated or extrapolated.
_LEVELS = 16


class LumaVideoSource(VideoSource):
    """A grey `tactip.sources.VideoSource` that reads the decoder's luma plane when that gives the same frames.

    Opens the video as `VideoSource` does (``grey=True``; its first frame decoded to BGR and
    converted; or takes over such a source, `adopt`), then a second capture of it with
    ``CAP_PROP_CONVERT_RGB`` off; when `luma_table`
    maps that capture's first frame onto the first's grey exactly, the second capture replaces
    the first and every later frame is its luma plane through the table; otherwise it is
    released and the source reads BGR and converts. `luma` says which path was taken.

    Parameters
    ----------
    path : str or path-like
    decode_threads : int, optional
        Threads of the FFmpeg decoder (`VideoSource`).
    """

    def __init__(self, path, *, decode_threads: int | None = None):
        super().__init__(path, grey=True, decode_threads=decode_threads)
        self._take_luma(decode_threads)

    @classmethod
    def adopt(cls, video: VideoSource, *, decode_threads: int | None = None) -> "LumaVideoSource":
        """`video` (a grey `VideoSource` not yet read from) as a `LumaVideoSource`: its capture and first frame taken
        over, not a second BGR capture opened and its first frame decoded again (`open_grey`); `video` is left closed.
        """
        if type(video) is not VideoSource or not video.grey or video._closed or video._index or video._pending is None:
            raise ValueError(f"a grey VideoSource not yet read from is adopted, not {video!r}")
        source = cls.__new__(cls)
        source.__dict__.update(video.__dict__)  # the capture, its first frame, rate, size and count
        video._closed = True  # its capture is the new source's: closing `video` must not release it
        source._take_luma(decode_threads)
        return source

    def _take_luma(self, decode_threads) -> None:
        self._table = None
        self._pairs = None  # `pair_table` of the table, made on the first frame this source maps
        self._quieted = False
        self._deferred = False
        try:
            self._open_luma(decode_threads)
        except Exception:  # an OpenCV that refuses the property: the BGR path, as before
            self._drop_luma()
        #: True when frames after the first are read from the luma plane.
        self.luma = self._table is not None

    def _open_luma(self, decode_threads) -> None:
        cv2 = self._cv2
        if self._capture.getBackendName() != "FFMPEG" or self._pending is None or self._pending.ndim != 3:
            return
        _quiet(True)
        self._quieted = True
        options = [cv2.CAP_PROP_CONVERT_RGB, 0] + ([] if decode_threads is None else
                                                    [cv2.CAP_PROP_N_THREADS, int(decode_threads)])
        capture = cv2.VideoCapture(str(self.path), cv2.CAP_FFMPEG, options)
        ok, luma = capture.read() if capture.isOpened() else (False, None)
        table = None
        if ok and luma is not None and capture.get(cv2.CAP_PROP_CONVERT_RGB) == 0:
            table = luma_table(luma, cv2.cvtColor(self._pending, cv2.COLOR_BGR2GRAY))
        if table is None:
            capture.release()
            self._drop_luma()
            return
        self._capture.release()
        self._capture, self._table, self._pending = capture, table, luma  # (its first frame mapped as the others)

    def _drop_luma(self) -> None:
        self._table = None
        if self._quieted:
            self._quieted = False
            _quiet(False)

    def defer_table(self) -> np.ndarray | None:
        """Stop mapping luma to grey here and return the table (None on the BGR path): the caller maps every frame
        read from now on (`mapped`, `look_up`: ``cv2.LUT(image, table)`` in place), e.g. on another thread than the
        decoder's."""
        table, self._deferred = self._table, self._table is not None
        return table

    def _read(self):
        item = super()._read()
        if item is not None and self._table is not None and not self._deferred:
            if self._pairs is None:
                self._pairs = pair_table(self._table)
            look_up(item[0], self._table, self._pairs)
        return item

    def _close(self) -> None:
        try:
            super()._close()
        finally:
            self._drop_luma()


def mapped(frames, table, region=None):
    """`frames`, their luma mapped to grey in place by `table` (`tactip.replay.luma.LumaVideoSource.defer_table`) on
    the thread that iterates (replay's tracking thread: there the lookup also brings the frame into that core's
    cache; on the decode thread it cost the decoder more than it saved the tracking, `bench/bench_replay.py`).
    None: the frames as they are. Each frame is looked up two pixels at a time (`look_up`), or only its part that
    `region` gives: a callable asked before each frame for the (rows, columns) slices that will be read of it, or
    None for all (replay's: the tracker's `pins.PinTracker.frame_region` once it has started; its slide bench's
    pad fills 12 % of the frame, the lookup 52 -> 14 us a frame). The rest of such a frame stays luma."""
    if table is None:
        yield from frames
        return
    pairs = pair_table(table)
    for frame in frames:
        part = None if region is None else region()
        if part is None:
            look_up(frame.image, table, pairs)
        else:
            look_up_part(frame.image, part, table)
        yield frame


def look_up_part(image: np.ndarray, part: tuple[slice, slice], table: np.ndarray) -> np.ndarray:
    """``cv2.LUT`` in place on the (rows, columns) `part` of a (H, W) uint8 `image` alone (`mapped`'s region; the
    rest of the image unchanged). Returns `image`."""
    import cv2

    view = image[part]
    if cv2.LUT(view, table, dst=view) is not view:  # (in place on a view whose rows are contiguous)
        view[...] = cv2.LUT(view, table)
    return image


def pair_table(table: np.ndarray) -> np.ndarray:
    """The (65536,) uint16 table of two neighbouring pixels, from a 256-entry uint8 `table`: entry ``b << 8 | a``
    holds ``table[b] << 8 | table[a]`` (pixel a first in memory, little-endian: `look_up`)."""
    table = np.asarray(table, dtype=np.uint8).ravel()
    pairs = (table[:, None].astype(np.uint16) << 8) | table[None, :]
    return pairs.ravel().astype("<u2")


def look_up(image: np.ndarray, table: np.ndarray, pairs: np.ndarray | None = None) -> np.ndarray:
    """``cv2.LUT(image, table)`` in place on a (H, W) uint8 `image`, the same pixels, ~0.6 x its CPU: two pixels a
    lookup in `pair_table` (128 kB, in the core's cache) by a compiled loop (Numba; `cv2.LUT` reads one pixel a
    lookup, 89 -> 52 us a 640 x 480 frame, replay's tracking thread on its slide bench). `cv2.LUT` where Numba is
    missing, ``TACTIP_KERNELS=numpy`` (`pins._kernels`), or the image is not a C-contiguous even number of bytes
    on a little-endian machine. Returns `image`."""
    kernel = _pair_kernel() if pairs is not None else None
    if (kernel is None or image.dtype != np.uint8 or not image.flags.c_contiguous or image.size % 2
            or sys.byteorder != "little"):
        import cv2

        if image.flags.c_contiguous:
            return cv2.LUT(image, table, dst=image)
        image[...] = cv2.LUT(image, table)  # (OpenCV writes into no strided view)
        return image
    kernel(image.reshape(-1).view(np.uint16), pairs)
    return image


_KERNEL: list = []  # the compiled pair lookup, or None (no Numba, or the NumPy reference chosen); once tried


def _pair_kernel():
    """The compiled `look_up` loop, or None."""
    from pins._kernels import compiled

    if compiled() is None:  # ``TACTIP_KERNELS=numpy`` or no Numba: OpenCV's lookup
        return None
    if not _KERNEL:
        try:
            from tactip.replay._jit_luma import look_up_pairs
        except ImportError:
            look_up_pairs = None
        _KERNEL.append(look_up_pairs)
    return _KERNEL[0]


def open_grey(video, threads: int | None = None):
    """`tactip.sources.open_source`'s grey source for `video`; a video file read from its luma plane where that
    gives the same frames (`tactip.replay.luma.LumaVideoSource`: no colour conversion on the decode thread)."""
    from tactip.sources import open_source

    source = open_source(video, grey=True, decode_threads=threads)
    return LumaVideoSource.adopt(source, decode_threads=threads) if type(source) is VideoSource else source
