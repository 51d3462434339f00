"""The synthetic TacTip: layout, contact mechanics, ground truth, determinism and frame statistics."""

import numpy as np
import pytest
from scipy import ndimage
from scipy.spatial import cKDTree

from tactip.sim import Contact, SyntheticFrame, SyntheticTacTip, tap_profile

PRESETS = (127, 331, 532)


def clean(pins, **options):
    """A noise-free renderer with uniform light and no glare: the blobs are exactly what is drawn."""
    return SyntheticTacTip(pins=pins, noise_sigma=0.0, glare=False, gradient=False, **options)


def blob_centroids(frame, sensor, background=25.0):
    """Intensity-weighted centroids (x, y) of every blob inside the disc, and their label image."""
    height, width = frame.image.shape
    cx, cy, radius = sensor.disc
    yy, xx = np.mgrid[0:height, 0:width]
    signal = (frame.image.astype(float) - background) * (np.hypot(xx - cx, yy - cy) < radius - 3)
    labels, count = ndimage.label(signal > 0.5)
    centroids = np.array(ndimage.center_of_mass(signal, labels, np.arange(1, count + 1)))[:, ::-1]
    return centroids.reshape(-1, 2), labels


def displacement(sensor, contact):
    """Pin displacement magnitudes from rest, px, (N,)."""
    centres, _ = sensor.pin_centres(contact)
    return np.linalg.norm(centres - sensor.rest_centres, axis=1)


@pytest.mark.parametrize("pins", PRESETS)
def test_preset_counts_are_exact(pins):
    sensor = SyntheticTacTip(pins=pins)
    frame = sensor.render()
    assert sensor.n_pins == pins
    assert sensor.rest_centres.shape == frame.centres.shape == (pins, 2)
    assert frame.visible.shape == (pins,) and frame.visible.all()
    assert frame.image.shape == (480, 640) and frame.image.dtype == np.uint8


def test_any_pin_count_and_image_size_works():
    assert SyntheticTacTip(pins=200).rest_centres.shape == (200, 2)
    small = SyntheticTacTip(pins=331, image_size=(320, 240))
    frame = small.render(Contact(3.0))
    assert frame.image.shape == (240, 320) and frame.visible.all()
    distance, _ = cKDTree(small.rest_centres).query(small.rest_centres, k=2)
    assert distance[:, 1].min() > 2.5 * small.pin_radius_px


def test_docstring_examples_run():
    import doctest

    import tactip.sim.synthetic

    assert doctest.testmod(tactip.sim.synthetic).failed == 0


@pytest.mark.parametrize("pins", PRESETS)
def test_pins_lie_inside_the_disc_and_the_disc_inside_the_image(pins):
    sensor = SyntheticTacTip(pins=pins)
    cx, cy, radius = sensor.disc
    r = np.hypot(*(sensor.rest_centres - [cx, cy]).T)
    assert r.max() + sensor.pin_radius_px < radius
    assert cx - radius > 10 and cy - radius > 10 and cx + radius < 630 and cy + radius < 470


@pytest.mark.parametrize("pins, low, high", [(127, 5.0, 6.0), (331, 5.0, 6.0), (532, 4.0, 5.0)])
def test_pins_are_separable(pins, low, high):
    sensor = SyntheticTacTip(pins=pins)
    assert low <= sensor.pin_radius_px <= high
    distance, _ = cKDTree(sensor.rest_centres).query(sensor.rest_centres, k=2)
    assert distance[:, 1].min() > 2.5 * sensor.pin_radius_px


@pytest.mark.parametrize("pins", PRESETS)
@pytest.mark.parametrize("depth", [3.0, 5.0])
def test_pins_stay_separate_blobs_under_contact(pins, depth):
    sensor = clean(pins)
    frame = sensor.render(Contact(depth, gap_width_mm=5.0, gap_offset_mm=2.0))
    centroids, _ = blob_centroids(frame, sensor)
    assert len(centroids) == pins  # no two tips merge into one blob


def axes_of_blob(labels, label):
    """Semi-axes (minor, major) px of a binary blob from its second moments (a uniform ellipse has var = a^2/4)."""
    ys, xs = np.nonzero(labels == label)
    covariance = np.cov(np.stack([xs, ys]))
    return 2.0 * np.sqrt(np.linalg.eigvalsh(covariance))


