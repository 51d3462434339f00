"""The polarity probes of the pin-field search (`pins.lattice._other_keeps_more`): `pins._candidates._keeps_more`
judges a probe's blobs only when there are more of them than the field's pins, and must answer as the whole
run does (``_evaluate(...).kept.sum() > count``) for every count."""

import numpy as np
import pytest

import pins.lattice as lattice
from pins._candidates import _evaluate, _keeps_more
from tests.pins.conftest import TAP, preset_frame


def _probes(image):
    """Every `_keeps_more` call of one `find_pin_field` on `image`: (grey, disc, params, count) each."""
    calls = []
    real = lattice._keeps_more

    def spy(grey, disc, params, cache, count):
        calls.append((grey, disc, params, count))
        return real(grey, disc, params, cache, count)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(lattice, "_keeps_more", spy)
        lattice.find_pin_field(image)
    return calls


@pytest.mark.parametrize("name, contact, seed", [("radial-led-120", None, 0), ("radial-led-120", TAP, 1),
                                                  ("tactip-127", None, 2), ("radial-led-120", None, 3)])
def test_keeps_more_answers_as_the_whole_run(name, contact, seed):
    """For each probe of a search, at the field's count and at counts round the probe's own blob and kept
    counts (where the shortcut and the judgement part), `_keeps_more` says what the judged run says."""
    calls = _probes(preset_frame(name, contact, seed=seed).image)
    assert calls
    for grey, disc, params, count in calls:
        run = _evaluate(grey, disc, params, {})
        kept, blobs = int(run.kept.sum()), len(run.blobs.centres)
        for n in sorted({count, kept - 1, kept, kept + 1, blobs - 1, blobs, max(blobs - kept, 0)}):
            if n >= 0:
                assert _keeps_more(grey, disc, params, {}, n) == (kept > n), (name, seed, n, kept, blobs)


def test_the_judgement_is_skipped_only_where_it_cannot_keep_more():
    """On radial-led-120 the second probe (sqrt(3) pitches) detects fewer blobs than the field's pins (no
    judgement needed) and the first more (judged): both paths are taken, and the first keeps fewer than
    the field (a bright-pin sensor, not the other polarity's)."""
    calls = _probes(preset_frame("radial-led-120", seed=0).image)
    blobs = [len(_evaluate(grey, disc, params, {}).blobs.centres) - count for grey, disc, params, count in calls]
    assert len(calls) == 2 and blobs[0] > 0 >= blobs[1]
    grey, disc, params, count = calls[0]
    assert not _keeps_more(grey, disc, params, {}, count)
    assert np.count_nonzero(_evaluate(grey, disc, params, {}).kept) < count
