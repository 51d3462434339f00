"""The synthetic TacTip's presets: the phenomena of real TacTips that broke the front end (issue 8).

Each preset must render deterministically, carry consistent ground truth (visible tips centred on the
truth, partial tips at the rim, glare outside the pin field) and look as its name says; the default
renderer must stay byte-identical to the one that wrote samples/.
"""

import functools
import pathlib

import cv2
import numpy as np
import pytest
from scipy import ndimage
from scipy.spatial import cKDTree

from tactip.sources import SyntheticSource, open_source
from tactip.sim import PRESETS, Contact, SyntheticTacTip, preset_names
from tests.pins.conftest import preset_frame, score

SAMPLES = pathlib.Path(__file__).resolve().parents[3] / "samples"
TAP = Contact(4.5, 2.0, 1.0, 30.0)
NAMES = preset_names()
CLEAN = dict(noise_sigma=0.0, glare=False, gradient=False, veil=0.0, jpeg_quality=None, blur_sigma=0.0)

# name: (pins, (width, height), dark disc diameter / image height, colour, frames/s)
NAMED = {
    "tactip-331": (331, (640, 480), 0.87, False, 20.0),
    "tactip-127": (127, (640, 480), 0.87, False, 20.0),
    "tactip-532": (532, (640, 480), 0.87, False, 20.0),
    "dark-331": (331, (640, 480), 0.87, False, 20.0),
    "rim-ring-331": (331, (640, 480), 0.87, False, 20.0),
    "brown-127": (127, (640, 480), 0.87, True, 20.0),
    "radial-120": (120, (640, 480), 1 / 3, False, 120.0),
    "radial-led-120": (120, (640, 480), 1 / 3, False, 120.0),
    "white-dark-331": (331, (640, 480), 0.87, False, 20.0),
    "small-pad-100": (100, (320, 240), 0.25, False, 20.0),
    "dense-1000": (1000, (1280, 720), 0.9, False, 20.0),
}


@functools.lru_cache(maxsize=None)
def clean_sensor(name):
    """The preset without noise, gradient, LED glare or veil: what is left is the phenomenon itself."""
    return SyntheticTacTip.from_preset(name, **CLEAN)


def grey(image):
    """A frame as float grey levels (BT.601 for colour frames, as OpenCV converts them)."""
    return (cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image).astype(float)


def radius_from(sensor, points):
    """Distance of points (M, 2) from the disc centre, px."""
    return np.hypot(*(np.asarray(points) - sensor.disc[:2]).T)


def weighted_centroids(sensor, contact):
    """Intensity-weighted centroid of each visible tip over its ellipse (+1 px), above the local background.

    The background is a constant per tip: the mean, over the same window, of the frame rendered with
    every pin hidden. Returns the centroids (M, 2) and the true centres (M, 2) of the visible pins.
    """
    frame = sensor.render(contact)
    image = grey(frame.image)
    empty = grey(sensor.render(contact, hidden=np.ones(sensor.n_pins, bool)).image)
    centres, shape = sensor.pin_ellipses(contact)
    found, truth = [], []
    for i in np.flatnonzero(frame.visible):
        minor, major = np.sqrt(np.linalg.eigvalsh(shape[i]))
        half = int(np.ceil(major + 2))
        x0, y0 = np.rint(centres[i]).astype(int) - half
        yy, xx = np.mgrid[y0:y0 + 2 * half + 1, x0:x0 + 2 * half + 1]
        offset = np.stack([xx - centres[i, 0], yy - centres[i, 1]], axis=-1)
        scaled = np.einsum("...i,ij,...j->...", offset, np.linalg.inv(shape[i]), offset)
        window = scaled <= ((minor + 1) / minor) ** 2
        patch = image[yy, xx]
        contrast = (empty[yy, xx][window].mean() - patch) if sensor.dark_pins else (patch - empty[yy, xx][window].mean())
        weight = np.clip(contrast, 0.0, None) * window  # what stands out from the background towards the tip
        found.append([(weight * xx).sum() / weight.sum(), (weight * yy).sum() / weight.sum()])
        truth.append(centres[i])
    return np.array(found), np.array(truth)