@pytest.mark.parametrize("pins", [127, 331])
def test_pin_tips_are_5_to_6_px_at_the_centre_and_foreshortened_at_the_rim(pins):
    sensor = clean(pins)
    frame = sensor.render()
    _, labels = blob_centroids(frame, sensor, background=(25.0 + 215.0) / 2)  # half-level masks
    cx, cy, _ = sensor.disc
    r = np.hypot(*(frame.centres - [cx, cy]).T)
    centre_pin, rim_pin = np.argmin(r), np.argmax(r)
    label_at = lambda i: labels[tuple(np.rint(frame.centres[i, ::-1]).astype(int))]  # noqa: E731
    centre_axes = axes_of_blob(labels, label_at(centre_pin))
    rim_axes = axes_of_blob(labels, label_at(rim_pin))
    assert np.all((4.8 <= centre_axes) & (centre_axes <= 6.2))
    assert centre_axes[0] / centre_axes[1] > 0.95  # round at the centre
    assert rim_axes[0] / rim_axes[1] < 0.8  # an ellipse near the rim
    # the minor axis points at the centre (radial foreshortening)
    ys, xs = np.nonzero(labels == label_at(rim_pin))
    _, vectors = np.linalg.eigh(np.cov(np.stack([xs, ys])))
    radial = (frame.centres[rim_pin] - [cx, cy]) / r[rim_pin]
    assert abs(vectors[:, 0] @ radial) > 0.9


@pytest.mark.parametrize("pins", PRESETS)
@pytest.mark.parametrize("contact", [Contact(), Contact(4.5, 3.0, 1.0, 30.0)])
def test_ground_truth_is_the_centroid_of_the_drawn_blob(pins, contact):
    sensor = clean(pins)
    frame = sensor.render(contact)
    centroids, _ = blob_centroids(frame, sensor)
    distance, index = cKDTree(frame.centres).query(centroids)
    assert len(centroids) == pins and len(set(index)) == pins
    assert distance.max() < 0.05


def test_no_contact_gives_the_rest_centres():
    sensor = SyntheticTacTip(pins=331)
    for contact in (None, Contact(), Contact(-1.0, gap_width_mm=3.0, gap_offset_mm=2.0)):
        centres, visible = sensor.pin_centres(contact)
        np.testing.assert_array_equal(centres, sensor.rest_centres)
        assert visible.all()
    np.testing.assert_array_equal(sensor.render().centres, sensor.rest_centres)


def test_render_and_pin_centres_agree():
    sensor = SyntheticTacTip(pins=331)
    contact = Contact(3.0, 2.0, -1.0)
    frame = sensor.render(contact)
    centres, visible = sensor.pin_centres(contact)
    np.testing.assert_array_equal(frame.centres, centres)
    np.testing.assert_array_equal(frame.visible, visible)
    assert frame.contact == contact


@pytest.mark.parametrize("pins", PRESETS)
def test_displacement_grows_with_indentation_to_10_15_px_at_5_mm(pins):
    sensor = SyntheticTacTip(pins=pins)
    depths = np.arange(0.5, 6.01, 0.5)
    fields = np.array([displacement(sensor, Contact(d)) for d in depths])
    assert np.all(np.diff(fields.max(axis=1)) > 0) and np.all(np.diff(fields.mean(axis=1)) > 0)
    assert 10.0 <= displacement(sensor, Contact(5.0)).max() <= 15.0
    # pins spread out from the contact: the centre pin stays (nearly) put, the ring around it moves out
    cx, cy, _ = sensor.disc
    before = np.hypot(*(sensor.rest_centres - [cx, cy]).T)
    after = np.hypot(*(sensor.pin_centres(Contact(4.0))[0] - [cx, cy]).T)
    assert np.all(after[before > 20] > before[before > 20])
    # the pad is clamped at its base: the outermost ring barely moves
    moved = displacement(sensor, Contact(5.0))
    assert moved[before > 0.95 * before.max()].max() < 0.3 * moved.max()


@pytest.mark.parametrize("pins", PRESETS)
def test_gap_imprint_is_subtle_and_grows_with_width(pins):
    sensor = SyntheticTacTip(pins=pins)
    base, _ = sensor.pin_centres(Contact(4.0, gap_width_mm=1.0))
    differences = [np.linalg.norm(sensor.pin_centres(Contact(4.0, gap_width_mm=w))[0] - base, axis=1).max()
                   for w in (2.0, 3.0, 4.0, 5.0)]
    assert np.all(np.diff(differences) > 0)
    assert 2.0 < differences[-1] < 8.0  # w = 1 vs 5 mm: a few px, on the pins right over the gap
    assert differences[0] < 1.5  # w = 1 vs 2 mm: subtle, about a px at most


