"""Replay a recorded TacTip video through the pin pipeline and store the result in HDF5.

``replay_video`` reads every frame of a video (or any non-live frame source), finds the pins in
the rest frame (the first frame unless told otherwise; it must be off contact) as the blobs that
form the pin lattice (`pins.find_pin_field`: rim-ring glare, specks and skin texture rejected), tracks them
through the video (`pins.PinTracker`: Lucas-Kanade, windowed refinement, a windowed search for
lost pins, retirement of pins that stay lost, blank frames marked), integrates displacements from
the rest frame, finds the taps (`pins.segment_taps`), selects the tactile pins
(`pins.select_feature_pins`) and resamples each tap into a feature array (`pins.tap_features`).
Frames before the rest frame are not tracked (NaN, and counted lost).

The tracking is never thrown away: once the video has been read, positions, displacements, lost
masks and time stamps are always written. Problems of the later steps (a pad too small for the
requested feature pins, no taps, a scale that cannot be measured, a rest frame that looks taken
during a tap) become warnings in the summary and in the file (``warnings`` attribute).

The scale (mm per px) is the sensor's pin pitch in mm over the rest pins' pitch in px
(`pins.pad_scale`): the pitch in mm comes from a named sensor (``sensor``, `pins.SENSOR_PRESETS`),
or from the pin count on the whole pad (``pins_on_pad``, default the expected or detected count)
and the pad diameter (``pad_diameter_mm``, default 40 mm), unless ``mm_per_px`` is given.

The HDF5 file (format ``tactip-replay/2``) holds:

- ``positions`` float32 (frames, pins, 2): (x, y) px, NaN where a pin was lost (or before the rest frame);
- ``displacements`` float32 (frames, pins, 2): from the rest frame, px, NaN likewise;
- ``lost`` bool (frames, pins): pin not found (retired pins, blank frames and frames before the rest
  frame included); ``retired`` bool (frames, pins): lost long enough to be searched for only now and
  then (a rim pin out of view); ``lost_count``, ``retired_count`` int32 (frames,); ``blank`` bool
  (frames,): nothing trackable in the frame (LEDs off, a dropped or black frame); ``tracked`` bool
  (frames,): at or after the rest frame;
- ``timestamps`` float64 (frames,): s;  ``rest_positions`` float64 (pins, 2): px;
- ``selected_pins`` int (P,): indices of the tactile pins, in selection order (attributes
  ``requested``, ``min_separation_mm`` asked, ``separation_mm`` reached);
- ``tap_bounds`` int (taps, 2): [start, stop) frame indices;
- ``taps`` float32 (taps, samples, 2 P) when taps were found: columns 0..P-1 dx, P..2P-1 dy of the
  selected pins (``feature_names`` attribute); ``tap_valid`` bool (taps,): False where a selected
  pin was lost for a whole tap (its features are NaN);
- attributes: format, software version, video path, frame size and rate, rest frame, disc
  (cx, cy, radius px), ``mm_per_px`` and ``scale`` (JSON: mm_per_px, pitch_px, pitch_mm, source,
  sensor), pad diameter, detection and tracking parameters (JSON), selection and sampling settings,
  ``warnings`` (JSON list of strings), ``blank_frames``, ``pins_detected`` and ``expected_pins``.

With a sensor calibration (``calibration``), its detection parameters, disc and reference pins
(snapped to the rest frame's blobs, as the station does for each tap) are used, and its feature
pins and scale, so the taps line up with a model trained on that station. With a model as well
(``model``), a passive perceiver decides the gap width from the valid taps in order
(`tactip.replay.decisions`), and the file gets a ``decisions`` group: per tap
``location_estimate``, ``identity_estimate``, ``belief`` (taps,) and ``what_belief`` (taps,
identities), NaN for taps that did not enter the belief (invalid, or after the decision);
``used`` (taps,) bool; ``identities``; attributes ``identity_estimate``, ``belief``, ``decided``,
``decided_at_tap`` (-1 if never), ``decision_threshold``, ``model`` (path) and the units.

Speed: frames are decoded on a thread (`tactip.sources.ThreadedReader`, blocking, so no frame is
dropped) while the main thread tracks, so a replay costs about the larger of decoding and
tracking rather than their sum (`bench/bench_replay.py`). The decoder gets one thread fewer than
the cores (one on a 2-core machine): its extra threads would only contend with the tracking.

The file is written to a temporary name next to the target and renamed at the end, so a failure
never leaves a half-written result; the output paths are checked before any processing.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import math
import os
import pathlib
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import ndimage

from pins import (DetectionParams, NoSensorError, PadScale, PinSelection, PinsError, PinTracker, SensorDisc,
                  displacement_from_rest, feature_dim_names, find_pin_field, pad_scale, segment_taps,
                  select_feature_pins, tap_features, tap_signal)

from tactip._output import check_video_written, claim_output, refuse_overwriting_inputs, write_error
from tactip.errors import ConfigError, SourceError

__all__ = ["ReplayResult", "replay_video", "FORMAT", "check_rest_frame"]

FORMAT = "tactip-replay/2"
DEFAULT_PAD_DIAMETER_MM = 40.0
# Pin spacing, px, at which the tap thresholds are segment_taps' defaults (331 pins, 640x480).
REFERENCE_PITCH_PX = 17.5
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
    lost_per_frame, retired_per_frame : (frames,) ndarray of int
        Pins lost (retired included) and retired in each frame (all pins before the rest frame
        and in blank frames).
    blank_frames : list of int
        Frames with nothing trackable (all pins lost), after the rest frame.
    rest_frame : int
    tap_bounds : list of (start, stop)
    invalid_taps : list of int
        Taps whose features are NaN (a selected pin lost for the whole tap).
    selected_pins : (P,) ndarray of int
    selection : pins.PinSelection or None
        How the feature pins were chosen (None with a calibration, or when selection failed).
    mm_per_px : float
    scale : pins.PadScale or None
        How the scale was derived (None with a calibration).
    disc : SensorDisc
    detection : DetectionParams
    pins_detected : int
        Pins found in the rest frame.
    pin_field : str
        The rest frame's pin field: pins kept, pitch, blobs rejected and why (`pins.PinField.summary`).
    expected_pins : int or None
    warnings : list of str
        What did not go as asked (also in the file).
    decisions : tactip.replay.decisions.ReplayDecisions or None
        The decision, when a model was given.
    """

    out_path: pathlib.Path
    annotate_path: pathlib.Path | None
    video: str
    frames: int
    pins: int
    frame_rate: float | None
    lost_per_frame: np.ndarray
    retired_per_frame: np.ndarray
    blank_frames: list
    rest_frame: int
    tap_bounds: list
    invalid_taps: list
    selected_pins: np.ndarray
    selection: PinSelection | None
    mm_per_px: float
    scale: PadScale | None
    disc: SensorDisc
    detection: DetectionParams
    pins_detected: int
    pin_field: str = ""
    expected_pins: int | None = None
    warnings: list = field(default_factory=list)
    decisions: Any = None

    @property
    def lost_pin_frames(self) -> int:
        """Pin-frames flagged lost after the rest frame (blank frames included)."""
        return int(self.lost_per_frame[self.rest_frame:].sum())

    @property
    def most_lost(self) -> int:
        """Largest number of pins lost in one frame after the rest frame."""
        return int(self.lost_per_frame[self.rest_frame:].max(initial=0))

    def summary(self) -> str:
        """A few readable lines: frames, pins, scale, lost and retired pins, taps, warnings, files."""
        rate = f" at {self.frame_rate:g} fps" if self.frame_rate else ""
        taps = ", ".join(f"{a}-{b - 1}" for a, b in self.tap_bounds) or "none"
        detected = f"rest frame {self.rest_frame}: {self.pin_field or f'{self.pins_detected} pins'}"
        if self.expected_pins and "expected" not in self.pin_field:
            off = self.pins_detected - self.expected_pins
            detected += f", {self.expected_pins} expected ({off:+d}, {off / self.expected_pins:+.1%})"
        scale = self.scale.describe() if self.scale is not None else f"{self.mm_per_px:.4f} mm/px (calibration)"
        lines = [
            f"Replayed {self.video}: {self.frames} frames{rate}",
            f"Pins: {self.pins} tracked ({detected}); disc radius {self.disc.radius_px:.1f} px",
            f"Scale: {scale}",
            self._losses(),
            f"Taps: {len(self.tap_bounds)} (frames {taps}); features of "
            + (self.selection.describe() if self.selection is not None else f"{len(self.selected_pins)} pins"),
        ]
        lines += [f"Warning: {w}" for w in self.warnings]
        if self.invalid_taps:
            lines.append(f"Warning: taps {self.invalid_taps} have a selected pin lost throughout (features NaN)")
        if self.decisions is not None:
            lines += self.decisions.lines()
        written = [str(self.out_path)] + ([str(self.annotate_path)] if self.annotate_path else [])
        lines.append("Wrote " + " and ".join(written))
        return "\n".join(lines)

    def _losses(self) -> str:
        """Lost and retired pins per tracked frame (blank frames apart), and the blank frames."""
        tracked = np.arange(self.frames) >= self.rest_frame
        tracked[self.blank_frames] = False
        lost, retired = self.lost_per_frame[tracked], self.retired_per_frame[tracked]
        if lost.size == 0:
            text = "Lost pins: no tracked frame"
        else:
            worst = np.flatnonzero(tracked)[np.argsort(-lost, kind="stable")[:3]]
            worst = [int(f) for f in worst if self.lost_per_frame[f] > 0]
            text = (f"Lost pins per frame (retired included): median {np.median(lost):g}, max {lost.max()} of {self.pins}"
                    + (f" (frames {', '.join(map(str, worst))})" if worst else "")
                    + f"; retired: median {np.median(retired):g}, max {retired.max()}")
        if self.blank_frames:
            shown = ", ".join(map(str, self.blank_frames[:10])) + (" ..." if len(self.blank_frames) > 10 else "")
            text += f"; {len(self.blank_frames)} blank frame(s) (nothing trackable, pins NaN): {shown}"
        return text


