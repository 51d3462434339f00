"""TacTip: sensor front ends (camera, video, synthetic TacTip, taxels), streaming, station and CLI."""

from .errors import ConfigError, SourceError, TactipError
from .sources import (CameraSource, Frame, FrameSource, ImageFolderSource, SyntheticSource, ThreadedReader,
                      VideoSource, open_source)
from .synthetic import Contact, SyntheticFrame, SyntheticTacTip, tap_profile

__all__ = ["TactipError", "SourceError", "ConfigError",
           "Contact", "SyntheticFrame", "SyntheticTacTip", "tap_profile",
           "Frame", "FrameSource", "open_source", "ThreadedReader", "CameraSource", "VideoSource",
           "ImageFolderSource", "SyntheticSource"]
__version__ = "0.1.0"
