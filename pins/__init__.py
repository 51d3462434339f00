"""Pins: detection, tracking, displacement integration, pin selection and tap features.

Pure array code: nothing here opens a camera, a file or an arm.
"""

from .detect import Blobs, DetectionParams, detect_blobs, detect_pins
from .disc import SensorDisc, as_grey, find_sensor_disc, frame_region
from .displacement import displacement_from_rest, displacement_magnitude, integrate_flow
from .errors import NoSensorError, PinsError, ShapeError
from .lattice import MIN_SENSOR_PINS, REJECTION_REASONS, PinField, draw_pin_field, find_pin_field
from .contacts import ContactKind, contact_kinds
from .features import (LostPinError, TapRecorder, feature_dim_names, fill_lost, resample_tap, seen_pins,
                       tap_features)
from .segment import converging_frames, jitter_floor_px, neighbour_median, segment_taps, tap_signal
from .skin import skin_rest
from .scale import (DEFAULT_PAD_DIAMETER_MM, SENSOR_PRESETS, PadScale, SensorDescription, central_spacing_px,
                    pad_scale, pin_pitch_mm, sensor_preset, sensor_scale)
from .select import PinSelection, median_spacing_px, select_feature_pins, select_pins
from .lk import LKParams, track_pins
from .track import PinTracker, match_to_blobs
from .propagate import match_by_propagation

__all__ = [
    "PinsError", "NoSensorError", "ShapeError", "LostPinError",
    "SensorDisc", "find_sensor_disc", "frame_region", "as_grey",
    "DetectionParams", "Blobs", "detect_pins", "detect_blobs",
    "find_pin_field", "PinField", "REJECTION_REASONS", "draw_pin_field", "MIN_SENSOR_PINS",
    "LKParams", "track_pins", "match_to_blobs", "PinTracker", "match_by_propagation",
    "displacement_from_rest", "integrate_flow", "displacement_magnitude",
    "select_pins", "select_feature_pins", "PinSelection", "median_spacing_px",
    "pad_scale", "PadScale", "pin_pitch_mm", "central_spacing_px", "SensorDescription", "SENSOR_PRESETS",
    "sensor_preset", "sensor_scale", "DEFAULT_PAD_DIAMETER_MM",
    "feature_dim_names", "fill_lost", "resample_tap", "seen_pins", "tap_features", "TapRecorder",
    "tap_signal", "neighbour_median", "segment_taps", "skin_rest", "converging_frames", "jitter_floor_px",
    "contact_kinds",
    "ContactKind",
]
