"""Replay a recorded TacTip video through the pin pipeline and store the result in HDF5.

``replay_video`` reads every frame of a video (or any non-live frame source), detects the pins
in the rest frame (the first frame unless told otherwise; it must be off contact), tracks them
through the video (`pins.PinTracker`: Lucas-Kanade, windowed centroid refinement, lost-pin recovery),
integrates displacements from the rest frame, finds the taps (`pins.segment_taps`), selects the
tactile pins (`pins.select_pins`) and resamples each tap into a feature array
(`pins.tap_features`). Frames before the rest frame are not tracked (NaN).

The HDF5 file (format ``tactip-replay/1``) holds:

- ``positions`` float32 (frames, pins, 2): (x, y) px, NaN where a pin was lost (or before the rest frame);
- ``displacements`` float32 (frames, pins, 2): from the rest frame, px, NaN likewise;
- ``timestamps`` float64 (frames,): s;  ``rest_positions`` float64 (pins, 2): px;
- ``selected_pins`` int (P,): indices of the tactile pins, in selection order;
- ``tap_bounds`` int (taps, 2): [start, stop) frame indices;
- ``taps`` float32 (taps, samples, 2 P) when taps were found: columns 0..P-1 dx, P..2P-1 dy of the
  selected pins (``feature_names`` attribute); ``tap_valid`` bool (taps,): False where a selected
  pin was lost for a whole tap (its features are NaN);
- attributes: format, software version, video path, frame size and rate, rest frame, disc
  (cx, cy, radius px), mm_per_px, pad diameter, detection and tracking parameters (JSON),
  selection and sampling settings.

With a sensor calibration (``calibration``), its detection parameters, disc and reference pins
(snapped to the rest frame's blobs, as the station does for each tap) are used, and its feature
pins and scale, so the taps line up with a model trained on that station. With a model as well
(``model``), a passive perceiver decides the gap width from the valid taps in order
(`tactip.replay_decisions`), and the file gets a ``decisions`` group: per tap
``location_estimate``, ``identity_estimate``, ``belief`` (taps,) and ``what_belief`` (taps,
identities), NaN for taps that did not enter the belief (invalid, or after the decision);
``used`` (taps,) bool; ``identities``; attributes ``identity_estimate``, ``belief``, ``decided``,
``decided_at_tap`` (-1 if never), ``decision_threshold``, ``model`` (path) and the units.

The file is written to a temporary name next to the target and renamed at the end, so a failure
never leaves a half-written result; the output paths are checked before any processing.
"""

from __future__ import annotations

import dataclasses
import json
import os
import pathlib
from dataclasses import dataclass
from typing import Any

import numpy as np

from pins import (DetectionParams, PinsError, PinTracker, SensorDisc, detect_pins,
                  displacement_from_rest, feature_dim_names, find_sensor_disc, segment_taps, select_pins,
                  tap_features, tune_detection)

from ._output import claim_output
from .errors import ConfigError, SourceError

__all__ = ["ReplayResult", "replay_video", "FORMAT"]

FORMAT = "tactip-replay/1"
# Displacement arrows in the annotated video are drawn this many times their length.
ARROW_SCALE = 3.0
_BAR_X = np.array([24, 0], dtype=np.int32)
_BAR_Y = np.array([0, 24], dtype=np.int32)


