"""The inspection station: an arm, a TacTip camera and the optical front end behind one object.

``Station.tap(gap, depth)`` is the one operation calibration and inspection need: move over the
gap, tap down to protocol depth ``depth`` (mm; the bottom of the stroke is at
``z = reference_height - depth`` in the work frame), capture exactly the frames of the tap (from
the arm's contact callback to its release callback), and turn them into the tap's feature array:
pins tracked from the tap's own rest frame, displacements of the calibrated feature pins, resampled
to the protocol's sample count (`pins.tap_features`).

The camera is any `tactip.station.camera.Camera` (a live one, or the synthetic TacTip on the
simulated arm), opened by `tactip.station.camera.make_camera`; the frames to features path is
`tactip.pipeline`, which replay shares.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from tactip.errors import TactipError
from tactip.station.camera import make_camera
from tactip.station.config import GapConfig, StationConfig

__all__ = ["OpticalFrontEnd", "Station", "TapResult"]


class OpticalFrontEnd:
    """Frames of one tap in, the tap's feature array out, with a sensor calibration.

    Parameters
    ----------
    calibration : calibration.SensorCalibration
        Detection parameters, reference pins and the feature-pin subset.
    samples : int
        Samples per tap (paper: 40).
    """

    def __init__(self, calibration, *, samples: int = 40):
        self.calibration = calibration
        self.samples = int(samples)

    @property
    def dims(self) -> int:
        """Feature dimensions: 2 x the selected pins (dx then dy)."""
        return 2 * self.calibration.n_selected

    @property
    def dim_names(self) -> list[str]:
        """Names of the feature dimensions (``pins.feature_dim_names``)."""
        from pins import feature_dim_names

        return feature_dim_names(self.calibration.n_selected)

    def features(self, frames: Sequence[np.ndarray], timestamps_s: Sequence[float] | None = None) -> np.ndarray:
        """The feature array of one tap.

        Parameters
        ----------
        frames : sequence of (H, W) or (H, W, 3) uint8 arrays
            The tap's frames; the first is off contact and is the rest frame.
        timestamps_s : sequence of float, optional
            Frame times, s.

        Returns
        -------
        features : (samples, 2 P) ndarray of float32
        """
        track = self.track(frames, timestamps_s)
        if not track.valid[0]:
            raise track.errors[0]
        return track.features[0].astype(np.float32)

    def track(self, frames: Sequence[np.ndarray], timestamps_s: Sequence[float] | None = None):
        """The tap's pins tracked and its features (`tactip.pipeline.PinTrack`, one contact: the whole tap).

        Parameters are those of `features`.
        """
        from pins import PinsError

        from tactip.pipeline import frames_to_features
        from tactip.sources import Frame

        if len(frames) < 2:
            raise TactipError(f"a tap needs at least 2 frames, got {len(frames)} (camera too slow or stalled?)")
        times = np.arange(len(frames), dtype=np.float64) if timestamps_s is None else timestamps_s
        stream = [Frame(k, float(t), np.asarray(image)) for k, (image, t) in enumerate(zip(frames, times))]
        try:
            track = frames_to_features(stream, start=self._start, selected=self.calibration.selected_pins,
                                       n_samples=self.samples)
        except PinsError as error:
            raise TactipError(f"no frame of the tap shows the pins ({error}); is the camera's light on?") from None
        if track.rest_frame == len(frames) - 1:
            raise TactipError("no frame of the tap shows the pins before its last; is the camera's light on?")
        return track

    def _start(self, image: np.ndarray):
        """The tracker started on the tap's rest frame from the calibrated pins, each moved onto its blob
        there, so the pin identities (and the feature subset) are those of the calibration."""
        from calibration import place_reference_pins
        from pins import PinTracker, as_grey

        cal = self.calibration
        grey = as_grey(image)
        tracker = PinTracker(detection=cal.detection, disc=cal.disc)
        rest = tracker.start(grey, pins=place_reference_pins(cal, grey))
        return tracker, rest, len(rest), cal.detection, "the calibration's pins", []


@dataclass(frozen=True)
class TapResult:
    """One tap of the station.

    Attributes
    ----------
    features : (samples, dims) ndarray of float32
    gap : GapConfig
    depth_mm : float
        Protocol depth of the tap, mm.
    lateral_mm : float
        Commanded lateral offset across the gap (the protocol's jitter), mm.
    contact : object or None
        The simulated world's true contact (`arm.world.WorldContact`), None on a real arm.
    frames : int
        Frames captured.
    duration_s : float
        Wall time of the tap, s.
    """

    features: np.ndarray
    gap: GapConfig
    depth_mm: float
    lateral_mm: float
    contact: Any
    frames: int
    duration_s: float


class Station:
    """An arm, a camera and the front end, opened from a `StationConfig`.

    Use as a context manager: leaving it (also on errors and Ctrl-C) stops the arm, disconnects it
    and releases the camera.

    Parameters
    ----------
    config : StationConfig
    calibration : calibration.SensorCalibration, optional
        Needed by `tap`; `calibrate` makes one from `rest_frames`.
    arm, camera : optional
        Injected parts (tests); built from ``config`` otherwise.
    """

    def __init__(self, config: StationConfig, *, calibration=None, arm=None, camera=None):
        self.config = config
        self.calibration = calibration
        self.arm = arm if arm is not None else _make_arm(config)
        self.camera = camera if camera is not None else make_camera(config)
        self.front_end = None if calibration is None else OpticalFrontEnd(calibration, samples=config.protocol.samples)
        self._open = False

    def __enter__(self) -> "Station":
        self.arm.connect()
        self._open = True
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Stop and disconnect the arm, release the camera (safe to call twice)."""
        try:
            if self._open:
                self.arm.disconnect()
        finally:
            self._open = False
            self.camera.close()

    def rest_frames(self, n: int = 10) -> list[np.ndarray]:
        """``n`` frames with the pad off contact, at the approach height over the first gap."""
        gap = self.config.gaps[0]
        pose = self.arm.pose()
        tap = self.config.arm.tap
        self.arm.move_linear(pose.moved_to(gap.x, gap.y, tap.approach_height_mm + 5.0),
                             speed_mm_s=tap.travel_speed_mm_s, acceleration_mm_s2=tap.acceleration_mm_s2)
        return self.camera.rest_frames(n)

    def check_depth(self, depth: float) -> None:
        """Refuse a protocol depth outside the protocol's range (`TactipError`), before anything moves."""
        p = self.config.protocol
        if not (p.depth_min - 1e-9 <= depth <= p.depth_max + 1e-9):
            raise TactipError(f"depth {depth:g} mm is outside the protocol range {p.depth_min:g}..{p.depth_max:g} mm")

    def tap(self, gap: GapConfig, depth: float, *, lateral_mm: float = 0.0, seed: int | None = None) -> TapResult:
        """Tap ``gap`` at protocol depth ``depth`` (mm) and return the tap's features.

        ``lateral_mm`` shifts the tap point across the gap (x of the work frame); ``seed`` makes a
        simulated tap reproducible (camera noise and placement error).
        """
        if self.front_end is None:
            raise TactipError("the station has no sensor calibration: run 'tactip calibrate' first")
        self.check_depth(depth)
        world = getattr(self.arm, "world", None)
        if seed is not None and world is not None:
            world.reseed(seed)
        start = time.monotonic()
        captured: dict = {}
        self.arm.tap(gap.x + lateral_mm, gap.y, depth_mm=self.config.protocol.arm_depth_mm(depth),
                     on_contact=lambda event: self.camera.begin_tap(event, seed=seed),
                     on_release=lambda event: captured.update(zip(("frames", "times", "event"),
                                                                  (*self.camera.end_tap(event), event))))
        features = self.front_end.features(captured["frames"], captured["times"])
        return TapResult(features=features, gap=gap, depth_mm=float(depth), lateral_mm=float(lateral_mm),
                         contact=captured["event"].contact, frames=len(captured["frames"]),
                         duration_s=time.monotonic() - start)


def _make_arm(config: StationConfig):
    """The configured arm; a simulated plate without gaps of its own gets the station's (at true width)."""
    from arm import Gap, make_arm

    gaps = tuple(Gap(g.name, g.x, g.y, g.true_width if g.true_width is not None else g.nominal_width)
                 for g in config.gaps)
    return make_arm(config.arm, default_gaps=gaps)
