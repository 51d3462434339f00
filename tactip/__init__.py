"""TacTip: sensor front ends (camera, video, synthetic TacTip, taxels), streaming, station and CLI."""

from .errors import ConfigError, SourceError, TactipError

__all__ = ["TactipError", "SourceError", "ConfigError"]
__version__ = "0.1.0"
