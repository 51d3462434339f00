"""pins.contact_kinds told by the field's shape (given the rest positions) and pins.segment.neighbour_median,
against the synthetic TacTip's ground truth (issue 20, outcome 3)."""

import numpy as np
import pytest

from pins import ShapeError, contact_kinds, neighbour_median, tap_signal
from tactip.sim import SyntheticTacTip
from tactip.sim.sequence import Stroke
from tests.pins.conftest import slides_and_presses


def _angle_error(a, b):
    return abs((a - b + 180.0) % 360.0 - 180.0)


# A skin that creeps back (residual 0.2, 0.1 s) shows what the last slide left in the patch a press puts down
# 1-3 frames after its lift: the press's pins share the slide's direction (drag ratio 0.7-0.9), and without
# the field's shape the press read as a slide.
@pytest.mark.parametrize("preset", ["radial-led-120", "tactip-127", "tactip-331", "white-dark-331", "small-pad-100",
                                    "dense-1000"])
@pytest.mark.parametrize("seed", [0, 1])
def test_a_press_right_after_a_slide_on_a_creeping_skin_is_a_press(preset, seed):
    sensor = SyntheticTacTip.from_preset(preset, seed=seed)
    rng = np.random.default_rng(seed)
    pitch = sensor.pin_spacing_mm
    strokes = []
    for angle in rng.uniform(0, 360, 3):
        strokes += [Stroke(2.0, float(angle), float(rng.uniform(2.0, 3.0)) * pitch),
                    Stroke(float(rng.uniform(2.0, 3.0)))]
    rests = [0.05, *(int(rng.integers(1, 4)) / 120 for _ in strokes[1:]), 0.1]
    run = sensor.sequence(strokes, rest_s=rests, press_s=0.05, hold_s=0.05, slide_s=0.15, lift_s=0.05,
                          frame_rate=120.0, residual=0.2, creep_s=0.1)
    displacements, (rest, _) = run.displacements_px(), sensor.pin_centres()
    bounds = [(e.start_frame, e.stop_frame) for e in run.events]
    kinds = contact_kinds(displacements, bounds, rest_positions=rest)
    assert [k.kind for k in kinds] == [e.kind for e in run.events], kinds
    for kind, event in zip(kinds, run.events):
        if event.kind == "slide":
            assert _angle_error(kind.direction_deg, event.direction_deg) <= 3.0, (event, kind)


# The field's shape keeps every kind the drag alone got right: slides of half a pitch to 3 pitches and
# presses at 20 frames/s (as tests/pins/test_contacts.py), and a rigid translation (no spread: a slide).
@pytest.mark.parametrize("preset", ["radial-led-120", "tactip-331", "small-pad-100", "dark-331", "tactip-127"])
@pytest.mark.parametrize("seed", [0, 1])
def test_the_field_shape_keeps_slides_and_presses_the_drag_tells(preset, seed):
    sensor, run = slides_and_presses(preset, seed)
    displacements, (rest, _) = run.displacements_px(), sensor.pin_centres()
    bounds = [(e.start_frame, e.stop_frame) for e in run.events]
    assert ([k.kind for k in contact_kinds(displacements, bounds, rest_positions=rest)]
            == [k.kind for k in contact_kinds(displacements, bounds)] == [e.kind for e in run.events])
    grid = np.stack(np.meshgrid(np.arange(-3, 4), np.arange(-3, 4)), -1).reshape(-1, 2) * 10.0
    shift = np.zeros((5, len(grid), 2))
    shift[..., 0] = np.linspace(0, 6, 5)[:, None]                              # every pin 6 px along x
    (kind,) = contact_kinds(shift, [(0, 5)], rest_positions=grid)
    assert kind.kind == "slide" and kind.direction_deg == pytest.approx(0.0)


def test_contact_kinds_checks_the_rest_positions():
    with pytest.raises(ShapeError, match="rest_positions"):
        contact_kinds(np.zeros((5, 3, 2)), [(0, 5)], rest_positions=np.zeros((4, 2)))
    with pytest.raises(ValueError, match="shift_over_spread"):
        contact_kinds(np.zeros((5, 3, 2)), [(0, 5)], rest_positions=np.zeros((3, 2)), shift_over_spread=0.0)


def test_neighbour_median_outvotes_a_pin_alone_and_keeps_a_patch_moving_together():
    sensor = SyntheticTacTip.from_preset("tactip-331", seed=0)
    rest, _ = sensor.pin_centres()
    run = sensor.sequence([Stroke(3.0), Stroke(2.0, 60.0, 2.0 * sensor.pin_spacing_mm)], rest_s=0.1, frame_rate=20.0)
    truth = run.displacements_px()
    rng = np.random.default_rng(0)
    noisy = truth.copy()
    lonely = rng.choice(len(rest), 50, replace=False)                          # 15 % of the pins, 3 px off
    angle = rng.uniform(0, 2 * np.pi, 50)
    noisy[:, lonely] += 3.0 * np.c_[np.cos(angle), np.sin(angle)]
    noisy[:, rng.choice(len(rest), 60, replace=False)] = np.nan                # and a fifth lost
    smoothed = neighbour_median(noisy, rest, chunk_frames=7)
    magnitude = np.hypot(*np.moveaxis(smoothed - truth, -1, 0))
    at_rest = [k for k, c in enumerate(run.contacts) if c.indentation_mm == 0.0]
    # at rest the pins alone are outvoted: the tap signal (90th percentile) falls from their 3 px to near 0
    assert tap_signal(noisy)[at_rest].min() > 2.5 and tap_signal(smoothed)[at_rest].max() < 0.2
    # in contact the neighbourhood's median follows the field within a fraction of its size
    moving = np.hypot(*np.moveaxis(truth, -1, 0))
    contact = [e.start_frame + (e.stop_frame - e.start_frame) // 2 for e in run.events]
    for k in contact:
        big = moving[k] > 0.5 * np.nanpercentile(moving[k], 90)
        assert np.nanmedian(magnitude[k][big]) < 0.25 * np.nanmedian(moving[k][big])
    assert np.isfinite(smoothed[:, :, 0]).all()                                # every pin has seen neighbours
    with pytest.raises(ShapeError):
        neighbour_median(np.zeros((3, 4, 2)), np.zeros((5, 2)))
    with pytest.raises(ValueError, match="neighbours"):
        neighbour_median(np.zeros((3, 4, 2)), np.zeros((4, 2)), neighbours=-1)