@pytest.mark.parametrize("offset_mm, angle_deg", [(0.0, 0.0), (3.0, 0.0), (-2.0, 0.0), (0.0, 90.0)])
def test_the_imprint_follows_the_gap_line(offset_mm, angle_deg):
    sensor = SyntheticTacTip(pins=331)
    flat, _ = sensor.pin_centres(Contact(4.0))
    gap, _ = sensor.pin_centres(Contact(4.0, 5.0, offset_mm, angle_deg))
    imprint = np.linalg.norm(gap - flat, axis=1)
    strongest = sensor.rest_centres[imprint > 0.5 * imprint.max()] - sensor.disc[:2]
    along, across = (0, 1) if angle_deg == 0 else (1, 0)
    expected_across = offset_mm / sensor.mm_per_px * (1 if angle_deg == 0 else -1)
    assert np.abs(strongest[:, across] - expected_across).max() < 2.5 * sensor.pin_spacing_mm / sensor.mm_per_px
    assert np.ptp(strongest[:, along]) > np.ptp(strongest[:, across])


def test_same_seed_same_frames_and_different_seeds_differ():
    contact = Contact(3.0, 2.0)
    first, second = SyntheticTacTip(seed=7), SyntheticTacTip(seed=7)
    for _ in range(3):
        a, b = first.render(contact), second.render(contact)
        np.testing.assert_array_equal(a.image, b.image)
        np.testing.assert_array_equal(a.centres, b.centres)
    other = SyntheticTacTip(seed=8).render(contact)
    assert np.mean(other.image != a.image) > 0.5
    assert not np.array_equal(other.centres, a.centres)  # the pins' manufacturing jitter differs too


def test_noise_is_fresh_each_frame_with_the_requested_sigma():
    sensor = SyntheticTacTip(noise_sigma=4.0, glare=False, gradient=False)
    a, b = sensor.render().image, sensor.render().image
    cx, cy, radius = sensor.disc
    yy, xx = np.mgrid[0:480, 0:640]
    flat = np.hypot(xx - cx, yy - cy) > radius + 5  # uniform casing
    difference = a[flat].astype(float) - b[flat]
    assert difference.std() == pytest.approx(4.0 * np.sqrt(2), rel=0.05)
    assert abs(difference.mean()) < 0.1
    quiet = SyntheticTacTip(noise_sigma=0.0).render().image
    np.testing.assert_array_equal(quiet, SyntheticTacTip(noise_sigma=0.0).render().image)


def test_frames_look_like_a_real_tactip():
    sensor = SyntheticTacTip(pins=331)
    frame = sensor.render()
    image = frame.image.astype(float)
    cx, cy, radius = sensor.disc
    yy, xx = np.mgrid[0:480, 0:640]
    r = np.hypot(xx - cx, yy - cy)
    near_pin = np.zeros(image.shape, bool)
    near_pin[tuple(np.rint(frame.centres[:, ::-1]).astype(int).T)] = True
    near_pin = ndimage.binary_dilation(near_pin, iterations=9)
    assert image[r > radius + 5].mean() > 150  # bright surround
    assert image[(r < radius - 15) & ~near_pin].mean() < 60  # dark membrane
    at_centres = image[tuple(np.rint(frame.centres[:, ::-1]).astype(int).T)]
    assert at_centres.min() > 150  # white pin tips
    # glare spots on the rim are brighter than the membrane around them
    rim = (r > radius - 6) & (r < radius - 1)
    assert np.percentile(image[rim], 99) > 150 and np.median(image[rim]) < 100


def test_hidden_pins_are_not_drawn():
    sensor = clean(331)
    hidden = np.zeros(331, bool)
    hidden[[0, 10, 200]] = True
    frame = sensor.render(hidden=hidden)
    assert not frame.visible[hidden].any() and frame.visible[~hidden].all()
    pixels = frame.image[tuple(np.rint(frame.centres[:, ::-1]).astype(int).T)]
    assert np.all(pixels[hidden] < 40) and np.all(pixels[~hidden] > 150)
    np.testing.assert_array_equal(frame.centres, sensor.rest_centres)  # truth still given for hidden pins
    with pytest.raises(ValueError, match="hidden"):
        sensor.render(hidden=np.zeros(5, bool))


