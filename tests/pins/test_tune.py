"""pins.tune: auto-tuning recovers the pin count from deliberately poor starting parameters."""

import numpy as np
import pytest

from pins import DetectionParams, PinsError, detect_pins, expected_spacing_px, find_pin_field, find_sensor_disc, tune_detection
from tests.pins.conftest import TAP, frame, match

# Far off for every preset: blurred to mush, a tiny block, a huge offset, areas no pin has.
POOR = DetectionParams(blur_sigma_px=6.0, block_size_px=3, offset=80.0, min_area_px=400, max_area_px=500)


@pytest.mark.parametrize("pins", [127, 331, 532])
def test_tuning_recovers_the_expected_count(pins):
    f = frame(pins)
    assert len(detect_pins(f.image, params=POOR)) < pins // 2
    params = tune_detection(f.image, pins, start=POOR)
    found = detect_pins(f.image, params=params)
    assert abs(len(found) - pins) <= 0.01 * pins
    recall, precision, rmse = match(found, f.centres[f.visible])
    assert recall >= 0.995 and precision >= 0.995 and rmse <= 0.15


def test_tuned_parameters_work_under_contact():
    params = tune_detection(frame(331).image, 331, start=POOR)
    f = frame(331, TAP)
    recall, precision, rmse = match(detect_pins(f.image, params=params), f.centres[f.visible])
    assert recall >= 0.995 and precision >= 0.995 and rmse <= 0.15


def test_tuning_keeps_dark_polarity():
    f = frame(331, dark_pins=True)
    params = tune_detection(f.image, 331, start=POOR.replace(dark_pins=True))
    assert params.dark_pins
    assert abs(len(detect_pins(f.image, params=params)) - 331) <= 3


def test_impossible_count_is_a_clear_error():
    with pytest.raises(PinsError, match="1000 pins"):
        tune_detection(frame(331).image, 1000)


def test_expected_spacing_scales_with_pin_count():
    disc = find_sensor_disc(frame(331).image)
    spacing = [expected_spacing_px(disc, n) for n in (127, 331, 532)]
    assert spacing[0] > spacing[1] > spacing[2]
    # Four times the pins in the same disc: half the spacing.
    assert expected_spacing_px(disc, 400) == pytest.approx(expected_spacing_px(disc, 100) / 2)


@pytest.mark.parametrize("kwargs, name", [({"expected_pins": 0}, "expected_pins"),
                                          ({"expected_pins": 331, "tolerance": 1.5}, "tolerance")])
def test_arguments_validated_by_name(kwargs, name):
    with pytest.raises(ValueError, match=name):
        tune_detection(np.zeros((48, 64), np.uint8), **kwargs)


def test_a_count_confirms_where_pins_are_hidden():
    """A rim ring hides 6 of 331 pins: the count confirms the field (it used to make tuning fail)."""
    from tests.pins.conftest import preset_frame, score

    f = preset_frame("rim-ring-331")
    params = tune_detection(f.image, 331)
    recall, precision, rmse = score(detect_pins(f.image, params=params), f)
    assert recall >= 0.99 and precision >= 0.97 and rmse <= 0.1
    # A tolerance tighter than the hidden pins refuses, saying how far off the field is: 6 pins are
    # hidden and some of the 12 the ring cuts are too little of a tip to find.
    found = find_pin_field(f.image).count
    assert 331 - 6 - 12 <= found <= 331 - 6
    with pytest.raises(PinsError, match=rf"{found} pins \({found - 331}, -[23]%"):
        tune_detection(f.image, 331, tolerance=0.01)


@pytest.mark.parametrize("count", [1, 2, 5])
def test_a_tiny_count_is_refused_in_one_line(count):
    with pytest.raises(PinsError, match=f"to {count} pins: the pin lattice has 331 pins") as info:
        tune_detection(frame(331).image, count)
    assert "\n" not in str(info.value) and "count right" in str(info.value)
