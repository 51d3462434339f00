"""pins.detect: recall, precision and centroid accuracy against the renderer's ground truth."""

import cv2
import numpy as np
import pytest

from pins import DetectionParams, NoSensorError, SensorDisc, detect_blobs, detect_pins
from tactip.sim import Contact
from tests.pins.conftest import TAP, frame, match, sensor


@pytest.mark.parametrize("pins", [331, 532])
@pytest.mark.parametrize("contact", [None, TAP, Contact(indentation_mm=3.0, gap_width_mm=5.0, gap_offset_mm=-4.0)],
                         ids=["rest", "tap5mm", "tap3mm-offset"])
def test_detection_meets_the_bar(pins, contact):
    f = frame(pins, contact)
    recall, precision, rmse = match(detect_pins(f.image), f.centres[f.visible])
    assert recall >= 0.995 and precision >= 0.995
    assert rmse <= 0.15


@pytest.mark.parametrize("contact", [None, TAP], ids=["rest", "tap5mm"])
def test_dark_marker_polarity(contact):
    f = frame(331, contact, dark_pins=True)
    recall, precision, rmse = match(detect_pins(f.image, dark_pins=True), f.centres[f.visible])
    assert recall >= 0.995 and precision >= 0.995 and rmse <= 0.15
    # The wrong polarity finds no disc (a light disc on a dark surround) rather than wrong pins.
    with pytest.raises(NoSensorError):
        detect_pins(f.image)


def test_127_pins_and_bgr_input():
    f = frame(127)
    grey = detect_pins(f.image)
    bgr = detect_pins(cv2.cvtColor(f.image, cv2.COLOR_GRAY2BGR))
    assert np.array_equal(grey, bgr)
    recall, precision, rmse = match(grey, f.centres[f.visible])
    assert recall == 1.0 and precision == 1.0 and rmse <= 0.15


def test_blank_disc_gives_empty_array():
    s = sensor(331)
    blank = s.render(hidden=np.ones(s.n_pins, dtype=bool)).image
    pins = detect_pins(blank)
    assert pins.shape == (0, 2) and pins.dtype == np.float64


def test_no_disc_raises():
    with pytest.raises(NoSensorError):
        detect_pins(np.full((480, 640), 25, np.uint8))


def test_output_sorted_and_inside_disc():
    f = frame(331, TAP)
    disc = SensorDisc(*sensor(331).disc)
    pins = detect_pins(f.image, disc=disc)
    assert np.all(disc.contains(pins))
    order = np.lexsort((pins[:, 0], pins[:, 1]))
    assert np.array_equal(order, np.arange(len(pins)))


def test_knobs_equal_params():
    image = frame(331, TAP).image
    assert np.array_equal(detect_pins(image, offset=8.0, blur_sigma_px=1.5),
                          detect_pins(image, params=DetectionParams(offset=8.0, blur_sigma_px=1.5)))


def _two_touching_pins(distance_px: float, radius_px: float = 5.0):
    """Two anti-aliased discs that touch, on a dark disc in a bright surround (1/16 px precision)."""
    image = np.full((240, 320), 200, np.uint8)
    cv2.circle(image, (160, 120), 100, 30, -1, cv2.LINE_AA)
    scale = 16
    centres = np.array([[150.3, 117.6], [150.3 + distance_px * 0.8, 117.6 + distance_px * 0.6]])
    for x, y in centres:
        cv2.circle(image, (int(round(x * scale)), int(round(y * scale))), int(radius_px * scale), 210, -1,
                   cv2.LINE_AA, shift=4)
    return image, centres


@pytest.mark.parametrize("distance_px, split_radius_px", [(11.0, 2.0), (10.0, 2.5)])
def test_touching_pins_are_split(distance_px, split_radius_px):
    image, centres = _two_touching_pins(distance_px)
    pins = detect_pins(image, split_radius_px=split_radius_px)
    # Each half of a touching pair keeps its centre to a fraction of a px.
    recall, precision, rmse = match(pins, centres, gate_px=1.0)
    assert len(pins) == 2 and recall == precision == 1.0 and rmse < 0.3
    # Without splitting, the pair is one blob.
    assert len(detect_pins(image, split_radius_px=0.0)) < 2


