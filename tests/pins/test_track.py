"""pins.track and its helper pins._refine: LK tracking and windowed refinement against ground truth,
lost-pin flags, recovery without identity swaps."""

import functools

import cv2
import numpy as np
import pytest
from scipy.spatial import cKDTree

from pins import (DetectionParams, LKParams, PinsError, PinTracker, ShapeError, detect_pins, find_sensor_disc,
                  match_to_blobs, track_pins)
from pins._refine import Refiner
from tactip.sim import Contact
from tests.pins.conftest import TAP, frame, preset_sensor, sensor, tracker_on_rest


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
    # Every windowed centroid was plausible: the tap needed no blob detection.
    assert tracker.detection_frames == 0


def test_start_settles_given_pins_on_their_tips():
    f = frame(331)
    given = f.centres + [0.2, -0.15]
    given[0] += 3.0  # beyond the plausibility bound: kept as given
    tracker = PinTracker()
    rest = tracker.start(f.image, pins=given)
    # Rest positions by the same estimator as later frames: displacements carry none of its bias.
    assert np.abs(rest[1:] - f.centres[1:]).max() < 0.1
    assert np.array_equal(rest[0], given[0]) and np.array_equal(tracker.rest_positions, rest)
    assert np.array_equal(PinTracker(refine=False).start(f.image, pins=given), given)


def test_dark_markers_are_tracked_through_a_tap():
    s = sensor(331, dark_pins=True)
    frames = [s.render()] + list(s.tap(TAP, frame_rate=20.0))
    tracker = PinTracker(detection=DetectionParams(dark_pins=True))
    identity = _identity(tracker.start(frames[0].image), frames[0].centres)
    errors = np.concatenate([tracker.update(f.image) - f.centres[identity] for f in frames[1:]])
    assert np.sqrt(np.mean(np.sum(errors**2, axis=1))) <= 0.15
    assert tracker.detection_frames == 0


def _refiner(pins):
    """A Refiner on the whole rest frame (crop origin 0), as `PinTracker.start` builds it, and the rest frame."""
    rest = frame(pins)
    spacing = float(np.median(cKDTree(rest.centres).query(rest.centres, k=2)[0][:, 1]))
    refiner = Refiner(rest.image, rest.centres, np.zeros(2), spacing_px=spacing, gate_px=0.4 * spacing, neighbours=6,
                      detection=DetectionParams(), disc=find_sensor_disc(rest.image))
    return refiner, rest


@pytest.mark.parametrize("pins", [331, 532])
@pytest.mark.parametrize("depth_mm", [0.0, 5.0])
def test_windowed_centroids_meet_the_bar_without_detection(pins, depth_mm, rng):
    refiner, rest = _refiner(pins)
    f = sensor(pins).render(Contact(indentation_mm=depth_mm, gap_width_mm=2.0))
    assert f.visible.all()
    # LK-like estimates; under 5 mm contact neighbouring tips come within 2 px of each other.
    guess = f.centres + rng.normal(0.0, 0.1, f.centres.shape)
    positions, detected = refiner(f.image, f.image, guess, rest.centres)
    assert not detected
    error = np.linalg.norm(positions - f.centres, axis=1)
    assert np.sqrt(np.mean(error**2)) <= 0.05 and error.max() <= 0.2


@pytest.mark.parametrize("half_px", [9, 15])
def test_windows_in_blocks_of_rows_measure_each_tip_as_it_alone(half_px, rng):
    # Hundreds of windows go through the moment product in blocks of rows (one BLAS thread);
    # each window's measures must not depend on the block it fell in, nor on its neighbours.
    from pins._refine import WindowCentroids

    rest = frame(331)
    windows = WindowCentroids(half_px)
    points = np.concatenate([rest.centres, rest.centres[:200] + rng.uniform(-3.0, 3.0, (200, 2))])
    radius = rng.uniform(2.0, half_px + 1.0, len(points))
    assert len(points) > 2 * windows._moment_rows
    centres, measures = windows.measure(rest.image, points, radius)
    alone = [windows.measure(rest.image, points[k:k + 1], radius[k:k + 1]) for k in range(len(points))]
    # Mass and first moments are sums of integers below 2^24: exact in float32 whatever the order.
    np.testing.assert_array_equal(centres, np.concatenate([c for c, _ in alone]))
    np.testing.assert_allclose(measures, np.concatenate([m for _, m in alone], axis=1), rtol=1e-6)
    assert np.isfinite(centres).all() and (measures[1] > 0).all()
    # The four arrays of __call__ are the same measures.
    for got, want in zip(windows(rest.image, points, radius), (centres, *measures)):
        np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("pins", [331, 532])
