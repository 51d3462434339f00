"""The flat-gel sensor (`tactip.sim.gel.SyntheticGel`): its frames look as described and its ground truth is exact."""

import cv2
import numpy as np
import pytest
from scipy.spatial import cKDTree

from tactip.sim import GEL_PRESETS, Contact, SyntheticGel

PRESS = Contact(indentation_mm=5.0)
SHEAR = Contact(indentation_mm=3.0, slide_x_mm=1.5, slide_y_mm=-1.0)


def grey(image):
    return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY).astype(float) if image.ndim == 3 else image.astype(float)


def test_the_preset_is_a_gelsight_mini_like_colour_sensor():
    sensor = SyntheticGel.from_preset("gelsight-mini", seed=0)
    frame = sensor.render()
    assert set(GEL_PRESETS) == {"gelsight-mini"} and sensor.preset == "gelsight-mini"
    assert frame.image.shape == (240, 320, 3) and frame.image.dtype == np.uint8
    assert sensor.frame_rate == 25.0 and sensor.grid == (8, 10) and sensor.dark_pins
    assert sensor.n_pins == 10 * 12 and frame.centres.shape == (120, 2)
    assert 75 <= frame.visible.sum() <= 90  # about 8 x 10 whole markers in view
    assert not (frame.visible & frame.partial).any()
    assert sensor.mm_per_px == pytest.approx(1.8 / 30.0)
    # the whole frame is the sensing area: the 'disc' holds every pixel
    cx, cy, radius = sensor.disc
    assert np.hypot(cx, cy) < radius and np.hypot(319 - cx, 239 - cy) < radius


def test_colour_gradient_across_the_frame_from_three_lights():
    image = SyntheticGel(noise_sigma=0.0, vignette=0.0, seed=0).render(hidden=np.ones(120, bool)).image.astype(float)
    left, right = image[:, :40].mean(axis=(0, 1)), image[:, -40:].mean(axis=(0, 1))
    top, bottom = image[:40].mean(axis=(0, 1)), image[-40:].mean(axis=(0, 1))
    assert left[0] - right[0] > 50 and right[2] - left[2] > 50 and top[1] - bottom[1] > 50  # B left, R right, G top
    # dark markers on the lit gel, in every channel
    frame = SyntheticGel(noise_sigma=0.0, seed=0).render()
    x, y = np.rint(frame.centres[frame.visible][0]).astype(int)
    assert (frame.image[y, x].astype(float) < 0.4 * image[y, x]).all()


@pytest.mark.parametrize("contact", [None, PRESS, SHEAR], ids=["rest", "press", "shear"])
def test_visible_markers_are_centred_on_the_truth(contact):
    """The darkness-weighted centroid of each visible marker, against the same frame drawn without
    markers (gradient, vignetting and contact shading left in), is its true centre."""
    sensor = SyntheticGel(noise_sigma=0.0, seed=3)
    frame = sensor.render(contact)
    image, empty = grey(frame.image), grey(sensor.render(contact, hidden=np.ones(sensor.n_pins, bool)).image)
    half = int(np.ceil(sensor.pin_radius_px + 2))
    errors = []
    for x, y in frame.centres[frame.visible]:
        yy, xx = np.mgrid[round(y) - half:round(y) + half + 1, round(x) - half:round(x) + half + 1]
        window = np.hypot(xx - x, yy - y) <= sensor.pin_radius_px + 1.0
        weight = np.clip(empty[yy, xx] - image[yy, xx], 0, None) * window
        errors.append(np.hypot((weight * xx).sum() / weight.sum() - x, (weight * yy).sum() / weight.sum() - y))
    assert len(errors) >= 75 and max(errors) < 0.05


def test_partial_markers_are_cut_by_the_frame_edge_and_hidden_ones_are_outside():
    for seed in range(4):
        sensor = SyntheticGel(seed=seed)
        for contact in (None, SHEAR):
            frame = sensor.render(contact)
            c, r = frame.centres, sensor.pin_radius_px
            room = np.minimum(np.minimum(c[:, 0], c[:, 1]), np.minimum(319 - c[:, 0], 239 - c[:, 1]))
            assert (room[frame.visible] >= r + 1.0).all()
            assert ((room[frame.partial] < r + 1.0) & (room[frame.partial] > -r - 1.0)).all()
            assert (room[~frame.visible & ~frame.partial] <= -r).all()
    # some seed cuts markers: they are drawn (dark pixels at the edge)
    frame = SyntheticGel(seed=0, noise_sigma=0.0).render()
    x, y = np.rint(frame.centres[frame.partial][0]).astype(int)
    assert grey(frame.image)[np.clip(y, 0, 239), np.clip(x, 0, 319)] < 80


