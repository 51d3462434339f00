"""Shared by the contacts tests: the tours' creeping skin, contacts found as replay finds them, and the check that
they are the rendered events."""

import numpy as np

from pins import tap_signal
from tactip.replay.contacts import find_contacts, tap_thresholds_px

# The tours' creeping skin (bench_tour_contacts.py): a tenth of each drag kept, creeping back with a time constant
# of 1 s, and a set of 2 %.
CREEPING_SKIN = dict(residual=0.1, creep_s=1.0, set_share=0.02)


def angle_error(a, b):
    """The angle between two directions, degrees (0-180)."""
    return abs((a - b + 180.0) % 360.0 - 180.0)


def contacts_of(displacements, rest, **options):
    """`find_contacts` as replay calls it (the tap signal, the thresholds from the pins' spacing, no blank frame).

    Returns its result and ``(signal, high_px, low_px)``; ``options`` go to `find_contacts` (``with_rests``)."""
    spacing = float(np.median(np.sort(np.linalg.norm(rest[:, None] - rest[None], axis=2), axis=1)[:, 1]))
    signal = tap_signal(displacements)
    high, low = tap_thresholds_px(displacements, spacing, signal=signal)
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
