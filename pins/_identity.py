"""One pin per tip, whatever the pins' neighbours at rest: identities through slides (issue 20).

A slide squeezes the skin ahead of it: pins lost there (their tips merged) are searched for from
predictions that may lie a spacing off, and a window searching there may settle on another pin's tip,
not only a neighbour's at rest. A pin found (searched for, or followed away from its guess) keeps its
tip only when, of every pin's expected position (a placed pin's place, another found pin's start, a
missing pin's guess or prediction), its own start is the nearest to it: the tip lies in the pin's own
cell of the Voronoi diagram of where the pins are expected. That cell shrinks with the squeezed skin
around it, so the test gates by the local pitch, with no gate to tune.

A missing pin's expected position is a prediction, up to a spacing off where a slide squeezes the skin
(`pins._predict`), and a found pin near it may sit on the merged blob of both tips: there the found pin
keeps the tip only when its own start is `MISSING_MARGIN` times nearer to it than the missing pin's
prediction (a placed pin's place is measured: nearest wins). Otherwise neither pin is placed there this
frame: the missing one is searched for again, the found one too, once the tips part. Measured on
`bench/bench_slides.py` (8 slides of 3 pitches), seeds 0-5, main f84c508 -> margin 2: pin-frames on
another pin's tip, model skin, radial-led-120 176 -> 140, tactip-331 7140 -> 6494, small-pad-100 397 ->
238; realistic skin (``min_area=0.5``) 75 -> 88 (seed 0 18 -> 57, one cascade; seeds 1-5 57 -> 31),
185 -> 173, 176 -> 61; lost visible pins per frame 4.11 -> 4.20, 13.56 -> 14.06, 5.37 -> 5.50 (model:
the trade, more pins left missing on merged blobs), 3.05 -> 3.04, 1.73 -> 1.75, 4.77 -> 4.71
(realistic). Seeds 0-2, margins 1.22 / 1.5 / 2: 4086 / 3921 / 3645 pin-frames in all against 4269.
The gain (and the lost pins it costs) comes from missing pins whose predictions are not searched
(`Refiner._trusted` false): with the margin for the searched ones alone, seeds 0-2 of the model skin
gave main's figures (radial-led-120 82, tactip-331 3708, small-pad-100 185 against 199).

Margin 4 since the renderer draws overlapping tips as the brighter one, not the sum of their light
(`tactip.sim._render._occlude`): without seams a window settles on the merged blob of two tips, and a
found pin there lies nearer its own start than its missing neighbour's prediction more often. Seeds 0-2
on the render without seams, margins 2 / 3 / 4 / 6: pin-frames on another pin's tip, realistic skin
radial-led-120 20 / 19 / 12 / 8, tactip-331 173 / 120 / 107 / 145, small-pad-100 39 / 32 / 32 / 29;
model skin 27 / 25 / 17 / 5, 3436 / 3136 / 3118 / 2927, 206 / 185 / 108 / 87; lost visible pins per
frame (the cost) realistic tactip-331 1.37 / 1.42 / 1.52 / 2.13, small-pad-100 4.61 / 4.75 / 4.88 /
5.69, model tactip-331 11.8 / 12.5 / 12.9 / 14.9, small-pad-100 5.24 / 5.40 / 5.81 / 6.95.
"""

from __future__ import annotations

import numpy as np

from ._kernels import compiled
from ._window import _squared_norm

# Pins whose tips a found pin may have taken: its nearest this many at rest (three rings of a hexagonal
# lattice: the skin squeezed ahead of a slide brings the outer rings near; on tactip-331 slides two
# rings let 12 % more pin-frames onto other pins' tips than all pins do, three as few).
IDENTITY_NEIGHBOURS = 36
# Gathers of at least this many points go through complex numbers (`gathered`): below it the few more
# calls cost more than the gather saves (microbenchmark: 36 neighbours of 1 / 3 / 10 / 30 pins, 4.0 / 5.2
# / 9.0 / 20 us by rows against 5.6 / 6.0 / 6.8 / 8.9; 6 neighbours of 10 / 80 pins 1.5 / 5.5 against 2.5 / 2.9).
_COMPLEX_GATHER_SIZE = 160
# A found pin keeps a tip near a missing pin's prediction only when its own start is this many times nearer
# (2 on renders with seams where tips overlap; 4 without, see the module docstring).
MISSING_MARGIN = 4.0


