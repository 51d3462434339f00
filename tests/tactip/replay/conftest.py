"""Shared by the contacts tests: the tours' creeping skin, contacts found as replay finds them, and the check that
they are the rendered events."""

import numpy as np

from pins import median_spacing_px, tap_signal
from tactip.replay.contacts import find_contacts, tap_thresholds_px
from tactip.sim import SyntheticTacTip
from tactip.sim.sequence import Stroke

# The tours' creeping skin (bench_tour_contacts.py): a tenth of each drag kept, creeping back with a time constant
# of 1 s, and a set of 2 %.
CREEPING_SKIN = dict(residual=0.1, creep_s=1.0, set_share=0.02)


def angle_error(a, b):
    """The angle between two directions, degrees (0-180)."""
    return abs((a - b + 180.0) % 360.0 - 180.0)


def slides_and_a_press_after_long_rests(preset: str, frame_rate: float, seed: int):
    """Two 3-pitch slides, a press and a third slide after rests of 0.7-0.9 s on the creeping skin, in random
    directions of the compass: (rng, run, rest positions px, the renderer's displacements + 0.1 px noise); the
    rng goes on from there (for what a test does to the displacements)."""
    sensor = SyntheticTacTip.from_preset(preset, seed=seed)
    rng = np.random.default_rng(seed)
    angles = rng.choice(range(0, 360, 45), 3, replace=False)
    pitch = sensor.pin_spacing_mm
    strokes = [Stroke(2.0, float(angles[0]), 3 * pitch), Stroke(2.0, float(angles[1]), 3 * pitch), Stroke(2.5),
               Stroke(2.0, float(angles[2]), 3 * pitch)]
    run = sensor.sequence(strokes, rest_s=[0.1, 0.9, 0.8, 0.7, 0.3], press_s=0.05, hold_s=0.05, slide_s=0.15,
                          lift_s=0.05, frame_rate=frame_rate, **CREEPING_SKIN)
    rest = sensor.pin_centres()[0]
    return rng, run, rest, run.displacements_px() + rng.normal(0.0, 0.1, (len(run), len(rest), 2))


def contacts_of(displacements, rest, **options):
    """`find_contacts` as replay calls it (the tap signal, the thresholds from the pins' spacing, no blank frame).

    Returns its result and ``(signal, high_px, low_px)``; ``options`` go to `find_contacts` (``with_rests``)."""
    signal = tap_signal(displacements)
    high, low = tap_thresholds_px(displacements, median_spacing_px(rest), signal=signal)
    found = find_contacts(displacements, signal=signal, blank=np.zeros(len(signal), bool), thresholds_px=(high, low),
                          rest_positions=rest, **options)
    return found, (signal, high, low)


def assert_contacts_are_events(bounds, kinds, events, *, frames=3, angle_deg=15.0):
    """One contact per rendered event, its bounds within ``frames``, its kind, and a slide's direction within
    ``angle_deg`` (None: not asked)."""
    assert len(bounds) == len(events), (bounds, events)
    for (start, stop), kind, event in zip(bounds, kinds, events):
        assert abs(start - event.start_frame) <= frames and abs(stop - event.stop_frame) <= frames, (bounds, events)
        assert kind.kind == event.kind, (bounds, kinds)
        if event.kind == "slide" and angle_deg is not None:
            assert angle_error(kind.direction_deg, event.direction_deg) <= angle_deg, (kind, event)
