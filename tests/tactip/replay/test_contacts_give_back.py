"""A press put down right after a slide, on the shear the slide left in the skin, lets the patch under the plate go
part of the way back towards its first rest: its pins share one direction and read as a slide (issue 20, outcome
3: tactip-127's tours on the creeping skin, 1-2 presses a tour; on the replay's tracking such presses moved their
patch back 1.7-2.9 px, drag ratio 0.82-1.0). A slide drags its patch on, away from where the skin rested before it;
`find_contacts` reads a contact whose pins only went back as a press."""

import numpy as np
import pytest

from pins import tap_signal
from tactip.replay.contacts import find_contacts, tap_thresholds_px


def _pad(pins_across: int, pitch_px: float):
    """A hexagonal-ish grid of rest positions, px."""
    row, col = np.mgrid[0:pins_across, 0:pins_across]
    return np.stack([col * pitch_px + (row % 2) * pitch_px / 2, row * pitch_px * 0.866], -1).reshape(-1, 2).astype(float)


def _ramp(frames: int):
    return 0.5 * (1 - np.cos(np.pi * np.arange(1, frames + 1) / frames))


def _tour(rest, pitch_px, direction_deg, back_share, second_deg, rng):
    """A 3-pitch slide that leaves a tenth of its drag (fading off the patch), a press 2 frames after its lift
    that lets the patch go ``back_share`` of that leftover back (no spread: the worst case) and returns it at its
    lift, a rest, then a second slide along ``second_deg``; the field (px) and the truth's (start, stop, kind)."""
    centre = rest.mean(axis=0)
    width = np.ptp(rest[:, 0])
    fall = np.exp(-np.sum((rest - centre) ** 2, axis=1) / (2 * (0.3 * width) ** 2))[:, None]    # (N, 1)
    unit = np.array([np.cos(np.radians(direction_deg)), np.sin(np.radians(direction_deg))])
    second = np.array([np.cos(np.radians(second_deg)), np.sin(np.radians(second_deg))])
    drag = 3 * pitch_px * unit * fall                                       # (N, 2) at the slide's end
    frames = []
    frames += [np.zeros_like(rest)] * 10                                     # rest
    frames += [r * drag for r in _ramp(20)]                                  # slide 10-30
    frames += [drag * (1 - 0.9 * r) for r in _ramp(6)]                       # lift 30-36: a tenth left
    left = 0.1 * drag
    frames += [left] * 2                                                     # 2 frames of rest
    frames += [left * (1 - back_share * r) for r in _ramp(6)]                # press 38-50: the patch goes back
    frames += [left * (1 - back_share)] * 6
    frames += [left * (1 - back_share * (1 - r)) for r in _ramp(6)]          # its lift: the leftover again
    frames += [left] * 30                                                    # rest
    frames += [left + r * 3 * pitch_px * second * fall for r in _ramp(20)]   # second slide 86-106
    frames += [left + 3 * pitch_px * second * fall * (1 - r) for r in _ramp(6)]
    frames += [left] * 15
    field = np.array(frames) + rng.normal(0.0, 0.05, (len(frames), *rest.shape))
    return field, [(10, 36, "slide"), (38, 56, "press"), (86, 112, "slide")]


@pytest.mark.parametrize("pins_across, pitch_px, direction_deg, second_deg, seed",
                         [(11, 27.0, 90.0, 225.0, 0), (19, 17.5, 0.0, 180.0, 1), (25, 12.0, 315.0, 90.0, 2)])
def test_a_press_that_lets_the_leftover_go_back_is_a_press(pins_across, pitch_px, direction_deg, second_deg, seed):
    rng = np.random.default_rng(seed)
    rest = _pad(pins_across, pitch_px)
    field, truth = _tour(rest, pitch_px, direction_deg, 0.5, second_deg, rng)
    signal = tap_signal(field)
    bounds, kinds = find_contacts(field, signal=signal, blank=np.zeros(len(field), bool),
                                  thresholds_px=tap_thresholds_px(field, pitch_px, signal=signal), rest_positions=rest)
    assert len(bounds) == 3, bounds
    for (start, stop), kind, (begin, end, what) in zip(bounds, kinds, truth):
        assert abs(start - begin) <= 3 and abs(stop - end) <= 3, (bounds, truth)
        assert kind.kind == what, (bounds, kinds)
    off = abs((kinds[0].direction_deg - direction_deg + 180) % 360 - 180)
    assert off < 10 and abs((kinds[2].direction_deg - second_deg + 180) % 360 - 180) < 10   # against the leftover too


@pytest.mark.parametrize("pitch_px, drag_px, seed", [(29.5, 1.6, 3), (17.5, 1.5, 4)])
def test_a_drag_of_less_than_a_tenth_of_a_pitch_is_no_slide(pitch_px, drag_px, seed):
    """tactip-127's presses after a slide moved their patch 1.3-2.0 px one way (a twentieth of its 29.5 px pitch):
    a slide drags it a tenth of a pitch or more (the tours' slides 3 pitches; half a pitch is a slide)."""
    rng = np.random.default_rng(seed)
    rest = _pad(15, pitch_px)
    centre = rest.mean(axis=0)
    fall = np.exp(-np.sum((rest - centre) ** 2, axis=1) / (2 * (0.3 * np.ptp(rest[:, 0])) ** 2))[:, None]
    unit = np.array([np.cos(np.radians(290.0)), np.sin(np.radians(290.0))])
    kinds = {}
    for length in (drag_px, 0.5 * pitch_px):
        ramp = np.concatenate([np.zeros(8), _ramp(10), np.ones(6), 1 - _ramp(6), np.zeros(10)])
        field = ramp[:, None, None] * (length * unit * fall)[None]
        field = field + rng.normal(0.0, 0.05, field.shape)
        signal = tap_signal(field)
        bounds, found = find_contacts(field, signal=signal, blank=np.zeros(len(field), bool),
                                      thresholds_px=(1.0, 0.3), rest_positions=rest)
        assert len(bounds) == 1, bounds
        kinds[length] = found[0]
    assert kinds[drag_px].kind == "press" and kinds[drag_px].drag_px > 1.0     # more than a px, yet no slide
    slide = kinds[0.5 * pitch_px]
    assert slide.kind == "slide" and abs((slide.direction_deg - 290.0 + 180) % 360 - 180) < 5
