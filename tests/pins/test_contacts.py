"""pins.contacts and the contact pieces of pins.segment, against the synthetic TacTip's ground truth."""

import numpy as np
import pytest

from pins import ShapeError, contact_kinds, jitter_floor_px, segment_taps, tap_signal
from tactip.sim import SyntheticTacTip
from tactip.sim.sequence import Stroke
from tests.pins.conftest import slides_and_presses


@pytest.mark.parametrize("preset", ["radial-led-120", "tactip-331", "small-pad-100", "dark-331", "tactip-127"])
@pytest.mark.parametrize("seed", [0, 1])
def test_kinds_and_directions_match_the_rendered_strokes(preset, seed):
    _, run = slides_and_presses(preset, seed)
    kinds = contact_kinds(run.displacements_px(), [(e.start_frame, e.stop_frame) for e in run.events])
    assert [k.kind for k in kinds] == [e.kind for e in run.events]
    for kind, event in zip(kinds, run.events):
        if event.kind == "slide":
            error = (kind.direction_deg - event.direction_deg + 180.0) % 360.0 - 180.0
            assert abs(error) <= 3.0, (event, kind)
        else:
            assert np.isnan(kind.direction_deg)


def test_a_contact_that_hardly_moves_the_pins_is_a_press():
    drift = np.zeros((6, 50, 2))
    drift[..., 0] = 0.2  # every pin 0.2 px along x: a translation, but far below a drag
    (kind,) = contact_kinds(drift, [(0, 6)])
    assert kind.kind == "press" and kind.drag_ratio == pytest.approx(1.0)


def test_contact_kinds_checks_its_input():
    with pytest.raises(ShapeError):
        contact_kinds(np.zeros((5, 3)), [(0, 5)])
    with pytest.raises(ValueError, match="bounds"):
        contact_kinds(np.zeros((5, 3, 2)), [(2, 9)])
    with pytest.raises(ValueError, match="slide_ratio"):
        contact_kinds(np.zeros((5, 3, 2)), [], slide_ratio=0.0)
    assert contact_kinds(np.zeros((5, 3, 2)), []) == []


@pytest.mark.parametrize("sigma", [0.02, 0.1, 0.4])
@pytest.mark.parametrize("pins", [100, 331, 1000])
def test_jitter_floor_is_a_still_pads_tap_signal(sigma, pins):
    rng = np.random.default_rng(pins)
    still = rng.normal(0.0, sigma, (120, pins, 2))
    still[rng.uniform(size=still.shape[:2]) < 0.05] = np.nan  # a few pins lost now and then
    truth = np.median(tap_signal(still - still[0]))
    assert jitter_floor_px(still) == pytest.approx(truth, rel=0.1)


def test_jitter_floor_needs_no_quiet_frames():
    """A recording that is nearly all contact: the signal's low percentile is a contact's; the jitter's is not."""
    rng = np.random.default_rng(3)
    t = np.arange(400)
    envelope = np.where(t % 100 < 98, np.sin(np.pi * (t % 100) / 98) * 6.0, 0.0)  # 2 rest frames in 100
    pins = rng.normal(size=(300, 2))
    displacements = envelope[:, None, None] * pins[None] + rng.normal(0.0, 0.05, (400, 300, 2))
    quiet_truth = 2.15 * np.sqrt(2) * 0.05
    assert jitter_floor_px(displacements) == pytest.approx(quiet_truth, rel=0.15)
    assert np.percentile(tap_signal(displacements), 10) > 5 * quiet_truth


def test_jitter_floor_of_too_few_frames_is_infinite():
    assert jitter_floor_px(np.zeros((2, 5, 2))) == np.inf
    assert jitter_floor_px(np.zeros((9, 5, 2)), usable=np.arange(9) % 2 == 0) == np.inf


def test_one_quiet_frame_separates_two_contacts():
    signal = np.concatenate([[0, 0], np.full(10, 4.0), [0.1], np.full(10, 4.0), [0, 0]])
    assert segment_taps(signal, merge_gap_frames=0, pad_frames=0) == [(2, 12), (13, 23)]


def test_a_given_tap_signal_gives_the_same_kinds_and_is_checked():
    sensor = SyntheticTacTip.from_preset("tactip-127", seed=4)
    run = sensor.sequence([Stroke(3.0), Stroke(2.0, 120.0, 2.0 * sensor.pin_spacing_mm)], rest_s=0.1, frame_rate=20.0)
    displacements = run.displacements_px()
    bounds = [(e.start_frame, e.stop_frame) for e in run.events]
    given = contact_kinds(displacements, bounds, signal=tap_signal(displacements))
    computed = contact_kinds(displacements, bounds)
    assert [k.kind for k in given] == [k.kind for k in computed] == ["press", "slide"]
    np.testing.assert_array_equal([[k.direction_deg, k.drag_ratio, k.drag_px] for k in given],
                                  [[k.direction_deg, k.drag_ratio, k.drag_px] for k in computed])  # NaN == NaN here
    with pytest.raises(ShapeError, match="signal"):
        contact_kinds(displacements, bounds, signal=np.zeros(3))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_few_pins_misplaced_after_the_lift_do_not_turn_a_slide(seed):
    # After a slide's lift the tracker may put a few pins on their neighbours' tips for a frame or two (issue
    # 20's webcam-like slides: 31.9 px drags at a signal of 12 px, the slide's own 24.5): those frames are
    # not the contact; before, the slide took the direction of those few pins (303 deg for 135).
    sensor = SyntheticTacTip.from_preset("radial-led-120", seed=seed)
    run = sensor.sequence([Stroke(2.0, 135.0, 3 * sensor.pin_spacing_mm)], rest_s=0.05, press_s=0.05, slide_s=0.15,
                          lift_s=0.05, frame_rate=120.0, final_rest_s=0.1)
    displacements = run.displacements_px()
    event = run.events[0]
    rng = np.random.default_rng(seed)
    displacements += rng.normal(0.0, 0.3, displacements.shape)  # tracking noise, px
    after = event.stop_frame + 1
    seen = np.flatnonzero(np.isfinite(displacements[after, :, 0]))
    glitch = rng.choice(seen, 20, replace=False)  # a sixth of the pins: the tap signal half the slide's or less
    pitch_px = sensor.pin_spacing_mm / sensor.mm_per_px
    angle = np.radians(300.0)
    for far, pins in ((5.0, glitch[:10]), (1.3, glitch[10:])):  # pitches
        displacements[after:after + 2, pins] = far * pitch_px * np.array([np.cos(angle), np.sin(angle)])
    assert tap_signal(displacements)[after] < 0.5 * tap_signal(displacements)[event.start_frame:after].max()
    kind = contact_kinds(displacements, [(event.start_frame, after + 3)])[0]
    assert kind.kind == "slide" and abs((kind.direction_deg - 135.0 + 180.0) % 360.0 - 180.0) <= 5.0, kind