def _decode_threads() -> int:
    """Threads for the video decoder in replay: every core but the one that tracks (at least one)."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 2
    return max(1, cores - 1)


@contextlib.contextmanager
def _opencv_threads(count: int):
    """OpenCV's worker pool at ``count`` threads inside the block, restored after it."""
    import cv2

    before = cv2.getNumThreads()
    cv2.setNumThreads(count)
    try:
        yield
    finally:
        cv2.setNumThreads(before)


def replay_video(video: str | os.PathLike, out_path: str | os.PathLike, *,
                 annotate_path: str | os.PathLike | None = None, expected_pins: int | None = None,
                 params: DetectionParams | None = None, n_samples: int = 40, n_pins: int = 40,
                 min_separation_mm: float = 4.0, sensor: str | None = None, pins_on_pad: int | None = None,
                 pad_diameter_mm: float | None = None, mm_per_px: float | None = None,
                 rest_frame: int = 0, calibration=None, model=None, decision_threshold: float | None = None,
                 progress: bool = False) -> ReplayResult:
    """Track the pins of a recorded video and write positions, displacements, lost masks and tap features to HDF5.

    Parameters
    ----------
    video : str or path
        A video file (or an image folder; any non-live `tactip.sources.open_source` spec).
    out_path : str or path
        The HDF5 file to write (replaced if it exists).
    annotate_path : str or path, optional
        Also write an MP4 showing the pins, their displacements (x3) and the tap state.
    expected_pins : int, optional
        The pins expected in view on the rest frame: it confirms the pin field found there
        (`pins.find_pin_field`, which does not need it); the summary says how far off the count
        is, and a count more than 10 % off is a warning. Also the default of `pins_on_pad`.
    params : DetectionParams, optional
        Detection parameters: a hint for the pin field search (default: none; ``dark_pins`` is
        always kept).
    n_samples : int
        Samples per tap feature array (paper: 40).
    n_pins, min_separation_mm : int, float
        Tactile pins wanted and their preferred separation, mm (paper: 40 pins at least 4 mm
        apart). A pad with no room for them gets `n_pins` pins as far apart as it allows (or all
        its pins, when it has fewer), with a warning.
    sensor : str, optional
        A named sensor (`pins.SENSOR_PRESETS`): its pin pitch gives the scale.
    pins_on_pad : int, optional
        Pins on the whole pad (in view or not), for the pin pitch; default the sensor's, else
        `expected_pins`, else the pins detected.
    pad_diameter_mm : float, optional
        Diameter of the hemispherical pad, mm; default the sensor's, else 40.
    mm_per_px : float, optional
        The scale, mm per px, instead of the one from the pin pitch.
    rest_frame : int
        Index of the rest frame (off contact) the displacements are measured from. A rest frame
        that looks taken during a tap is reported in the warnings, with a frame that looks at rest.
    calibration : str, path or calibration.SensorCalibration, optional
        The station's sensor calibration: its detection parameters, disc, reference pins, feature
        pins and scale replace detection, selection and the scale (do not give those too).
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
    ValueError
        An option out of range (checked before processing).
    OSError
        An output path cannot be written (checked before processing).
    SourceError
        The video is missing, unreadable, live, or shorter than `rest_frame`.
    PinsError
        No sensor disc or too few pins in the rest frame (nothing could be tracked). Nothing after
        the tracking raises for lack of pins: it warns.
    ConfigError
        A model without a calibration, or a calibration with `expected_pins`, `params`, a sensor
        description or `mm_per_px`.
    CalibrationError
        The calibration cannot be read, or was made for frames of another size.
    ModelError
        The model cannot be read or does not fit the taps (checked before processing).

    Examples
    --------
    >>> result = replay_video("samples/synthetic_tap.mp4", "out/replay.h5", sensor="tactip-331")  # doctest: +SKIP
    >>> print(result.summary())                                                                   # doctest: +SKIP
    """
    from tactip.sources import ThreadedReader, open_source

    if int(rest_frame) != rest_frame or rest_frame < 0:
        raise ValueError(f"rest_frame must be a non-negative integer, got {rest_frame}")
    for name, value in (("pad_diameter_mm", pad_diameter_mm), ("mm_per_px", mm_per_px)):
        if value is not None and not (value > 0 and math.isfinite(value)):
            raise ValueError(f"{name} must be a finite number > 0, got {value}")
    for name, value in (("n_pins", n_pins), ("pins_on_pad", pins_on_pad), ("expected_pins", expected_pins)):
        if value is not None and (int(value) != value or value < 1):
            raise ValueError(f"{name} must be a positive integer, got {value}")
    if not (min_separation_mm >= 0 and math.isfinite(min_separation_mm)):
        raise ValueError(f"min_separation_mm must be a finite number >= 0, got {min_separation_mm}")
    if sensor is not None:
        from pins import sensor_preset

        sensor_preset(sensor)  # ValueError naming the choices
    cal, model, model_path = _load_station_files(calibration, model, decision_threshold, n_samples=n_samples,
                                                 given=dict(expected_pins=expected_pins, params=params,
                                                            mm_per_px=mm_per_px, sensor=sensor,
                                                            pins_on_pad=pins_on_pad, pad_diameter_mm=pad_diameter_mm))
    out_path = pathlib.Path(out_path)
    annotate = None if annotate_path is None else pathlib.Path(annotate_path)
    refuse_overwriting_inputs([out_path, annotate], [video, calibration, model])  # issue 9: never over an input
    if annotate is not None and annotate.suffix.lower() != ".mp4":
        raise SourceError(f"cannot write the annotated video {str(annotate)!r}: it is MPEG-4, give a .mp4 name")
    temporary: list[pathlib.Path] = []
    try:
        temporary.append(claim_output(out_path, ".h5"))
        if annotate:
            temporary.append(claim_output(annotate, ".mp4"))
        # The decoder on one thread fewer than the cores: this thread tracks on the last one, and
        # FFmpeg's second thread on a 2-core machine only adds its own overhead to the contention.
        with open_source(video, grey=True, decode_threads=_decode_threads()) as source:
            if source.live:
                raise SourceError(f"{video!r} is a live source; replay reads recorded videos (use a file)")
            if cal is not None and tuple(source.frame_size) != tuple(cal.frame_size):
                from calibration import CalibrationError

                raise CalibrationError(f"the calibration was made for {cal.frame_size[0]}x{cal.frame_size[1]} px "
                                       f"frames, the video's are {source.frame_size[0]}x{source.frame_size[1]} px")
            # Decode on a thread while this one tracks; blocking, so that no frame is dropped. OpenCV's
            # own worker pool stays at one thread meanwhile: the two threads already fill a 2-core
            # machine, and the pool's workers only contend with them.
            with _opencv_threads(1), ThreadedReader(source, maxsize=8, when_full="block",
                                                    close_source=False) as reader:
                track = _track_video(reader, rest_frame=int(rest_frame), expected_pins=expected_pins,
                                     params=params, calibration=cal, progress=progress,
                                     total=getattr(source, "frame_count", None))
        # From here on the tracking is kept whatever happens: problems become warnings.
        analysis = _analyse(track, calibration=cal, n_pins=int(n_pins), min_separation_mm=float(min_separation_mm),
                            sensor=sensor, pins_on_pad=pins_on_pad, pad_diameter_mm=pad_diameter_mm,
                            mm_per_px=mm_per_px, expected_pins=expected_pins, n_samples=int(n_samples),
                            rest_frame=int(rest_frame))
        decisions = None
        if model is not None and analysis["taps"] is not None:
            from tactip.replay.decisions import decide_taps

            try:
                decisions = decide_taps(analysis["taps"], analysis["valid"], model,
                                        decision_threshold=decision_threshold, model_path=model_path)
            except Exception as exc:  # the tracking is still written
                analysis["warnings"].append(f"no decision: {exc}")
        scale = analysis["scale"]
        settings = dict(video=str(video), rest_frame=int(rest_frame), mm_per_px=float(analysis["mm_per_px"]),
                        pad_diameter_mm=float(scale.sensor.get("pad_diameter_mm", np.nan)) if scale else np.nan,
                        n_pins=int(n_pins), n_samples=int(n_samples), min_separation_mm=float(min_separation_mm),
                        calibration=str(calibration) if isinstance(calibration, (str, os.PathLike)) else "")
        for part, final in zip(temporary, [out_path, annotate]):
            try:  # a full disk or a lost permission is named as such; the outputs keep their old content
                if final is out_path:
                    _write_hdf5(part, track, analysis, settings, decisions)
                else:
                    _write_annotated(video, part, track, analysis["bounds"], analysis["selected"], decisions)
                with open(part, "rb+") as written:
                    os.fsync(written.fileno())
            except (OSError, RuntimeError) as exc:
                raise write_error(exc, final) from None
            if final is annotate:  # OpenCV's writer says nothing of a full disk: count the frames stored
                check_video_written(part, final, len(track["timestamps"]))
        for part, final in zip(temporary, [out_path, annotate]):
            os.replace(part, final)
    finally:
        for part in temporary:
            part.unlink(missing_ok=True)
    return ReplayResult(out_path=out_path, annotate_path=annotate, video=str(video), frames=len(track["timestamps"]),
                        pins=track["rest"].shape[0], frame_rate=track["frame_rate"],
                        lost_per_frame=track["lost"].sum(axis=1), retired_per_frame=track["retired"].sum(axis=1),
                        blank_frames=np.flatnonzero(track["blank"]).tolist(), rest_frame=int(rest_frame),
                        tap_bounds=analysis["bounds"],
                        invalid_taps=[k for k, ok in enumerate(analysis["valid"]) if not ok],
                        selected_pins=analysis["selected"], selection=analysis["selection"],
                        mm_per_px=float(analysis["mm_per_px"]), scale=scale, disc=track["disc"],
                        detection=track["detection"], pins_detected=track["pins_detected"], pin_field=track["field"],
                        expected_pins=expected_pins, warnings=list(analysis["warnings"]), decisions=decisions)


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
        from tactip.replay.decisions import check_model

        check_model(model, calibration, n_samples=int(n_samples), path=model_path or "the model")
    return calibration, model, model_path


