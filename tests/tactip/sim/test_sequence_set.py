"""A skin that creeps back over seconds and keeps a set (`tactip.sim.sequence.schedule`'s ``set_share``,
``set_s``): what each slide leaves, how it relaxes, and that a press on it does not drag it further."""

import math

import numpy as np
import pytest

from tactip.sim import Contact, Stroke, SyntheticTacTip
from tactip.sim import _slide
from tactip.sim.sequence import schedule

TIMING = dict(press_s=0.05, hold_s=0.05, slide_s=0.15, lift_s=0.05)


def test_a_slide_leaves_a_share_that_creeps_back_and_a_set_that_stays():
    strokes = [Stroke(2.0, 90.0, 6.0)]
    contacts, (event,) = schedule(strokes, frame_rate=100.0, rest_s=[0.1, 3.0], residual=0.1, creep_s=1.0,
                                  set_share=0.02, **TIMING)
    shear_y = np.array([c.shear_y_mm for c in contacts])
    after = np.arange(len(contacts)) - event.stop_frame + 1                 # frames since the lift's last
    kept = 6.0 * (0.1 * np.exp(-after / 100.0) + 0.02)
    np.testing.assert_allclose(shear_y[event.stop_frame:], kept[event.stop_frame:], rtol=1e-9)
    assert abs(contacts[-1].shear_x_mm) < 1e-12 and shear_y[-1] > 0.12     # 3 s on: the set and 5 % of the rest
    # the lift releases the drag down to both shares, and the skin keeps the slide's fall-off
    assert contacts[event.stop_frame - 1].slide_y_mm == pytest.approx(6.0 * (0.12 + 0.88 * 0.5 * (1 + math.cos(
        math.pi * 5 / 6))))
    assert {c.shear_decay_mm for c in contacts[event.stop_frame:]} == {2 * 6.0}


def test_a_set_relaxes_with_its_own_time_constant_and_off_by_default_renders_as_before():
    strokes = [Stroke(2.0, 0.0, 4.0), Stroke(3.0)]
    slow, _ = schedule(strokes, frame_rate=50.0, rest_s=0.5, residual=0.2, set_share=0.05, set_s=2.0, **TIMING)
    plain, _ = schedule(strokes, frame_rate=50.0, rest_s=0.5, residual=0.2, **TIMING)
    same, _ = schedule(strokes, frame_rate=50.0, rest_s=0.5, residual=0.2, set_share=0.0, set_s=2.0, **TIMING)
    assert same == plain
    extra = np.array([a.shear_x_mm - b.shear_x_mm for a, b in zip(slow, plain)])[-10:]
    np.testing.assert_allclose(extra[1:] / extra[:-1], math.exp(-1 / (2.0 * 50.0)), rtol=1e-9)
    for bad in (dict(set_share=0.8, residual=0.2), dict(set_share=-0.1), dict(set_share=0.1, set_s=0.0)):
        with pytest.raises(ValueError, match="set_"):
            schedule(strokes, frame_rate=50.0, rest_s=0.5, **TIMING, **{"residual": 0.0, **bad})


@pytest.mark.parametrize("preset", ["tactip-127", "radial-led-120"])
def test_a_press_on_the_shear_a_slide_left_spreads_the_pins_without_dragging_them(preset):
    sensor = SyntheticTacTip.from_preset(preset, seed=0)
    shear = Contact(shear_x_mm=0.6, shear_y_mm=0.3, shear_decay_mm=12.0)
    sheared, _ = sensor.pin_centres(shear)
    pressed, _ = sensor.pin_centres(Contact(3.0, shear_x_mm=0.6, shear_y_mm=0.3, shear_decay_mm=12.0))
    plain_rest, _ = sensor.pin_centres()
    plain, _ = sensor.pin_centres(Contact(3.0))
    moved = np.linalg.norm(plain - plain_rest, axis=1) > 0.5                   # the pins the press moves
    drag = np.median(pressed[moved] - sheared[moved], axis=0)                # from the sheared rest, px
    pitch_px = sensor.pin_spacing_mm / sensor.mm_per_px
    assert np.hypot(*drag) < 0.05 * pitch_px, drag
    # laid out with the plate (no fall-off of its own), the patch is dragged by what it had not taken at rest
    old, _ = sensor.pin_centres(Contact(3.0, shear_x_mm=0.6, shear_y_mm=0.3))
    assert np.hypot(*np.median(old[moved] - sheared[moved], axis=0)) > np.hypot(*drag)


def test_a_slide_on_a_shear_that_would_fold_the_skin_takes_what_fits():
    most = _slide.max_slide_mm(2.0, 20.0)
    sensor = SyntheticTacTip(pins=127)
    centres, _ = sensor.pin_centres(Contact(2.0, slide_x_mm=most - 0.5, shear_x_mm=3.0))
    assert np.isfinite(centres).all()
    assert np.hypot(*_slide._drag_mm(Contact(2.0, slide_x_mm=most - 0.5, shear_x_mm=3.0), 20.0)) <= most
    with pytest.raises(ValueError, match="folds"):
        sensor.pin_centres(Contact(2.0, slide_x_mm=most + 0.5))