def test_a_pin_slipped_towards_its_neighbour_is_recovered_on_its_own_tip(pins):
    refiner, rest = _refiner(pins)
    f = sensor(pins).render(Contact(indentation_mm=3.0, gap_width_mm=2.0))
    guess = f.centres.copy()
    i = int(np.argmin(np.linalg.norm(guess - [320, 240], axis=1)))
    j = cKDTree(guess).query(guess[i], k=2)[1][1]
    guess[i] = 0.5 * (guess[i] + guess[j])
    positions, detected = refiner(f.image, f.image, guess, rest.centres)
    # Its window holds halves of two tips: implausible, so the pin is searched for in a window
    # around its prediction (its neighbours' displacement) and found on its own tip, without blob
    # detection; the neighbour keeps its own.
    assert not detected
    assert np.abs(positions - f.centres).max() < 0.15


def test_a_vanished_pin_that_lk_still_follows_is_lost():
    refiner, rest = _refiner(331)
    hidden = np.zeros(331, dtype=bool)
    hidden[np.random.default_rng(3).choice(331, 17, replace=False)] = True
    f = sensor(331).render(Contact(indentation_mm=3.0, gap_width_mm=2.0), hidden=hidden)
    positions, detected = refiner(f.image, f.image, f.centres, rest.centres)
    # No contrast in their windows and no blob there: NaN, never the window's noise.
    assert detected and np.isnan(positions[hidden]).all()
    assert np.abs(positions[~hidden] - f.centres[~hidden]).max() < 0.15


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


# Tracking on the phenomenon presets (tactip.sim.synthetic.PRESETS): one 5 mm tap over a 2 mm gap,
# started from the drawn pins' true rest centres (detection has its own tests).
TRACKING_PRESETS = ["tactip-331", "dark-331", "rim-ring-331", "brown-127", "radial-120", "small-pad-100", "dense-1000"]


@functools.lru_cache(maxsize=None)
def _preset_tap(name):
    s = preset_sensor(name)
    return s, [s.render()] + list(s.tap(TAP))


def _preset_tracker(name):
    s, frames = _preset_tap(name)
    rest = frames[0]
    tracker, drawn = tracker_on_rest(s, rest)
    return tracker, drawn, frames