def _track_video(source, *, rest_frame: int, expected_pins, params, calibration, progress: bool,
                 total: int | None = None) -> dict:
    """Read every frame: find the pins in the rest frame (or place the calibrated pins there), track after it.

    Positions are kept as float32 (half the memory of a long recording), with the tracker's lost
    and retired masks and blank flag of every frame (`getattr` defaults for trackers without them).
    """
    from tqdm import tqdm

    params = calibration.detection if calibration is not None else params or DetectionParams()
    tracker: PinTracker | None = None
    positions, lost, retired, blank, timestamps = [], [], [], [], []
    warnings: list[str] = []
    before = 0
    detected, field = 0, ""
    failed: list[tuple[int, str]] = []  # frames the tracker raised on: (index, message)
    frames = iter(source)
    with tqdm(total=total, unit="frame", disable=not progress, desc="replay", mininterval=0.5) as bar:
        while True:
            try:
                frame = next(frames)
            except StopIteration:
                break
            except (SourceError, OSError) as exc:  # a damaged file: keep what was tracked before it
                if tracker is None:
                    raise
                warnings.append(f"the video could not be read after frame {len(timestamps) - 1} ({exc}); the "
                                f"frames before it are kept")
                break
            timestamps.append(frame.timestamp_s)
            if tracker is not None:
                try:
                    moved = tracker.update(frame.image).astype(np.float32)
                except (PinsError, ValueError) as exc:  # the tracking so far is kept; this frame is lost
                    failed.append((frame.index, f"{type(exc).__name__}: {exc}"))
                    moved = np.full((len(tracker.rest_positions), 2), np.nan, np.float32)
                    gone, away, dark = np.ones(len(moved), dtype=bool), None, False
                else:
                    gone = getattr(tracker, "lost", None)
                    gone = np.isnan(moved[:, 0]) if gone is None else np.array(gone, dtype=bool)
                    away = getattr(tracker, "retired", None)
                    dark = bool(getattr(tracker, "blank", gone.all()))
                positions.append(moved)
                lost.append(gone)
                retired.append(np.zeros_like(gone) if away is None else np.array(away, dtype=bool) & gone)
                blank.append(dark)
            elif frame.index == rest_frame:
                try:
                    tracker, rest, detected, params, field = _start(frame.image, params=params,
                                                                    expected_pins=expected_pins,
                                                                    calibration=calibration, warnings=warnings)
                except PinsError as exc:  # say which frame, and how to choose another (a black first frame)
                    raise type(exc)(f"rest frame {rest_frame}: {exc}; give --rest-frame of a frame off contact "
                                    f"with the pad lit and in view") from None
                positions.append(rest.astype(np.float32))
                lost.append(np.zeros(len(rest), dtype=bool))
                retired.append(np.zeros(len(rest), dtype=bool))
                blank.append(False)
            else:
                before += 1
            if progress:
                bar.update(1)
    if tracker is None:
        raise SourceError(f"the video has {len(timestamps)} frames, so there is no rest frame {rest_frame}")
    if failed:
        warnings.append(f"tracking failed in {len(failed)} frame(s), every pin lost there (first: frame "
                        f"{failed[0][0]}, {failed[0][1]})")
    pins = tracker.rest_positions.shape[0]
    stacked = np.concatenate([np.full((before, pins, 2), np.nan, np.float32), np.stack(positions)])
    lost = np.concatenate([np.ones((before, pins), bool), np.stack(lost)])
    retired = np.concatenate([np.zeros((before, pins), bool), np.stack(retired)])
    blank = np.concatenate([np.zeros(before, bool), np.asarray(blank, dtype=bool)])
    rest32 = tracker.rest_positions.astype(np.float32)
    displacements = displacement_from_rest(stacked, rest32).astype(np.float32, copy=False)
    return dict(positions=stacked, displacements=displacements, lost=lost, retired=retired, blank=blank,
                tracked=np.arange(len(stacked)) >= rest_frame,
                timestamps=np.asarray(timestamps, dtype=np.float64), rest=tracker.rest_positions,
                disc=tracker.disc, detection=params, tracker=tracker, frame_rate=source.frame_rate,
                frame_size=source.frame_size, pins_detected=int(detected), field=field, warnings=warnings)


