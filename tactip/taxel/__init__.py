"""Capacitive taxel front end: simulated iCub fingertip and skin, pre-processing, CSV and UDP sources.

- `tactip.taxel.sensors`: geometry and receptive fields of the two sensors of paper 000;
- `tactip.taxel.sim`: the simulated sensor tapping along its location range (raw 8-bit stream);
- `tactip.taxel.preprocess`: high-pass filter, normalisation, resampling, per-tap baseline;
- `tactip.taxel.segment`: cutting streams into taps (explicit times or signal magnitude, live or recorded);
- `tactip.taxel.sources`: recorded (CSV) and live (UDP) readings, and taps from any source;
- `tactip.taxel.collect`: simulated training and test datasets (``tactip-dataset/1``).

The papers' acuity tables and stimuli built on this front end are in `tactip.reproduce`.
"""

from tactip.taxel.collect import (DEFAULT_TAPS, TaxelDatasetPaths, simulate_taxel_dataset, simulate_taxel_datasets,
                      write_taxel_test_stream)
from tactip.taxel.preprocess import (BASELINE_SAMPLES, FULL_SCALE_COUNTS, HighPassFilter, highpass, remove_tap_baseline,
                         resample_taps, taxel_pressure)
from tactip.taxel.segment import TapSegmenter, TapSegments, detect_taps, segment_taps
from tactip.taxel.sensors import TAXEL_SENSORS, TaxelSensor, receptive_field_response, taxel_sensor
from tactip.taxel.sim import TaxelSimulator, TaxelStream, contact_profile, sweep_locations
from tactip.taxel.sources import (ENCODINGS, CsvTaxelSource, TaxelReading, TaxelSource, UdpTaxelSender, UdpTaxelSource,
                      decode_reading, encode_reading, read_taps, write_taxel_csv)

__all__ = [
    "TAXEL_SENSORS", "TaxelSensor", "taxel_sensor", "receptive_field_response",
    "TaxelSimulator", "TaxelStream", "contact_profile", "sweep_locations",
    "FULL_SCALE_COUNTS", "BASELINE_SAMPLES", "HighPassFilter", "highpass", "taxel_pressure", "resample_taps",
    "remove_tap_baseline", "detect_taps", "segment_taps", "TapSegments", "TapSegmenter",
    "ENCODINGS", "TaxelReading", "TaxelSource", "CsvTaxelSource", "UdpTaxelSource", "UdpTaxelSender",
    "encode_reading", "decode_reading", "write_taxel_csv", "read_taps",
    "DEFAULT_TAPS", "TaxelDatasetPaths", "simulate_taxel_dataset", "simulate_taxel_datasets",
    "write_taxel_test_stream",
]
