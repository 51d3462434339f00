"""Replay a recorded TacTip video through the pin pipeline and store the result in HDF5.

``replay_video`` reads every frame of a video (or any non-live frame source), finds the pins in
the rest frame (the first frame unless told otherwise; it must be off contact) as the blobs that
form the pin lattice (`pins.find_pin_field`: rim-ring glare, specks and skin texture rejected; the polarity
decided as `tactip detect` decides it, and a frame without a sensor refused with its message), tracks them
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
- ``tap_bounds`` int (taps, 2): [start, stop) frame indices of the contacts (any rest separates two);
  ``tap_kinds`` bytes (taps,): ``press`` or ``slide``; ``tap_directions_deg`` (taps,): a slide's direction
  (degrees from image x towards image y), NaN for a press (`pins.contact_kinds`); ``tap_rest_frames`` int
  (taps,): the frame each tap's features are measured from (`tactip.replay.contacts.feature_rests_of`);
- ``taps`` float32 (taps, samples, 2 P) when taps were found: columns 0..P-1 dx, P..2P-1 dy of the
  selected pins (``feature_names`` attribute), NaN in the columns of a pin unseen for the whole tap;
  ``tap_pins_seen`` int (taps,), of P (``of``); ``tap_valid`` bool (taps,): False below P / 2 seen (NaN);
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
dropped; up to 64 MB of frames ahead, so decoding goes on while the pin field is searched for) while the main thread tracks, so a replay costs about the larger of decoding and
tracking rather than their sum (`bench/bench_replay.py`). The decoder gets one thread fewer than
the cores (one on a 2-core machine): its extra threads would only contend with the tracking. A video
file's grey frames are read from the decoder's luma plane, without converting each to BGR and back
(`tactip.replay.luma`), where its first frame shows that this gives the same frames (grey content: a
monochrome pad, the synthetic videos); a colour recording is read as before. The table from luma to
grey is looked up on the tracking thread when the decoder has one thread, two pixels a lookup
(`tactip.replay.luma.look_up`): there it also brings the frame into the tracking core's cache (on the decode
thread it cost the decoder more than it saved the tracking, `bench/bench_replay.py`). The contacts'
neighbourhood medians (`find_contacts`) are computed frame by frame as the pins are tracked
(`pins.segment.NeighbourMedians`, fed by `tactip.pipeline.track_pins`' ``each_row``), not after the last frame: what follows the last frame (contacts,
features, the HDF5 file) is on the critical path whole.

The file is written to a temporary name next to the target and renamed at the end, so a failure
never leaves a half-written result; the output paths are checked before any processing.
"""

from __future__ import annotations

import contextlib
import math
import os
import pathlib

import numpy as np

from pins import DetectionParams, PinsError, PinTracker, find_pin_field
from pins.segment import NeighbourMedians

from tactip._output import (check_video_written, claim_output, discard_temporary, publish, refuse_overwriting_inputs,
                            write_error)
from tactip.errors import ConfigError, SourceError
from tactip.pipeline import frames_to_features
from tactip.replay.contacts import analyse, check_rest_frame
from tactip.replay.result import ReplayResult
from tactip.replay.writers import FORMAT, write_annotated, write_hdf5

__all__ = ["ReplayResult", "replay_video", "track_video", "check_replay_options", "FORMAT", "check_rest_frame"]



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


# Decoded grey frames replay's reader may hold ahead of the tracking, bytes: while the pin field is searched for
# in the rest frame (0.14 s on the slide bench, ~150-230 frames of decoding) the decoder runs on instead of
# stopping at a short queue (8 frames). Slide bench, quiet 2-core VM, replay / decode: interleaved in one
# process, medians of 3 rounds, 8 -> 256 frames, 1.51 -> 1.42 (mp4v) and 1.28 -> 1.02 (MJPG); bench_replay.py's medians of its
# repeats, separate runs, 1.64 -> 1.60 and 1.31 -> 1.27. 218 frames of 640x480, 32 of 1920x1080.
_QUEUE_BYTES = 64 * 2 ** 20