def _start(image, *, params, expected_pins, calibration, warnings):
    """The tracker started on the rest frame: (tracker, rest positions, pins found, detection params, field line).

    Without a calibration the pins are the rest frame's pin field (`pins.find_pin_field`: the blobs
    that form the pin lattice, the rim ring's glare, specks and skin texture rejected); its
    detection parameters and field circle serve the tracker's recovery in later frames.
    """
    if calibration is not None:
        from calibration import place_reference_pins

        tracker = PinTracker(detection=params, disc=calibration.disc)
        rest = tracker.start(image, pins=place_reference_pins(calibration, image))
        return tracker, rest, len(rest), params, "the calibration's pins"
    # Default parameters are no hint: the field search finds its own (polarity apart).
    hint = None if params == DetectionParams(dark_pins=params.dark_pins) else params
    try:
        field = find_pin_field(image, expected_pins=expected_pins, params=hint, dark_pins=params.dark_pins)
    except NoSensorError as exc:
        if params.dark_pins:
            raise
        # No dark membrane disc: perhaps dark markers on a light membrane.
        try:
            field = find_pin_field(image, expected_pins=expected_pins,
                                   params=None if hint is None else hint.replace(dark_pins=True), dark_pins=True)
        except NoSensorError:
            raise NoSensorError(f"{exc} (nor with dark markers on a light membrane)") from None
        warnings.append("no dark membrane with bright pins in the rest frame: dark markers on a light membrane "
                        "assumed (--dark-pins)")
    tracker = PinTracker(detection=field.params, disc=field.disc)
    rest = tracker.start(image, field.centres)
    return tracker, rest, field.count, field.params, field.summary()


