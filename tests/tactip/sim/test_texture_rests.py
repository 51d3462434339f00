"""Uneven rests between contacts and slides over a textured plate (issue 20's user: slides over textures,
the pad back at rest for 1-3 frames or for up to a second between them)."""

import numpy as np
import pytest

from tactip.sim import SyntheticTacTip
from tactip.sim.contact import Contact
from tactip.sim.sequence import Stroke, schedule


def test_uneven_rests_put_each_contact_where_its_rests_say():
    strokes = [Stroke(2.0, 0.0, 3.0), Stroke(2.5), Stroke(2.0, 90.0, 3.0)]
    rests_s = [0.1, 1 / 120, 0.75, 0.5]
    contacts, events = schedule(strokes, frame_rate=120.0, rest_s=rests_s, press_s=0.05, hold_s=0.05, slide_s=0.15,
                                lift_s=0.05)
    touching = np.array([c.indentation_mm > 0 for c in contacts])
    assert [e.start_frame for e in events] == [12, events[0].stop_frame + 1, events[1].stop_frame + 90]
    assert len(contacts) - events[-1].stop_frame == 60
    for before, event in zip([0] + [e.stop_frame for e in events], events):
        assert not touching[before:event.start_frame].any() and touching[event.start_frame:event.stop_frame].all()
    assert [e.kind for e in events] == ["slide", "press", "slide"]


def test_uneven_rests_equal_the_even_schedule_when_all_alike():
    strokes = [Stroke(2.0, 45.0, 3.0), Stroke(2.0)]
    timing = dict(frame_rate=120.0, press_s=0.05, hold_s=0.05, slide_s=0.15, lift_s=0.05)
    even = schedule(strokes, rest_s=0.05, final_rest_s=0.3, **timing)
    listed = schedule(strokes, rest_s=[0.05, 0.05, 0.3], **timing)
    assert even == listed


@pytest.mark.parametrize("rests_s", [[0.1, 0.1], [0.1, 0.1, 0.1, 0.1]])
def test_a_list_of_rests_must_fit_the_strokes(rests_s):
    with pytest.raises(ValueError, match="rest_s"):
        schedule([Stroke(2.0), Stroke(2.0)], frame_rate=120.0, rest_s=rests_s, press_s=0.05, hold_s=0.05,
                 slide_s=0.1, lift_s=0.05)


def test_a_textured_plate_moves_the_patch_pins_back_and_forth_along_the_slide():
    sensor = SyntheticTacTip.from_preset("radial-led-120", seed=3)
    texture_mm = 0.12
    smooth, textured = [], []
    for slide in np.linspace(0.5, 9.0, 18):
        smooth.append(sensor.pin_centres(Contact(2.0, slide_x_mm=slide))[0])
        textured.append(sensor.pin_centres(Contact(2.0, slide_x_mm=slide, texture_mm=texture_mm))[0])
    wobble = np.array(textured) - np.array(smooth)  # (frames, pins, 2) px
    assert np.abs(wobble[..., 1]).max() < 0.15 * np.abs(wobble[..., 0]).max()  # along the slide (x), but the dome
    bound_px = texture_mm / (sensor.mm_per_px * 0.9)  # the apex scale; the dome is seen smaller off it
    assert np.abs(wobble).max() <= bound_px
    moving = np.abs(wobble[..., 0]).max(axis=0) > 0.5 * bound_px  # the contact patch's pins
    assert moving.sum() >= 5
    assert (wobble[:, moving, 0].max(axis=0) > 0).all() and (wobble[:, moving, 0].min(axis=0) < 0).all()  # both ways
    assert np.ptp(wobble[5, moving, 0]) > 0.3 * bound_px  # neighbours differ: not one rigid shift


def test_texture_needs_a_slide_under_contact_and_a_plausible_size():
    sensor = SyntheticTacTip.from_preset("radial-led-120", seed=3)
    rest = sensor.pin_centres()[0]
    assert np.array_equal(sensor.pin_centres(Contact(0.0, slide_x_mm=3.0, texture_mm=0.1))[0], rest)
    press = sensor.pin_centres(Contact(2.0))[0]
    assert np.array_equal(sensor.pin_centres(Contact(2.0, texture_mm=0.1))[0], press)
    with pytest.raises(ValueError, match="texture_mm"):
        Contact(2.0, slide_x_mm=1.0, texture_mm=0.5)
    with pytest.raises(ValueError, match="texture_period_mm"):
        Contact(2.0, texture_period_mm=0.0)


def test_a_textured_stroke_renders_its_slide_frames_textured_only():
    contacts, events = schedule([Stroke(2.0, 30.0, 3.0, texture_mm=0.1), Stroke(2.5, texture_mm=0.1)],
                                frame_rate=120.0, rest_s=0.05, press_s=0.05, hold_s=0.05, slide_s=0.1, lift_s=0.05)
    slide, press = events
    assert all(c.texture_mm == 0.1 for c in contacts[slide.start_frame:slide.stop_frame])
    assert all(c.texture_mm == 0.0 for c in contacts[press.start_frame:press.stop_frame])
    assert all(c.texture_mm == 0.0 for c in contacts[:slide.start_frame])
