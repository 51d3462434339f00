"""Slides (`tactip.sim._slide`) and contact sequences (`tactip.sim.sequence`) against ground truth.

Slides drag the skin several pitches sideways under a sticking plate; the map from rest to slid pins
must stay one-to-one, and a sequence's events must be exactly the frames in contact.
"""

import numpy as np
import pytest
from scipy.spatial import Delaunay

from tactip.sim import PRESETS, Contact, Stroke, SyntheticTacTip
from tactip.sim import _slide

DEPTHS_MM = (1.0, 3.0, 5.0)
DIRECTIONS_DEG = (0.0, 60.0, 135.0, 250.0)


def slide(depth_mm, distance_mm, direction_deg):
    angle = np.radians(direction_deg)
    return Contact(depth_mm, slide_x_mm=distance_mm * np.cos(angle), slide_y_mm=distance_mm * np.sin(angle))


def unrolled(x, y, radius_mm):
    """Lateral positions (mm) to unrolled pad coordinates (arc length along the azimuth), mm."""
    r = np.hypot(x, y)
    arc = radius_mm * np.arcsin(np.clip(r / radius_mm, 0, 1))
    scale = np.divide(arc, r, out=np.ones_like(r), where=r > 0)
    return np.column_stack([x * scale, y * scale])


def test_slides_are_validated_and_default_to_none():
    with pytest.raises(ValueError, match="slide_x_mm"):
        Contact(2.0, slide_x_mm=float("nan"))
    with pytest.raises(ValueError, match="slide_y_mm"):
        Contact(2.0, slide_y_mm=float("inf"))
    assert Contact().slide_x_mm == Contact().slide_y_mm == 0.0
    with pytest.raises(ValueError, match="indentation_mm"):
        Stroke(0.0)
    with pytest.raises(ValueError, match="distance_mm"):
        Stroke(2.0, 0.0, -1.0)


@pytest.mark.parametrize("seed", range(3))
def test_no_contact_no_slide(seed):
    sensor = SyntheticTacTip.from_preset("radial-led-120", seed=seed)
    for depth in (0.0, -1.0):
        centres, _ = sensor.pin_centres(Contact(depth, slide_x_mm=5.0, slide_y_mm=-3.0))
        np.testing.assert_array_equal(centres, sensor.rest_centres)


@pytest.mark.parametrize("name", ["radial-led-120", "tactip-331", "small-pad-100", "dense-1000"])
def test_the_contact_patch_moves_by_the_whole_slide_and_far_skin_stays(name):
    sensor = SyntheticTacTip.from_preset(name)
    radius = sensor.pad_diameter_mm / 2
    rest = unrolled(sensor._base_x, sensor._base_y, radius)
    arc = np.hypot(*rest.T)
    for depth in DEPTHS_MM:
        for direction in DIRECTIONS_DEG:
            distance = min(3 * sensor.pin_spacing_mm, _slide.max_slide_mm(depth, radius))
            contact = slide(depth, distance, direction)
            moved = unrolled(*_slide.slid_points(sensor._base_x, sensor._base_y, contact, radius), radius) - rest
            expected = distance * np.array([np.cos(np.radians(direction)), np.sin(np.radians(direction))])
            patch = arc <= np.sqrt(radius * depth)
            far = arc >= np.sqrt(radius * depth) + max(_slide.SLIDE_DECAY_MM, 2 * distance)
            assert patch.sum() >= 1
            np.testing.assert_allclose(moved[patch], np.broadcast_to(expected, moved[patch].shape), atol=1e-9)
            assert np.abs(moved[far]).max(initial=0.0) < 1e-9
            # the shift falls monotonically from the patch outward, never beyond the slide
            share = moved @ expected / distance ** 2
            order = np.argsort(arc)
            assert np.all(np.diff(share[order]) <= 1e-9) and share.max() <= 1 + 1e-9