def check_rest_frame(displacements: np.ndarray, rest_positions: np.ndarray, *, rest_frame: int,
                     high_px: float = 1.5, signal: np.ndarray | None = None) -> str:
    """A warning when the rest frame looks taken during a tap (`pins.converging_frames`), else "".

    Parameters
    ----------
    displacements : (T, N, 2) ndarray
        Displacements from the rest frame, px (NaN where lost or not tracked).
    rest_positions : (N, 2) ndarray
        px.
    rest_frame : int
        The rest frame's index (named in the warning).
    high_px : float
        Smallest tap signal of a frame that counts, px.
    signal : (T,) ndarray, optional
        The tap signal (`pins.tap_signal`) when already computed, px.

    Returns
    -------
    warning : str
        Names the frames where the pins are drawn together (as at rest after a press, seen from
        a pressed reference) and suggests for ``--rest-frame`` the middle of the longest run of
        frames drawn together about the most (the pad still, at rest); "" when fewer than
        max(3, 5 % of the tracked frames) converge.
    """
    from pins import converging_frames

    if signal is None:
        signal = tap_signal(displacements)
    frames = converging_frames(displacements, rest_positions, high_px=high_px, signal=signal)
    tracked = int(np.isfinite(displacements[:, :, 0]).any(axis=1).sum())
    if len(frames) < max(3, 0.05 * tracked):
        return ""
    signal = np.where(np.isin(np.arange(len(displacements)), frames), signal, 0.0)
    # The pad at rest: the middle of the longest run of frames drawn together about the most.
    runs, count = ndimage.label(signal >= 0.9 * signal.max())
    longest = np.argmax(np.bincount(runs.ravel())[1:]) + 1
    suggested = int(np.median(np.flatnonzero(runs == longest)))
    return (f"the rest frame {rest_frame} looks taken during a tap: in {len(frames)} frames (e.g. {suggested}) "
            f"the pins are drawn together by up to {signal.max():.1f} px from it, as a pad at rest looks from a "
            f"pressed one; displacements and taps are measured from a deformed pad: give --rest-frame of a "
            f"frame off contact (frame {suggested} looks like one)")