def test_presets_are_named_and_read_only():
    assert set(NAMES) == set(NAMED) and tuple(PRESETS) == NAMES
    with pytest.raises(TypeError):
        PRESETS["mine"] = {}
    with pytest.raises(TypeError):
        PRESETS["tactip-331"]["pins"] = 7
    with pytest.raises(ValueError, match="unknown synthetic TacTip preset 'nope'.*rim-ring-331"):
        SyntheticTacTip.from_preset("nope")


@pytest.mark.parametrize("name", NAMES)
def test_each_preset_has_its_size_pins_pad_and_frame_rate(name):
    pins, size, fraction, colour, fps = NAMED[name]
    sensor = SyntheticTacTip.from_preset(name)
    frame = sensor.render()
    assert sensor.preset == name and sensor.n_pins == pins and sensor.image_size == size
    assert frame.image.shape == ((size[1], size[0], 3) if colour else (size[1], size[0]))
    assert frame.image.dtype == np.uint8 and frame.centres.shape == (pins, 2)
    assert 2 * sensor.disc[2] / size[1] == pytest.approx(fraction, rel=1e-9)
    assert sensor.frame_rate == fps
    # the dark disc really is that size: dark inside (beyond the pins), bright around it
    image = grey(frame.image)
    yy, xx = np.mgrid[0:size[1], 0:size[0]]
    r = np.hypot(xx - sensor.disc[0], yy - sensor.disc[1]) / sensor.disc[2]
    inside, outside = np.median(image[(r > 0.6) & (r < 0.95)]), np.median(image[(r > 1.1) & (r < 1.4)])
    if sensor.dark_pins:
        inside, outside = -inside, -outside
    if PRESETS[name].get("surround_level", 255) < 60:  # a dark casing: no bright surround, by design
        assert abs(outside - inside) < 30
    else:
        assert outside - inside > 60
    # every pin lies inside the disc, whole or cut by the rim ring
    assert (radius_from(sensor, frame.centres) < sensor.disc[2]).all()
    assert (frame.visible | frame.partial).sum() >= 0.95 * pins
    assert not (frame.visible & frame.partial).any()


@pytest.mark.parametrize("name", NAMES)
def test_each_preset_is_deterministic_per_seed(name):
    contact = Contact(3.0, 2.0)
    a, b = SyntheticTacTip.from_preset(name, seed=5), SyntheticTacTip.from_preset(name, seed=5)
    for _ in range(2):  # the noise stream too
        fa, fb = a.render(contact), b.render(contact)
        np.testing.assert_array_equal(fa.image, fb.image)
        np.testing.assert_array_equal(fa.centres, fb.centres)
        np.testing.assert_array_equal(fa.partial, fb.partial)
    other = SyntheticTacTip.from_preset(name, seed=6).render(contact)
    assert not np.array_equal(other.image, fa.image) and not np.array_equal(other.centres, fa.centres)


@pytest.mark.parametrize("name, tolerance_px", [
    ("tactip-331", 0.03), ("dark-331", 0.03), ("rim-ring-331", 0.03), ("brown-127", 0.05),
    ("radial-120", 0.04), ("small-pad-100", 0.07), ("dense-1000", 0.03)])
@pytest.mark.parametrize("contact", [None, TAP], ids=["rest", "tap"])
def test_visible_tips_are_centred_on_the_truth(name, tolerance_px, contact):
    sensor = clean_sensor(name)
    found, truth = weighted_centroids(sensor, contact)
    assert len(found) >= 0.9 * sensor.n_pins
    assert np.linalg.norm(found - truth, axis=1).max() < tolerance_px


def test_visible_tips_stay_apart():
    for name in NAMES:
        sensor = SyntheticTacTip.from_preset(name)
        for contact in (None, Contact(5.0, 2.0)):
            frame = sensor.render(contact)
            centres, shape = sensor.pin_ellipses(contact)
            drawn = frame.visible | frame.partial
            centres, shape = centres[drawn], shape[drawn]
            _, index = cKDTree(centres).query(centres, k=4)
            for k in range(1, 4):  # the three nearest neighbours of every tip
                offset = centres[index[:, k]] - centres
                distance = np.linalg.norm(offset, axis=1)
                u = offset / distance[:, None]
                reach = (np.sqrt(np.einsum("ni,nij,nj->n", u, shape, u))  # each ellipse's extent towards the other
                         + np.sqrt(np.einsum("ni,nij,nj->n", u, shape[index[:, k]], u)))
                assert (distance - reach - 1.0).min() > 0.3, name  # edge ramps included: no shared pixel


