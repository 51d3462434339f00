"""The start frame given again, on radial-led-120 seeds nobody tuned on (issue 20's first bar).

`tests/pins/test_track_still.py` holds the bar on seeds 0-2 (met on 0-5); started as there, on held-out
seeds 6, 9 and 10 (of 0-23) one faint pin beside an LED reflection was lost on its own rest frame (started
from the pin field, as replay starts: seeds 6 and 8 of 6-15). Its window's contrast at rest (one noisy
frame, against the plane through the window's darkest side runs) is -5.5 and -3.9 grey levels there (the
median pin's 47-49; the same pin over seeds 0-15: -5.5 to 33.8), so the tracker's bounds on a tip like at
rest (half the rest contrast and area, at most twice the area) lay above the rest measures themselves and
failed on every frame; near 0 (seeds 9, 10: 2.1 and 0.9) the area at rest was unbounded but for noise and
a noisy frame dropped the pin. Now each bound reaches as far as the rest frame's noise may have moved the
measure it comes from, and a tip whose contrast at rest lies within that reach of nothing is judged by
its contrast alone (`pins._like.bounds_at_rest`; `tests/pins/test_track_faint.py` on a small render).
"""

import pytest

from tests.pins.test_track_still import _started


@pytest.mark.parametrize("seed", [6, 9, 10])
def test_the_start_frame_given_again_loses_no_pin_on_held_out_seeds(seed):
    s, rest, drawn, tracker = _started("radial-led-120", seed)
    tracker.update(rest.image)
    assert not tracker.lost[rest.visible[drawn]].any()
