"""pins.track on a pad cut by the frame's edge (issue 20, outcome 1): a pin whose tip is whole in the frame is
never lost at rest because its window reaches beyond the frame; a pin the edge cuts stays out.

Before, the windows of pins whose tips lay a few px inside the edge (closer than half a pin spacing) did not
fit in the crop, and `PinTracker.update` on the very frame it started from lost them (tactip-127 cut by the
bottom edge: 8 of 120, tips 4-7 px inside it). The crop now grows by replicated border beyond the frame.
"""

import math

import numpy as np
import pytest

from pins import DetectionParams, PinTracker, SensorDisc
from tactip.sim import SyntheticTacTip
from tests.pins.conftest import cropped_frame


def _cut_near_a_tip(name: str, seed: int, sides: str, gap_px: float):
    """A rest frame of preset `name` whose edge on each of `sides` lies `gap_px` beyond the whole tip (radius
    and 1.5 px edge ramp, as `cropped_frame` counts it visible) of the pin nearest 0.55 disc radii out on
    that side: (cut frame with its truth, sensor, its disc in the cut frame, half the windows' side, px)."""
    sensor = SyntheticTacTip.from_preset(name, seed=seed)
    f = sensor.render()
    width, height = sensor.image_size
    cx, cy, radius = sensor.disc
    reach = sensor.pin_radius_px + 1.5 + gap_px
    visible = f.centres[f.visible]

    def pin_towards(dx, dy):
        return visible[np.argmin(np.hypot(*(visible - (cx + 0.55 * radius * dx, cy + 0.55 * radius * dy)).T))]

    x0, y0, x1, y1 = 0, 0, width, height
    if "left" in sides:
        x0 = math.floor(pin_towards(-1, 0)[0] - reach)
    if "right" in sides:
        x1 = math.ceil(pin_towards(1, 0)[0] + reach) + 1
    if "top" in sides:
        y0 = math.floor(pin_towards(0, -1)[1] - reach)
    if "bottom" in sides:
        y1 = math.ceil(pin_towards(0, 1)[1] + reach) + 1
    cut = cropped_frame(f, x0, y0, x1, y1, sensor.pin_radius_px)
    return cut, sensor, SensorDisc(cx - x0, cy - y0, radius)


def _room_px(centres, image):
    """Each centre's distance to the nearest frame edge (the pixel grid's outer border), px."""
    height, width = image.shape[:2]
    x, y = centres[:, 0], centres[:, 1]
    return np.minimum(np.minimum(x + 0.5, width - 0.5 - x), np.minimum(y + 0.5, height - 0.5 - y))


@pytest.mark.parametrize("name, sides, seed, gap_px", [
    ("tactip-127", "bottom", 42, 0.5), ("brown-127", "bottom", 42, 1.5), ("tactip-127", "left+top", 1, 1.0),
    ("dark-331", "right", 2, 0.5), ("tactip-331", "top+right", 3, 0.0), ("dense-1000", "left", 4, 0.0),
    ("dense-1000", "right+bottom", 5, 0.5)])
def test_a_whole_tip_next_to_the_frame_edge_is_kept_on_its_start_frame(name, sides, seed, gap_px):
    f, sensor, disc = _cut_near_a_tip(name, seed, sides, gap_px)
    given = f.centres[f.visible]
    tracker = PinTracker(detection=DetectionParams(dark_pins=sensor.dark_pins), disc=disc)
    rest = tracker.start(f.image, pins=given)
    # The case: whole tips whose windows reach beyond the frame (they were lost there).
    assert (_room_px(given, f.image) < tracker.windows.half_px).sum() >= 1
    positions = tracker.update(f.image)
    assert not tracker.lost.any()
    assert np.abs(positions - rest).max() < 0.05      # the same estimator on the same pixels
    assert np.abs(positions - given).max() < 1.0      # and where the tips are
    for _ in range(3):                                # and on still frames with fresh noise
        positions = tracker.update(f.image)
    assert not tracker.lost.any() and not tracker.retired.any()


@pytest.mark.parametrize("name, sides, seed", [("tactip-127", "bottom", 7), ("white-dark-331", "left+bottom", 8)])
def test_a_pin_the_frame_edge_cuts_stays_out(name, sides, seed):
    """Given the tips the edge cuts too (their centres in the frame), those it cuts near their centres are
    reported lost, never placed on the replicated border; the whole ones are kept."""
    radius = SyntheticTacTip.from_preset(name, seed=seed).pin_radius_px
    # The edge a quarter of a tip radius beyond the chosen pins' centres.
    f, sensor, disc = _cut_near_a_tip(name, seed, sides, -0.75 * radius - 1.5)
    room = _room_px(f.centres, f.image)
    drawn = (f.visible | f.partial) & (room > 0)
    given, whole = f.centres[drawn], f.visible[drawn]
    halved = room[drawn] < 0.5 * radius
    assert halved.sum() >= 1
    tracker = PinTracker(detection=DetectionParams(dark_pins=sensor.dark_pins), disc=disc)
    tracker.start(f.image, pins=given)
    tracker.update(f.image)
    assert tracker.lost[halved].all()
    assert not tracker.lost[whole].any()


def test_the_numpy_path_keeps_them_as_the_compiled_kernels_do(monkeypatch):
    """``TACTIP_KERNELS=numpy`` (the reference of the compiled kernels) keeps the same pins at the same places."""
    f, sensor, disc = _cut_near_a_tip("tactip-127", 11, "top", 0.5)
    given = f.centres[f.visible]
    runs = []
    for kernels in ("compiled", "numpy"):
        if kernels == "numpy":
            monkeypatch.setenv("TACTIP_KERNELS", "numpy")
        tracker = PinTracker(detection=DetectionParams(dark_pins=sensor.dark_pins), disc=disc)
        tracker.start(f.image, pins=given)
        runs.append(tracker.update(f.image))
        assert not tracker.lost.any(), kernels
    assert np.abs(runs[0] - runs[1]).max() < 1e-9