def test_rim_ring_cuts_the_outer_pins():
    sensor = SyntheticTacTip.from_preset("rim-ring-331", noise_sigma=0.0)
    rim = sensor.rim_radius_px
    assert 0.8 * sensor.disc[2] < rim < sensor.disc[2] - 3 * sensor.pin_radius_px
    for contact in (None, Contact(5.0, 2.0)):
        frame = sensor.render(contact)
        r = radius_from(sensor, frame.centres)
        assert frame.partial.sum() >= 6 and frame.visible.sum() >= 300
        # partial pins straddle the ring's inner edge; whole ones are inside it; the others beyond it
        assert np.all(np.abs(r[frame.partial] - rim) < 1.5 * sensor.pin_radius_px + 1.0)
        assert np.all(r[frame.visible] < rim - 0.7 * sensor.pin_radius_px)
        assert np.all(r[~frame.visible & ~frame.partial] > rim)
        # a cut pin shows its inner part and not its outer part
        image = frame.image.astype(float)
        cut = 0
        for i in np.flatnonzero(frame.partial):
            direction = (frame.centres[i] - sensor.disc[:2]) / r[i]
            inner, outer = (np.asarray(sensor.disc[:2]) + direction * radius for radius in (rim - 1.5, rim + 2.0))
            if np.linalg.norm(inner - frame.centres[i]) < 0.5 * sensor.pin_radius_px:  # still on the tip
                assert image[tuple(np.rint(inner[::-1]).astype(int))] > 120
            if np.min(np.hypot(*(sensor.ring_glare_centres - outer).T)) > 4 * sensor.pin_radius_px:  # off the glare
                assert image[tuple(np.rint(outer[::-1]).astype(int))] < 40
                cut += 1
        assert cut >= 3
    other = SyntheticTacTip.from_preset("tactip-331")
    assert other.rim_radius_px is None and not other.render(Contact(5.0)).partial.any()


def test_glare_blobs_lie_on_the_ring_outside_the_pin_field():
    sensor = clean_sensor("rim-ring-331")
    frame = sensor.render(hidden=np.ones(sensor.n_pins, bool))  # the scene without pins
    image = frame.image.astype(float)
    height, width = image.shape
    yy, xx = np.mgrid[0:height, 0:width]
    r = np.hypot(xx - sensor.disc[0], yy - sensor.disc[1])
    rim, disc = sensor.rim_radius_px, sensor.disc[2]
    ring = (r > rim + 1) & (r < disc - 1)
    assert np.median(image[ring]) < 20  # a black ring
    labels, count = ndimage.label((image > 90) & (r < disc - 1))
    areas = np.bincount(labels.ravel())[1:]
    assert 12 <= count <= 20  # about as many blobs as on the real 331-pin frames (17)
    assert np.all(r[labels > 0] > rim)  # all on the ring: none in the pin field
    pin_area = np.pi * sensor.pin_radius_px ** 2
    assert 0.1 * pin_area < np.median(areas) < 5 * pin_area  # about pin-sized
    assert np.std(areas) > 0.2 * np.mean(areas)  # irregular
    peaks = ndimage.maximum(image, labels, np.arange(1, count + 1))
    assert np.ptp(peaks) > 30  # uneven in brightness
    truth = sensor.ring_glare_centres
    assert len(truth) == 18 and np.all((radius_from(sensor, truth) > rim) & (radius_from(sensor, truth) < disc))
    drawn = sensor.render()
    pin_field = radius_from(sensor, drawn.centres[drawn.visible | drawn.partial]).max()
    assert radius_from(sensor, truth).min() > pin_field  # glare beyond every pin centre


def test_radial_layout_puts_pins_on_rings_and_spokes():
    sensor = SyntheticTacTip.from_preset("radial-120")
    offset = sensor.rest_centres - sensor.disc[:2]
    r = np.hypot(*offset.T)
    centre = np.argmin(r)
    assert r[centre] < 0.5  # a centre pin
    others = np.delete(np.arange(120), centre)
    spoke = np.arctan2(offset[others, 1], offset[others, 0]) * 17 / (2 * np.pi)
    assert np.abs(spoke - np.rint(spoke)).max() < 0.1  # on 17 straight spokes
    assert np.all(np.bincount(np.rint(spoke).astype(int) % 17) == 7)  # 7 pins on each
    # 7 rings: along a spoke the pitch is even, around a ring it grows with the radius
    radii = np.sort(r[others].reshape(-1))
    rings = radii.reshape(7, 17)
    assert np.all(rings.max(axis=1)[:-1] < rings.min(axis=1)[1:])
    along_ring = 2 * np.pi * rings.mean(axis=1) / 17
    assert along_ring[-1] > 2 * along_ring[0]
    assert np.ptp(np.diff(rings.mean(axis=1))) < 0.5 * np.diff(rings.mean(axis=1)).mean()
    assert 1.5 <= sensor.pin_radius_px <= 3.0  # small pins


