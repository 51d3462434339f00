"""Detection without a disc (issue 26): a flat gel's dark markers fill the frame, on a colour gradient.

The whole frame is the sensing region (`pins.frame_region`) when neither polarity shows a sensor
disc, or when the pins go on beyond the disc found; the lattice judgement takes the rectangular grid
as it takes hexagonal and radial ones; markers cut by the frame's edge are kept only when enough is in
view to measure them.
"""

import functools

import numpy as np
import pytest

from pins import NoSensorError, detect_pins, find_pin_field, frame_region
from tactip.sim import Contact, SyntheticGel
from tests.pins.conftest import score

CONTACTS = {"rest": None, "press5mm": Contact(5.0), "shear": Contact(3.0, slide_x_mm=1.5, slide_y_mm=-1.0),
            "slide3mm": Contact(2.0, slide_x_mm=-3.0)}
SEEDS = (0, 1, 2, 3)


@functools.lru_cache(maxsize=None)
def _frame(seed, contact):
    return SyntheticGel.from_preset("gelsight-mini", seed=seed).render(CONTACTS[contact])


@functools.lru_cache(maxsize=None)
def _field(seed, contact):
    return find_pin_field(_frame(seed, contact).image)


@pytest.mark.parametrize("contact", list(CONTACTS))
@pytest.mark.parametrize("seed", SEEDS)
def test_markers_found_without_a_count_meet_the_bar(seed, contact):
    f, field = _frame(seed, contact), _field(seed, contact)
    recall, precision, rmse = score(field.centres, f, gate_px=3.0)
    assert recall >= 0.99 and precision >= 0.99, (recall, precision, field.summary())
    assert rmse <= 0.1
    assert field.params.dark_pins and field.disc.whole_frame  # polarity decided; the region is the frame
    assert field.disc.mask(f.image.shape).all()


def test_the_field_is_a_rectangular_grid_at_the_marker_pitch():
    field, sensor = _field(0, "rest"), SyntheticGel.from_preset("gelsight-mini", seed=0)
    assert field.pitch_px == pytest.approx(sensor.pitch_px, rel=0.03)
    assert not (field.rejected_reason == "off lattice").any() and not (field.rejected_reason == "size").any()


@pytest.mark.parametrize("seed", range(6))
def test_markers_cut_by_the_frame_edge_are_kept_only_when_measurable(seed):
    """A marker cut through its middle is left out; a whole one is kept; a cut one kept is measured well."""
    f = SyntheticGel.from_preset("gelsight-mini", seed=seed).render()
    field = find_pin_field(f.image)
    radius = SyntheticGel.from_preset("gelsight-mini").pin_radius_px
    c = f.centres
    room = np.minimum(np.minimum(c[:, 0] + 0.5, 320 - 0.5 - c[:, 0]), np.minimum(c[:, 1] + 0.5, 240 - 0.5 - c[:, 1]))
    distance = np.min(np.hypot(*(field.centres[None] - c[:, None]).transpose(2, 0, 1)), axis=1)
    deep = f.partial & (room < radius - 1.0)  # more than a px of the disc beyond the edge
    assert not (distance[deep] < 3.0).any()  # left out
    kept = f.partial & (distance < 3.0)
    assert (distance[kept] < 0.25).all()
    assert (distance[f.visible] < 0.2).all()


def test_later_frames_found_with_the_field_parameters_over_the_frame():
    field = _field(1, "rest")
    f = _frame(1, "press5mm")
    pins = detect_pins(f.image, params=field.params, disc=field.disc)
    recall, _, rmse = score(pins, f, gate_px=3.0)
    assert recall >= 0.99 and rmse <= 0.1


def test_a_forced_dark_polarity_searches_the_whole_frame():
    f = _frame(2, "rest")
    field = find_pin_field(f.image, dark_pins=True, expected_pins=80)
    recall, precision, _ = score(field.centres, f)
    assert field.disc.whole_frame and recall >= 0.99 and precision >= 0.99 and abs(field.count_error) <= 8


def test_frame_region_holds_every_pixel():
    region = frame_region((240, 320, 3))
    assert region.whole_frame and region.mask((240, 320)).all()
    assert region.contains(np.array([[0, 0], [319, 239], [319, 0], [0, 239]])).all()


def test_a_blank_frame_is_no_sensor_even_over_the_whole_frame():
    with pytest.raises(NoSensorError, match="whole frame: 0 pins"):
        find_pin_field(np.full((240, 320, 3), 140, np.uint8))
    with pytest.raises(NoSensorError, match="nor a pin lattice filling the frame"):
        find_pin_field(np.full((240, 320), 140, np.uint8), dark_pins=True)


def test_camera_noise_filling_the_frame_is_no_sensor(seed=0):
    """Blobs of noise pass the lattice judgement in thousands, but lie on no regular lattice."""
    noise = np.random.default_rng(seed).integers(0, 256, (240, 320), dtype=np.uint8)
    with pytest.raises(NoSensorError, match="not on a regular lattice"):
        find_pin_field(noise)
    with pytest.raises(NoSensorError, match="not on a regular lattice"):
        find_pin_field(noise, dark_pins=True)


@pytest.mark.parametrize("seed", [0, 1])
def test_markers_going_on_beyond_a_false_disc_spill_over_it(seed):
    """A disc laid on a flat gel (as a gradient might make one): its markers go on beyond it in rows at
    the pitch, so the field spills over (`pins._flat._spills_over`) and the whole frame is searched."""
    from pins._flat import _spills_over
    from pins.disc import SensorDisc

    f = _frame(seed, "rest")
    grey = f.image if f.image.ndim == 2 else f.image.mean(axis=2).astype(np.uint8)
    height, width = grey.shape
    field = find_pin_field(f.image, disc=SensorDisc(width / 2, height / 2, 0.3 * height), dark_pins=True)
    assert field.count >= 7 and not field.disc.whole_frame
    assert _spills_over(grey, field)
