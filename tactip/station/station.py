"""The inspection station: an arm, a TacTip camera and the optical front end behind one object.

``Station.tap(gap, depth)`` is the one operation calibration and inspection need: move over the
gap, tap down to protocol depth ``depth`` (mm; the bottom of the stroke is at
``z = reference_height - depth`` in the work frame), capture exactly the frames of the tap (from
the arm's contact callback to its release callback), and turn them into the tap's feature array:
pins tracked from the tap's own rest frame, displacements of the calibrated feature pins, resampled
to the protocol's sample count (`pins.tap_features`).

Two cameras share the interface ``rest_frames(n)``, ``begin_tap(event)``, ``end_tap(event)``:

- `LiveCamera`: an OpenCV camera (or video) read on a thread into a bounded queue; the frames
  queued between the arm's two callbacks are the tap.
- `SimulatedCamera`: the synthetic TacTip renders the tap from the simulated arm's true contact
  (indentation, gap width, lateral offset) on the tap's own timeline: the stroke down from the
  approach height at the tap speed, the dwell, the stroke back up, at the camera's frame rate.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from tactip.station.config import GapConfig, StationConfig
from tactip.errors import SourceError, TactipError

__all__ = ["OpticalFrontEnd", "SimulatedCamera", "LiveCamera", "Station", "TapResult"]


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
        from calibration import place_reference_pins
        from pins import PinsError, PinTracker, as_grey, tap_features

        if len(frames) < 2:
            raise TactipError(f"a tap needs at least 2 frames, got {len(frames)} (camera too slow or stalled?)")
        cal = self.calibration
        # Start from the calibrated pins, each moved onto its blob in this tap's rest frame, so the
        # pin identities (and the feature subset) are those of the calibration. A blank first frame
        # (LEDs off, a dropped USB frame) is skipped: the first frame showing the pins is the rest.
        tracker = PinTracker(detection=cal.detection, disc=cal.disc)
        for first_index in range(len(frames) - 1):
            first = as_grey(np.asarray(frames[first_index]))
            try:
                rest = tracker.start(first, pins=place_reference_pins(cal, first))
                break
            except PinsError as error:
                blank_error = error
        else:
            raise TactipError(f"no frame of the tap shows the pins ({blank_error}); is the camera's light on?")
        positions = np.full((len(frames), len(rest), 2), np.nan)
        positions[first_index] = rest
        for k in range(first_index + 1, len(frames)):
            # NaN in a blank frame (`tracker.blank`) and for lost pins: tap_features fills them in time.
            positions[k] = tracker.update(frames[k])
        times = None if timestamps_s is None else np.asarray(timestamps_s, dtype=np.float64)
        return tap_features(positions - rest, pins=cal.selected_pins, n_samples=self.samples,
                            timestamps_s=times).astype(np.float32)


class SimulatedCamera:
    """The synthetic TacTip filming the simulated arm's taps (see the module docstring).

    Parameters
    ----------
    pins : int
        Pin preset (127, 331 or 532).
    frame_rate : float
        Camera frames/s.
    tap_speed_mm_s, dwell_s, approach_height_mm : float
        The arm's tap motion (``[arm.tap]``): they set the tap's timeline.
    noise_sigma : float
        Camera noise, grey levels.
    seed : int
        Seed of the sensor (pin layout and noise).
    """

    def __init__(self, *, pins: int = 331, frame_rate: float = 20.0, tap_speed_mm_s: float = 20.0,
                 dwell_s: float = 0.25, approach_height_mm: float = 5.0, noise_sigma: float = 4.0, seed: int = 0):
        from tactip.sim.synthetic import SyntheticTacTip

        self.sensor = SyntheticTacTip(pins=pins, noise_sigma=noise_sigma, seed=seed)
        self.frame_rate = float(frame_rate)
        self.tap_speed_mm_s = float(tap_speed_mm_s)
        self.dwell_s = float(dwell_s)
        self.approach_height_mm = float(approach_height_mm)
        self._event = None

    def rest_frames(self, n: int) -> list[np.ndarray]:
        """``n`` frames off contact."""
        return [self.sensor.render(timestamp_s=k / self.frame_rate).image for k in range(n)]

    def begin_tap(self, event, *, seed: int | None = None) -> None:
        """The arm starts its stroke down; ``event.contact`` is the simulated world's contact."""
        if seed is not None:
            self.sensor.reseed_noise(seed)
        self._event = event

    def end_tap(self, event) -> tuple[list[np.ndarray], list[float]]:
        """The arm is back up: render the tap's frames on its timeline. Returns (frames, times in s)."""
        from tactip.sim.synthetic import Contact

        contact = (self._event or event).contact
        if contact is None:
            raise TactipError("the simulated camera needs the simulated arm (no world contact in the tap event)")
        speed = self.tap_speed_mm_s
        indentation = max(float(contact.indentation_mm), 0.0)
        offset = 0.0 if not math.isfinite(contact.gap_offset_mm) else float(contact.gap_offset_mm)
        # From the approach height down to the surface (z = 0), the pressed stroke, dwell, back up.
        free_s = max(self.approach_height_mm / speed, 1.0 / self.frame_rate)
        press_s = max(indentation / speed, 1.0 / self.frame_rate)
        frames, times = [], []
        for f in self.sensor.tap(Contact(indentation_mm=indentation, gap_width_mm=float(contact.gap_width_mm),
                                         gap_offset_mm=offset),
                                 frame_rate=self.frame_rate, rise_s=press_s, plateau_s=self.dwell_s,
                                 release_s=press_s, rest_before_s=free_s, rest_after_s=free_s):
            frames.append(f.image)
            times.append(f.timestamp_s)
        self._event = None
        return frames, times

    def close(self) -> None:
        """Nothing to release."""