def test_brown_skin_is_low_contrast_textured_and_coloured():
    sensor = SyntheticTacTip.from_preset("brown-127")
    frame = sensor.render()
    image = grey(frame.image)
    height, width = image.shape
    yy, xx = np.mgrid[0:height, 0:width]
    at = tuple(np.rint(frame.centres[:, ::-1]).astype(int).T)
    near = np.zeros(image.shape, bool)
    near[at] = True
    near = ndimage.binary_dilation(near, iterations=int(sensor.pin_radius_px) + 3)
    skin = (np.hypot(xx - sensor.disc[0], yy - sensor.disc[1]) < 0.9 * sensor.disc[2]) & ~near
    tips = ndimage.uniform_filter(image, 3)[at]
    local_skin = np.array([np.median(image[skin & (np.hypot(xx - x, yy - y) < 30)]) for x, y in frame.centres])
    contrast = tips - local_skin
    assert 40 <= np.median(contrast) <= 70 and contrast.min() > 20 and contrast.max() < 90
    b, g, r = np.median(frame.image[skin], axis=0)
    assert r > g + 10 > b + 20  # brown
    # texture and shadows: the skin between pins varies as much as a third of the pins' contrast,
    # in blobs: bright spots between the pins a white top-hat (pin-sized) picks out
    assert np.std(image[skin]) > 8
    tophat = cv2.morphologyEx(cv2.GaussianBlur(image.astype(np.float32), (0, 0), 1.5), cv2.MORPH_TOPHAT,
                              cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (25, 25)))
    labels, count = ndimage.label((tophat > 12) & skin)
    assert count >= 30  # many spurious candidates, as on the real 127-pin frames (up to 58)
    clean = SyntheticTacTip.from_preset("brown-127", skin_texture=0.0, pin_shadows=0.0)
    plain = np.std(grey(clean.render().image)[skin])  # the illumination gradient alone
    assert np.std(image[skin]) ** 2 - plain ** 2 > 6.0 ** 2  # texture and shadows add > 6 grey rms


def test_radial_pad_is_small_in_a_very_bright_surround():
    sensor = SyntheticTacTip.from_preset("radial-120")
    image = sensor.render().image.astype(float)
    yy, xx = np.mgrid[0:480, 0:640]
    r = np.hypot(xx - sensor.disc[0], yy - sensor.disc[1]) / sensor.disc[2]
    assert np.median(image[r > 1.3]) > 230  # near saturation
    edge = (r > 0.9) & (r < 0.98)
    assert np.percentile(image[edge], 95) > 200  # strong glare into the disc edge
    assert np.median(image[r < 0.5]) < 60


def test_tap_uses_the_sensor_frame_rate():
    frames = list(SyntheticTacTip.from_preset("radial-120", noise_sigma=0.0).tap(Contact(3.0)))
    assert len(frames) == 115  # 0.95 s at 120 frames/s, both ends included
    np.testing.assert_allclose([f.timestamp_s for f in frames[:3]], [0.0, 1 / 120, 2 / 120])
    assert len(list(SyntheticTacTip.from_preset("tactip-127").tap(Contact(3.0), frame_rate=10.0))) == 10


def test_sources_open_a_preset():
    with open_source("synthetic:radial-120", taps=[Contact(3.0)]) as source:
        assert source.frame_rate == 120.0 and source.name == "synthetic:radial-120"
        assert source.read().image.shape == (480, 640)  # the renderer's grey frames
        assert source.truth.centres.shape == (120, 2)
    assert SyntheticSource(preset="brown-127", taps=[]).sensor.colour
    with pytest.raises(Exception, match="unknown synthetic TacTip preset"):
        SyntheticSource(preset="nope")