@dataclass(frozen=True)
class ReplayResult:
    """What a replay found (the arrays are in the HDF5 file).

    Attributes
    ----------
    out_path, annotate_path : pathlib.Path, pathlib.Path or None
    video : str
    frames, pins : int
        Frames read; pins tracked.
    frame_rate : float or None
    lost_pin_frames : int
        Pin-frames flagged lost after the rest frame.
    most_lost : int
        Largest number of pins lost in one frame.
    tap_bounds : list of (start, stop)
    invalid_taps : list of int
        Taps whose features are NaN (a selected pin lost for the whole tap).
    selected_pins : (P,) ndarray of int
    mm_per_px : float
    disc : SensorDisc
    detection : DetectionParams
    decisions : tactip.replay_decisions.ReplayDecisions or None
        The decision, when a model was given.
    """

    out_path: pathlib.Path
    annotate_path: pathlib.Path | None
    video: str
    frames: int
    pins: int
    frame_rate: float | None
    lost_pin_frames: int
    most_lost: int
    tap_bounds: list
    invalid_taps: list
    selected_pins: np.ndarray
    mm_per_px: float
    disc: SensorDisc
    detection: DetectionParams
    decisions: Any = None

    def summary(self) -> str:
        """A few readable lines: frames, pins, lost pins, taps and the files written."""
        rate = f" at {self.frame_rate:g} fps" if self.frame_rate else ""
        taps = ", ".join(f"{a}-{b - 1}" for a, b in self.tap_bounds) or "none"
        lines = [
            f"Replayed {self.video}: {self.frames} frames{rate}",
            f"Pins: {self.pins} tracked (disc radius {self.disc.radius_px:.1f} px, {self.mm_per_px:.4f} mm/px); "
            f"lost: {self.lost_pin_frames} pin-frames, at most {self.most_lost} in one frame",
            f"Taps: {len(self.tap_bounds)} (frames {taps}); features of {len(self.selected_pins)} pins",
        ]
        if self.invalid_taps:
            lines.append(f"Warning: taps {self.invalid_taps} have a selected pin lost throughout (features NaN)")
        if self.decisions is not None:
            lines += self.decisions.lines()
        written = [str(self.out_path)] + ([str(self.annotate_path)] if self.annotate_path else [])
        lines.append("Wrote " + " and ".join(written))
        return "\n".join(lines)


