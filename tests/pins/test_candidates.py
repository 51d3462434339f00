"""The candidate parameter sets of the pin-field search (`pins._candidates`): their two threads share
the filtered images of one search and must give the runs one thread gives, bit for bit."""

import numpy as np
import pytest

import pins.lattice as lattice
from pins._candidates import _SharedCache, _evaluate, _evaluate_all
from tests.pins.conftest import TAP, preset_frame


def _searched(image):
    """Every `_evaluate_all` and `_strongest` (the coarse pass) call of one `find_pin_field` on `image`:
    (grey, disc, candidates) each."""
    calls = []

    def spy(real):
        def spied(grey, disc, candidates, cache):
            calls.append((grey, disc, list(candidates)))
            return real(grey, disc, candidates, cache)
        return spied

    with pytest.MonkeyPatch.context() as patch:
        for name in ("_evaluate_all", "_strongest"):
            patch.setattr(lattice, name, spy(getattr(lattice, name)))
        lattice.find_pin_field(image)
    return calls


def _same(a, b) -> bool:
    return (a.params == b.params and np.array_equal(a.blobs.centres, b.blobs.centres)
            and np.array_equal(a.blobs.areas, b.blobs.areas) and np.array_equal(a.blobs.contrasts, b.blobs.contrasts)
            and np.array_equal(a.reason, b.reason) and np.array_equal(a.pitch, b.pitch, equal_nan=True))


@pytest.mark.parametrize("name, contact", [("tactip-331", None), ("brown-127", TAP)])
def test_threaded_candidate_runs_equal_one_thread_bit_for_bit(name, contact):
    """Every candidate set of a search, run on the two threads sharing one cache (three times over),
    gives the blobs, verdicts and pitch that it gives alone with a cache of its own."""
    calls = _searched(preset_frame(name, contact, seed=0).image)
    assert len(calls) >= 2
    for grey, disc, candidates in calls:
        alone = [_evaluate(grey, disc, params, {}) for params in candidates]
        for _ in range(3):
            shared = _evaluate_all(grey, disc, candidates, _SharedCache())
            assert all(_same(a, b) for a, b in zip(shared, alone, strict=True))


def test_the_shared_filtered_images_are_read_only():
    """What the threads share is read-only once stored (no thread can change what another reads), and
    the threads share nothing but such a cache."""
    grey, disc, candidates = _searched(preset_frame("tactip-331", seed=0).image)[0]
    cache = _SharedCache()
    _evaluate_all(grey, disc, candidates, cache)
    arrays = [a for value in cache.values() for a in (value if isinstance(value, tuple) else (value,))]
    assert len(arrays) >= len(candidates)
    for array in arrays:
        with pytest.raises(ValueError, match="read-only"):
            array.flat[0] = 0
    with pytest.raises(TypeError, match="_SharedCache"):
        _evaluate_all(grey, disc, candidates, {})