def _analyse(track: dict, *, calibration, n_pins: int, min_separation_mm: float, sensor, pins_on_pad,
             pad_diameter_mm, mm_per_px, expected_pins, n_samples: int, rest_frame: int) -> dict:
    """Scale, feature pins, rest-frame check, taps and features; every problem becomes a warning."""
    warnings = list(track["warnings"])
    rest, disc, displacements = track["rest"], track["disc"], track["displacements"]
    found = track["pins_detected"]
    if expected_pins and abs(found - expected_pins) > 0.1 * expected_pins:
        warnings.append(f"{found} pins found in the rest frame, {expected_pins} expected "
                        f"({(found - expected_pins) / expected_pins:+.0%}): check --expected-pins and the rest frame")
    scale = selection = None
    selected = np.zeros(0, dtype=np.intp)
    if calibration is not None:
        scale_mm_per_px, selected = float(calibration.mm_per_px), np.asarray(calibration.selected_pins)
    else:
        pad = pad_diameter_mm if pad_diameter_mm is not None or sensor is not None else DEFAULT_PAD_DIAMETER_MM
        count = pins_on_pad if pins_on_pad is not None or sensor is not None else expected_pins
        try:
            scale = pad_scale(rest, sensor=sensor, pins=count, pad_diameter_mm=pad, mm_per_px=mm_per_px)
        except (PinsError, ValueError) as exc:
            fallback = (pad or DEFAULT_PAD_DIAMETER_MM) / (2.0 * disc.radius_px)
            scale = PadScale(fallback, float("nan"), float("nan"),
                             f"pad diameter {pad or DEFAULT_PAD_DIAMETER_MM:g} mm / disc diameter "
                             f"{2 * disc.radius_px:.1f} px", {"pad_diameter_mm": pad or DEFAULT_PAD_DIAMETER_MM})
            warnings.append(f"the scale could not come from the pin pitch ({exc}); the disc's diameter was used")
        if sensor is None and pad_diameter_mm is None and mm_per_px is None:
            scale = dataclasses.replace(scale, source=f"{scale.source}; pad diameter assumed, describe the sensor "
                                                      f"with --sensor or --pad-diameter-mm")
        scale_mm_per_px = scale.mm_per_px
        try:
            selection = _select(track, n_pins=n_pins, min_separation_mm=min_separation_mm, mm_per_px=scale_mm_per_px)
            selected = selection.indices
            if selection.warning:
                warnings.append(f"feature pins: {selection.warning}")
        except (PinsError, ValueError) as exc:
            warnings.append(f"no feature pins ({exc})")
    signal = tap_signal(displacements)  # per frame, px: for the rest-frame check, the thresholds and the taps
    try:
        spacing = track["tracker"].spacing_px
        check = check_rest_frame(displacements, rest, rest_frame=rest_frame, signal=signal,
                                 high_px=1.5 * min(1.0, spacing / REFERENCE_PITCH_PX) if spacing > 0 else 1.5)
        if check:
            warnings.append(check)
    except (PinsError, ValueError) as exc:
        warnings.append(f"the rest frame could not be checked ({exc})")
    bounds, taps, valid = [], None, np.zeros(0, dtype=bool)
    high_px, low_px = tap_thresholds_px(displacements, track["tracker"].spacing_px,
                                        usable=track["tracked"] & ~track["blank"], signal=signal)
    try:
        bounds = segment_taps(signal, high_px=high_px, low_px=low_px)
        if not bounds:
            warnings.append(f"no taps found (no frame moved the pins by {high_px:.2g} px): only the tracking "
                            f"was written")
        elif len(selected):
            taps, valid = _features(displacements, track["timestamps"], bounds, selected, n_samples)
        else:
            valid = np.zeros(len(bounds), dtype=bool)
    except (PinsError, ValueError) as exc:
        warnings.append(f"no tap features ({exc})")
    return dict(scale=scale, mm_per_px=scale_mm_per_px, selection=selection, selected=np.asarray(selected, np.intp),
                bounds=bounds, taps=taps, valid=valid, warnings=warnings, tap_thresholds_px=(high_px, low_px))


