"""Sensor calibration: from rest frames to the file every later step reads.

A TacTip is calibrated off contact: a few rest frames are averaged (sensor noise falls as
1/sqrt(n)), the sensor disc is found, the pin field is found (`pins.find_pin_field`: the blobs
that form the pin lattice, with detection parameters for later frames) and its count checked
against the expected pin count, and the subset used as features is chosen (paper 002 III-A.3:
40 pins at least 4 mm apart; on a pad where they cannot be, as far apart as it allows, by the rule
replay uses: `pins.select_feature_pins`). The scale, mm per px, is the sensor's pin pitch in mm over
the central pin pitch in px (`pins.sensor_scale`, the rule ``tactip detect`` and ``tactip replay``
use too) unless the caller measured it.

The calibration file is HDF5 (schema ``tactip-calibration/1``): datasets ``reference_pins``
(N, 2) float64 px and ``selected_pins`` (P,) int; attributes ``schema``, ``detection`` (JSON of
`pins.DetectionParams`), ``disc`` (cx, cy, radius px), ``mm_per_px``, ``expected_pins``,
``frame_size`` (width, height px), ``rest_frames``, ``min_separation_mm``, ``sensor`` (JSON),
``created_at``; and, in files written since the scale comes from the pin pitch, ``scale`` (JSON:
mm_per_px, pitch_px, pitch_mm, source, sensor) and ``separation_mm`` (the selected pins' smallest
distance, mm).
"""

from __future__ import annotations

import datetime as _dt
import json
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Sequence

import numpy as np

from _shared import cut_short
from pins import (DetectionParams, NoSensorError, PinsError, SensorDescription, SensorDisc, as_grey, detect_pins,
                  find_pin_field, match_to_blobs, median_spacing_px, select_feature_pins,
                  sensor_scale)

from .errors import CalibrationError

__all__ = ["SensorCalibration", "calibrate_sensor", "save_calibration", "load_calibration", "SCHEMA",
           "place_reference_pins", "check_model_fits"]

SCHEMA = "tactip-calibration/1"


@dataclass(frozen=True)
class SensorCalibration:
    """What the station needs to turn a TacTip's frames into tap features.

    Attributes
    ----------
    detection : pins.DetectionParams
        Tuned detection parameters.
    disc : pins.SensorDisc
        The sensor disc in the rest frames, px.
    reference_pins : (N, 2) ndarray of float64
        Pin positions (x, y) in the averaged rest frame, px; their order is the pin identity.
    selected_pins : (P,) ndarray of int
        Indices into ``reference_pins`` of the feature pins, in selection order.
    mm_per_px : float
        Image scale at the pad, mm per px.
    expected_pins : int
        Pin count the detection was tuned to.
    frame_size : (int, int)
        (width, height) of the frames, px.
    min_separation_mm : float
        Minimum separation of the selected pins, mm.
    rest_frames : int
        How many rest frames were averaged.
    sensor : dict
        Free description of the sensor (source, preset, serial ...).
    scale : dict
        How `mm_per_px` was derived (`pins.PadScale.to_dict`: mm_per_px, pitch_px, pitch_mm, source,
        sensor); empty in files older than that.
    separation_mm : float
        Smallest distance between two selected pins, mm: `min_separation_mm` or more, less only on a
        pad where the pins cannot be that far apart (NaN in older files).
    """

    detection: DetectionParams
    disc: SensorDisc
    reference_pins: np.ndarray
    selected_pins: np.ndarray
    mm_per_px: float
    expected_pins: int
    frame_size: tuple[int, int]
    min_separation_mm: float = 4.0
    rest_frames: int = 1
    sensor: dict = field(default_factory=dict)
    scale: dict = field(default_factory=dict)
    separation_mm: float = float("nan")

    @cached_property
    def reference_spacing_px(self) -> float:
        """Median nearest-neighbour spacing of the reference pins, px: computed once per calibration (a
        station places the same pins on every tap's rest frame)."""
        return float(median_spacing_px(np.asarray(self.reference_pins, dtype=np.float64)))

    @property
    def n_selected(self) -> int:
        """Number of feature pins P (the feature arrays have 2 P dimensions)."""
        return int(len(self.selected_pins))

    def describe(self) -> str:
        """One line for a person: pins found, pins selected, scale and how it was derived."""
        apart = f">= {self.min_separation_mm:g} mm apart"
        if self.separation_mm < self.min_separation_mm * (1 - 1e-9):
            apart = (f">= {self.separation_mm:.2f} mm apart (as far as the pad allows; "
                     f"{self.min_separation_mm:g} mm asked)")
        source = f" ({self.scale['source']})" if self.scale.get("source") else ""
        return (f"{len(self.reference_pins)} pins (expected {self.expected_pins}), {self.n_selected} selected "
                f"{apart}, {self.mm_per_px:.4f} mm/px{source}, disc r = "
                f"{self.disc.radius_px:.1f} px at ({self.disc.cx:.1f}, {self.disc.cy:.1f})")


