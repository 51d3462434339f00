"""TacTip: sensor front ends (camera, video, synthetic TacTip, taxels), streaming, station and CLI."""

from .errors import ConfigError, SourceError, TactipError
from .synthetic import Contact, SyntheticFrame, SyntheticTacTip, tap_profile

__all__ = ["TactipError", "SourceError", "ConfigError",
           "Contact", "SyntheticFrame", "SyntheticTacTip", "tap_profile"]
__version__ = "0.1.0"
