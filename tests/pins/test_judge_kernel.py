"""pins._jit_judge: the lattice judgement's compiled verdict passes and field groups give the NumPy reference's
verdicts, field groups, pitches and nearest distances, bit for bit, on random blob sets (impostors, doubles,
area ratios at the thresholds) and on the field search's own blob sets of preset frames; where the kernel is
unsure (a tie between neighbours) it says so and the reference judges. (Its speed: bench/bench_replay_judge.py.)"""

import numpy as np
import pytest

import pins._judge as judge
import pins._kernels
import pins._candidates as candidates
from pins import find_pin_field
from tests.pins.conftest import preset_frame
from tests.pins.test_judge_speed import _blob_set

kernels = pins._kernels.compiled("_jit_judge")
pytestmark = pytest.mark.skipif(kernels is None, reason="Numba missing or TACTIP_KERNELS=numpy: no kernels to test")


def _reference(function, *args):
    """`function(*args)` with the NumPy reference chosen."""
    before = pins._kernels.choose("numpy")
    try:
        return function(*args)
    finally:
        pins._kernels.choose(before)


def _same_passes(got, want):
    assert len(got) == len(want) == 5
    for a, b in zip(got, want):
        if b is None:
            assert a is None
        else:
            np.testing.assert_array_equal(a, b)


def _status(blobs, sharpness) -> int:
    return int(kernels.judge_passes(np.ascontiguousarray(blobs.centres, dtype=np.float64), blobs.areas.astype(float),
                                    np.asarray(blobs.fills, float), np.maximum(blobs.contrasts, 1e-6),
                                    np.asarray(sharpness, float), *judge._judge_logs())[-1])


def test_the_kernel_compiles_the_judges_constants():
    import pins._jit_judge as jit

    for name in ("_KEPT", "_OFF", "_SIZE", "_CONTRAST", "_NEIGHBOURS", "_SIZE_RANGE", "_MIN_FILL", "_FILL_AREA",
                 "_MIN_CONTRAST", "_MIN_SHARPNESS", "_TOO_CLOSE", "_LINK", "_MIRROR", "_MIN_ANCHORS", "_WEAK_CONTRAST",
                 "_WEAK_SIZE", "_INWARD", "_SPREAD", "_MIN_PINS", "_AREA_SLACK"):
        assert getattr(jit, name) == getattr(judge, name), name
    # The ratios whose NumPy logs it is given are the thresholds' ratios (a blob's area over its neighbours').
    ratios = (judge._WEAK_SIZE[0], 1 / judge._WEAK_SIZE[0], judge._WEAK_SIZE[1], 1 / judge._WEAK_SIZE[1])
    assert np.array_equal(jit.EXACT_X, np.array(ratios))


@pytest.mark.parametrize("seed", range(40))
def test_the_compiled_passes_are_the_references_on_random_blob_sets(seed):
    """Verdicts, the active blobs, their field groups, pitches and nearest distances: the reference's. A set the
    kernel leaves to the reference has a tie between neighbours (the doubles of `_blob_set` are one offset
    apart), and the judgement is then the reference's."""
    blobs, sharpness = _blob_set(seed)
    want = _reference(judge._passes, blobs, sharpness)
    got = judge._compiled_passes(blobs, sharpness)
    if got is None:
        assert _status(blobs, sharpness) == 1
    else:
        _same_passes(got, want)
    reason, pitch = judge._judge_lattice(blobs, sharpness)
    want_reason, want_pitch = _reference(judge._judge_lattice, blobs, sharpness)
    assert np.array_equal(reason, want_reason)
    assert np.array_equal(pitch, want_pitch, equal_nan=True)


def test_the_kernel_judges_most_random_blob_sets_itself():
    """Ties are rare: the kernel leaves few sets to the reference (and area ratios at a threshold, 9/5 and
    the like among integer areas, met in about half of these sets, it judges itself)."""
    statuses = [_status(*_blob_set(seed)) for seed in range(40)]
    assert statuses.count(0) >= 35
    assert 2 not in statuses


def test_a_twin_blob_is_left_to_the_reference():
    """Two blobs at one place: which the tree lists first is its own choice, so the kernel does not judge."""
    blobs, sharpness = _blob_set(3)
    twin = np.vstack([blobs.centres, blobs.centres[:1]])
    blobs = type(blobs)(twin, np.append(blobs.areas, blobs.areas[0]), np.append(blobs.fills, blobs.fills[0]),
                        blobs.candidates + 1, np.append(blobs.contrasts, blobs.contrasts[0]))
    sharpness = np.append(sharpness, sharpness[0])
    assert _status(blobs, sharpness) == 1
    assert judge._compiled_passes(blobs, sharpness) is None
    reason, pitch = judge._judge_lattice(blobs, sharpness)
    want_reason, want_pitch = _reference(judge._judge_lattice, blobs, sharpness)
    assert np.array_equal(reason, want_reason) and np.array_equal(pitch, want_pitch, equal_nan=True)


@pytest.mark.parametrize("name", ["radial-led-120", "brown-127", "dense-1000"])
def test_every_judgement_of_a_field_search_is_the_references(name, monkeypatch):
    """On a preset's rest frame: each blob set the search judges, judged compiled and by the reference, and the
    field found either way (centres, parameters, pitch)."""
    image = preset_frame(name, None, seed=0).image
    sets = []
    real = judge._judge_lattice

    def spy(blobs, sharpness):
        sets.append((blobs, sharpness))
        return real(blobs, sharpness)

    monkeypatch.setattr(candidates, "_judge_lattice", spy)
    field = find_pin_field(image)
    assert len(sets) >= 5
    judged = 0
    for blobs, sharpness in sets:
        if len(blobs.centres) < judge._MIN_PINS:
            continue
        got = judge._compiled_passes(blobs, sharpness)
        judged += got is not None
        if got is not None:
            _same_passes(got, _reference(judge._passes, blobs, sharpness))
    assert judged >= len(sets) - 1
    monkeypatch.setattr(candidates, "_judge_lattice", real)
    want = _reference(find_pin_field, image)
    assert np.array_equal(field.centres, want.centres)
    assert field.params == want.params
    assert np.array_equal(field.pitch_px, want.pitch_px, equal_nan=True)