def calibrate_sensor(rest_frames: Sequence[np.ndarray], *, expected_pins: int, pad_diameter_mm: float | None = None,
                     selected_pins: int = 40, min_separation_mm: float = 4.0, count_tolerance: float = 0.1,
                     mm_per_px: float | None = None, dark_pins: bool | None = None,
                     sensor: dict | None = None,
                     description: str | SensorDescription | None = None) -> SensorCalibration:
    """Calibrate a TacTip from frames taken off contact.

    Parameters
    ----------
    rest_frames : sequence of (H, W) or (H, W, 3) uint8 arrays
        Frames with nothing touching the pad (averaged).
    expected_pins : int
        The sensor's pin count; it confirms the pin field found (which does not depend on it) and,
        unless `description` says otherwise, is the pin count of the pin pitch in mm.
    pad_diameter_mm : float, optional
        Diameter of the hemispherical pad, mm, for the pin pitch in mm (default the description's,
        else 40 mm, assumed).
    selected_pins : int
        How many feature pins to choose (paper: 40).
    min_separation_mm : float
        Their minimum separation, mm (paper: 4).
    count_tolerance : float
        Largest accepted relative difference between the pins found and `expected_pins` (0.1: 10 %;
        rim pins hidden by a rim ring or the image edge are usually a few %).
    mm_per_px : float, optional
        A measured scale, mm per px, instead of the one from the pin pitch.
    dark_pins : bool or None
        Dark markers on a light membrane (True) or bright pins on a dark one (False); None: decided
        from the frames as `tactip detect` and `tactip replay` decide it (`pins.find_pin_field`).
    sensor : dict, optional
        Description stored with the calibration.
    description : str or pins.SensorDescription, optional
        The sensor (a `pins.SENSOR_PRESETS` name), for the pin pitch in mm.

    Returns
    -------
    SensorCalibration

    Raises
    ------
    CalibrationError
        No frames, frames of different sizes, no sensor disc in view, a pin count far from
        expected, fewer pins than `selected_pins`, or too few to measure the pin pitch.
    """
    if len(rest_frames) == 0:
        raise CalibrationError("no rest frames to calibrate from")
    greys = [as_grey(np.asarray(f)) for f in rest_frames]
    if len({g.shape for g in greys}) != 1:
        raise CalibrationError(f"rest frames differ in size: {sorted({g.shape for g in greys})}")
    if expected_pins < 2:
        raise CalibrationError(f"expected_pins must be at least 2, got {expected_pins}")
    mean = np.rint(np.mean(np.stack(greys), axis=0)).astype(np.uint8)

    try:
        # find_pin_field finds the disc of the polarity (or takes the whole frame for a flat gel)
        field = find_pin_field(mean, expected_pins=expected_pins, dark_pins=dark_pins)
    except NoSensorError as exc:
        raise CalibrationError(f"no sensor in view: {exc} (is the camera the TacTip's, and its LEDs on?)") from None
    disc = field.disc
    if abs(field.count_error) > count_tolerance * expected_pins:
        raise CalibrationError(
            f"pin detection cannot be tuned to {expected_pins} pins: the pin lattice has {field.count} pins "
            f"({field.count_error:+d}, {field.count_error / expected_pins:+.0%}, more than {count_tolerance:.0%} off); "
            f"is the pad touching something, the count ([sensor] pins) wrong, or the image out of focus?")
    params, reference = field.params, field.centres
    try:
        scale = sensor_scale(reference, sensor=description, pad_diameter_mm=pad_diameter_mm, mm_per_px=mm_per_px,
                             expected_pins=expected_pins)
    except PinsError as exc:
        raise CalibrationError(f"cannot derive the scale: {exc}") from None
    if len(reference) < selected_pins:
        raise CalibrationError(f"cannot select the feature pins: only {len(reference)} pins were found, "
                               f"{selected_pins} asked; lower [sensor] selected_pins")
    # As far apart as the pad allows when the pins cannot be min_separation_mm apart (replay's rule).
    chosen = select_feature_pins(reference, n_pins=selected_pins, min_separation_mm=min_separation_mm,
                                 mm_per_px=scale.mm_per_px, centre=(disc.cx, disc.cy))
    height, width = mean.shape
    return SensorCalibration(detection=params, disc=disc, reference_pins=reference, selected_pins=chosen.indices,
                             mm_per_px=scale.mm_per_px, expected_pins=int(expected_pins), frame_size=(width, height),
                             min_separation_mm=float(min_separation_mm), rest_frames=len(greys),
                             sensor=dict(sensor or {}), scale=scale.to_dict(), separation_mm=chosen.separation_mm)


