"""pins._motion in a slide's first lift frame on the 127-pin TacTip (issue 20, outcome 2): the field is fitted to the
pins the follow passes placed, and a few of those (a fifth on tactip-127 seeds 0 and 4) sit where they were while
their tips sprang back half a spacing. The plain least-squares fit, pulled by them, holds too few of the pins it was
fitted to and no field was used: LK started from constant-velocity guesses 0.4 spacings off, and pins swapped
(`bench/bench_slide_losses.py --onsets`). A trimmed refit (`pins._motion._trimmed`) then holds. Ground truth from the
synthetic TacTip."""

import numpy as np

import pins.track
from tests.pins.conftest import preset_sensor, tracker_on_rest


def _first_lift_frames(seed: int, monkeypatch) -> list[tuple[float, float]]:
    """Two slides of 3 pitches (0 and 180 degrees, 2 mm deep, 120 frames/s, as `bench_conditions`' slides) tracked
    from the drawn pins' true rest centres: in the first frame of each slide the field is asked for (its lift's
    first), the median distance from the truth of the visible pins needing LK, spacings: their
    constant-velocity guesses' and the guesses LK starts from."""
    s = preset_sensor("tactip-127", seed)
    s.reseed_noise(seed)
    slides = s.slides([0, 180], distance_mm=3 * s.pin_spacing_mm, indentation_mm=2.0, rest_s=0.025, press_s=0.05,
                      slide_s=0.15, lift_s=0.05, frame_rate=120.0)
    run = iter(slides)
    tracker, drawn = tracker_on_rest(s, next(run))
    calls = []
    real = pins.track.field_guesses

    def recorded(rest, reference, last_step, guess, positions, need, spacing_px):
        out = real(rest, reference, last_step, guess, positions, need, spacing_px)
        calls.append((guess.copy(), out[0], need))
        return out

    monkeypatch.setattr(pins.track, "field_guesses", recorded)
    errors = {}
    for k, f in enumerate(run, start=1):
        calls.clear()
        tracker.update(f.image)
        event = next((e for e, ev in enumerate(slides.events) if ev.start_frame <= k < ev.stop_frame), None)
        if calls and event is not None and event not in errors:
            guess, field, need = calls[0]
            pins_ = need & f.visible[drawn]
            truth = f.centres[drawn[pins_]]
            errors[event] = tuple(float(np.median(np.linalg.norm(g[pins_] - truth, axis=1))) / tracker.spacing_px
                                  for g in (guess, field))
    return list(errors.values())

def test_the_field_holds_in_a_lifts_first_frame_despite_pins_left_behind(monkeypatch):
    # Medians of the field's guesses in the two lifts' first frames, spacings (constant velocity: 0.40-0.42), main
    # 43b3857 (an affine field, no trimmed refit) -> here: seed 1 0.10, 0.21 -> 0.15, 0.15; seed 4 0.09, 0.40 -> 0.06,
    # 0.09; seed 5 0.18, 0.13 -> 0.11, 0.18. (Not yet: seeds 0, 6 and 7 each have a first lift frame whose plain fit
    # holds but steps the pins by under a third of a spacing, so no field is used there: 0.40 against 0.06-0.25
    # trimmed, `pins._motion._LEAST_STEP`.)
    for seed in (1, 4, 5):
        errors = _first_lift_frames(seed, monkeypatch)
        assert len(errors) == 2  # the case: both slides' lifts ask for the field
        for constant_velocity, field in errors:
            assert constant_velocity > 0.35
            assert field < 0.25