def test_centroid_is_sub_pixel():
    for dx, dy in [(0.0, 0.0), (0.25, 0.5), (0.5, -0.375), (-0.125, 0.75)]:
        image, centres = _two_touching_pins(20.0)  # well apart
        shifted = cv2.warpAffine(image, np.float32([[1, 0, dx], [0, 1, dy]]), image.shape[::-1],
                                 flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REPLICATE)
        recall, _, rmse = match(detect_pins(shifted), centres + [dx, dy], gate_px=1.0)
        assert recall == 1.0 and rmse < 0.05


def test_blobs_report_areas_and_fills():
    blobs = detect_blobs(frame(331).image)
    assert blobs.centres.shape == (331, 2)
    assert blobs.areas.shape == blobs.fills.shape == (331,)
    assert np.all((blobs.fills > 0.45) & (blobs.fills <= 1.0))
    assert blobs.candidates >= 331


@pytest.mark.parametrize("field, value", [("block_size_px", 4), ("block_size_px", 1), ("blur_sigma_px", -1.0),
                                          ("min_area_px", 0), ("min_fill", 0.0), ("max_aspect", 0.5),
                                          ("rim_margin_px", -1.0), ("split_radius_px", -0.5)])
def test_params_validated_by_name(field, value):
    with pytest.raises(ValueError, match=field):
        DetectionParams(**{field: value})


def test_params_round_trip_through_dict():
    params = DetectionParams(offset=7.5, dark_pins=True)
    assert DetectionParams(**params.to_dict()) == params


def test_weighted_sums_by_row_runs_equal_sums_by_pixel(rng):
    from pins.detect import _weighted_sums
    width, count = 7, 5
    # Sparse pixels with runs of one label that reach the end of a row and go on in the next one.
    index = np.sort(rng.choice(20 * width, 90, replace=False))
    index = np.union1d(index, [2 * width - 1, 2 * width, 2 * width + 1])
    lab = rng.integers(1, count, len(index))
    lab[np.searchsorted(index, [2 * width - 1, 2 * width, 2 * width + 1])] = 3
    lab[10:30] = 2  # long runs across rows
    weight = rng.uniform(0.0, 50.0, len(index))
    ys, xs = np.divmod(index, width)
    expected = [np.bincount(lab, weights=weight * f, minlength=count) for f in (1.0, xs, ys)]
    for got, want in zip(_weighted_sums(index, lab, weight, width, count), expected):
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-9)


def test_detection_does_not_depend_on_what_was_detected_before():
    """The disc's mask and neighbourhood coverage are cached per disc (rounded to 1e-3 px) and frame
    size: a detection gives the same blobs with the caches cold and after detections of other frames,
    discs and blocks filled them, including a disc 0.4e-3 px away (the same key)."""
    from pins.detect import _inverse_coverage_cached, _roi_cached

    f = frame(331)
    disc = SensorDisc(319.6, 239.4, 206.3)
    near = SensorDisc(319.6 + 4e-4, 239.4 - 4e-4, 206.3 + 4e-4)
    params = DetectionParams(block_size_px=21)

    def blobs(d):
        found = detect_blobs(f.image, disc=d, params=params)
        return np.concatenate([found.centres.ravel(), found.areas, found.contrasts])

    _roi_cached.cache_clear()
    _inverse_coverage_cached.cache_clear()
    cold, cold_near = blobs(disc), blobs(near)
    _roi_cached.cache_clear()
    _inverse_coverage_cached.cache_clear()
    cold_near_first = blobs(near)
    for other in (frame(127).image, frame(532, TAP).image, f.image[:400, :600]):
        for d in (SensorDisc(300.0, 230.0, 180.0), disc, near):
            for block in (15, 21, 41):
                detect_blobs(other, disc=d, params=params.replace(block_size_px=block))
    assert np.array_equal(blobs(disc), cold) and np.array_equal(blobs(near), cold_near)
    assert np.array_equal(cold_near_first, cold_near)
