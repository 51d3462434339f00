"""pins._follow through slides at 120 frames/s (issue 20, outcome 2): in the skin squeezed ahead of the plate a
pin's re-centred window may hold its own tip and one approaching from behind (its pin often missing) and settle
between the two; the constant-velocity guess then carries that pull on until the pin sits on the other's tip.
Tips in such windows are assigned to the pins expected there one-to-one (`_Following._part_tips`), so fewer
pins are placed on another pin's tip. Ground truth from the synthetic TacTip, both polarities."""

import pytest

from pins._follow import _Following
from tests.pins.conftest import apart_swaps_through_slides


def _no_parting(self, crop, positions, pins, start, filled, held_from=None):
    return None


@pytest.mark.parametrize("preset", ["tactip-331", "dark-331"])
def test_tips_assigned_one_to_one_swap_fewer_pins_in_slides(monkeypatch, preset):
    # Diagonal slides, seed 0 (main 1414123 -> parted): tactip-331 66 -> 33 apart pin-frames, dark-331 87 -> 63;
    # slides along the axes gain less (90 -> 86, 125 -> 128); bench_slide_losses --onsets has the 8 directions.
    directions = [45, 135, 225, 315]
    parted = apart_swaps_through_slides(preset, 0, directions, 120.0)[0]
    monkeypatch.setattr(_Following, "_part_tips", _no_parting)
    merged = apart_swaps_through_slides(preset, 0, directions, 120.0)[0]
    assert parted <= 0.85 * merged