class LiveCamera:
    """A real camera (OpenCV) read on a thread; a tap is the frames between the arm's callbacks.

    Parameters
    ----------
    source : str, int or FrameSource
        Camera index, device path or video file (`tactip.sources.open_source`), or an open source.
    queue_frames : int
        Capacity of the frame queue; a tap must fit in it.
    timeout_s : float
        How long to wait for a frame before the camera counts as stalled, s.
    """

    def __init__(self, source: str | int, *, queue_frames: int = 512, timeout_s: float = 2.0):
        from tactip.sources import ThreadedReader, open_source

        self.timeout_s = float(timeout_s)
        if not hasattr(source, "read"):
            source = open_source(source, grey=True)
        self._reader = ThreadedReader(source, maxsize=queue_frames, when_full="drop")
        self.frame_rate = self._reader.frame_rate
        self._rest = None

    def rest_frames(self, n: int) -> list[np.ndarray]:
        """The next ``n`` frames (after dropping what was queued)."""
        self._reader.drain()
        frames = []
        for _ in range(n):
            frame = self._reader.read(timeout_s=self.timeout_s)
            if frame is None:
                raise SourceError("the camera stream ended while taking rest frames")
            frames.append(frame.image)
        return frames

    def begin_tap(self, event, *, seed: int | None = None) -> None:
        """The stroke starts: the newest queued frame (still off contact) is the tap's rest frame."""
        queued = self._reader.drain()
        if not queued:
            frame = self._reader.read(timeout_s=self.timeout_s)
            if frame is None:
                raise SourceError("the camera stream ended")
            queued = [frame]
        self._rest = queued[-1]

    def end_tap(self, event) -> tuple[list[np.ndarray], list[float]]:
        """The pad is back up: the rest frame and every frame since are the tap."""
        frames = [self._rest, *self._reader.drain()]
        self._rest = None
        return [f.image for f in frames], [f.timestamp_s for f in frames]

    def close(self) -> None:
        """Stop the reader thread and release the camera."""
        self._reader.close()


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
        self.camera = camera if camera is not None else _make_camera(config)
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

    def use_calibration(self, calibration) -> None:
        """Set the sensor calibration `tap` uses."""
        self.calibration = calibration
        self.front_end = OpticalFrontEnd(calibration, samples=self.config.protocol.samples)

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


def _make_camera(config: StationConfig):
    if config.arm.backend == "sim" or config.sensor.source == "synthetic":
        if config.arm.backend != "sim":
            raise TactipError("[sensor] source 'synthetic' needs the simulated arm (arm.backend = 'sim')")
        tap = config.arm.tap
        return SimulatedCamera(pins=config.sensor.pins, frame_rate=config.sensor.frame_rate,
                               tap_speed_mm_s=tap.speed_mm_s, dwell_s=tap.dwell_s,
                               approach_height_mm=tap.approach_height_mm, noise_sigma=config.sim.noise_sigma,
                               seed=config.sim.seed)
    return LiveCamera(config.sensor.source)