def replay_video(video: str | os.PathLike, out_path: str | os.PathLike, *,
                 annotate_path: str | os.PathLike | None = None, expected_pins: int | None = None,
                 params: DetectionParams | None = None, n_samples: int = 40, n_pins: int = 40,
                 min_separation_mm: float = 4.0, pad_diameter_mm: float = 40.0, mm_per_px: float | None = None,
                 rest_frame: int = 0, calibration=None, model=None, decision_threshold: float | None = None,
                 progress: bool = False) -> ReplayResult:
    """Track the pins of a recorded video and write positions, displacements and tap features to HDF5.

    Parameters
    ----------
    video : str or path
        A video file (or an image folder; any non-live `tactip.sources.open_source` spec).
    out_path : str or path
        The HDF5 file to write (replaced if it exists).
    annotate_path : str or path, optional
        Also write an MP4 showing the pins, their displacements (x3) and the tap state.
    expected_pins : int, optional
        Tune detection to this many pins on the rest frame (`pins.tune_detection`) first.
    params : DetectionParams, optional
        Detection parameters (default ones, or the starting point of tuning).
    n_samples : int
        Samples per tap feature array (paper: 40).
    n_pins, min_separation_mm : int, float
        Tactile pin selection (paper: 40 pins at least 4 mm apart).
    pad_diameter_mm : float
        Diameter of the pad, mm: the scale is pad diameter / detected disc diameter.
    mm_per_px : float, optional
        The scale, mm per px, overriding the one from the disc.
    rest_frame : int
        Index of the rest frame (off contact) the displacements are measured from.
    calibration : str, path or calibration.SensorCalibration, optional
        The station's sensor calibration: its detection parameters, disc, reference pins, feature
        pins and scale replace detection, selection and `mm_per_px` (do not give those too).
    model : str, path or perception.HistogramModel, optional
        The station's model (needs `calibration`): decide the gap width from the taps.
    decision_threshold : float in [0, 1], optional
        theta_dec of the decision; default the model's recommended one, else 0.9.
    progress : bool
        Show a tqdm progress bar in frames (on stderr).

    Returns
    -------
    ReplayResult

    Raises
    ------
    OSError
        An output path cannot be written (checked before processing).
    SourceError
        The video is missing, unreadable, live, or shorter than `rest_frame`.
    PinsError
        No sensor disc or too few pins in the rest frame, or too few pins for the selection.
    ConfigError
        A model without a calibration, or a calibration with `expected_pins`, `params` or `mm_per_px`.
    CalibrationError
        The calibration cannot be read, or was made for frames of another size.
    ModelError
        The model cannot be read or does not fit the taps (checked before processing).

    Examples
    --------
    >>> result = replay_video("samples/synthetic_tap.mp4", "out/replay.h5")   # doctest: +SKIP
    >>> print(result.summary())                                                # doctest: +SKIP
    """
    from tactip.sources import open_source

    if int(rest_frame) != rest_frame or rest_frame < 0:
        raise ValueError(f"rest_frame must be a non-negative integer, got {rest_frame}")
    if not pad_diameter_mm > 0:
        raise ValueError(f"pad_diameter_mm must be > 0, got {pad_diameter_mm}")
    if mm_per_px is not None and not mm_per_px > 0:
        raise ValueError(f"mm_per_px must be > 0, got {mm_per_px}")
    cal, model, model_path = _load_station_files(calibration, model, decision_threshold, n_samples=n_samples,
                                                 given=dict(expected_pins=expected_pins, params=params,
                                                            mm_per_px=mm_per_px))
    out_path = pathlib.Path(out_path)
    annotate = None if annotate_path is None else pathlib.Path(annotate_path)
    temporary: list[pathlib.Path] = []
    try:
        temporary.append(claim_output(out_path, ".h5"))
        if annotate:
            temporary.append(claim_output(annotate, ".mp4"))
        with open_source(video, grey=True) as source:
            if source.live:
                raise SourceError(f"{video!r} is a live source; replay reads recorded videos (use a file)")
            if cal is not None and tuple(source.frame_size) != tuple(cal.frame_size):
                from calibration import CalibrationError

                raise CalibrationError(f"the calibration was made for {cal.frame_size[0]}x{cal.frame_size[1]} px "
                                       f"frames, the video's are {source.frame_size[0]}x{source.frame_size[1]} px")
            track = _track_video(source, rest_frame=int(rest_frame), expected_pins=expected_pins,
                                 params=params, calibration=cal, progress=progress)
        if cal is None:
            scale = mm_per_px or pad_diameter_mm / (2.0 * track["disc"].radius_px)
            selected = select_pins(track["rest"], n_pins=n_pins, min_separation_mm=min_separation_mm,
                                   mm_per_px=scale)
        else:
            scale, selected = cal.mm_per_px, np.asarray(cal.selected_pins)
            n_pins, min_separation_mm = cal.n_selected, cal.min_separation_mm
        bounds = segment_taps(track["displacements"])
        taps, valid = _features(track["displacements"], track["timestamps"], bounds, selected, n_samples)
        decisions = None
        if model is not None:
            from .replay_decisions import decide_taps

            decisions = decide_taps(taps, valid, model, decision_threshold=decision_threshold, model_path=model_path)
        settings = dict(video=str(video), rest_frame=int(rest_frame), mm_per_px=float(scale),
                        pad_diameter_mm=float(pad_diameter_mm), n_pins=int(n_pins), n_samples=int(n_samples),
                        min_separation_mm=float(min_separation_mm),
                        calibration=str(calibration) if isinstance(calibration, (str, os.PathLike)) else "")
        _write_hdf5(temporary[0], track, selected, bounds, taps, valid, settings, decisions)
        if annotate:
            _write_annotated(video, temporary[1], track, bounds, selected, decisions)
        for part, final in zip(temporary, [out_path, annotate]):
            os.replace(part, final)
    finally:
        for part in temporary:
            part.unlink(missing_ok=True)
    lost = ~np.isfinite(track["positions"][rest_frame:, :, 0])
    return ReplayResult(out_path=out_path, annotate_path=annotate, video=str(video), frames=len(track["timestamps"]),
                        pins=track["rest"].shape[0], frame_rate=track["frame_rate"],
                        lost_pin_frames=int(lost.sum()), most_lost=int(lost.sum(axis=1).max(initial=0)),
                        tap_bounds=bounds, invalid_taps=[k for k, ok in enumerate(valid) if not ok],
                        selected_pins=selected, mm_per_px=float(scale), disc=track["disc"],
                        detection=track["detection"], decisions=decisions)


def _load_station_files(calibration, model, decision_threshold, *, n_samples: int, given: dict):
    """The calibration and model objects (read from paths), checked against each other and the options."""
    if decision_threshold is not None and not 0.0 <= decision_threshold <= 1.0:
        raise ValueError(f"decision_threshold must be in [0, 1], got {decision_threshold}")
    if calibration is None:
        if model is not None:
            raise ConfigError("a model needs the calibration of its station (--calibration): the taps must use "
                              "the feature pins it was trained on")
        return None, None, ""
    clash = [name for name, value in given.items() if value is not None]
    if clash:
        raise ConfigError(f"{', '.join(clash)} cannot be combined with a calibration (it sets detection and "
                          f"scale)")
    if not hasattr(calibration, "reference_pins"):
        from calibration import load_calibration

        calibration = load_calibration(calibration)
    model_path = ""
    if model is not None:
        if not hasattr(model, "log_likelihood"):
            from perception import load_model

            model_path, model = str(model), load_model(model)
        from .replay_decisions import check_model

        check_model(model, calibration, n_samples=int(n_samples), path=model_path or "the model")
    return calibration, model, model_path