def test_dark_pins_colour_blur_and_jpeg():
    contact = Contact(2.0)
    dark = SyntheticTacTip(dark_pins=True, seed=1).render(contact)
    at = tuple(np.rint(dark.centres[:, ::-1]).astype(int).T)
    cx, cy, radius = SyntheticTacTip().disc
    yy, xx = np.mgrid[0:480, 0:640]
    assert dark.image[at].max() < 100 and np.median(dark.image[np.hypot(xx - cx, yy - cy) < radius]) > 150
    colour = SyntheticTacTip(colour=True, seed=1).render(contact)
    assert colour.image.shape == (480, 640, 3) and colour.image.dtype == np.uint8
    plain = SyntheticTacTip(noise_sigma=0.0).render(contact).image.astype(float)
    blurred = SyntheticTacTip(noise_sigma=0.0, blur_sigma=1.5).render(contact).image.astype(float)
    assert np.abs(np.diff(blurred, axis=1)).mean() < np.abs(np.diff(plain, axis=1)).mean()
    jpeg = SyntheticTacTip(noise_sigma=0.0, jpeg_quality=75).render(contact).image.astype(float)
    assert 0 < np.abs(jpeg - plain).mean() < 3.0


def test_tap_rises_holds_and_releases():
    sensor = SyntheticTacTip(pins=127)
    frames = list(sensor.tap(Contact(5.0, 2.0, 1.0), frame_rate=20.0))
    assert all(isinstance(f, SyntheticFrame) for f in frames)
    times = np.array([f.timestamp_s for f in frames])
    np.testing.assert_allclose(times, np.arange(len(frames)) / 20.0)
    assert len(frames) == 20  # 0.1 + 3 x 0.25 + 0.1 s at 20 fps, both ends included
    depth = np.array([f.contact.indentation_mm for f in frames])
    assert depth[0] == depth[-1] == 0.0 and depth.max() == pytest.approx(5.0)
    assert all(f.contact.gap_width_mm == 2.0 and f.contact.gap_offset_mm == 1.0 for f in frames)
    peak = np.flatnonzero(depth == depth.max())
    np.testing.assert_allclose(times[[peak[0], peak[-1]]], [0.35, 0.6])  # plateau 0.25 s after a 0.25 s rise
    moved = np.array([np.linalg.norm(f.centres - sensor.rest_centres, axis=1).max() for f in frames])
    assert moved[0] == moved[-1] == 0.0 and np.all(np.diff(moved[2: peak[0] + 1]) > 0)  # rise from 0.1 s


def test_tap_profile():
    t = np.linspace(-0.5, 1.5, 2001)
    fraction = tap_profile(t, rise_s=0.25, plateau_s=0.25, release_s=0.25)
    assert fraction.min() == 0.0 and fraction.max() == 1.0
    assert np.abs(np.diff(fraction)).max() < 0.01  # continuous
    np.testing.assert_allclose(tap_profile([0.125, 0.375, 0.625, 0.8]), [0.5, 1.0, 0.5, 0.0], atol=1e-12)
    assert tap_profile(0.05, rise_s=0.1, plateau_s=0.0, release_s=0.1) == pytest.approx(0.5)
    assert isinstance(tap_profile(0.1), float)
    with pytest.raises(ValueError, match="rise_s"):
        tap_profile(0.1, rise_s=0.0)


def test_invalid_arguments_name_the_parameter():
    with pytest.raises(ValueError, match="gap_width_mm"):
        Contact(3.0, gap_width_mm=-1.0)
    with pytest.raises(ValueError, match="indentation_mm"):
        Contact(float("nan"))
    with pytest.raises(ValueError, match="pins"):
        SyntheticTacTip(pins=3)
    with pytest.raises(ValueError, match="jpeg_quality"):
        SyntheticTacTip(jpeg_quality=0)
    with pytest.raises(ValueError, match="noise_sigma"):
        SyntheticTacTip(noise_sigma=-1.0)
    with pytest.raises(ValueError, match="frame_rate"):
        next(SyntheticTacTip().tap(Contact(1.0), frame_rate=0.0))