def tap_thresholds_px(displacements: np.ndarray, spacing_px: float, *, usable: np.ndarray | None = None,
                      signal: np.ndarray | None = None) -> tuple[float, float]:
    """The hysteresis thresholds of `pins.segment_taps` for this sensor, px: (high, low).

    The defaults (1.5 and 0.5 px) fit a pad whose pins are about `REFERENCE_PITCH_PX` apart in the
    image; on a pad seen smaller (a small pad, a low resolution) the pins move proportionally less
    and the thresholds shrink with the pitch (never grow), but stay above the tracking noise: the
    low threshold at least twice the quiet frames' tap signal (its 10th percentile).

    Parameters
    ----------
    displacements : (T, N, 2) ndarray
        px, NaN where lost.
    spacing_px : float
        Median nearest-neighbour pin spacing at rest, px.
    usable : (T,) ndarray of bool, optional
        Frames to measure the noise on (tracked, not blank); all by default.
    signal : (T,) ndarray, optional
        The tap signal of every frame (`pins.tap_signal`) when already computed, px.
    """
    factor = min(1.0, spacing_px / REFERENCE_PITCH_PX) if np.isfinite(spacing_px) and spacing_px > 0 else 1.0
    if signal is None:
        signal = tap_signal(displacements)
    if usable is not None:
        signal = signal[usable]
    floor = float(np.percentile(signal, 10)) if signal.size else 0.0
    low = max(0.5 * factor, 2.0 * floor)
    return max(1.5 * factor, 2.0 * low), low


