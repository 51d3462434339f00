"""pins.skin_rest: a press that follows a slide's lift at once (no still frame between them, tactip-127's tours) is a
contact of its own, measured from what the slide left (issue 20, outcome 3; retire23: what the slide left in the skin,
on more pins than the press moves, hid the press in the tap signal's percentile, and main took a rest in the press's
hold: the press merged into the slide and its release read as a contact). Ground truth: the field is drawn."""

import numpy as np

from pins import segment_taps, skin_rest, tap_signal

LOW, HIGH = 0.5, 1.5
SLIDE, PRESS = (5, 18), (18, 38)  # frames [start, stop) of the drawn contacts


def _field(rng: np.random.Generator) -> np.ndarray:
    """(60, 100, 2) px: a 10 x 10 grid (10 px apart) dragged +x by up to 30 px over frames 5-14, lifted in frames 15-17
    leaving 8 px in the 60 pins of the contact's patch, then at once pressed (frames 18-37): the 16 pins nearest the
    patch's centre pushed out from it by up to 3 px (0.75 px a frame), held, released; noise 0.03 px."""
    y, x = np.mgrid[0:10, 0:10].reshape(2, -1) * 10.0
    patch = x < 60.0
    centre = np.array([30.0, 45.0])
    outward = np.stack([x, y], axis=1) - centre
    pressed = np.argsort(np.hypot(*outward.T))[:16]
    outward = outward[pressed] / np.maximum(np.hypot(*outward[pressed].T), 1.0)[:, None]
    field = np.zeros((60, 100, 2))
    drag = np.concatenate([np.linspace(0.0, 30.0, 10), [24.0, 16.0, 8.0]])  # frames 5-17
    field[5:18, patch, 0] = drag[:, None]
    field[18:, patch, 0] = 8.0
    depth = np.concatenate([np.linspace(0.75, 3.0, 4), np.full(12, 3.0), np.linspace(2.25, 0.0, 4)])  # frames 18-37
    field[18:38, pressed] += depth[:, None, None] * outward[None]
    return field + rng.normal(0.0, 0.03, field.shape)


def test_press_right_after_a_slide_is_its_own_contact():
    for seed in range(4):
        field = _field(np.random.default_rng(seed))
        rest = skin_rest(field, low_px=LOW, high_px=HIGH)
        bounds = segment_taps(tap_signal(field - rest), high_px=HIGH, low_px=LOW, pad_frames=0, min_frames=1,
                              merge_gap_frames=0)
        presses = [(a, b) for a, b in bounds if a >= SLIDE[1] - 2]
        assert len(presses) == 1, (seed, bounds)  # main: [(6, 22), (34, 60)]
        assert abs(presses[0][0] - PRESS[0]) <= 2 and abs(presses[0][1] - PRESS[1]) <= 2, (seed, bounds)
