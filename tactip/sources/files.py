"""Recorded frames: video files and folders of images, as frame sources."""

from __future__ import annotations

import math
import pathlib
import re

from tactip.errors import SourceError
from tactip.sources.base import FrameSourceBase

__all__ = ["VideoSource", "ImageFolderSource", "IMAGE_SUFFIXES"]

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")


class VideoSource(FrameSourceBase):
    """Frames of a video file (any container and codec OpenCV's FFmpeg backend reads).

    Time stamps are ``index / frame_rate`` (from the file's frame rate), or the decoder's position in
    ms when the file has none.

    Parameters
    ----------
    path : str or path-like
    grey : bool
        Convert frames to grey (once, on read); decoded videos are BGR even when written grey.
    decode_threads : int, optional
        Threads of the FFmpeg decoder (default: FFmpeg's choice, about one per core). One leaves
        the other cores to whatever consumes the frames (`tactip replay` tracks on the main thread
        while a thread decodes).

    Raises
    ------
    SourceError
        Naming the path, when the file is missing, not a video, corrupt, or has no readable frame.

    Examples
    --------
    >>> with VideoSource("samples/synthetic_tap.mp4", grey=True) as video:  # doctest: +SKIP
    ...     frames = list(video)
    """

    def __init__(self, path, *, grey: bool = False, decode_threads: int | None = None):
        super().__init__(grey=grey)
        if decode_threads is not None and (int(decode_threads) != decode_threads or decode_threads < 1):
            raise ValueError(f"decode_threads must be a positive integer, got {decode_threads!r}")
        import cv2

        self._cv2 = cv2
        self.path = pathlib.Path(path)
        self.name = f"video {str(self.path)!r}"
        if not self.path.is_file():
            self._closed = True
            what = "a folder, not a video file" if self.path.is_dir() else "no such file"
            raise SourceError(f"cannot open video {str(self.path)!r}: {what}")
        container = _sniff_video(self.path)  # permission denied and empty files are told apart here
        options = [] if decode_threads is None else [cv2.CAP_PROP_N_THREADS, int(decode_threads)]
        self._capture = cv2.VideoCapture(str(self.path), cv2.CAP_ANY, options)
        if not self._capture.isOpened():
            self._closed = True
            raise SourceError(f"cannot open video {str(self.path)!r}: " + (
                f"a corrupt {container} file (the decoder cannot open it)" if container else
                "not a video (its content is no known video container: mp4, avi, mkv, webm, mov ...)"))
        ok, first = self._capture.read()
        if not ok or first is None:
            self.close()
            kind = f"{container} " if container else ""
            raise SourceError(f"cannot read video {str(self.path)!r}: a corrupt {kind}file with no decodable frame")
        self._pending = first
        fps = self._capture.get(cv2.CAP_PROP_FPS)
        self.frame_rate = float(fps) if fps and math.isfinite(fps) and 0 < fps < 1000 else None
        self.frame_size = (first.shape[1], first.shape[0])
        count = self._capture.get(cv2.CAP_PROP_FRAME_COUNT)
        self.frame_count = int(count) if count and math.isfinite(count) and count > 0 else None

    def _read(self):
        if self._pending is not None:
            image, self._pending = self._pending, None
        else:
            ok, image = self._capture.read()
            if not ok or image is None:
                return None
        if self.frame_rate:
            return image, self._index / self.frame_rate
        return image, self._capture.get(self._cv2.CAP_PROP_POS_MSEC) / 1000.0

    def _seek(self, index: int) -> None:
        self._pending = None
        if not self._capture.set(self._cv2.CAP_PROP_POS_FRAMES, index):
            raise SourceError(f"cannot seek to frame {index} in {self.name}")

    def _close(self) -> None:
        self._capture.release()


def _natural_key(path: pathlib.Path):
    """Sort key that orders frame2 before frame10."""
    return [int(part) if part.isdigit() else part.lower() for part in re.split(r"(\d+)", path.name)]


