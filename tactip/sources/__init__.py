"""Frame sources: one streaming interface for cameras, video files, image folders and the synthetic TacTip.

>>> from tactip.sources import open_source
>>> with open_source("synthetic:127") as source:
...     first = source.read()
>>> first.index, first.image.shape
(0, (480, 640))
"""

from __future__ import annotations

import pathlib
import re

from tactip.errors import SourceError
from tactip.sources.base import Frame, FrameSource, FrameSourceBase
from tactip.sources.camera import CameraSource
from tactip.sources.files import IMAGE_SUFFIXES, ImageFolderSource, VideoSource
from tactip.sim.source import DEFAULT_TAPS, SyntheticSource
from tactip.sources.threaded import ThreadedReader

__all__ = ["Frame", "FrameSource", "FrameSourceBase", "CameraSource", "VideoSource", "ImageFolderSource",
           "SyntheticSource", "ThreadedReader", "open_source", "DEFAULT_TAPS", "IMAGE_SUFFIXES"]

# Options of a live camera that no recorded or synthetic source has.
_CAMERA_OPTIONS = {"exposure"}

_CHOICES = ("a camera index (0) or /dev/videoN, a video file, an image file or folder, "
            "or 'synthetic' / 'synthetic:PINS' / 'synthetic:PRESET'")


def open_source(spec: str | int | pathlib.Path, **options) -> FrameSource:
    """Open a frame source from a command-line style specification.

    Parameters
    ----------
    spec : str, int or path
        - an int, a digit string or ``/dev/videoN``: a live camera (`CameraSource`);
        - ``"synthetic"``, ``"synthetic:331"`` or ``"synthetic:rim-ring-331"`` (a preset of
          `tactip.sim.synthetic.PRESETS`): the synthetic TacTip tapping (`SyntheticSource`);
        - a directory or an image file: `ImageFolderSource`;
        - any other existing file: a video (`VideoSource`).
    **options
        Passed to the source's constructor (for example ``grey=True``, ``exposure=50``, ``taps=[...]``).
        ``decode_threads`` (threads of a video file's decoder, `VideoSource`) is dropped for the
        other sources, which decode no video stream.

    Returns
    -------
    FrameSource

    Raises
    ------
    SourceError
        When the spec matches nothing (naming it and the choices) or the source cannot be opened.
    """
    if isinstance(spec, bool):
        raise SourceError(f"cannot open source {spec!r}; choose {_CHOICES}")
    decode_threads = options.pop("decode_threads", None)
    if isinstance(spec, int):
        return CameraSource(spec, **options)
    text = str(spec)
    if text.isdigit():
        return CameraSource(int(text), **options)
    if re.fullmatch(r"/dev/video\d+", text):
        return CameraSource(text, **options)
    camera_only = sorted(set(options) & _CAMERA_OPTIONS)
    if camera_only:
        raise SourceError(f"{', '.join(camera_only)} applies to a camera only, not to {text!r}")
    match = re.fullmatch(r"synthetic(?::([\w.-]+))?", text)
    if match:
        if match.group(1) and match.group(1).isdigit():
            options.setdefault("pins", int(match.group(1)))
        elif match.group(1):
            options.setdefault("preset", match.group(1))
        try:
            return SyntheticSource(**options)
        except ValueError as exc:  # e.g. synthetic:0 pins: a spec out of range, said as a source error
            raise SourceError(f"cannot open source {text!r}: {exc}") from None
    path = pathlib.Path(text)
    if path.is_dir() or (path.is_file() and path.suffix.lower() in IMAGE_SUFFIXES):
        return ImageFolderSource(path, **options)
    if path.is_file():
        return VideoSource(path, decode_threads=decode_threads, **options)
    raise SourceError(f"cannot open source {text!r}: no such file, folder or camera; choose {_CHOICES}")