def _queue_frames(frame_size) -> int:
    """Frames of `frame_size` (width, height) px, grey, that fill `_QUEUE_BYTES` (at least 8)."""
    width, height = (int(v) for v in frame_size)
    pixels = width * height
    return 8 if pixels <= 0 else max(8, _QUEUE_BYTES // pixels)  # (a size the source does not know: 8)


def replay_video(video: str | os.PathLike, out_path: str | os.PathLike, *,
                 annotate_path: str | os.PathLike | None = None, expected_pins: int | None = None,
                 params: DetectionParams | None = None, n_samples: int = 40, n_pins: int = 40,
                 min_separation_mm: float = 4.0, sensor: str | None = None, pins_on_pad: int | None = None,
                 pad_diameter_mm: float | None = None, mm_per_px: float | None = None,
                 rest_frame: int = 0, calibration=None, model=None, decision_threshold: float | None = None,
                 progress=False, decode_threads: int | None = None, wrap_windows=None) -> ReplayResult:
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
        Detection parameters: a hint for the pin field search, whose ``dark_pins`` is kept (default:
        none, and the polarity is decided from the rest frame as `tactip detect` decides it).
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
    progress : bool or callable
        Show a tqdm progress bar in frames (on stderr); or a callable given the frames read, a few at a
        time (`tactip.pipeline.track_pins`; a batch's workers report to its bar so).
    decode_threads : int, optional
        Threads of the video decoder (default: every core but the one that tracks); a batch running
        a replay per core gives each one (the output is the same whatever the count).
    wrap_windows : callable, optional
        Given the tracker's windowed centroids once it has started, returns their stand-in
        (`pins.accel.WindowBatcher.wrap`: many videos' windows measured together on a GPU,
        `tactip.replay.batch.replay_together`); the same positions.

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

    check_replay_options(rest_frame=rest_frame, pad_diameter_mm=pad_diameter_mm, mm_per_px=mm_per_px, n_pins=n_pins,
                         pins_on_pad=pins_on_pad, expected_pins=expected_pins, min_separation_mm=min_separation_mm,
                         sensor=sensor)
    cal, model, model_path = _load_station_files(calibration, model, decision_threshold, n_samples=n_samples,
                                                 given=dict(expected_pins=expected_pins, params=params,
                                                            mm_per_px=mm_per_px, sensor=sensor,
                                                            pins_on_pad=pins_on_pad, pad_diameter_mm=pad_diameter_mm))
    out_path = pathlib.Path(out_path)
    annotate = None if annotate_path is None else pathlib.Path(annotate_path)
    refuse_overwriting_inputs([out_path, annotate], [video, calibration, model])  # a result never replaces what it was made from
    if annotate is not None and annotate.suffix.lower() != ".mp4":
        raise SourceError(f"cannot write the annotated video {str(annotate)!r}: it is MPEG-4, give a .mp4 name")
    temporary: list[pathlib.Path] = []
    try:
        temporary.append(claim_output(out_path, ".h5"))
        if annotate:
            temporary.append(claim_output(annotate, ".mp4"))
        track, analysis, frame_size, frame_rate = track_video(
            video, calibration=cal, params=params, expected_pins=expected_pins, n_samples=n_samples,
            n_pins=n_pins, min_separation_mm=min_separation_mm, sensor=sensor, pins_on_pad=pins_on_pad,
            pad_diameter_mm=pad_diameter_mm, mm_per_px=mm_per_px, rest_frame=rest_frame, progress=progress,
            decode_threads=decode_threads, wrap_windows=wrap_windows)
        # From here on the tracking is kept whatever happens: problems become warnings.
        bounds = analysis["bounds"]
        valid = track.valid if len(analysis["selected"]) else np.zeros(len(bounds), dtype=bool)
        decisions = None
        if model is not None and len(track.contacts):
            from tactip.replay.decisions import decide_taps

            try:
                decisions = decide_taps(track.features, track.valid, model,
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
                    write_hdf5(part, track, analysis, dict(settings, frame_size=frame_size, frame_rate=frame_rate),
                               decisions)
                else:
                    write_annotated(video, part, track, bounds, analysis["selected"], frame_size=frame_size,
                                    frame_rate=frame_rate, decisions=decisions)
                if annotate is not None:  # both on the disk before either is published (a single one: `publish`)
                    with open(part, "rb+") as written:
                        os.fsync(written.fileno())
            except (OSError, RuntimeError) as exc:
                raise write_error(exc, final) from None
            if final is annotate:  # OpenCV's writer says nothing of a full disk: count the frames stored
                check_video_written(part, final, len(track.timestamps_s))
        for part, final in zip(temporary, [out_path, annotate]):
            publish(part, final)       # renamed over a file, streamed into /dev/null or a FIFO
    finally:
        for part in temporary:
            discard_temporary(part)
    return ReplayResult(out_path=out_path, annotate_path=annotate, video=str(video), frames=len(track.timestamps_s),
                        pins=len(track.rest_positions), frame_rate=frame_rate,
                        lost_per_frame=track.lost.sum(axis=1), retired_per_frame=track.retired.sum(axis=1),
                        blank_frames=np.flatnonzero(track.blank).tolist(), rest_frame=int(rest_frame),
                        tap_bounds=bounds, invalid_taps=[k for k, ok in enumerate(valid) if not ok],
                        selected_pins=analysis["selected"], selection=analysis["selection"],
                        mm_per_px=float(analysis["mm_per_px"]), scale=scale, disc=track.disc,
                        detection=track.detection, pins_detected=track.pins_detected, pin_field=track.pin_field,
                        expected_pins=expected_pins, warnings=list(analysis["warnings"]), decisions=decisions,
                        contact_kinds=list(analysis.get("kinds", [])),
                        pins_seen=[int(n) for n in track.pins_seen])


def check_replay_options(*, rest_frame: int = 0, pad_diameter_mm: float | None = None, mm_per_px: float | None = None,
                         n_pins: int = 40, pins_on_pad: int | None = None, expected_pins: int | None = None,
                         min_separation_mm: float = 4.0, sensor: str | None = None) -> None:
    """Refuse `replay_video`'s options out of range, before any video is opened (a batch checks them once).

    Raises
    ------
    ValueError
        The first option out of range, named, with its value (an unknown sensor lists the choices).
    """
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


def track_video(video, *, calibration=None, params: DetectionParams | None = None, expected_pins: int | None = None,
                n_samples: int = 40, n_pins: int = 40, min_separation_mm: float = 4.0, sensor: str | None = None,
                pins_on_pad: int | None = None, pad_diameter_mm: float | None = None, mm_per_px: float | None = None,
                rest_frame: int = 0, progress=False, decode_threads: int | None = None,
                wrap_windows=None) -> tuple:
    """Track the pins of a recording and find its contacts and their features (replay's work, no file written).

    The options are `replay_video`'s (checked there), except that `calibration` must be a loaded
    `calibration.SensorCalibration` (or None), ``decode_threads`` sets the decoder's threads
    (default: every core but the one that tracks) and ``wrap_windows`` is `replay_video`'s. ``tactip dataset build`` calls it per recording.

    Returns
    -------
    track : tactip.pipeline.PinTrack
        With its contacts' features (``features``, ``pins_seen``, ``valid``).
    analysis : dict
        `tactip.replay.contacts.analyse`'s: scale, feature pins, contacts (``bounds``, ``kinds``), warnings.
    frame_size : (int, int)
        (width, height) of the frames, px.
    frame_rate : float
        Frames per second.

    Raises
    ------
    SourceError
        The video is missing, unreadable, live, or shorter than `rest_frame`.
    CalibrationError
        The calibration was made for frames of another size.
    PinsError
        No sensor in the rest frame.
    """
    from tactip.replay.luma import mapped, open_grey
    from tactip.sources import ThreadedReader

    # The decoder on one thread fewer than the cores: this thread tracks on the last one, and
    # FFmpeg's second thread on a 2-core machine only adds its own overhead to the contention.
    threads = _decode_threads() if decode_threads is None else max(1, int(decode_threads))
    with open_grey(video, threads) as source:
        if source.live:
            raise SourceError(f"{video!r} is a live source; replay reads recorded videos (use a file)")
        if calibration is not None and tuple(source.frame_size) != tuple(calibration.frame_size):
            from calibration import CalibrationError

            width, height = calibration.frame_size
            raise CalibrationError(f"the calibration was made for {width}x{height} px frames, the video's are "
                                   f"{source.frame_size[0]}x{source.frame_size[1]} px")
        # Decode on a thread while this one tracks; blocking, so that no frame is dropped. OpenCV's
        # own worker pool stays at one thread meanwhile: the two threads already fill a 2-core
        # machine, and the pool's workers only contend with them. With a one-thread decoder (2 cores)
        # luma is mapped to grey on this thread, where it costs least (`tactip.replay.luma.mapped`);
        # with more, the decoder's own threads decode and this one is the busier: the reader maps.
        table = source.defer_table() if threads == 1 and hasattr(source, "defer_table") else None
        with _opencv_threads(1), ThreadedReader(source, maxsize=_queue_frames(source.frame_size), when_full="block",
                                                close_source=False) as reader:
            plan = _Plan(calibration=calibration, n_pins=int(n_pins), min_separation_mm=float(min_separation_mm),
                         sensor=sensor, pins_on_pad=pins_on_pad, pad_diameter_mm=pad_diameter_mm,
                         mm_per_px=mm_per_px, expected_pins=expected_pins, rest_frame=int(rest_frame))
            start = _Start(params=params, expected_pins=expected_pins, calibration=calibration, wrap=wrap_windows)
            plan.start = start
            try:
                # (Luma mapped to grey where the tracker reads, once it has started: `PinTracker.frame_region`.)
                track = frames_to_features(mapped(reader, table, region=lambda: start.region), start=start,
                                           rest_frame=int(rest_frame), selected=plan.selected, contacts=plan.contacts,
                                           rests=lambda _: plan.analysis["rests"], n_samples=int(n_samples),
                                           progress=progress, total=getattr(source, "frame_count", None),
                                           each_row=lambda row: start.medians.add(row))
            except PinsError as exc:  # say which frame, and how to choose another (a black first frame)
                raise type(exc)(f"rest frame {rest_frame}: {exc}; give --rest-frame of a frame off contact "
                                f"with the pad lit and in view") from None
            frame_size, frame_rate = source.frame_size, source.frame_rate
    return track, plan.analysis, frame_size, frame_rate


class _Plan:
    """What replay asks of the tracked pins: the feature pins, then the contacts (`contacts.analyse`)."""

    def __init__(self, **options):
        self.options = options
        self.analysis: dict = {}
        self.start = None  # the `_Start` of the rest frame: its pin field's centres give the pitch

    def selected(self, track) -> np.ndarray:
        """The feature pins (the analysis is made here, once the pins are tracked)."""
        centres = getattr(self.start, "centres", None)
        medians = getattr(self.start, "medians", None)
        self.analysis = analyse(track, pitch_positions=centres, neighbour_medians=medians, **self.options)
        return self.analysis["selected"]

    def contacts(self, track) -> list:
        """The contacts whose features are computed: none without feature pins."""
        return self.analysis["bounds"] if len(self.analysis["selected"]) else []


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


class _Start:
    """Starts the tracker on the rest frame (`tactip.pipeline.Start`)."""

    def __init__(self, *, params, expected_pins, calibration, wrap=None):
        # Without parameters the polarity is decided from the rest frame, as `tactip detect` does.
        self.params = calibration.detection if calibration is not None else params
        self.expected_pins, self.calibration, self.wrap = expected_pins, calibration, wrap
        #: The rest frame's pin field centres, px (None with a calibration, or before the start): the
        #: pins `tactip detect` reports, whose pitch gives the scale (the tracker's rest positions are its
        #: windows' fixed points, up to 0.4 px off them on a reflection's flank).
        self.centres = None
        #: The contacts' neighbourhood medians, frame by frame as the pins are tracked (`track_pins`' ``each_row``;
        #: None before the start).
        self.medians = None
        #: The (rows, columns) of later frames the tracker reads (`pins.PinTracker.frame_region`; None before the start).
        self.region = None

    def __call__(self, image):
        """(tracker, rest positions, pins found, detection params, field line, warnings) of the rest frame."""
        warnings: list[str] = []
        started = _start(image, params=self.params, expected_pins=self.expected_pins, calibration=self.calibration,
                         warnings=warnings)
        tracker, self.centres = started[0], started[5]
        self.region = tracker.frame_region
        started = started[:5]
        if self.wrap is not None and tracker.windows is not None:  # e.g. measured with other videos' windows
            tracker.windows = self.wrap(tracker.windows)
        self.medians = NeighbourMedians(tracker.rest_positions)  # fed each row as `track_pins` stores it
        return (*started, warnings)


def _start(image, *, params, expected_pins, calibration, warnings):
    """The tracker started on the rest frame: (tracker, rest positions, pins found, detection params, field line,
    the pin field's centres (None with a calibration)).

    Without a calibration the pins are the rest frame's pin field (`pins.find_pin_field`: the blobs
    that form the pin lattice, the rim ring's glare, specks and skin texture rejected); its
    detection parameters and field circle serve the tracker's recovery in later frames. Without
    `params` the polarity is decided there exactly as `tactip detect` decides it, and a frame that
    shows no sensor is refused with the same message (`pins.NoSensorError`).
    """
    if calibration is not None:
        from calibration import place_reference_pins

        tracker = PinTracker(detection=params, disc=calibration.disc)
        rest = tracker.start(image, pins=place_reference_pins(calibration, image))
        return tracker, rest, len(rest), params, "the calibration's pins", None
    # Default parameters are no hint: the field search finds its own (polarity apart).
    hint = None if params is None or params == DetectionParams(dark_pins=params.dark_pins) else params
    field = find_pin_field(image, expected_pins=expected_pins, params=hint,
                           dark_pins=None if params is None else params.dark_pins)
    tracker = PinTracker(detection=field.params, disc=field.disc)
    rest = tracker.start(image, field.centres)
    warnings.extend(f"rest frame: {w}" for w in field.warnings)  # as `tactip detect` warns
    line = field.summary(pitch=False) + ("; dark markers on a light membrane" if field.params.dark_pins else "")
    return tracker, rest, field.count, field.params, line, field.centres  # the pitch: on the scale's line
