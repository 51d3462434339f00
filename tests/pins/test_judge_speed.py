"""The lattice judge's shortcuts (`pins._judge`, `pins._candidates._strongest`) give the verdicts, pitch
and strongest run of the plain computation, bit for bit (their speed is bench/bench_replay.py's)."""

import numpy as np
import pytest

import pins._judge as judge
import pins._kernels as _kernels
import pins.lattice as lattice
from pins._candidates import _SharedCache, _evaluate_all, _strongest
from pins.detect import Blobs
from tests.pins.conftest import TAP, preset_frame


def _blob_set(seed: int) -> tuple[Blobs, np.ndarray]:
    """A jittered hexagonal lattice of 40-300 pins, a few missing, with impostors (specks, glare,
    doubles) among them: random sizes, contrasts, fills and sharpness."""
    rng = np.random.default_rng(seed)
    side = int(rng.integers(7, 20))
    pitch = rng.uniform(6.0, 25.0)
    i, j = np.mgrid[:side, :side]
    sites = np.column_stack([(i + 0.5 * (j % 2)).ravel(), 0.866 * j.ravel()]) * pitch
    sites = sites[rng.random(len(sites)) > rng.uniform(0.0, 0.2)]
    sites += rng.normal(0.0, rng.uniform(0.01, 0.08) * pitch, sites.shape)
    extra = rng.uniform(-pitch, (side + 1) * pitch, (int(rng.integers(0, side * 3)), 2))
    doubles = sites[rng.integers(0, len(sites), int(rng.integers(0, 6)))] + rng.uniform(-0.3, 0.3, 2) * pitch
    centres = np.vstack([sites, extra, doubles])
    n = len(centres)
    areas = np.maximum(rng.normal(0.1 * pitch**2, 0.3 * 0.1 * pitch**2, n), 2.0).round().astype(int)
    fills = rng.uniform(0.4, 0.9, n)
    contrasts = np.abs(rng.normal(40.0, 15.0, n)) + 1.0
    sharpness = rng.uniform(0.3, 1.5, n)
    return Blobs(centres, areas, fills, n, contrasts), sharpness


def _plain_judgement(blobs: Blobs, sharpness: np.ndarray):
    """`_judge_lattice` with its final neighbourhood built anew and the kept pins' pitch looked up anew
    (as until session 22), by the NumPy reference."""
    before = _kernels.choose("numpy")
    try:
        with pytest.MonkeyPatch.context() as patch:
            patch.setattr(judge._Neighbourhood, "among_members", lambda self: judge._Neighbourhood(self.points[self.index]))
            reason, pitch = judge._judge_lattice(blobs, sharpness)
    finally:
        _kernels.choose(before)
    # NaN: no field (an early return); else the median nearest-neighbour distance of the kept.
    return reason, pitch if np.isnan(pitch) else judge._median_nn(blobs.centres[reason == judge._KEPT])


@pytest.mark.parametrize("kernels", ["numpy", "compiled"])
@pytest.mark.parametrize("seed", range(40))
def test_the_judgement_reuses_its_last_neighbourhood_bit_for_bit(seed, kernels):
    """On random lattices with impostors, the verdicts and the kept pins' pitch equal the plain computation's
    (the NumPy reference's and the compiled passes', `pins._jit_judge`)."""
    blobs, sharpness = _blob_set(seed)
    before = _kernels.choose(kernels)
    try:
        reason, pitch = judge._judge_lattice(blobs, sharpness)
    finally:
        _kernels.choose(before)
    plain_reason, plain_pitch = _plain_judgement(blobs, sharpness)
    assert np.array_equal(reason, plain_reason)
    assert np.array_equal(pitch, plain_pitch, equal_nan=True)


@pytest.mark.parametrize("seed", range(10))
def test_the_members_neighbourhood_equals_one_built_anew(seed):
    """`_Neighbourhood.among_members` (rows of a neighbourhood judged among members) is the one built on the
    members alone: nearest members, distances, pitch, links, and the graph."""
    blobs, _ = _blob_set(seed)
    rng = np.random.default_rng(seed + 100)
    members = rng.random(len(blobs.centres)) > 0.2
    got = judge._Neighbourhood(blobs.centres, members).among_members()
    new = judge._Neighbourhood(blobs.centres[members])
    for name in ("dist", "near", "pitch", "link"):
        assert np.array_equal(getattr(got, name), getattr(new, name)), name
    assert (got.graph() != new.graph()).nnz == 0


def _coarse_sets(image):
    """The coarse pass's arguments of every polarity's search in one `find_pin_field` on `image`."""
    calls = []
    real = lattice._strongest

    def spy(grey, disc, candidates, cache):
        calls.append((grey, disc, list(candidates)))
        return real(grey, disc, candidates, cache)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(lattice, "_strongest", spy)
        lattice.find_pin_field(image)
    return calls


@pytest.mark.parametrize("name, contact", [("radial-led-120", None), ("brown-127", TAP), ("dense-1000", None)])
def test_the_strongest_run_is_the_one_every_judgement_gives(name, contact):
    """The coarse pass's strongest run, judging only the sets that could be it, is the first of the
    strongest that judging every set gives: the same parameters, verdicts and pitch."""
    calls = _coarse_sets(preset_frame(name, contact, seed=0).image)
    assert calls
    for grey, disc, candidates in calls:
        every = _evaluate_all(grey, disc, candidates, _SharedCache())
        want = max(every, key=lambda run: run.strength)
        got = _strongest(grey, disc, candidates, _SharedCache())
        assert got.params == want.params
        assert np.array_equal(got.reason, want.reason)
        assert np.array_equal(got.pitch, want.pitch, equal_nan=True)