def keep_own_tips(positions: np.ndarray, found: np.ndarray, start: np.ndarray, expected: np.ndarray,
                  near: np.ndarray) -> None:
    """Unplace (NaN, in place) found pins whose tips lie nearer another pin's expected position than their own start.

    Nearer a missing pin's expected position (a prediction) means within `MISSING_MARGIN` times the
    distance from the found pin's own start: on the merged blob of two squeezed tips neither is placed.

    Parameters
    ----------
    positions : (N, 2) ndarray
        Positions so far, px; NaN where missing. Changed in place.
    found : (F,) ndarray of int
        Pins just found (searched for, or followed away from their guesses).
    start : (F, 2) ndarray
        Where each of them was expected (its guess or prediction), px.
    expected : (N, 2) ndarray
        Where every pin is expected, px (NaN: nowhere), for the pins without a position.
    near : (N, m) ndarray of int
        Each pin's nearest pins at rest (three rings of them: `IDENTITY_NEIGHBOURS`), the only ones
        whose tips a pin found within its gate can reach.

    Examples
    --------
    >>> positions = np.array([[0.0, 0.0], [10.0, 0.0], [np.nan, np.nan]])
    >>> expected = np.array([[0.0, 0.0], [10.0, 0.0], [20.0, 0.0]])
    >>> near = np.array([[1, 2], [0, 2], [1, 0]])
    >>> keep_own_tips(positions, np.array([1]), np.array([[9.0, 0.0]]), expected, near)  # its start nearest: kept
    >>> positions[1]
    array([10.,  0.])
    >>> positions[1] = [19.0, 0.0]   # the tip where pin 2 is expected: not pin 1's
    >>> keep_own_tips(positions, np.array([1]), np.array([[12.0, 0.0]]), expected, near)
    >>> positions[1]
    array([nan, nan])
    >>> positions[1] = [15.0, 0.0]   # 4 px from its start, 5 px from missing pin 2's prediction: not 4 times as far
    >>> keep_own_tips(positions, np.array([1]), np.array([[11.0, 0.0]]), expected, near)
    >>> positions[1]
    array([nan, nan])

    By the compiled kernel (`pins._jit_track.keep_own_tips`, one call, the same decisions) unless
    ``TACTIP_KERNELS=numpy`` or Numba is missing (`pins._kernels`).
    """
    if not found.size:
        return
    kernels = compiled()
    if kernels is not None and positions.dtype == np.float64:
        kernels.keep_own_tips(positions, np.asarray(found, dtype=np.int64), np.asarray(start, dtype=np.float64),
                              np.asarray(expected, dtype=np.float64), near, MISSING_MARGIN ** 2)
        return
    _keep_own_tips_numpy(positions, found, start, expected, near)


def _keep_own_tips_numpy(positions: np.ndarray, found: np.ndarray, start: np.ndarray, expected: np.ndarray,
                         near: np.ndarray) -> None:
    """`keep_own_tips` in NumPy: the reference of the compiled kernel (`pins._jit_track.keep_own_tips`)."""
    tips = positions[found]
    placed = np.isfinite(tips[:, 0])
    if not np.logical_and.reduce(placed):  # (one call where, as mostly, every found pin is placed)
        found, start, tips = found[placed], start[placed], tips[placed]
        if found.size == 0:
            return
    missing = np.isnan(positions[:, 0])
    at = np.where(np.isfinite(positions), positions, expected)
    at[found] = start
    own = _squared_norm(tips - start)
    # (NaN, a pin expected nowhere, compares False.)
    around = near[found]
    others = squared_distances(at, around, tips)  # (F, m)
    # A missing pin's prediction (uncertain) wins unless the pin's own start is MISSING_MARGIN times nearer.
    others = np.where(missing.take(around), others / MISSING_MARGIN ** 2, others)
    positions[found[np.logical_or.reduce(others < own[:, None], axis=1)]] = np.nan


def squared_distances(points: np.ndarray, index: np.ndarray, to: np.ndarray) -> np.ndarray:
    """Squared distances, px^2 (F, m), from (F, 2) points `to` to (N, 2) `points` gathered at (F, m) `index`.

    Bit for bit ``_squared_norm(points[index] - to[:, None, :])``: the same subtractions, squares and sum,
    with a large gather's points as complex numbers (`gathered`: one 16-byte element a point, a third of
    the cost of gathering rows). NaN where either point is NaN.

    >>> squared_distances(np.array([[0.0, 0.0], [3.0, 4.0]]), np.array([[1, 0]]), np.array([[0.0, 0.0]]))
    array([[25.,  0.]])
    """
    if index.size < _COMPLEX_GATHER_SIZE:
        return _squared_norm(points[index] - to[:, None, :])
    gap = _as_complex(points).take(index) - _as_complex(to)[:, None]
    return gap.real * gap.real + gap.imag * gap.imag


def gathered(points: np.ndarray, index: np.ndarray) -> np.ndarray:
    """``points[index]`` (index.shape + (2,)) of (N, 2) float `points` (a fresh array), bit for bit: a large
    gather (`_COMPLEX_GATHER_SIZE`) as complex numbers, single 16-byte elements, which costs less than one of rows.

    >>> gathered(np.array([[0.0, 1.0], [2.0, 3.0]]), np.array([[1, 1, 0]]))
    array([[[2., 3.],
            [2., 3.],
            [0., 1.]]])
    """
    if index.size < _COMPLEX_GATHER_SIZE:
        return points[index]
    return _as_complex(points).take(index).view(np.float64).reshape(index.shape + (2,))


def _as_complex(points: np.ndarray) -> np.ndarray:
    """(N, 2) float points as (N,) complex x + iy: a view when `points` is C-contiguous float64."""
    if points.dtype != np.float64 or not points.flags.c_contiguous:
        points = np.ascontiguousarray(points, dtype=np.float64)
    return points.view(np.complex128)[:, 0]  # (method calls: `np.take` and the like wrap them in three)


def kept_on_own_tips(before: np.ndarray, after: np.ndarray, start: np.ndarray, guess: np.ndarray,
                     near: np.ndarray) -> np.ndarray:
    """A step's positions `after` (N, 2), px, with the pins it moved or placed kept only on their own tips.

    `keep_own_tips` for the pins whose positions differ from `before` (N, 2), px: each expected at its
    `start` (N, 2), px; the others where `before` places them, else at their `guess` (N, 2), px;
    `near` as in `keep_own_tips`.
    `after` is changed in place (a step returns `before` itself when it changed nothing).
    """
    if after is before:
        return after
    changed = np.flatnonzero(np.isfinite(after[:, 0]) & ~(after == before).all(axis=1))
    if changed.size:
        keep_own_tips(after, changed, start[changed], np.where(np.isfinite(before), before, guess), near)
    return after