def _track_video(source, *, rest_frame: int, expected_pins, params, calibration, progress: bool) -> dict:
    """Read every frame: detect in the rest frame (or place the calibrated pins there), track after it."""
    from tqdm import tqdm

    params = calibration.detection if calibration is not None else params or DetectionParams()
    tracker: PinTracker | None = None
    positions, timestamps = [], []
    total = getattr(source, "frame_count", None)
    with tqdm(total=total, unit="frame", disable=not progress, desc="replay") as bar:
        for frame in source:
            timestamps.append(frame.timestamp_s)
            if frame.index == rest_frame and calibration is not None:
                from calibration import place_reference_pins

                tracker = PinTracker(detection=params, disc=calibration.disc)
                rest = tracker.start(frame.image, pins=place_reference_pins(calibration, frame.image))
                positions = [np.full(rest.shape, np.nan, np.float32)] * len(positions)
                positions.append(rest.astype(np.float32))
            elif frame.index == rest_frame:
                disc = find_sensor_disc(frame.image, dark_pins=params.dark_pins)
                if expected_pins is not None:
                    params = tune_detection(frame.image, int(expected_pins), start=params, disc=disc)
                tracker = PinTracker(detection=params, disc=disc)
                rest = tracker.start(frame.image, detect_pins(frame.image, params=params, disc=disc))
                # float32, as stored: half the memory of a long recording.
                positions = [np.full(rest.shape, np.nan, np.float32)] * len(positions)
                positions.append(rest.astype(np.float32))
            elif tracker is not None:
                positions.append(tracker.update(frame.image).astype(np.float32))
            else:
                positions.append(None)
            bar.update(1)
    if tracker is None:
        raise SourceError(f"the video has {len(timestamps)} frames, so there is no rest frame {rest_frame}")
    stacked = np.stack(positions)
    displacements = displacement_from_rest(stacked, tracker.rest_positions).astype(np.float32)
    return dict(positions=stacked, displacements=displacements,
                timestamps=np.asarray(timestamps, dtype=np.float64), rest=tracker.rest_positions,
                disc=tracker.disc, detection=params, tracker=tracker, frame_rate=source.frame_rate,
                frame_size=source.frame_size)


def _features(displacements, timestamps, bounds, selected, n_samples):
    """Feature arrays of the taps; NaN (and invalid) where a selected pin was lost for a whole tap."""
    taps = np.full((len(bounds), n_samples, 2 * len(selected)), np.nan)
    valid = np.ones(len(bounds), dtype=bool)
    for k, (start, stop) in enumerate(bounds):
        times = timestamps[start:stop]
        if not np.all(np.diff(times) > 0):  # a decoder without time stamps: resample by frame
            times = None
        try:
            taps[k] = tap_features(displacements[start:stop], pins=selected, n_samples=n_samples,
                                   timestamps_s=times)
        except PinsError:  # LostPinError, or a tap of a single frame
            valid[k] = False
    return taps, valid


def _write_hdf5(path, track, selected, bounds, taps, valid, settings, decisions=None) -> None:
    import h5py

    from tactip import __version__

    tracker = track["tracker"]
    with h5py.File(path, "w") as h5:
        h5.create_dataset("positions", data=track["positions"].astype(np.float32), compression="gzip")
        h5.create_dataset("displacements", data=track["displacements"].astype(np.float32), compression="gzip")
        h5.create_dataset("timestamps", data=track["timestamps"])
        h5.create_dataset("rest_positions", data=track["rest"])
        h5.create_dataset("selected_pins", data=np.asarray(selected, dtype=np.int64))
        h5.create_dataset("tap_bounds", data=np.asarray(bounds, dtype=np.int64).reshape(-1, 2))
        if len(bounds):
            dataset = h5.create_dataset("taps", data=taps.astype(np.float32))
            dataset.attrs["feature_names"] = json.dumps(feature_dim_names(len(selected)))
            dataset.attrs["layout"] = "columns 0..P-1 dx, P..2P-1 dy of the selected pins, px"
            h5.create_dataset("tap_valid", data=valid)
        disc = track["disc"]
        h5.attrs.update({
            "format": FORMAT,
            "software_version": __version__,
            "frame_size": np.asarray(track["frame_size"], dtype=np.int64),
            "frame_rate": float(track["frame_rate"] or np.nan),
            "disc": json.dumps({"cx": disc.cx, "cy": disc.cy, "radius_px": disc.radius_px}),
            "detection_params": json.dumps(track["detection"].to_dict()),
            "tracking_params": json.dumps({"lk": dataclasses.asdict(tracker.lk), "refine": tracker.refine,
                                           "gate_fraction": tracker.gate_fraction,
                                           "neighbours": tracker.neighbours}),
            "sensor": json.dumps({"kind": "tactip", "pins": int(track["rest"].shape[0]),
                                  "pad_diameter_mm": settings["pad_diameter_mm"]}),
            **settings,
        })
        if decisions is not None:
            from .replay_decisions import write_decisions

            write_decisions(h5, decisions)