def test_press_spreads_the_markers_from_the_contact():
    sensor = SyntheticGel(seed=0)
    rest, pressed = sensor.pin_centres()[0], sensor.pin_centres(PRESS)[0]
    centre = np.array([159.5, 119.5])
    before, after = np.hypot(*(rest - centre).T), np.hypot(*(pressed - centre).T)
    moved = np.hypot(*(pressed - rest).T)
    assert (after >= before - 1e-9).all()  # everything moves outward (or stays)
    assert 6.0 < moved.max() < 12.0  # a few px: a fraction of the 30 px pitch
    assert moved[before > 150].max() < 0.2 * moved.max()  # the far markers hardly move
    shallow = np.hypot(*(sensor.pin_centres(Contact(2.0))[0] - rest).T).max()
    assert shallow < moved.max()


def test_shear_drags_the_markers_under_the_contact_and_never_folds():
    sensor = SyntheticGel(seed=0)
    rest = sensor.pin_centres()[0]
    for slide in (1.0, 2.0, 3.0):
        contact = Contact(3.0, slide_x_mm=slide)
        moved = sensor.pin_centres(contact)[0] - rest
        middle = np.argmin(np.hypot(*(rest - [159.5, 119.5]).T))
        expected = slide / sensor.mm_per_px
        assert moved[middle, 0] == pytest.approx(expected, abs=0.35 * expected)  # the patch moves with the plate
        assert np.abs(moved[:, 0]).max() <= expected + 10.0
        pressed = sensor.pin_centres(contact)[0]
        distance, _ = cKDTree(pressed).query(pressed, k=2)
        assert distance[:, 1].min() > 0.55 * sensor.pitch_px  # markers stay apart: no folding, no crossing


def test_deterministic_per_seed_and_seeds_differ():
    a, b = SyntheticGel(seed=5), SyntheticGel(seed=5)
    for _ in range(2):
        fa, fb = a.render(SHEAR), b.render(SHEAR)
        np.testing.assert_array_equal(fa.image, fb.image)
        np.testing.assert_array_equal(fa.centres, fb.centres)
    other = SyntheticGel(seed=6).render(SHEAR)
    assert not np.array_equal(other.centres, fa.centres)


def test_hidden_markers_are_not_drawn_and_grey_frames():
    sensor = SyntheticGel(seed=0, noise_sigma=0.0, colour=False)
    hidden = np.zeros(sensor.n_pins, bool)
    hidden[sensor.render().visible.nonzero()[0][0]] = True
    frame = sensor.render(hidden=hidden)
    assert frame.image.shape == (240, 320) and not frame.visible[hidden].any()
    x, y = np.rint(frame.centres[hidden][0]).astype(int)
    assert frame.image[y, x] > 100  # gel, no marker


def test_sequences_and_taps_carry_their_ground_truth():
    sensor = SyntheticGel.from_preset("gelsight-mini")
    run = sensor.slides([0, 90], distance_mm=1.0, indentation_mm=3.0, rest_s=0.08)
    frames = list(run)
    assert [e.kind for e in run.events] == ["slide", "slide"] and len(frames) == len(run)
    assert frames[0].image.shape == (240, 320, 3)
    tap = list(sensor.tap(Contact(4.0)))
    assert len(tap) == int(0.95 * 25) + 1 and tap[len(tap) // 2].contact.indentation_mm == pytest.approx(4.0, rel=0.2)


@pytest.mark.parametrize("options, name", [
    ({"grid": (1, 10)}, "grid"), ({"pitch_mm": 0.0}, "pitch_mm"), ({"marker_fraction": 0.5}, "marker_fraction"),
    ({"gradient": -1.0}, "gradient"), ({"jpeg_quality": 0}, "jpeg_quality"), ({"frame_rate": 0.0}, "frame_rate"),
    ({"image_size": (32, 32)}, "image_size"), ({"marker_reflectance": 2.0}, "marker_reflectance")])
def test_invalid_options_name_the_parameter(options, name):
    with pytest.raises(ValueError, match=name):
        SyntheticGel(**options)
    with pytest.raises(ValueError, match="unknown synthetic gel preset 'nope'.*gelsight-mini"):
        SyntheticGel.from_preset("nope")


def test_docstring_examples_run():
    import doctest

    import tactip.sim.gel

    result = doctest.testmod(tactip.sim.gel, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


def test_a_synthetic_source_of_the_flat_gel():
    from tactip.sources import open_source

    with open_source("synthetic:gelsight-mini", taps=[Contact(3.0)], rest_s=0.1) as source:
        frames = list(source)
        assert source.name == "synthetic:gelsight-mini" and source.frame_rate == 25.0
        assert source.truth.visible.sum() >= 75
    assert frames[0].image.shape == (240, 320, 3) and len(frames) == int((0.1 + 0.75 + 0.1) * 25) + 1


def test_the_package_names_the_simulated_sensors():
    import tactip

    assert tactip.SyntheticGel is SyntheticGel and tactip.Contact is Contact
    assert tactip.SyntheticTacTip.__name__ == "SyntheticTacTip"
