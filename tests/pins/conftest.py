"""Shared helpers for the pins tests: renders from the synthetic TacTip and ground-truth matching."""

import functools

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment
from scipy.spatial.distance import cdist

from tactip.sim import Contact, SyntheticTacTip
from tactip.sim.sequence import Stroke

TAP = Contact(indentation_mm=5.0, gap_width_mm=2.0)


@functools.lru_cache(maxsize=None)
def sensor(pins: int = 331, *, dark_pins: bool = False, seed: int = 0) -> SyntheticTacTip:
    """A synthetic TacTip with gradient, glare and noise sigma 4 (the bars' conditions)."""
    return SyntheticTacTip(pins=pins, noise_sigma=4.0, glare=True, gradient=True, dark_pins=dark_pins, seed=seed)


@functools.lru_cache(maxsize=None)
def frame(pins: int = 331, contact: Contact | None = None, *, dark_pins: bool = False, seed: int = 0):
    """One rendered frame (cached: tests must not modify it)."""
    return sensor(pins, dark_pins=dark_pins, seed=seed).render(contact)


def match(detected: np.ndarray, truth: np.ndarray, gate_px: float = 3.0):
    """Recall, precision and centroid RMSE (px) of detections against true centres.

    One-to-one by the Hungarian method, pairs farther than `gate_px` do not count.
    """
    if len(detected) == 0:
        return 0.0, 0.0, np.inf
    distance = cdist(truth, detected)
    cost = np.where(distance <= gate_px, distance, 1e6)
    rows, cols = linear_sum_assignment(cost)
    ok = cost[rows, cols] <= gate_px
    errors = detected[cols[ok]] - truth[rows[ok]]
    rmse = float(np.sqrt(np.mean(np.sum(errors**2, axis=1)))) if ok.any() else np.inf
    return ok.sum() / len(truth), ok.sum() / len(detected), rmse


@functools.lru_cache(maxsize=None)
def preset_sensor(name: str, seed: int = 0, **overrides) -> SyntheticTacTip:
    """The synthetic TacTip preset ``name`` (`tactip.sim.synthetic.PRESETS`), cached."""
    return SyntheticTacTip.from_preset(name, seed=seed, **overrides)


def slide_run(name: str, seed: int, directions, **slides):
    """The preset's sensor (its noise restarted from `seed`), the frames of its `slides` in `directions`
    (degrees; `SyntheticTacTip.slides`, at 120 frames/s) as a list, and the indices of the pins drawn in the
    first (rest) frame, whole or cut."""
    s = preset_sensor(name, seed)
    s.reseed_noise(seed)
    run = list(s.slides(directions, frame_rate=120.0, **slides))
    return s, run, np.flatnonzero(run[0].visible | run[0].partial)


def tracker_on_rest(s: SyntheticTacTip, rest, *, partial: bool = True, **options):
    """A `pins.PinTracker` (``options``) started on the render ``rest`` of sensor ``s`` from its drawn pins' true
    centres (the visible ones, and the partly cut ones unless ``partial`` is False): (tracker, drawn indices)."""
    from pins import DetectionParams, PinTracker, SensorDisc

    drawn = np.flatnonzero(rest.visible | rest.partial if partial else rest.visible)
    tracker = PinTracker(detection=DetectionParams(dark_pins=s.dark_pins), disc=SensorDisc(*s.disc), **options)
    tracker.start(rest.image, pins=rest.centres[drawn])
    return tracker, drawn


def slides_and_presses(preset: str, seed: int):
    """The preset's sensor (`seed`) and a `ContactSequence` of 4 slides of 0.5-3 pitches in random directions,
    1-3 mm deep, each followed by a press 1-5 mm deep (rests 0.1 s, 20 frames/s), drawn from `seed`."""
    sensor = SyntheticTacTip.from_preset(preset, seed=seed)
    rng = np.random.default_rng(seed)
    pitch = sensor.pin_spacing_mm
    slides = [Stroke(float(rng.uniform(1.0, 3.0)), float(angle), float(rng.uniform(0.5, 3.0)) * pitch)
              for angle in rng.uniform(0, 360, 4)]
    presses = [Stroke(float(rng.uniform(1.0, 5.0)), gap_width_mm=float(rng.uniform(0.0, 4.0))) for _ in range(4)]
    return sensor, sensor.sequence([s for pair in zip(slides, presses) for s in pair], rest_s=0.1, frame_rate=20.0)