def test_default_renderer_is_byte_identical_to_the_samples():
    """samples/ were written by samples/make_samples.py before the presets existed: same bytes today."""
    reference = cv2.imread(str(SAMPLES / "synthetic_frame.png"), cv2.IMREAD_UNCHANGED)
    for sensor in (SyntheticTacTip(pins=331, noise_sigma=3.0, seed=0),
                   SyntheticTacTip.from_preset("tactip-331", noise_sigma=3.0, seed=0)):
        np.testing.assert_array_equal(sensor.render().image, reference)
    truth = np.load(SAMPLES / "synthetic_tap_truth.npz")
    source = SyntheticSource(SyntheticTacTip(pins=331, noise_sigma=3.0, seed=0), rest_s=0.5)
    times = truth["timestamps_s"]
    centres = np.array([source.sensor.pin_centres(source.contact_at(t))[0] for t in times], dtype=np.float32)
    np.testing.assert_array_equal(centres, truth["centres"])
    assert repr(SyntheticTacTip()) == ("SyntheticTacTip(pins=331, pad_diameter_mm=40.0, image_size=(640, 480), "
                                       "noise_sigma=4.0, glare=True, gradient=True, blur_sigma=0.0, "
                                       "jpeg_quality=None, colour=False, dark_pins=False, seed=0)")
    assert "layout='radial'" in repr(SyntheticTacTip.from_preset("radial-120"))


@pytest.mark.parametrize("options, parameter", [
    (dict(layout="spiral"), "layout"), (dict(pad_fraction=0.2), "pad_fraction"),
    (dict(pad_fraction=0.95), "pad_fraction"), (dict(pin_fraction=0.5), "pin_fraction"),
    (dict(rim_polar_deg=90.0), "rim_polar_deg"), (dict(ring_glare=5), "rim_polar_deg"),
    (dict(rim_polar_deg=77.0, ring_glare=-1), "ring_glare"), (dict(membrane_level=300.0), "membrane_level"),
    (dict(skin_texture=-1.0), "skin_texture"), (dict(veil=float("nan")), "veil"),
    (dict(skin_tint="green"), "skin_tint"), (dict(frame_rate=0.0), "frame_rate"),
    (dict(pins=17, layout="radial"), "pins")])
def test_invalid_options_name_the_parameter(options, parameter):
    with pytest.raises(ValueError, match=parameter):
        SyntheticTacTip(**options)


def test_score_counts_partial_pins_neither_for_nor_against():
    frame = preset_frame("rim-ring-331")
    visible, partial = frame.centres[frame.visible], frame.centres[frame.partial]
    assert score(visible, frame) == (1.0, 1.0, 0.0)
    recall, precision, rmse = score(np.concatenate([visible, partial]), frame)
    assert (recall, precision, rmse) == (1.0, 1.0, 0.0)
    spurious = np.concatenate([visible + [0.1, 0.0], [[5.0, 5.0], [10.0, 10.0]]])
    recall, precision, rmse = score(spurious, frame)
    assert recall == 1.0 and precision == pytest.approx(len(visible) / (len(visible) + 2))
    assert rmse == pytest.approx(0.1)
    recall, precision, _ = score(visible[::2], frame)
    assert recall == pytest.approx(np.ceil(len(visible) / 2) / len(visible)) and precision == 1.0
    assert score(np.zeros((0, 2)), frame)[:2] == (0.0, 1.0)


def test_pins_cut_by_the_image_edge_are_partial():
    sensor = SyntheticTacTip(pins=331, image_size=(320, 480), noise_sigma=0.0)  # narrower than the pad
    frame = sensor.render()
    x = frame.centres[:, 0]
    assert frame.partial.sum() >= 5 and frame.visible.sum() >= 150
    reach = 1.5 * sensor.pin_radius_px + 1.0
    assert np.all((x[frame.partial] < reach) | (x[frame.partial] > 319 - reach))
    margin = 0.3 * sensor.pin_radius_px
    assert np.all((x[frame.visible] > margin) & (x[frame.visible] < 319 - margin))
    assert np.all((x[~frame.visible & ~frame.partial] < 0) | (x[~frame.visible & ~frame.partial] > 319))
    # the part inside the image is drawn: the column at the edge is bright where a cut pin reaches it
    for i in np.flatnonzero(frame.partial):
        column = 0 if x[i] < 160 else 319
        if abs(x[i] - column) < 0.5 * sensor.pin_radius_px:
            assert frame.image[int(round(frame.centres[i, 1])), column] > 120
