"""Recorded frames: video files and folders of images, as frame sources."""

from __future__ import annotations

import math
import pathlib
import re

from ..errors import SourceError
from .base import FrameSourceBase

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

    Raises
    ------
    SourceError
        Naming the path, when the file is missing, not a video, corrupt, or has no readable frame.

    Examples
    --------
    >>> with VideoSource("samples/synthetic_tap.mp4", grey=True) as video:  # doctest: +SKIP
    ...     frames = list(video)
    """

    def __init__(self, path, *, grey: bool = False):
        super().__init__(grey=grey)
        import cv2

        self._cv2 = cv2
        self.path = pathlib.Path(path)
        self.name = f"video {str(self.path)!r}"
        if not self.path.is_file():
            self._closed = True
            raise SourceError(f"cannot open video {str(self.path)!r}: no such file")
        self._capture = cv2.VideoCapture(str(self.path))
        if not self._capture.isOpened():
            self._closed = True
            raise SourceError(f"cannot open video {str(self.path)!r}: not a readable video (corrupt, or an "
                              f"unsupported format)")
        ok, first = self._capture.read()
        if not ok or first is None:
            self.close()
            raise SourceError(f"cannot read video {str(self.path)!r}: no decodable frame")
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
        image = self._cv2.imread(str(file), self._cv2.IMREAD_ANYCOLOR)
        if image is None:
            raise SourceError(f"cannot read image {str(file)!r}: not an image or corrupt")
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