def apart_swaps_through_slides(name: str, seed: int, directions, frame_rate: float) -> tuple[int, float]:
    """Slides of 3 pitches in `directions` (degrees), 2 mm deep, pressed and lifted in 50 ms, at `frame_rate`
    (as `bench_conditions`' slides), tracked from the drawn pins' true rest centres: pin-frames placed nearer
    another visible pin's true centre than their own, the two at least half a spacing apart; and the largest
    step of a visible pin in a frame, spacings."""
    from scipy.spatial import cKDTree


    s = preset_sensor(name, seed)
    s.reseed_noise(seed)
    run = iter(s.slides(directions, distance_mm=3 * s.pin_spacing_mm, indentation_mm=2.0,
                        rest_s=max(3 / frame_rate, 0.025), press_s=0.05, slide_s=0.15, lift_s=0.05,
                        frame_rate=frame_rate))
    rest = previous = next(run)
    tracker, drawn = tracker_on_rest(s, rest)
    apart, step = 0, 0.0
    for f in run:
        positions = tracker.update(f.image)
        step = max(step, np.max(np.linalg.norm(f.centres - previous.centres, axis=1)[f.visible & previous.visible]))
        previous = f
        placed = np.flatnonzero(f.visible[drawn] & np.isfinite(positions[:, 0]))
        nearest = cKDTree(f.centres).query(positions[placed])[1]
        gap = np.linalg.norm(f.centres[nearest] - f.centres[drawn[placed]], axis=1)
        apart += int(np.count_nonzero((nearest != drawn[placed]) & (gap >= 0.5 * tracker.spacing_px)))
    return apart, step / tracker.spacing_px


@functools.lru_cache(maxsize=None)
def preset_frame(name: str, contact: Contact | None = None, seed: int = 0):
    """One rendered frame of the preset ``name`` (cached: tests must not modify it).

    The frame carries its ground truth: ``centres``, ``visible`` (whole tips: must be found) and
    ``partial`` (tips cut by the rim ring or the image edge: may be found or not).
    """
    # The sensor is shared (cached): its camera noise restarts from the seed, so the frame does not
    # depend on which tests rendered before it in this process.
    sensor = preset_sensor(name, seed)
    sensor.reseed_noise(seed)
    return sensor.render(contact)


def score(detected: np.ndarray, frame, gate_px: float = 3.0):
    """Recall, precision and RMSE (px) of detections scored against a frame's ground truth.

    Detections are matched one-to-one (Hungarian method, pairs farther than ``gate_px`` do not count)
    to the drawn pins, visible or partial. Recall is the fraction of visible pins matched; a detection
    matched to a visible or a partial pin is correct (precision: correct / detections; partial pins
    count neither for nor against); RMSE is over the matched visible pins. No detections: (0, 0, inf)
    (precision 1.0 when nothing is drawn either).

    Parameters
    ----------
    detected : (M, 2) ndarray of (x, y), px
    frame : tactip.sim.synthetic.SyntheticFrame
    gate_px : float

    Returns
    -------
    recall, precision, rmse_px : float
    """
    detected = np.asarray(detected, dtype=float).reshape(-1, 2)
    visible = np.asarray(frame.visible, bool)
    drawn = visible | np.asarray(frame.partial, bool)
    truth = frame.centres[drawn]
    is_visible = visible[drawn]
    if len(detected) == 0 or len(truth) == 0:
        return (0.0 if is_visible.any() else 1.0), (1.0 if len(detected) == 0 else 0.0), np.inf
    distance = cdist(truth, detected)
    cost = np.where(distance <= gate_px, distance, 1e6)
    rows, cols = linear_sum_assignment(cost)
    ok = cost[rows, cols] <= gate_px
    rows, cols = rows[ok], cols[ok]
    on_visible = is_visible[rows]
    errors = detected[cols[on_visible]] - truth[rows[on_visible]]
    rmse = float(np.sqrt(np.mean(np.sum(errors ** 2, axis=1)))) if on_visible.any() else np.inf
    recall = on_visible.sum() / is_visible.sum() if is_visible.any() else 1.0
    return float(recall), float(ok.sum() / len(detected)), rmse


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