@pytest.mark.parametrize("name", list(PRESETS))
def test_slides_of_up_to_three_pitches_never_fold_the_pin_field(name):
    """Every non-degenerate Delaunay triangle of the rest pins keeps its orientation: no pin crosses another."""
    sensor = SyntheticTacTip.from_preset(name)
    triangles = Delaunay(sensor.rest_centres).simplices

    def area(c):
        a, b, d = c[triangles[:, 0]], c[triangles[:, 1]], c[triangles[:, 2]]
        return (b - a)[:, 0] * (d - a)[:, 1] - (b - a)[:, 1] * (d - a)[:, 0]

    rest = area(sensor.rest_centres)
    triangles = triangles[np.abs(rest) > 0.3 * np.median(np.abs(rest))]  # hull slivers are not a lattice cell
    rest = area(sensor.rest_centres)
    for depth in DEPTHS_MM:
        for direction in DIRECTIONS_DEG:
            for pitches in (1.0, 3.0):
                distance = min(pitches * sensor.pin_spacing_mm, _slide.max_slide_mm(depth, sensor.pad_diameter_mm / 2))
                centres, visible = sensor.pin_centres(slide(depth, distance, direction))
                assert np.all(np.sign(area(centres)) == np.sign(rest)), (depth, direction, pitches)


def test_the_slide_map_has_a_positive_jacobian_everywhere():
    """On a fine grid over the pad (not only at pins): det(d q' / d q) >= 1 - pi / 4 in unrolled coordinates."""
    radius = 20.0
    g = np.linspace(-19.0, 19.0, 241)
    x, y = np.meshgrid(g, g)
    inside = np.hypot(x, y) < 19.5
    for depth in DEPTHS_MM:
        for distance in (2.0, 8.0, _slide.max_slide_mm(depth, radius)):
            q = unrolled(*_slide.slid_points(x.ravel(), y.ravel(), slide(depth, distance, 30.0), radius), radius)
            q0 = unrolled(x.ravel(), y.ravel(), radius)
            qx, qy = (v.reshape(x.shape) for v in q.T)
            px, py = (v.reshape(x.shape) for v in q0.T)
            # Jacobian of q' with respect to q0 by finite differences along the grid
            d = lambda f: (np.gradient(f, axis=1), np.gradient(f, axis=0))
            (ax, ay), (bx, by) = d(qx), d(qy)
            (cx, cy), (ex, ey) = d(px), d(py)
            det = (ax * by - ay * bx) / (cx * ey - cy * ex)
            assert det[inside].min() > min(1 - np.pi / 4, _slide.MIN_JACOBIAN) - 0.03


def test_a_slide_too_long_for_the_pad_is_refused_by_name():
    sensor = SyntheticTacTip.from_preset("small-pad-100")
    longest = _slide.max_slide_mm(5.0, 20.0)
    sensor.pin_centres(Contact(5.0, slide_x_mm=longest))
    with pytest.raises(ValueError, match="slide_x_mm"):
        sensor.pin_centres(Contact(5.0, slide_x_mm=longest * 1.05))


@pytest.mark.parametrize("seed", range(3))
def test_slides_move_pins_pitches_sideways_in_their_direction(seed):
    sensor = SyntheticTacTip.from_preset("radial-led-120", seed=seed)
    pitch_px = sensor.pin_spacing_mm / sensor.mm_per_px
    for direction in DIRECTIONS_DEG:
        pressed, _ = sensor.pin_centres(Contact(2.0))
        slid, _ = sensor.pin_centres(slide(2.0, 3 * sensor.pin_spacing_mm, direction))
        move = slid - pressed
        unit = np.array([np.cos(np.radians(direction)), np.sin(np.radians(direction))])
        centre = np.linalg.norm(sensor.rest_centres - sensor.disc[:2], axis=1) < 1.5 * pitch_px
        along = move[centre] @ unit
        across = move[centre] @ np.array([-unit[1], unit[0]])
        assert np.all(along > 2.7 * pitch_px) and np.all(along < 3.6 * pitch_px)  # 3 pitches, a bit magnified
        assert np.abs(across).max() < 0.3 * pitch_px