def save_calibration(path: str | Path, calibration: SensorCalibration) -> None:
    """Write a calibration file (HDF5, ``tactip-calibration/1``), atomically."""
    from _shared import atomic_path, hdf5_in_memory

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp, hdf5_in_memory(tmp) as f:  # temporary name, fsync, rename; a full disk an OSError
        f.attrs["schema"] = SCHEMA
        f.create_dataset("reference_pins", data=np.asarray(calibration.reference_pins, dtype=np.float64))
        f.create_dataset("selected_pins", data=np.asarray(calibration.selected_pins, dtype=np.int64))
        f.attrs["detection"] = json.dumps(calibration.detection.to_dict())
        d = calibration.disc
        f.attrs["disc"] = np.array([d.cx, d.cy, d.radius_px], dtype=np.float64)
        if d.whole_frame:  # a flat gel: the sensing region is the whole frame (absent: a disc)
            f.attrs["disc_whole_frame"] = True
        f.attrs["mm_per_px"] = float(calibration.mm_per_px)
        f.attrs["expected_pins"] = int(calibration.expected_pins)
        f.attrs["frame_size"] = np.array(calibration.frame_size, dtype=np.int64)
        f.attrs["min_separation_mm"] = float(calibration.min_separation_mm)
        f.attrs["rest_frames"] = int(calibration.rest_frames)
        f.attrs["sensor"] = json.dumps(calibration.sensor)
        f.attrs["scale"] = json.dumps(calibration.scale)
        f.attrs["separation_mm"] = float(calibration.separation_mm)
        f.attrs["created_at"] = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")


def load_calibration(path: str | Path) -> SensorCalibration:
    """Read a calibration file; `CalibrationError` when it is missing or of another kind."""
    import h5py

    path = Path(path)
    if not path.exists():
        raise CalibrationError(f"no calibration file at {path}: run 'tactip calibrate' first")
    try:
        with h5py.File(path, "r") as f:
            schema = f.attrs.get("schema")
            if schema != SCHEMA:
                raise CalibrationError(f"{path} is not a TacTip calibration file (schema {schema!r}, "
                                       f"expected {SCHEMA!r})")
            missing = [n for n in ("reference_pins", "selected_pins") if n not in f] + \
                [n for n in _ATTRIBUTES if n not in f.attrs]
            if missing:
                raise CalibrationError(f"{path} misses {', '.join(missing)} (a damaged calibration file: run "
                                       f"'tactip calibrate' again)")
            try:
                cx, cy, r = (float(v) for v in f.attrs["disc"])
                calibration = SensorCalibration(
                    detection=DetectionParams(**json.loads(f.attrs["detection"])),
                    disc=SensorDisc(cx, cy, r, whole_frame=bool(f.attrs.get("disc_whole_frame", False))),
                    reference_pins=np.asarray(f["reference_pins"][()], dtype=np.float64),
                    selected_pins=np.asarray(f["selected_pins"][()], dtype=np.intp),
                    mm_per_px=float(f.attrs["mm_per_px"]),
                    expected_pins=int(f.attrs["expected_pins"]),
                    frame_size=tuple(int(v) for v in f.attrs["frame_size"]),
                    min_separation_mm=float(f.attrs["min_separation_mm"]),
                    rest_frames=int(f.attrs["rest_frames"]),
                    sensor=json.loads(f.attrs["sensor"]),
                    scale=json.loads(f.attrs.get("scale", "{}")),  # optional: older files lack these two
                    separation_mm=float(f.attrs.get("separation_mm", np.nan)),
                )
            except (TypeError, ValueError) as exc:  # JSON, numbers or shapes that are not what was written
                raise CalibrationError(f"{path} holds unreadable settings ({' '.join(str(exc).split())}): a damaged "
                                       f"calibration file: run 'tactip calibrate' again") from None
    except OSError as exc:
        cut = cut_short(exc)
        if cut:
            raise CalibrationError(f"{path} is cut short ({cut[0]} of its {cut[1]} bytes: a copy or a write that did "
                                   f"not finish); copy it again or run 'tactip calibrate' again") from None
        raise CalibrationError(f"{path} cannot be read as a calibration file ({exc})") from None
    _check_calibration(path, calibration)
    return calibration


