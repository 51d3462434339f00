"""TacTip: sensor front ends (camera, video, synthetic TacTip, taxels), streaming, station and CLI."""

from .errors import ConfigError, SourceError, TactipError
from .sources import (CameraSource, Frame, FrameSource, ImageFolderSource, SyntheticSource, ThreadedReader,
                      VideoSource, open_source)
from .synthetic import Contact, SyntheticFrame, SyntheticTacTip, tap_profile
from .taxel import (CsvTaxelSource, TapSegmenter, TaxelSensor, TaxelSimulator, UdpTaxelSource, read_taps,
                    simulate_taxel_datasets, taxel_sensor)

__all__ = ["TactipError", "SourceError", "ConfigError",
           "Contact", "SyntheticFrame", "SyntheticTacTip", "tap_profile",
           "Frame", "FrameSource", "open_source", "ThreadedReader", "CameraSource", "VideoSource",
           "ImageFolderSource", "SyntheticSource",
           "TaxelSensor", "taxel_sensor", "TaxelSimulator", "simulate_taxel_datasets", "TapSegmenter",
           "CsvTaxelSource", "UdpTaxelSource", "read_taps"]
__version__ = "0.1.0"