class ImageFolderSource(FrameSourceBase):
    """Frames from image files (png, jpg, bmp, tif), in natural name order.

    Parameters
    ----------
    path : str or path-like
        A folder of images, or a single image file (a one-frame stream).
    frame_rate : float or None
        Frames per second for the time stamps (``index / frame_rate``); None leaves the rate unknown
        and time stamps equal to the frame index.
    grey : bool
        Convert frames to grey (once, on read). Grey files are read as grey, colour files as BGR.

    Raises
    ------
    SourceError
        Naming the path, when the folder is missing or holds no image, or an image cannot be read.
    """

    def __init__(self, path, *, frame_rate: float | None = None, grey: bool = False):
        super().__init__(grey=grey)
        import cv2

        self._cv2 = cv2
        self.path = pathlib.Path(path)
        self.name = f"image folder {str(self.path)!r}"
        if self.path.is_file() and self.path.suffix.lower() in IMAGE_SUFFIXES:
            self.files = [self.path]
        elif self.path.is_dir():
            self.files = sorted((p for p in self.path.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES
                                 and p.is_file()), key=_natural_key)
        elif self.path.is_file():
            head = _read_head(self.path, "image")
            names = ", ".join(IMAGE_SUFFIXES)
            if any(magic in head[:12] for magic in _VIDEO_MAGIC):
                why = f"a video, not an image (videos go to 'tactip replay'; images are {names} files)"
            elif any(head.startswith(magic) for magic in _IMAGE_MAGIC):
                why = f"an image under another name: give it one of {names}"
            else:
                why = f"not an image (images are {names} files)"
            raise SourceError(f"cannot open image {str(self.path)!r}: {why}")
        else:
            raise SourceError(f"cannot open {self.name}: no such folder or image file")
        if not self.files:
            raise SourceError(f"{self.name} holds no images ({', '.join(IMAGE_SUFFIXES)})")
        if frame_rate is not None and not frame_rate > 0:
            raise SourceError(f"frame_rate must be > 0, got {frame_rate!r}")
        self.frame_rate = None if frame_rate is None else float(frame_rate)
        first = self._load(self.files[0])
        self.frame_size = (first.shape[1], first.shape[0])

    def _load(self, file: pathlib.Path):
        try:
            image = self._cv2.imread(str(file), self._cv2.IMREAD_ANYCOLOR)
        except self._cv2.error as exc:  # e.g. a header claiming more pixels than the decoder's limit
            limit = "larger than the decoder's limit" if "MAX_IMAGE_PIXELS" in str(exc) else "undecodable"
            raise SourceError(f"cannot read image {str(file)!r}: its header claims an image {limit} "
                              f"({_claimed_size(file)})") from None
        if image is None:
            head = _read_head(file, "image")
            if not head:
                raise SourceError(f"cannot read image {str(file)!r}: an empty file")
            known = any(head.startswith(magic) for magic in _IMAGE_MAGIC)
            raise SourceError(f"cannot read image {str(file)!r}: " + (
                "a corrupt image (its header is an image format's, its data cannot be decoded)" if known
                else "not an image (its content is no png, jpeg, bmp or tiff)"))
        return image

    def _read(self):
        if self._index >= len(self.files):
            return None
        image = self._load(self.files[self._index])
        return image, self._index / self.frame_rate if self.frame_rate else float(self._index)

    def _seek(self, index: int) -> None:
        """Any index is accepted; past the end, `read` returns None."""

    def __len__(self) -> int:
        return len(self.files)


# File signatures: what a file claims to be, to tell "not a video" from "a corrupt video".
_IMAGE_MAGIC = (b"\x89PNG", b"\xff\xd8\xff", b"BM", b"II*\x00", b"MM\x00*")
# Container signatures of videos (MP4/MOV "ftyp", AVI "RIFF", Matroska/WebM), found in the first 12 bytes.
_VIDEO_MAGIC = (b"ftyp", b"RIFF", b"\x1a\x45\xdf\xa3")


def _read_head(path: pathlib.Path, what: str, size: int = 512) -> bytes:
    """The first ``size`` bytes of ``path``; `SourceError` saying so when it cannot be read."""
    try:
        with open(path, "rb") as handle:
            return handle.read(size)
    except PermissionError:
        raise SourceError(f"cannot open {what} {str(path)!r}: permission denied") from None
    except OSError as exc:
        raise SourceError(f"cannot open {what} {str(path)!r}: {exc.strerror or exc}") from None


def _sniff_video(path: pathlib.Path) -> str | None:
    """The container a video file's first bytes announce (``"MP4"``, ``"AVI"`` ...), or None.

    Raises
    ------
    SourceError
        The file cannot be read (permission denied) or is empty.
    """
    head = _read_head(path, "video")
    if not head:
        raise SourceError(f"cannot open video {str(path)!r}: an empty file")
    if head[4:8] in (b"ftyp", b"moov", b"mdat", b"free", b"wide", b"skip"):
        return "MP4/MOV"
    if head[:4] == b"RIFF" and head[8:12] == b"AVI ":
        return "AVI"
    if head[:4] == b"\x1a\x45\xdf\xa3":
        return "Matroska/WebM"
    if head[:3] == b"FLV":
        return "FLV"
    if head[:4] == b"\x00\x00\x01\xba" or (len(head) > 188 and head[0] == head[188] == 0x47):
        return "MPEG"
    if head[:4] == b"OggS":
        return "Ogg"
    if head[:4] == b"\x30\x26\xb2\x75":
        return "ASF/WMV"
    if head[:6] in (b"GIF87a", b"GIF89a"):
        return "GIF"
    return None


def _claimed_size(file: pathlib.Path) -> str:
    """``"W x H px"`` from a PNG's header, else ``"size unknown"`` (for the message only)."""
    head = _read_head(file, "image")
    if head[:8] == b"\x89PNG\r\n\x1a\n" and len(head) >= 24:
        return f"{int.from_bytes(head[16:20], 'big')} x {int.from_bytes(head[20:24], 'big')} px"
    return "size unknown"