def _write_annotated(video, path, track, bounds, selected, decisions=None) -> None:
    """The video again, with pins, displacement arrows (x ARROW_SCALE), the tap state and the
    running decision (each tap's width estimate and belief) drawn on."""
    import cv2

    from tactip.sources import open_source

    width, height = track["frame_size"]
    rate = track["frame_rate"] or 20.0
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), rate, (width, height), True)
    if not writer.isOpened():
        raise OSError(f"cannot write the annotated video {str(path)!r} (no MPEG-4 encoder?)")
    tap_of_frame = np.full(len(track["timestamps"]), -1)
    for k, (start, stop) in enumerate(bounds):
        tap_of_frame[start:stop] = k
    rest = track["rest"]
    is_selected = np.zeros(len(rest), dtype=bool)
    is_selected[selected] = True
    shift = 4  # sub-pixel drawing: coordinates in 1/16 px (the crosses' half-bars are 24/16 = 1.5 px)
    try:
        with open_source(video) as source:
            for frame, positions, displacement, tap in zip(source, track["positions"], track["displacements"],
                                                           tap_of_frame):
                image = frame.image if frame.image.ndim == 3 else cv2.cvtColor(frame.image, cv2.COLOR_GRAY2BGR)
                seen = np.isfinite(positions[:, 0])
                # Arrows from the rest position to rest + ARROW_SCALE x displacement; a cross on the pin.
                tail = np.rint(rest * 16).astype(np.int32)
                tip = np.rint((rest + ARROW_SCALE * displacement) * 16).astype(np.int32)
                base = np.rint(positions * 16).astype(np.int32)
                for mask, colour in ((seen & ~is_selected, (0, 200, 0)), (seen & is_selected, (0, 0, 255))):
                    centre = base[mask]
                    # One polyline call per colour: arrow shafts and the two bars of each cross.
                    lines = np.concatenate([np.stack([tail[mask], tip[mask]], axis=1),
                                            np.stack([centre - _BAR_X, centre + _BAR_X], axis=1),
                                            np.stack([centre - _BAR_Y, centre + _BAR_Y], axis=1)])
                    cv2.polylines(image, list(lines), False, colour, 1, cv2.LINE_AA, shift)
                state = f"tap {tap + 1}" if tap >= 0 else "rest"
                text = f"frame {frame.index}  {frame.timestamp_s:6.2f} s  {state}  lost {int((~seen).sum())}"
                cv2.putText(image, text, (10, height - 12), cv2.FONT_HERSHEY_SIMPLEX, 0.55, (0, 255, 255), 1,
                            cv2.LINE_AA)
                if decisions is not None and tap >= 0:
                    cv2.putText(image, _decision_text(decisions, tap), (10, 22), cv2.FONT_HERSHEY_SIMPLEX, 0.55,
                                (0, 255, 255), 1, cv2.LINE_AA)
                writer.write(image)
    finally:
        writer.release()


def _decision_text(decisions, tap: int) -> str:
    """The running decision shown on the frames of tap ``tap``."""
    if decisions.used[tap]:
        mark = "  DECIDED" if tap == decisions.decided_at_tap else ""
        return (f"width {decisions.identity_estimate[tap]:g} {decisions.identity_unit}  "
                f"belief {decisions.belief[tap]:.3f}{mark}")
    if 0 <= decisions.decided_at_tap < tap:
        return f"decided {decisions.identity:g} {decisions.identity_unit} at tap {decisions.decided_at_tap + 1}"
    return "tap not used (pins lost)"
