"""`match_by_propagation`: pins matched from a rest image to one deep press (no frames between), against truth."""

import numpy as np
import pytest

from pins import detect_pins, find_pin_field, match_by_propagation, median_spacing_px
from tactip.sim import SyntheticTacTip
from tactip.sim.contact import Contact


@pytest.mark.parametrize("preset", ["tactip-331", "tactip-127", "radial-led-120", "dark-331"])
@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("contact", [Contact(5.0), Contact(4.0, gap_width_mm=3.0)], ids=["deep", "gap"])
def test_a_deep_press_is_matched_pin_for_pin(preset, seed, contact):
    sensor = SyntheticTacTip.from_preset(preset, seed=seed)
    rest = sensor.render()
    field = find_pin_field(rest.image)
    pressed = sensor.render(contact)
    # the true identity of each pin found at rest, and where that pin truly is in the pressed image
    truth = np.argmin(np.linalg.norm(field.centres[:, None] - rest.centres[None], axis=2), axis=1)
    moved_true = pressed.centres[truth]
    step = np.linalg.norm(moved_true - field.centres, axis=1)
    spacing = median_spacing_px(field.centres)
    assert step.max() > 0.25 * spacing  # a step frame-to-frame nearest-blob matching gets wrong near the rim
    found = match_by_propagation(field.centres, detect_pins(pressed.image, params=field.params, disc=field.disc),
                                 spacing_px=spacing)
    matched = np.isfinite(found[:, 0])
    visible = pressed.visible[truth]
    assert matched[visible].mean() >= 0.9
    error = np.linalg.norm(found[matched] - moved_true[matched], axis=1)
    assert error.max() < 1.0, np.sort(error)[-5:]  # no pin matched to its neighbour's blob


def test_nothing_to_match_gives_nan():
    rest = np.array([[0.0, 0.0], [10.0, 0.0]])
    assert np.isnan(match_by_propagation(rest, np.zeros((0, 2)), spacing_px=10.0)).all()
    assert match_by_propagation(np.zeros((0, 2)), rest, spacing_px=10.0).shape == (0, 2)
