"""pins.track keeps identities through slides (issue 20, outcome 2): slides of 3 pitches at 120 frames/s
with 3-frame rests; no pin takes another pin's tip, and after the return every visible pin is within
1 px of its rest position. Ground truth from the synthetic TacTip."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from pins import DetectionParams, PinTracker, SensorDisc
from pins._identity import keep_own_tips
from tests.pins.conftest import preset_sensor


def _swaps(positions, truth, shown, spacing_px):
    """Pins placed nearer another drawn pin's true centre than their own, that centre at least half
    a rest spacing from their own (tips squeezed together by a slide merge: nothing tells them apart)."""
    placed = np.flatnonzero(np.isfinite(positions[:, 0]))
    nearest = np.flatnonzero(shown)[cKDTree(truth[shown]).query(positions[placed])[1]]
    other = nearest != placed
    gap = np.linalg.norm(truth[placed[other]] - truth[nearest[other]], axis=1)
    return placed[other][gap >= 0.5 * spacing_px]


def _track_slides(name, seed, **skin):
    """Two slides of 3 pitches (0 and 180 degrees) from the drawn pins' true rest centres: swapped
    pin-frames, and the last (rest) frame's positions and truth (``skin``: `SyntheticTacTip.sequence`'s
    opt-in residual shear and stiffer skin)."""
    s = preset_sensor(name, seed)
    s.reseed_noise(seed)
    run = s.slides([0.0, 180.0], distance_mm=3.0 * s.pin_spacing_mm, rest_s=3 / 120, frame_rate=120.0, **skin)
    frames = iter(run)
    rest = next(frames)
    drawn = np.flatnonzero(rest.visible | rest.partial)
    tracker = PinTracker(detection=DetectionParams(dark_pins=s.dark_pins), disc=SensorDisc(*s.disc))
    tracker.start(rest.image, pins=rest.centres[drawn])
    swapped, moved = 0, 0.0
    for f in frames:
        positions = tracker.update(f.image)
        truth = f.centres[drawn]
        swapped += _swaps(positions, truth, f.visible[drawn] | f.partial[drawn], tracker.spacing_px).size
        moved = max(moved, np.max(np.linalg.norm(truth - rest.centres[drawn], axis=1)[f.visible[drawn]]))
    assert moved > 2.5 * tracker.spacing_px  # the slides moved pins by about 3 pitches
    return swapped, positions, f.centres[drawn], f.visible[drawn]


@pytest.mark.parametrize("name", ["radial-led-120", "small-pad-100"])
def test_slides_keep_identities_and_every_pin_returns_to_rest(name):
    swapped = 0
    for seed in (0, 1):
        count, positions, rest, visible = _track_slides(name, seed)
        swapped += count
        # Back at rest (the last frame's truth is the rest) every visible pin is found, within 1 px of it.
        assert (np.linalg.norm(positions - rest, axis=1)[visible] <= 1.0).all()
    # Pin-frames on another pin's tip, seeds 0-1: 124 (radial-led-120) and 526 (small-pad-100) before
    # `pins._identity` and the trusted searches; 14 and 21 after; 2 and 16 with lost pins predicted from
    # their neighbours' motion since they were last seen (`pins._predict`).
    assert swapped <= 40


@pytest.mark.parametrize("name", ["radial-led-120", "small-pad-100", "tactip-331"])
def test_a_skin_creeping_back_to_rest_after_slides_leaves_every_pin_on_its_own_tip(name):
    # A real elastomer keeps part of a slide when the plate lifts and creeps back over tens of frames
    # (issue 20: 6-18 real pins > 10 px from rest after the last slide). Here 15 % of each slide is
    # left, creeping back with a 0.1 s time constant over a last rest of 0.4 s: the pad's "back at rest"
    # test (`pins._rest`) sees a moving pad for most of it.
    swapped, positions, truth, visible = _track_slides(name, 0, residual=0.15, creep_s=0.1, final_rest_s=0.4)
    # The last frame: the skin is back within a tenth of a px of rest; every visible pin is found within
    # 1 px of its true centre.
    assert (np.linalg.norm(positions - truth, axis=1)[visible] <= 1.0).all()


def test_on_a_realistic_skin_windows_follow_their_tips_where_the_skin_is_squeezed():
    # A skin that squeezes ahead of a slide to no less than half its area (``min_area=0.5``, as a 1-2 mm
    # elastomer would before it wrinkles) still brings tactip-331's tips within 0.6 spacings, touching. A
    # window whose steps there were a few tenths of a px had them zeroed as jitter and sat between its tip
    # and the neighbour's, falling behind by 6 px; it now carries its moving neighbours' step
    # (`Refiner.carried_velocity`). Pin-frames on another pin's tip, seeds 0/1/2: 46/64/76 before, 9/36/47
    # after (main b811570, renders with seams where tips overlap); without seams 35/34/28 with `MISSING_MARGIN`
    # 2, 10/32/19 with 4.
    swapped = sum(_track_slides("tactip-331", seed, min_area=0.5)[0] for seed in (0, 1, 2))
    assert swapped <= 75


def test_on_a_small_pad_a_found_pin_leaves_a_merged_blob_to_its_lost_owner():
    # small-pad-100 (tips 2 px apart on a 4 px spacing where a slide squeezes a realistic skin): a pin
    # searched for from its prediction settled on the blob of its own and a lost neighbour's tip, nearer
    # its own prediction than the neighbour's, and took it. With `MISSING_MARGIN` neither takes an
    # ambiguous blob. Pin-frames on another pin's tip, seeds 0/1/2/3: 6/6/11/10 before, 6/7/2/0 now.
    swapped = 0
    for seed in (0, 1, 2, 3):
        count, positions, rest, visible = _track_slides("small-pad-100", seed, min_area=0.5)
        swapped += count
        assert (np.linalg.norm(positions - rest, axis=1)[visible] <= 1.0).all()
    assert swapped <= 20


@pytest.mark.xfail(reason="issue 20's bar, not yet met: radial-led-120 seeds 0-3 still put 4/13/12/0 pin-frames "
                          "on other pins' tips (8/1/10/14 on renders with seams where tips overlap, main b811570): "
                          "where the skin ahead of a slide squeezes tips into one blob, a window lagging its tip "
                          "settles in the blob's middle, nearer the neighbour", strict=False)
def test_slides_swap_no_identity():
    assert all(_track_slides("radial-led-120", seed)[0] == 0 for seed in (2, 3))


def test_on_a_realistic_skin_radial_slides_leave_few_pins_on_other_tips():
    # radial-led-120 (small tips, 0.4 spacings across, several grey levels of LED reflections and glare),
    # two slides on a skin squeezed to half its area ahead of them. Pin-frames on another pin's tip, seeds
    # 0-5: 1/0/0/9/0/0 on renders with seams where tips overlap and `MISSING_MARGIN` 2 (main b811570);
    # 1/0/1/0/0/1 now, each a window 2 px off its tip between two tips 0.5 spacings apart.
    swapped = [_track_slides("radial-led-120", seed, min_area=0.5)[0] for seed in range(6)]
    assert sum(swapped) <= 4 and max(swapped) <= 1


def test_a_found_pin_keeps_only_a_tip_in_its_own_cell():
    # Pins 0-2 placed in a row 10 px apart, pin 3 expected at (30, 0) and missing.
    positions = np.array([[0.0, 0.0], [10.0, 0.0], [20.0, 0.0], [np.nan, np.nan]])
    expected = np.array([[0.0, 0.0], [10.0, 0.0], [20.0, 0.0], [30.0, 0.0]])
    # Pin 1 found at 11 px, expected at 9: its own cell; pin 2 found on pin 3's expected tip: not its own.
    positions[1], positions[2] = [11.0, 0.0], [29.0, 0.0]
    near = np.array([[j for j in range(4) if j != i] for i in range(4)])  # every other pin
    keep_own_tips(positions, np.array([1, 2]), np.array([[9.0, 0.0], [21.0, 0.0]]), expected, near)
    assert np.allclose(positions[1], [11.0, 0.0]) and np.isnan(positions[2]).all()
    # Two found pins on one tip: the one expected nearer to it (pin 1, 3 px against 5) keeps it.
    positions = np.array([[5.0, 0.0], [5.0, 0.0]])
    keep_own_tips(positions, np.array([0, 1]), np.array([[0.0, 0.0], [8.0, 0.0]]), np.full((2, 2), np.nan),
                  np.array([[1], [0]]))
    assert np.isnan(positions[0]).all() and np.allclose(positions[1], [5.0, 0.0])
    # Nothing found: nothing changes.
    before = positions.copy()
    keep_own_tips(positions, np.array([], dtype=int), np.empty((0, 2)), np.full((2, 2), np.nan), np.array([[1], [0]]))
    assert np.array_equal(positions, before, equal_nan=True)


def test_a_found_pin_near_a_missing_pins_prediction_keeps_the_tip_only_when_clearly_its_own():
    # Two tips squeezed into one blob ahead of a slide: pin 1 is found on the blob 4 px from where it
    # was expected, pin 2 is missing and predicted 5 px from it (a prediction is up to a spacing off
    # there). Nearest-wins would give pin 1 the blob; it is not `MISSING_MARGIN` (4) times as near, so neither takes it.
    expected = np.array([[0.0, 0.0], [11.0, 0.0], [20.0, 0.0]])
    near = np.array([[1, 2], [0, 2], [1, 0]])
    positions = np.array([[0.0, 0.0], [15.0, 0.0], [np.nan, np.nan]])
    keep_own_tips(positions, np.array([1]), np.array([[11.0, 0.0]]), expected, near)
    assert np.isnan(positions[1]).all()
    # Twice as near its own start (3 px against 6): still the merged blob's ambiguity on a render without
    # seams (the margin of 2 kept it); four times as near (1.5 px against 6.5): its tip.
    positions = np.array([[0.0, 0.0], [14.0, 0.0], [np.nan, np.nan]])
    keep_own_tips(positions, np.array([1]), np.array([[11.0, 0.0]]), expected, near)
    assert np.isnan(positions[1]).all()
    positions = np.array([[0.0, 0.0], [13.5, 0.0], [np.nan, np.nan]])
    keep_own_tips(positions, np.array([1]), np.array([[12.0, 0.0]]), expected, near)
    assert np.allclose(positions[1], [13.5, 0.0])
    # A placed pin's place is measured, not predicted: nearest wins (4 px against 5).
    positions = np.array([[0.0, 0.0], [15.0, 0.0], [20.0, 0.0]])
    keep_own_tips(positions, np.array([1]), np.array([[11.0, 0.0]]), expected, near)
    assert np.allclose(positions[1], [15.0, 0.0])
