"""pins._predict.settle, the tracker's bookkeeping at the end of each update (steps carried, pins lost and retired, where
each was last seen) in one compiled call (`pins._jit_track.settle`), bit for bit its NumPy reference, on awkward
inputs: NaN or infinite in one column only, -0.0, long runs of frames lost."""

import numpy as np
import pytest

from pins._kernels import choose, compiled
from pins._predict import settle

pytestmark = pytest.mark.skipif(compiled() is None, reason="Numba missing or TACTIP_KERNELS=numpy: no kernels to test")


@pytest.mark.parametrize("seed", range(4))
def test_settle_is_the_reference(seed):
    rng = np.random.default_rng(seed)
    for n in (1, 2, 7, 120, 331):
        positions = rng.uniform(0.0, 400.0, (n, 2))
        positions[rng.random(n) < 0.2] = np.nan
        positions[rng.random(n) < 0.05, 1] = np.nan  # (x finite, y not: lost)
        positions[rng.random(n) < 0.05, 0] = np.inf
        velocity = rng.normal(0.0, 1.0, (n, 2))
        velocity[rng.random((n, 2)) < 0.2] = np.nan
        velocity[rng.random((n, 2)) < 0.05] = -0.0
        velocity[rng.random((n, 2)) < 0.05] = np.inf
        lost_run = rng.integers(0, 9, n).astype(np.int64)
        last_seen = rng.uniform(0.0, 400.0, (n, 2))
        retire_after = int(rng.integers(1, 6))
        got_seen, want_seen = last_seen.copy(), last_seen.copy()
        got = settle(positions, velocity, lost_run, retire_after, got_seen)
        before = choose("numpy")
        try:
            want = settle(positions, velocity, lost_run, retire_after, want_seen)
        finally:
            choose(before)
        for a, b in zip(got, want):
            assert a.dtype == b.dtype and a.shape == b.shape
            np.testing.assert_array_equal(a, b)
            np.testing.assert_array_equal(np.signbit(a), np.signbit(b))  # (-0.0 kept as -0.0)
        np.testing.assert_array_equal(got_seen, want_seen)
        lost = ~(np.isfinite(positions).all(axis=1))
        np.testing.assert_array_equal(got[1], lost)
        np.testing.assert_array_equal(got[2], np.where(lost, lost_run + 1, 0))
        np.testing.assert_array_equal(got_seen[~lost], positions[~lost])
        np.testing.assert_array_equal(got_seen[lost], last_seen[lost])