# Presets that show issue 20's phenomena before the front end copes with them: the detection bars are
# expected to fail on them (not strict: whoever fixes one removes it from here). Replay's test no longer
# reads this: radial-led-120 meets its replay bar.
NOT_YET_MET = {
    "radial-led-120": "issue 20: detection meets outcome 7's bar of the count within 1 % on 70 of 72 frames (seeds "
                      "0-35 at rest and under a 5 mm tap; seeds 0-11: 24/24, no pin missed, none false; seeds 24-35, "
                      "never looked at while developing: 24/24, 1 missed, 1 false; seeds 12-23: 22/24, seed 15 "
                      "misses 2 at rest and tapped, one a pin whose ideal SNR is 4.5); what is "
                      "left here is the field RMSE bar of 0.1 px on every frame, at the noise limit of a fit per pin: "
                      "seeds 0-35, frames' RMSE (rms over frames) 0.1015 at rest, 0.1051 tapped, 16 and 25 of 36 "
                      "frames over 0.1 (session 23: tips a fit left beyond its reach fitted again; was 0.1050, "
                      "0.1098, 20 and 26); fitted from the true centres 0.097, 0.103, 12 and 21 frames over; "
                      "Cramer-Rao bound per frame 0.083-0.093 with the membrane and tip level known; held out "
                      "48-59: 0.0997, 0.1029, 5 and 8 of 12 over; what is left needs a prior across pins. Replay "
                      "now meets its bar: faint outer-ring tips on the veil that their windows lose are fitted as "
                      "opaque tips (pins._recover.fit_tips); the seed-7 tap video tracks 100 % of the visible "
                      "pin-frames (bar 99 %), RMSE 0.177 px; seeds 0-11: 11 of 12 meet 99 % "
                      "(98.69-100 %, seed 9 lowest), RMSE 0.17-0.25 px (raw renders)",
}


def preset_params(names):
    """``names`` for ``parametrize``, those in `NOT_YET_MET` marked as expected failures with the reason."""
    return [pytest.param(name, marks=pytest.mark.xfail(reason=NOT_YET_MET[name], strict=False))
            if name in NOT_YET_MET else name for name in names]


def cropped_frame(frame, x0: int, y0: int, x1: int, y1: int, pin_radius_px: float):
    """A frame cut to the window [x0, x1) x [y0, y1) px, with its ground truth moved and re-flagged.

    A pin stays ``visible`` when its whole tip (`pin_radius_px` and the 1 px edge ramp, plus half a
    pixel) lies inside the window; a drawn pin the window cuts becomes ``partial``.
    """
    from types import SimpleNamespace

    centres = frame.centres - [x0, y0]
    width, height = x1 - x0, y1 - y0
    reach = pin_radius_px + 1.5
    x, y = centres[:, 0], centres[:, 1]
    inside = (x >= reach) & (y >= reach) & (x <= width - 1 - reach) & (y <= height - 1 - reach)
    near = (x >= -reach) & (y >= -reach) & (x <= width - 1 + reach) & (y <= height - 1 + reach)
    visible = np.asarray(frame.visible, bool) & inside
    drawn = np.asarray(frame.visible, bool) | np.asarray(frame.partial, bool)
    return SimpleNamespace(image=np.ascontiguousarray(frame.image[y0:y1, x0:x1]), centres=centres,
                           visible=visible, partial=drawn & near & ~visible)
