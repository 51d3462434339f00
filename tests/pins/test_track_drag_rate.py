"""pins.track through slides filmed at 30 frames/s (issue 20, outcome 2): the skin under the plate steps a spacing a
frame in the drag, beyond what any guess keeps from a neighbour's tip. The frame's motion field (`pins._motion`),
fitted to the slow pins placed first, steps the others by a fifth of that and would pull their guesses back
towards standing still: it is used only where it steps them by a third of a spacing or more (a lift's spring-back),
so such slides swap no more pins than with constant-velocity guesses alone. Ground truth from the synthetic TacTip."""

import pins.track
from tests.pins.conftest import apart_swaps_through_slides


def _constant_velocity_guesses(rest, reference, last_step, guess, positions, need, spacing_px):
    return guess, positions, need


def test_slides_at_30_frames_a_second_swap_no_more_than_with_constant_velocity_guesses(monkeypatch):
    # Apart pin-frames, tactip-127 seeds 0/1/2, three slides: 357/349/369 with the field on every LK retry frame
    # (main 0a5c057), 308/317/290 with constant-velocity guesses alone, and as many with the field's gate.
    directions = [0, 90, 225]
    field = [apart_swaps_through_slides("tactip-127", seed, directions, 30.0)[0] for seed in (0, 1, 2)]
    monkeypatch.setattr(pins.track, "field_guesses", _constant_velocity_guesses)
    alone = [apart_swaps_through_slides("tactip-127", seed, directions, 30.0)[0] for seed in (0, 1, 2)]
    assert sum(field) <= 1.03 * sum(alone)