# The attributes every calibration file holds (besides its schema).
_ATTRIBUTES = ("detection", "disc", "mm_per_px", "expected_pins", "frame_size", "min_separation_mm", "rest_frames",
               "sensor")


def _check_calibration(path, calibration: SensorCalibration) -> None:
    """Refuse a calibration whose numbers cannot be right, as a station file's keys would be refused."""
    def bad(what: str) -> CalibrationError:
        return CalibrationError(f"{path}: {what} (a damaged calibration file: run 'tactip calibrate' again)")

    pins, chosen = calibration.reference_pins, calibration.selected_pins
    if not (np.isfinite(calibration.mm_per_px) and 0 < calibration.mm_per_px <= 10):
        raise bad(f"mm_per_px must be in (0, 10] mm/px, got {calibration.mm_per_px}")
    if len(calibration.frame_size) != 2 or min(calibration.frame_size) < 8:
        raise bad(f"frame_size must be (width, height) of at least 8 px, got {calibration.frame_size}")
    disc = calibration.disc
    if not (np.isfinite([disc.cx, disc.cy, disc.radius_px]).all() and disc.radius_px > 0):
        raise bad(f"the disc must have a finite centre and a radius > 0 px, got {disc}")
    if pins.ndim != 2 or pins.shape[1:] != (2,) or len(pins) < 2 or not np.isfinite(pins).all():
        raise bad(f"reference_pins must be an (N >= 2, 2) array of finite px, got shape {pins.shape}")
    if chosen.ndim != 1 or len(chosen) == 0 or chosen.min() < 0 or chosen.max() >= len(pins):
        raise bad(f"selected_pins must index the {len(pins)} reference pins")
    if not (np.isfinite(calibration.min_separation_mm) and calibration.min_separation_mm >= 0):
        raise bad(f"min_separation_mm must be a finite number >= 0, got {calibration.min_separation_mm}")
    if calibration.expected_pins < 2 or calibration.rest_frames < 1:
        raise bad(f"expected_pins must be >= 2 and rest_frames >= 1, got {calibration.expected_pins} and "
                  f"{calibration.rest_frames}")


def place_reference_pins(calibration: SensorCalibration, image: np.ndarray) -> np.ndarray:
    """The calibration's reference pins, each moved onto its blob in ``image`` when one is close.

    Tracking a tap from these keeps the calibration's pin identities (and so its feature pins)
    while starting from where the pins really are in this rest frame.

    Parameters
    ----------
    calibration : SensorCalibration
    image : (H, W) or (H, W, 3) uint8 ndarray
        A rest frame (off contact).

    Returns
    -------
    rest : (N, 2) ndarray of float64
        Pin positions (x, y), px, in the calibration's pin order.
    """
    rest = np.array(calibration.reference_pins, dtype=np.float64)
    blobs = detect_pins(image, params=calibration.detection, disc=calibration.disc)
    index = match_to_blobs(rest, blobs, gate_px=0.4 * calibration.reference_spacing_px)
    rest[index >= 0] = blobs[index[index >= 0]]
    return rest


def check_model_fits(model, calibration: SensorCalibration, *, samples: int, source: str = "the model",
                     maker: str = "this station") -> None:
    """Refuse a model that does not fit this sensor's taps (`perception.ModelError`, one line).

    The model must be a TacTip model of ``2 x feature pins`` dimensions and ``samples`` samples, and
    (where it records them) trained on a sensor with the calibration's pin count, feature pins and
    pin separation: 40 feature pins of a 532-pin pad make taps of the same shape as a 331-pin one's.
    ``source`` names the model and ``maker`` what makes the taps, in the message.
    """
    from perception import ModelError

    dims = 2 * calibration.n_selected
    if (model.front_end, model.dims, model.samples) != ("tactip", dims, samples):
        raise ModelError(f"{source} was trained for {model.front_end} taps of {model.samples} samples x {model.dims} "
                         f"dims; {maker} makes tactip taps of {samples} x {dims} ({calibration.n_selected} pins): "
                         f"train a model for this sensor")
    ours = {"kind": "tactip", "pins": int(calibration.expected_pins), "selected_pins": calibration.n_selected,
            "min_separation_mm": float(calibration.min_separation_mm)}
    differ = {k: (model.sensor[k], v) for k, v in ours.items() if k in model.sensor and model.sensor[k] != v}
    if differ:
        detail = ", ".join(f"{k} {a} ({maker}: {b})" for k, (a, b) in differ.items())
        raise ModelError(f"{source} was trained on another sensor: {detail}; train a model for this sensor")
