"""The opt-in skin of slide sequences against ground truth: residual shear creeping back to rest after a
slide (``residual``, ``creep_s``, ``final_rest_s``) and a stiffer skin (``min_area``), issue 20.

Both are opt-in: without them a sequence's contacts, and so its renders, are those of before.
"""

import numpy as np
import pytest

from tactip.sim import Contact, Stroke, SyntheticTacTip
from tactip.sim import _slide
from tactip.sim.sequence import schedule

TIMING = dict(frame_rate=120.0, rest_s=3 / 120, press_s=0.2, hold_s=0.1, slide_s=0.4, lift_s=0.2)


def strokes(sensor, pitches=3.0, directions=(0.0, 135.0, 250.0)):
    return [Stroke(2.0, d, pitches * sensor.pin_spacing_mm) for d in directions]


def test_the_skin_options_are_opt_in_and_validated():
    sensor = SyntheticTacTip.from_preset("radial-led-120")
    plain, events = schedule(strokes(sensor), **TIMING)
    same, same_events = schedule(strokes(sensor), residual=0.0, **TIMING)
    assert same == plain and same_events == events
    assert all(c.shear_x_mm == c.shear_y_mm == c.slide_decay_mm == 0.0 for c in plain)
    for bad in (dict(residual=-0.1), dict(residual=1.0), dict(creep_s=0.0), dict(min_area=0.0), dict(min_area=1.0),
                dict(final_rest_s=-1.0)):
        with pytest.raises(ValueError, match=next(iter(bad))):
            schedule(strokes(sensor), **bad, **TIMING)
    with pytest.raises(ValueError, match="slide_decay_mm"):
        Contact(2.0, slide_decay_mm=-1.0)
    with pytest.raises(ValueError, match="shear_x_mm"):
        Contact(shear_x_mm=float("nan"))


def test_a_residual_shear_shifts_the_apex_by_all_of_it_and_far_skin_not_at_all():
    radius = 20.0
    x = np.array([0.0, 0.0, 15.0, -14.0])
    y = np.array([0.0, 0.0, 5.0, -6.0])
    qx, qy = _slide.slid_points(x, y, Contact(shear_x_mm=0.8, shear_y_mm=-0.3), radius)
    arc = np.hypot(0.8, -0.3)  # the shift lies along the pad surface: laterally R sin(arc / R)
    np.testing.assert_allclose([qx[0], qy[0]], np.array([0.8, -0.3]) * radius * np.sin(arc / radius) / arc, atol=1e-12)
    # beyond the fall-off (SLIDE_DECAY_MM of pad surface from the apex) nothing moves
    np.testing.assert_allclose([qx[2:], qy[2:]], [x[2:], y[2:]], atol=1e-12)


@pytest.mark.parametrize("name", ["radial-led-120", "tactip-331", "small-pad-100"])
def test_a_residual_shear_is_left_after_each_slide_and_creeps_back_to_rest(name):
    sensor = SyntheticTacTip.from_preset(name)
    plain, events = schedule(strokes(sensor), **TIMING)
    creep, creep_events = schedule(strokes(sensor), residual=0.15, creep_s=0.1, final_rest_s=0.6, **TIMING)
    # the same contacts, frame for frame (the last rest is longer), pressed in the same frames
    assert [(e.start_frame, e.stop_frame) for e in creep_events] == [(e.start_frame, e.stop_frame) for e in events]
    np.testing.assert_array_equal([c.indentation_mm for c in creep[:len(plain)]], [c.indentation_mm for c in plain])
    rest = sensor.rest_centres
    pitch_px = sensor.pin_spacing_mm / sensor.mm_per_px
    offsets = np.array([np.abs(sensor.pin_centres(c)[0] - rest).max() for c in creep])
    for event in creep_events:  # just after each lift, the skin is still shifted by a sizeable part of a pitch
        assert creep[event.stop_frame].indentation_mm == 0.0
        assert offsets[event.stop_frame] > 0.1 * pitch_px
    tail = offsets[creep_events[-1].stop_frame:]
    assert np.all(np.diff(tail) < 0)  # creeping back, never overshooting
    assert tail[-1] < 0.05  # back at rest within a twentieth of a px after 0.6 s
    # no jumps: a frame moves the pins no farther than the plain sequence's largest step (plus the creep's)
    steps = [np.abs(sensor.pin_centres(b)[0] - sensor.pin_centres(a)[0]).max() for a, b in zip(creep, creep[1:])]
    plain_steps = [np.abs(sensor.pin_centres(b)[0] - sensor.pin_centres(a)[0]).max() for a, b in zip(plain, plain[1:])]
    assert max(steps) < 1.2 * max(plain_steps)


def _min_jacobian(contact, radius=20.0):
    """Least area ratio of the slide map over a fine grid of the pad, in unrolled coordinates."""
    g = np.linspace(-19.0, 19.0, 241)
    x, y = np.meshgrid(g, g)
    inside = np.hypot(x, y) < 19.5

    def unrolled(px, py):
        r = np.hypot(px, py)
        scale = np.divide(radius * np.arcsin(np.clip(r / radius, 0, 1)), r, out=np.ones_like(r), where=r > 0)
        return px * scale, py * scale

    qx, qy = unrolled(*_slide.slid_points(x, y, contact, radius))
    px, py = unrolled(x, y)
    (ax, ay), (bx, by) = (np.gradient(qx, axis=1), np.gradient(qx, axis=0)), (np.gradient(qy, axis=1), np.gradient(qy, axis=0))
    (cx, cy), (ex, ey) = (np.gradient(px, axis=1), np.gradient(px, axis=0)), (np.gradient(py, axis=1), np.gradient(py, axis=0))
    return ((ax * by - ay * bx) / (cx * ey - cy * ex))[inside].min()


@pytest.mark.parametrize("min_area", [0.4, 0.6])
def test_a_stiffer_skin_is_squeezed_no_further_than_asked(min_area):
    sensor = SyntheticTacTip.from_preset("radial-led-120")
    run = strokes(sensor, pitches=1.5, directions=(30.0,))
    plain, _ = schedule(run, **TIMING)
    stiff, _ = schedule(run, min_area=min_area, **TIMING)
    peak = max(range(len(plain)), key=lambda k: np.hypot(plain[k].slide_x_mm, plain[k].slide_y_mm))
    assert _min_jacobian(plain[peak]) < min_area - 0.1  # the default model squeezes harder
    assert min(_min_jacobian(c) for c in stiff[peak - 8:peak + 1]) >= min_area - 0.03