@pytest.mark.parametrize("name", TRACKING_PRESETS)
def test_tracking_a_tap_on_every_preset_meets_the_bars(name):
    tracker, identity, frames = _preset_tracker(name)
    errors, swaps, lost_visible = [], 0, []
    for f in frames[1:]:
        positions = tracker.update(f.image)
        found = np.isfinite(positions[:, 0])
        visible = f.visible[identity]
        errors.append(positions[found & visible] - f.centres[identity][found & visible])
        # Identity: each found pin is nearest to its own true pin among all drawn ones.
        drawn = np.flatnonzero(f.visible | f.partial)
        swaps += int(np.count_nonzero(drawn[cKDTree(f.centres[drawn]).query(positions[found])[1]] != identity[found]))
        lost_visible.append(np.count_nonzero(tracker.lost & visible) / visible.sum())
    errors = np.concatenate(errors)
    assert np.sqrt(np.mean(np.sum(errors**2, axis=1))) <= 0.1
    assert swaps == 0
    assert np.median(lost_visible) <= 0.05
    # After the tap the pins are back at rest (the last frames are off contact).
    back = np.linalg.norm(positions - tracker.rest_positions, axis=1)
    assert np.nanmedian(back) <= 0.3
    assert tracker.detection_frames <= -(-(len(frames) - 1) // tracker.detect_every)


@pytest.mark.parametrize("blank", ["black", "grey"])
def test_a_blank_frame_is_marked_and_the_pins_recovered_after(blank):
    frames = _tap_frames(331)
    tracker = PinTracker()
    identity = _identity(tracker.start(frames[0].image), frames[0].centres)
    for k, f in enumerate(frames[1:], start=1):
        image = f.image
        if k == 5:
            image = np.zeros_like(image) if blank == "black" else np.random.default_rng(1).normal(
                120, 4, image.shape).clip(0, 255).astype(np.uint8)
        positions = tracker.update(image)
        if k == 5:
            # Marked blank: nothing trackable, every pin NaN and lost, none retired for it.
            assert tracker.blank and np.isnan(positions).all() and tracker.lost.all()
            assert not tracker.retired.any()
        else:
            # The next good frame recovers every pin (LK from the last good frame, then refinement).
            assert not tracker.blank and not tracker.lost.any()
            assert np.abs(positions - f.centres[identity]).max() < 0.3
    assert tracker.blank_frames == 1


def test_a_blank_rest_frame_is_refused():
    f = frame(331)
    with pytest.raises(PinsError, match="blank"):
        PinTracker(disc=find_sensor_disc(f.image)).start(np.zeros_like(f.image), pins=f.centres)


def test_rim_pins_leaving_view_are_retired_and_come_back_with_their_identity():
    s = sensor(331)
    rest = s.render()
    radius = np.linalg.norm(rest.centres - np.asarray(s.disc[:2]), axis=1)
    rim = radius > 0.85 * radius.max()
    tracker = PinTracker(retire_after=3, check_every=4, detect_every=1000)
    identity = _identity(tracker.start(rest.image), rest.centres)
    gone = rim[identity]
    contact = Contact(indentation_mm=2.0, gap_width_mm=2.0)
    for k in range(1, 26):
        f = s.render(contact, hidden=rim if 2 <= k < 14 else None)
        positions = tracker.update(f.image)
        if 2 <= k < 14:
            assert tracker.lost[gone].all() and np.isnan(positions[gone]).all()
            assert not tracker.lost[~gone].any()
            # Lost for more than retire_after frames: retired (searched for only every check_every frames).
            assert tracker.retired[gone].all() == (k - 1 > 3) and not tracker.retired[~gone].any()
        if k >= 14 + 4:
            # Back within check_every frames by windowed search, each on its own tip.
            assert not tracker.lost.any() and not tracker.retired.any()
            assert np.abs(positions - f.centres[identity]).max() < 0.3
    # One blob detection at most (when the pins were first lost: at most one frame in detect_every).
    assert tracker.detection_frames <= 1


def test_blob_detection_runs_at_most_once_in_detect_every_frames():
    s = sensor(331)
    rng = np.random.default_rng(5)
    tracker = PinTracker(detect_every=4, retire_after=1000)
    tracker.start(s.render().image)
    for k in range(1, 21):
        # A different set of pins hidden in every frame: some pin is always missing.
        hidden = np.zeros(s.n_pins, dtype=bool)
        hidden[rng.choice(s.n_pins, 10, replace=False)] = True
        before = tracker.detection_frames
        tracker.update(s.render(hidden=hidden).image)
        if tracker.detection_frames > before:
            assert k == 1 or k - last >= 4
            last = k
    assert tracker.detection_frames == 5


def test_blob_detection_looks_only_around_the_missing_pins_that_are_not_retired(monkeypatch):
    # Retired pins (a rim sector out of view) are searched for in turns; detection, when another
    # pin goes missing, covers the part of the disc around that pin only, not the retired ones too.
    import pins._recover as recover_module

    s = sensor(331)
    rest = s.render()
    offset = rest.centres - np.asarray(s.disc[:2])
    radius = np.hypot(*offset.T)
    sector = (radius > 0.8 * radius.max()) & (offset[:, 0] < -0.5 * radius.max())
    inner = np.flatnonzero((radius < 0.3 * radius.max()) & (offset[:, 0] > 0))[:1]
    tracker = PinTracker(retire_after=2, check_every=1000, detect_every=1)
    identity = _identity(tracker.start(rest.image), rest.centres)
    to_truth = np.argsort(identity)  # tracked index of each true pin
    sizes = []
    real_detect = recover_module._detect
    monkeypatch.setattr(recover_module, "_detect", lambda grey, *a, **k: sizes.append(grey.size) or real_detect(grey, *a, **k))
    for _ in range(4):  # the sector's pins lost for longer than retire_after: retired
        tracker.update(s.render(hidden=sector).image)
    assert tracker.retired[to_truth[sector]].all()
    sizes.clear()
    hidden = sector.copy()
    hidden[inner] = True
    tracker.update(s.render(hidden=hidden).image)
    assert tracker.lost[to_truth[inner]].all() and not tracker.retired[to_truth[inner]].any()
    disc_area = np.pi * s.disc[2] ** 2
    assert len(sizes) == 1 and sizes[0] < 0.25 * disc_area  # around the inner pin alone


@pytest.mark.parametrize("name", ["small-pad-100", "dark-331", "white-dark-331", "tactip-331"])
def test_a_tracker_made_without_parameters_finds_its_pins_and_polarity_in_the_rest_frame(name):
    """``PinTracker().start(rest)``: the pins, polarity and disc come from the rest frame as replay finds
    them (the default detection alone found 3 of small-pad-100's pins and no disc on dark-331 or
    white-dark-331), and the tap is tracked on them."""
    s, frames = _preset_tap(name)
    tracker = PinTracker()
    start = tracker.start(frames[0].image)
    truth = frames[0].centres[frames[0].visible]
    distance, identity = cKDTree(truth).query(start)
    assert len(start) == len(truth) and distance.max() < 0.5 and len(set(identity)) == len(truth)
    assert tracker.detection.dark_pins == s.dark_pins
    for f in frames[1:]:
        positions = tracker.update(f.image)
        found = np.isfinite(positions[:, 0]) & f.visible[frames[0].visible][identity]
        assert np.count_nonzero(found) >= 0.95 * np.count_nonzero(f.visible)
        assert np.abs(positions[found] - f.centres[frames[0].visible][identity][found]).max() < 1.0
