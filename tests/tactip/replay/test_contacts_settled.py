"""A slide's end on the creeping skin while the tracked pins catch up after the lift (issue 20, outcome 3). On
tactip-127's tours the replay's pins keep moving 0.3-0.7 px a frame for 2-3 frames after a slide's lift while the
skin has settled at what the slide left: the contact ended where they stopped, 4-7 frames late (6 of 132
contacts on the development tours). Here: the renderer's true displacements, 0.1 px of noise, and for 3 frames
after each slide's lift, a new random third of the pins off by 0.45 px in a random direction each frame (within
the noise of their neighbourhood: not outvoted). Main met 8 of 24 (3 presets x 30, 120 frames/s x seeds 0-3: slides
ending 4-6 frames late), this 24 of 24; without the jitter both 24 of 24."""

import numpy as np
import pytest

from tactip.replay._trim import trim_settled
from tests.tactip.replay.conftest import assert_contacts_are_events, contacts_of, slides_and_a_press_after_long_rests


# The cases main failed (a slide's stop 4-6 frames after the truth's).
@pytest.mark.parametrize("preset, frame_rate, seed", [("tactip-127", 30.0, 0), ("tactip-127", 120.0, 0),
                                                      ("white-dark-331", 30.0, 1), ("white-dark-331", 120.0, 0),
                                                      ("radial-led-120", 30.0, 2), ("radial-led-120", 120.0, 0)])
def test_slides_end_at_the_lift_while_the_tracked_pins_catch_up(preset, frame_rate, seed):
    rng, run, rest, displacements = slides_and_a_press_after_long_rests(preset, frame_rate, seed)
    for event in run.events:
        if event.kind != "slide":
            continue
        for frame in range(event.stop_frame, event.stop_frame + 3):   # the tracked pins catching up
            pins = rng.random(len(rest)) < 0.3
            angle = rng.uniform(0.0, 2.0 * np.pi, pins.sum())
            displacements[frame, pins] += 0.45 * np.stack([np.cos(angle), np.sin(angle)], axis=1)
    (bounds, kinds), _ = contacts_of(displacements, rest)
    assert_contacts_are_events(bounds, kinds, run.events, angle_deg=None)


def test_trim_settled_keeps_a_press_release_and_a_clean_end():
    low = 0.5
    # a slide (peak 20 px) whose signal settles at 1.4 px for 4 frames, then segment_taps' pad below low
    slide = np.array([0.2, 5, 12, 20, 9, 3, 1.4, 1.35, 1.45, 1.4, 0.1])
    # a press: a hold at its peak, then a release falling frame by frame; a clean tap falling below low
    press = np.array([0.2, 1.2, 1.8, 1.9, 1.9, 1.9, 1.5, 1.2, 0.9, 0.6, 0.1])
    clean = np.array([0.2, 4, 8, 8, 6, 3, 1.0, 0.4, 0.3, 0.2, 0.1])
    signal = np.concatenate([slide, press, clean])
    bounds = [(0, 11), (11, 22), (22, 33)]
    assert trim_settled(bounds, signal, low_px=low) == [(0, 6), (11, 22), (22, 33)]
    # fewer than 3 settled frames: kept
    assert trim_settled([(0, 8)], slide, low_px=low) == [(0, 8)]