def _select(track: dict, *, n_pins: int, min_separation_mm: float, mm_per_px: float) -> PinSelection:
    """Feature pins among the pins seen in at least half the tracked frames (all pins if too few are)."""
    rest = track["rest"]
    usable = track["tracked"] & ~track["blank"]
    seen = (~track["lost"][usable]).mean(axis=0) >= 0.5 if usable.any() else np.ones(len(rest), bool)
    candidates = np.flatnonzero(seen) if seen.sum() >= min(n_pins, len(rest)) else np.arange(len(rest))
    selection = select_feature_pins(rest[candidates], n_pins=n_pins, min_separation_mm=min_separation_mm,
                                    mm_per_px=mm_per_px, centre=tuple(rest.mean(axis=0)))
    return dataclasses.replace(selection, indices=candidates[selection.indices])


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


def _write_hdf5(path, track, analysis, settings, decisions=None) -> None:
    """The replay file (see the module docstring for its layout)."""
    from _files import hdf5_in_memory
    from tactip import __version__

    tracker = track["tracker"]
    frames, pins = track["lost"].shape
    # Positions are sub-pixel floats with sensor noise: gzip saves a third of their size for about
    # 10 % of the decoding time, so they are stored plain; the masks shrink to almost nothing.
    packed = dict(compression="gzip", compression_opts=1)
    with hdf5_in_memory(path) as h5:  # a full disk is an OSError, not a crash inside HDF5
        for name in ("positions", "displacements"):
            h5.create_dataset(name, data=track[name])
        for name in ("lost", "retired"):
            h5.create_dataset(name, data=track[name], chunks=(min(64, max(frames, 1)), pins) if frames else None,
                              **(packed if frames else {}))
        h5.create_dataset("lost_count", data=track["lost"].sum(axis=1, dtype=np.int32))
        h5.create_dataset("retired_count", data=track["retired"].sum(axis=1, dtype=np.int32))
        h5.create_dataset("blank", data=track["blank"])
        h5.create_dataset("tracked", data=track["tracked"])
        h5.create_dataset("timestamps", data=track["timestamps"])
        h5.create_dataset("rest_positions", data=track["rest"])
        selected = h5.create_dataset("selected_pins", data=np.asarray(analysis["selected"], dtype=np.int64))
        selection = analysis["selection"]
        if selection is not None:
            selected.attrs.update({"requested": selection.requested, "min_separation_mm": selection.min_separation_mm,
                                   "separation_mm": selection.separation_mm, "warning": selection.warning})
        bounds = analysis["bounds"]
        h5.create_dataset("tap_bounds", data=np.asarray(bounds, dtype=np.int64).reshape(-1, 2))
        if analysis["taps"] is not None:
            dataset = h5.create_dataset("taps", data=analysis["taps"].astype(np.float32))
            dataset.attrs["feature_names"] = json.dumps(feature_dim_names(len(analysis["selected"])))
            dataset.attrs["layout"] = "columns 0..P-1 dx, P..2P-1 dy of the selected pins, px"
            h5.create_dataset("tap_valid", data=analysis["valid"])
        disc = track["disc"]
        scale = analysis["scale"]
        scale_info = {"mm_per_px": float(analysis["mm_per_px"]), "source": "calibration"} if scale is None else {
            "mm_per_px": scale.mm_per_px, "pitch_px": scale.pitch_px, "pitch_mm": scale.pitch_mm,
            "source": scale.source, "sensor": scale.sensor}
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
            "scale": json.dumps(scale_info, default=float),
            "pins_detected": int(track["pins_detected"]),
            "blank_frames": np.flatnonzero(track["blank"]).astype(np.int64),
            "warnings": json.dumps(analysis["warnings"]),
            "tap_thresholds_px": np.asarray(analysis["tap_thresholds_px"], dtype=np.float64),
            **settings,
        })
        if decisions is not None:
            from tactip.replay.decisions import write_decisions

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
                # Lost pins (NaN) are drawn at rest, then masked out: no NaN reaches the integer cast.
                tip = np.rint((rest + ARROW_SCALE * np.nan_to_num(displacement)) * 16).astype(np.int32)
                base = np.rint(np.where(np.isfinite(positions), positions, rest) * 16).astype(np.int32)
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