@pytest.mark.parametrize("rest_frames", [2, 5])
def test_a_sequence_s_events_are_exactly_its_frames_in_contact(rest_frames):
    sensor = SyntheticTacTip.from_preset("radial-led-120", seed=1)
    directions = [0.0, 45.0, 180.0, 300.0]
    strokes = [Stroke(2.0, d, 6.0) for d in directions[:2]] + [Stroke(3.0)] + [Stroke(2.5, directions[3], 4.0)]
    run = sensor.sequence(strokes, rest_s=rest_frames / 120, press_s=0.05, hold_s=0.03, slide_s=0.1, lift_s=0.05)
    touching = run.in_contact()
    assert len(run.events) == len(strokes)
    bounds = np.zeros(len(run), bool)
    for stroke, event in zip(strokes, run.events):
        assert event.kind == stroke.kind and event.peak_indentation_mm == stroke.indentation_mm
        assert event.direction_deg == stroke.direction_deg and event.distance_mm == stroke.distance_mm
        assert touching[event.start_frame:event.stop_frame].all()
        assert not touching[event.start_frame - 1] and not touching[event.stop_frame]
        assert not touching[event.stop_frame:event.stop_frame + rest_frames].any()
        assert event.start_s == pytest.approx(event.start_frame / 120)
        bounds[event.start_frame:event.stop_frame] = True
        depth = [run.contacts[k].indentation_mm for k in range(event.start_frame, event.stop_frame)]
        assert max(depth) == pytest.approx(stroke.indentation_mm)
        if stroke.kind == "slide":
            shift = max(np.hypot(run.contacts[k].slide_x_mm, run.contacts[k].slide_y_mm)
                        for k in range(event.start_frame, event.stop_frame))
            assert shift == pytest.approx(stroke.distance_mm)
    np.testing.assert_array_equal(bounds, touching)  # nothing in contact outside the events
    assert len(run) == len(run.timestamps_s)


def test_sequence_frames_carry_exact_ground_truth_and_return_to_rest():
    sensor = SyntheticTacTip.from_preset("radial-led-120", seed=2, noise_sigma=0.0)
    run = sensor.slides([90.0, 200.0], distance_mm=8.0, indentation_mm=2.0, rest_s=3 / 120, press_s=0.03,
                        slide_s=0.05, lift_s=0.03)
    frames = list(run)
    assert len(frames) == len(run)
    for frame, contact, t in zip(frames, run.contacts, run.timestamps_s):
        truth, visible = sensor.pin_centres(contact)
        np.testing.assert_array_equal(frame.centres, truth)
        np.testing.assert_array_equal(frame.visible, visible)
        assert frame.timestamp_s == t
    for event in run.events:
        np.testing.assert_array_equal(frames[event.stop_frame].centres, sensor.rest_centres)
        peak = max(np.linalg.norm(frames[k].centres - sensor.rest_centres, axis=1).max()
                   for k in range(event.start_frame, event.stop_frame))
        assert peak > 2.5 * sensor.pin_spacing_mm / sensor.mm_per_px
    assert run.frame_rate == 120.0


def test_taps_and_slides_helpers_validate_and_count():
    sensor = SyntheticTacTip.from_preset("radial-led-120")
    run = sensor.taps(3, indentation_mm=2.0, rest_s=2 / 120)
    assert [e.kind for e in run.events] == ["press"] * 3
    assert [e.direction_deg for e in sensor.slides(range(0, 360, 45)).events] == list(range(0, 360, 45))
    with pytest.raises(ValueError, match="count"):
        sensor.taps(0)
    with pytest.raises(ValueError, match="rest_s"):
        sensor.taps(2, rest_s=-1.0)
    with pytest.raises(ValueError, match="frame_rate"):
        sensor.taps(2, frame_rate=0.0)
