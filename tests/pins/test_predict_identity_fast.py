"""The cheaper forms of `_Prediction._predict`, `keep_own_tips` and their gathers agree bit for bit with
the forms they replaced.

The references below are the earlier code (main 187772a), kept here only as oracles: NaN rows, neighbours all
NaN, ties (values on a coarse grid), one pin, no pins.
"""

import numpy as np
import pytest

from pins._identity import MISSING_MARGIN, gathered, keep_own_tips, squared_distances
from pins._predict import _Prediction, _median
from pins._window import _squared_norm


def _reference_predict(self, positions, which, last_seen):
    rest = self.rest_positions[which]
    now = (positions - self.rest_positions)[self._neighbour_index[which]]
    either = _median(now.copy())
    then = self._then[which]
    both = np.isfinite(now[..., 0]) & np.isfinite(then[..., 0])
    now[~both] = np.nan
    change = _median(now) - _median(np.where(both[..., None], then, np.nan))
    carried = last_seen[which] + change
    fallback = np.where(np.isnan(either), last_seen[which], rest + either)
    return np.where(np.isfinite(carried), carried, fallback)


def _reference_keep_own_tips(positions, found, start, expected, near):
    placed = np.isfinite(positions[found, 0])
    found, start = found[placed], start[placed]
    if found.size == 0:
        return
    at = np.where(np.isfinite(positions), positions, expected)
    at[found] = start
    tips = positions[found]
    own = _squared_norm(tips - start)
    around = near[found]
    others = _squared_norm(at[around] - tips[:, None, :])
    missing = np.isnan(positions[around, 0])
    others[missing] /= MISSING_MARGIN ** 2
    positions[found[(others < own[:, None]).any(axis=1)]] = np.nan


def _points(rng, n, nan_share, grid):
    """(n, 2) points, px, on a grid of `grid` px when given (ties), with a share of NaN rows."""
    points = rng.uniform(0.0, 40.0, (n, 2))
    if grid:
        points = np.round(points / grid) * grid
    points[rng.random(n) < nan_share] = np.nan
    return points


class _Predictor(_Prediction):
    def __init__(self, rest, index, then):
        self.rest_positions, self._neighbour_index, self._then = rest, index, then


@pytest.mark.parametrize("seed", range(40))
def test_predict_agrees_with_its_reference(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 30))
    k = int(rng.integers(1, 7))
    grid = [0.0, 0.5, 4.0][seed % 3]
    rest = _points(rng, n, 0.0, grid)
    index = rng.integers(0, n, (n, k))
    then = rng.normal(0.0, 2.0, (n, k, 2))
    then[rng.random((n, k)) < [0.0, 0.3, 1.0][seed % 3]] = np.nan  # none, some, all NaN then
    if grid:
        then = np.round(then / grid) * grid
    predictor = _Predictor(rest, index, then)
    positions = _points(rng, n, [0.0, 0.4, 1.0][(seed // 3) % 3], grid)
    last_seen = _points(rng, n, 0.0, grid)
    for which in (np.arange(n), rng.permutation(n)[: int(rng.integers(0, n + 1))], np.array([0]),
                  np.array([], dtype=np.intp)):
        got = predictor._predict(positions, which, last_seen)
        want = _reference_predict(predictor, positions, which, last_seen)
        assert got.shape == (len(which), 2)
        np.testing.assert_array_equal(got, want)  # NaN where NaN, every other bit equal


@pytest.mark.parametrize("seed", range(40))
def test_keep_own_tips_agrees_with_its_reference(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 30))
    m = int(rng.integers(1, 8))
    grid = [0.0, 1.0, 5.0][seed % 3]  # 5 px: ties between a tip's own start and another pin
    positions = _points(rng, n, [0.0, 0.3, 0.9][(seed // 3) % 3], grid)
    expected = _points(rng, n, 0.2, grid)
    near = rng.integers(0, n, (n, m))
    found = rng.permutation(n)[: int(rng.integers(0, n + 1))]
    start = positions[found] + (np.round(rng.normal(0.0, 3.0, (len(found), 2))) if grid else
                                rng.normal(0.0, 3.0, (len(found), 2)))
    got, want = positions.copy(), positions.copy()
    keep_own_tips(got, found, start, expected, near)
    _reference_keep_own_tips(want, found, start, expected, near)
    np.testing.assert_array_equal(got, want)
    if n == 1:
        return
    # A found pin on the tip where a missing pin is expected yields, as the reference says.
    one = positions.copy()
    one[0] = expected[1] = [10.0, 10.0]
    one[1] = np.nan
    near[0, 0] = 1
    got, want = one.copy(), one.copy()
    keep_own_tips(got, np.array([0]), np.array([[30.0, 30.0]]), expected, near)
    _reference_keep_own_tips(want, np.array([0]), np.array([[30.0, 30.0]]), expected, near)
    np.testing.assert_array_equal(got, want)
    assert np.isnan(got[0, 0])


@pytest.mark.parametrize("seed", range(20))
def test_complex_gathers_agree_with_row_gathers(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 40))
    points = _points(rng, n, [0.0, 0.3, 1.0][seed % 3], [0.0, 1.0][seed % 2])
    # (below and above the size at which the gather goes through complex numbers)
    for shape in ((0,), (1,), (n,), (200,), (7, 36), (int(rng.integers(0, 9)), int(rng.integers(1, 37)))):
        index = rng.integers(0, n, shape)
        want = points[index]
        got = gathered(points, index)
        assert got.shape == want.shape
        np.testing.assert_array_equal(got, want)
        got[...] = -1.0  # a fresh array: `points` untouched
        assert not (points == -1.0).any()
    for shape in ((1, 36), (7, 36), (int(rng.integers(0, 9)), int(rng.integers(1, 37)))):
        index = rng.integers(0, n, shape)
        to = _points(rng, len(index), 0.3, 0.0)
        # (a non-contiguous view of `points` too: the gather copies it first)
        for source in (points, np.asfortranarray(points)):
            np.testing.assert_array_equal(squared_distances(source, index, to),
                                          _squared_norm(points[index] - to[:, None, :]))


def test_drift_bound_follows_a_new_noise_scatter():
    predictor = _Predictor(np.zeros((3, 2)), np.array([[1, 2], [0, 2], [0, 1]]), np.zeros((3, 2, 2)))
    predictor._guess_px = 0.1
    predictor._noise_scatter_sq = np.array([0.0, 1.0, 4.0])
    first = predictor._drift_bound_sq()
    assert first[0] == pytest.approx(0.01) and first[2] == pytest.approx(9.0 * 2.0 * 4.0 * np.pi / 4)
    assert predictor._drift_bound_sq() is first  # kept
    predictor._noise_scatter_sq = np.array([1.0, 1.0, 1.0])  # assigned anew (as `Refiner` does): recomputed
    np.testing.assert_allclose(predictor._drift_bound_sq(), 9.0 * 2.0 * np.pi / 4)
    predictor._guess_px = 10.0
    np.testing.assert_allclose(predictor._drift_bound_sq(), 100.0)
