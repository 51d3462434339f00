"""TacTip: sensor front ends (camera, video, synthetic TacTip, taxels), streaming, station and CLI.

The front ends' names are imported on first use (PEP 562), so that ``import tactip.cli`` (the command
line's parsing and its refusals of bad input) does not wait for OpenCV, SciPy and h5py.
"""

import importlib

from tactip.errors import ConfigError, SourceError, TactipError

# Public name -> the module of this package that defines it (imported when the name is first used).
_LAZY = {
    **dict.fromkeys(("Contact", "SyntheticFrame", "SyntheticTacTip", "SyntheticGel", "tap_profile"), ".sim"),
    **dict.fromkeys(("Frame", "FrameSource", "open_source", "ThreadedReader", "CameraSource", "VideoSource",
                     "ImageFolderSource", "SyntheticSource"), ".sources"),
    **dict.fromkeys(("TaxelSensor", "taxel_sensor", "TaxelSimulator", "simulate_taxel_datasets", "TapSegmenter",
                     "CsvTaxelSource", "UdpTaxelSource", "read_taps"), ".taxel"),
}

__all__ = ["TactipError", "SourceError", "ConfigError", *_LAZY]
__version__ = "0.1.0"


def __getattr__(name: str):
    """The public name ``name``, its module imported on first use."""
    if name not in _LAZY:
        raise AttributeError(f"module 'tactip' has no attribute {name!r}")
    value = getattr(importlib.import_module(_LAZY[name], __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """The module's names, the lazily imported ones included."""
    return sorted(set(globals()) | set(_LAZY))
