"""pins.track judges a faint tip fairly at rest (issue 20, outcome 1): its bounds on a tip like at rest
(`pins._like.bounds_at_rest`) ask of a tip within the rest frame's noise of nothing a contrast alone.

A tip of a few grey levels in camera noise of 5 (a faint pin beside an LED reflection, whose windowed
contrast at rest was -5.5 to 33.8 grey levels over radial-led-120's seeds, the median pin's 45-50) shows
in one noisy rest frame an area and compactness that are mostly noise; bounds set from them (half and
twice that area) rejected the pin on later frames of a still pad, or on its own rest frame. Such a tip is
now judged by its contrast alone.
"""

import numpy as np
import pytest

from pins import DetectionParams, PinTracker, SensorDisc
from pins._like import bounds_at_rest

_SIZE = 160
_PITCH_PX = 16.0


def _pins():
    """A hexagonal field of 59 pins, 16 px apart, inside a disc of radius 64 px at the frame's centre."""
    c = _SIZE / 2
    pins = np.array([(c + _PITCH_PX * (i + 0.5 * (j % 2)), c + _PITCH_PX * 0.866 * j)
                     for j in range(-4, 5) for i in range(-5, 5)])
    return pins[np.hypot(*(pins - c).T) < 0.4 * _SIZE]


def _frame(pins, contrasts, rng, sigma=5.0, radius=3.0, membrane=110.0):
    """Flat anti-aliased tips of `contrasts` grey levels on a membrane, with Gaussian noise `sigma`."""
    yy, xx = np.mgrid[0:_SIZE, 0:_SIZE].astype(float)
    image = np.full((_SIZE, _SIZE), membrane)
    for (x, y), contrast in zip(pins, contrasts):
        image += contrast * np.clip(radius + 0.5 - np.hypot(xx - x, yy - y), 0.0, 1.0)
    image += rng.normal(0.0, sigma, image.shape)
    return np.clip(np.rint(image), 0, 255).astype(np.uint8)


@pytest.mark.parametrize("seed", range(6))
def test_a_faint_tip_on_a_still_pad_is_never_lost(seed):
    # (Before: lost on a still frame on 5 of these 6 seeds, 1-5.)
    pins = _pins()
    faint = int(np.argmin(np.hypot(*(pins - _SIZE / 2).T)))
    contrasts = np.full(len(pins), 40.0)
    contrasts[faint] = 3.0
    rng = np.random.default_rng(seed)
    tracker = PinTracker(detection=DetectionParams(), disc=SensorDisc(80.0, 80.0, 78.0))
    tracker.start(_frame(pins, contrasts, rng), pins=pins)
    for _ in range(10):
        positions = tracker.update(_frame(pins, contrasts, rng))
        assert not tracker.lost.any()
        # ... and placed where it is: within a px (its window's scatter in this noise), the others within 0.3.
        error = np.hypot(*(positions - pins).T)
        assert error[faint] < 1.0
        assert np.delete(error, faint).max() < 0.3


def test_a_crisp_tip_that_vanishes_is_still_lost():
    # A crisp tip keeps the bounds of its own measures at rest: hidden, it is lost.
    pins = _pins()
    contrasts = np.full(len(pins), 40.0)
    rng = np.random.default_rng(0)
    tracker = PinTracker(detection=DetectionParams(), disc=SensorDisc(80.0, 80.0, 78.0))
    tracker.start(_frame(pins, contrasts, rng), pins=pins)
    tracker.update(_frame(pins, contrasts, rng))
    hidden = int(np.argmin(np.hypot(*(pins - _SIZE / 2).T)))
    contrasts[hidden] = 0.0
    for _ in range(3):
        tracker.update(_frame(pins, contrasts, rng))
        assert tracker.lost[hidden] and tracker.lost.sum() == 1


def test_bounds_at_rest_are_the_ratios_but_for_a_tip_within_the_noise_of_nothing():
    area, contrast, compactness = np.array([30.0, 30.0, 30.0]), np.array([45.0, 6.0, -4.0]), np.array([1.0, 1.0, 1.0])
    at_least, at_most = bounds_at_rest(area, contrast, compactness, 0.0)
    np.testing.assert_allclose(at_least[:, :2], [[15.0, 15.0], [22.5, 3.0], [0.6, 0.6]])
    np.testing.assert_allclose(at_most[:2], [60.0, 60.0])
    assert not np.isfinite(at_most[2])  # no contrast at rest: no area to bound by
    at_least, at_most = bounds_at_rest(area, contrast, compactness, 2.0)  # a reach of 10 grey levels
    # The crisp tip keeps its ratios; the faint ones are bounded by their contrast alone, less the reach.
    np.testing.assert_allclose(at_least[:, 0], [15.0, 22.5, 0.6])
    assert at_most[0] == 60.0
    np.testing.assert_allclose(at_least[1, 1:], [-4.0, -14.0])
    assert np.isneginf(at_least[[0, 2]][:, 1:]).all() and np.isposinf(at_most[1:]).all()
    # A window off the image at rest (NaN) is like nothing.
    at_least, at_most = bounds_at_rest(*np.full((3, 1), np.nan), 2.0)
    assert not np.logical_and.reduce(np.ones((3, 1)) >= at_least, axis=0)[0]
