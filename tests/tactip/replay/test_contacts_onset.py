"""A contact begins where the plate moves the pins, not at a step of the skin at rest long before it
(`tactip.replay._trim.trim_still`, `ONSET_STILL_FRAMES`)."""

import numpy as np

from pins import tap_signal
from tactip.replay._trim import ONSET_STILL_FRAMES, trim_still


def _field(step_at: int, quiet: int, rng) -> np.ndarray:
    """120 pins: a step of 0.8 px at ``step_at`` (every pin), ``quiet`` still frames, then a slide's drag to 12 px
    over 20 frames and back; noise 0.03 px."""
    onset = step_at + 1 + quiet
    frames = onset + 50
    field = np.zeros((frames, 120, 2))
    field[step_at:, :, 0] = 0.8
    field[onset:onset + 20, :, 0] += np.linspace(0.3, 12.0, 20)[:, None]
    field[onset + 20:onset + 30, :, 0] += np.linspace(12.0, 0.0, 10)[:, None]
    return field + rng.normal(0.0, 0.03, field.shape), onset


def test_a_step_of_the_skin_long_before_a_slide_is_not_its_onset():
    """tactip-127's tour, seed 0: the skin at rest stepped 0.5 px in one frame 44 frames before a slide, the signal
    from its rest sat between the thresholds until the slide, and the slide was found from the step."""
    rng = np.random.default_rng(0)
    for quiet in (ONSET_STILL_FRAMES, 12, 40):
        field, onset = _field(20, quiet, rng)
        signal = tap_signal(field)
        (start, stop), = trim_still([(20, onset + 30)], field, signal, low_px=0.5, high_px=1.5)
        assert abs(start - onset) <= 1, (quiet, start, onset)
        assert stop == onset + 30


def test_a_moving_onset_keeps_its_start():
    """Fewer still frames in a row than `ONSET_STILL_FRAMES` between the first motion and the high threshold (a slow
    press's onset pausing): the contact begins at the first motion, as before."""
    rng = np.random.default_rng(1)
    field, onset = _field(20, ONSET_STILL_FRAMES - 2, rng)
    signal = tap_signal(field)
    (start, _), = trim_still([(20, onset + 30)], field, signal, low_px=0.5, high_px=1.5)
    assert start == 20
