"""pins.track: LK tracking against ground truth, lost-pin flags, recovery without identity swaps."""

import functools

import cv2
import numpy as np
import pytest
from scipy.spatial import cKDTree

from pins import LKParams, PinsError, PinTracker, ShapeError, detect_pins, match_to_blobs, track_pins
from tactip.synthetic import Contact
from tests.pins.conftest import TAP, frame, sensor


def _shift(image, dx, dy):
    matrix = np.float32([[1, 0, dx], [0, 1, dy]])
    return cv2.warpAffine(image, matrix, image.shape[::-1], flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REPLICATE)


@functools.lru_cache(maxsize=None)
def _tap_frames(pins):
    """A rest frame then a 5 mm tap over a 2 mm gap (peak displacement above 12 px)."""
    s = sensor(pins)
    return [s.render()] + list(s.tap(TAP, frame_rate=20.0))


def _identity(tracker_start, truth):
    """Index of the true pin each started pin is (nearest within 1 px)."""
    distance, index = cKDTree(truth).query(tracker_start)
    assert distance.max() < 1.0
    return index


def test_no_motion_gives_zero_displacement():
    image = frame(331).image
    pins = detect_pins(image)
    moved, ok = track_pins(image, image.copy(), pins)
    assert ok.all()
    assert np.abs(moved - pins).max() < 0.01


@pytest.mark.parametrize("dx, dy", [(1.3, -0.7), (-3.6, 2.2)])
def test_known_shift_is_recovered(dx, dy):
    image = frame(331).image
    pins = detect_pins(image)
    moved, ok = track_pins(image, _shift(image, dx, dy), pins)
    assert ok.mean() > 0.98
    flow = moved[ok] - pins[ok]
    assert np.median(flow, axis=0) == pytest.approx([dx, dy], abs=0.05)
    assert np.percentile(np.linalg.norm(flow - [dx, dy], axis=1), 95) < 0.2


def test_nan_points_stay_nan_and_shapes_checked():
    image = frame(331).image
    pins = detect_pins(image)
    pins[[3, 7]] = np.nan
    moved, ok = track_pins(image, image, pins)
    assert not ok[[3, 7]].any() and np.isnan(moved[[3, 7]]).all() and ok.sum() == len(pins) - 2
    assert track_pins(image, image, np.empty((0, 2)))[0].shape == (0, 2)
    with pytest.raises(ShapeError):
        track_pins(image, image, pins[:, :1])
    with pytest.raises(ShapeError):
        track_pins(image, image[:100], pins)


def test_tracker_without_refinement_equals_the_function():
    frames = _tap_frames(331)
    lk = LKParams(window_px=11, levels=1)
    tracker = PinTracker(lk=lk, refine=False)
    points = tracker.start(frames[0].image)
    for previous, current in zip(frames[:3], frames[1:4]):
        expected, ok = track_pins(previous.image, current.image, points, params=lk)
        got = tracker.update(current.image)
        # The tracker works on a crop and starts LK from a constant-velocity guess: same answer.
        assert np.allclose(got[ok], expected[ok], atol=0.02)
        assert np.array_equal(tracker.lost, ~np.isfinite(got).all(axis=1))
        points = expected


@pytest.mark.parametrize("pins", [331, 532])
def test_tracking_through_a_tap_meets_the_bar(pins):
    frames = _tap_frames(pins)
    peak = max(np.linalg.norm(f.centres - frames[0].centres, axis=1).max() for f in frames)
    assert peak >= 12.0
    tracker = PinTracker()
    identity = _identity(tracker.start(frames[0].image), frames[0].centres)
    errors = []
    for f in frames[1:]:
        positions = tracker.update(f.image)
        assert not tracker.lost.any()
        errors.append(positions - f.centres[identity])
        # No identity swaps: every tracked pin is nearest to its own true pin.
        assert np.array_equal(cKDTree(f.centres).query(positions)[1], identity)
    rmse = np.sqrt(np.mean(np.sum(np.concatenate(errors) ** 2, axis=1)))
    assert rmse <= 0.15


@pytest.mark.parametrize("pins, refine", [(331, True), (532, True), (331, False)])
def test_hidden_pins_are_flagged_and_recovered(pins, refine):
    s = sensor(pins)
    rng = np.random.default_rng(7)
    hidden = np.zeros(s.n_pins, dtype=bool)
    hidden[rng.choice(s.n_pins, int(round(0.05 * s.n_pins)), replace=False)] = True
    contact = [Contact(indentation_mm=4.0 * t, gap_width_mm=2.0) for t in np.linspace(0, 1, 8)]
    contact += [contact[-1]] * 8
    tracker = PinTracker(refine=refine)
    identity = _identity(tracker.start(s.render(contact[0]).image), s.rest_centres)
    hide = range(5, 10)
    for k, c in enumerate(contact[1:], start=1):
        f = s.render(c, hidden=hidden if k in hide else None)
        positions = tracker.update(f.image)
        gone = hidden[identity]
        if k in hide:
            # Flagged while hidden: NaN and lost, never frozen at an old position.
            assert tracker.lost[gone].all() and np.isnan(positions[gone]).all()
            assert not tracker.lost[~gone].any()
        elif k > hide.stop:
            if refine:
                # Recovered by re-detection, with the right identity.
                assert not tracker.lost.any()
                assert np.abs(positions - f.centres[identity]).max() < 0.5
            else:
                # Plain LK cannot bring a pin back: it stays flagged.
                assert tracker.lost[gone].all() and not tracker.lost[~gone].any()


def test_match_to_blobs_is_one_to_one_inside_the_gate():
    points = np.array([[0.0, 0.0], [1.0, 0.0], [10.0, 0.0], [np.nan, np.nan], [30.0, 0.0]])
    blobs = np.array([[0.8, 0.0], [10.2, 0.1], [33.5, 0.0]])
    index = match_to_blobs(points, blobs, gate_px=3.0)
    # Point 1 is nearer to blob 0 than point 0 is; point 4's blob is outside the gate.
    assert index.tolist() == [-1, 0, 1, -1, -1]


def test_tracker_state_and_errors():
    tracker = PinTracker(lk=LKParams(window_px=9), gate_fraction=0.3)
    assert "window_px=9" in repr(tracker) and "not started" in repr(tracker)
    with pytest.raises(PinsError, match="before start"):
        tracker.update(frame(331).image)
    tracker.start(frame(331).image)
    assert "331 pins, 0 lost" in repr(tracker)
    assert tracker.gate_px == pytest.approx(0.3 * tracker.spacing_px)
    with pytest.raises(PinsError, match="at least two"):
        PinTracker().start(frame(331).image, pins=np.array([[1.0, 2.0]]))
    with pytest.raises(ValueError, match="gate_fraction"):
        PinTracker(gate_fraction=0.7)
    with pytest.raises(ValueError, match="window_px"):
        LKParams(window_px=8)
