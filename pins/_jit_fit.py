"""Compiled kernel (Numba) of `pins._recover._Recovery.fit_tips`, the tracker's fits of tips on slopes: one call a frame.

On a still pad of small faint tips (issue 20's radial-led-120: tips on LED reflections) a few pins are lost
by their windows and placed by these fits on most frames (a few each: 1-9 on its slide bench, on 70 % of the
frames); in NumPy the fits' steps cost ~0.15 ms a frame in about thirty calls round the tip fit's own kernel
(`pins._jit.centre_step`), their fixed costs more than their arithmetic. `fit_tips` runs the same steps in one
call: the predictions from the neighbours' median displacements (`pins._jit_track.displacement_median`), the
windows' contrast before and after (`pins._jit.window_contrast`), the tip fit (`centre_step`, on the disc of
`pins._tipfit._disc_offsets`), the overlap with a neighbour expected within two tip radii, one pin per tip and
pins kept on their own tips (`pins._jit_track`). The same float64 operations in the same order: the positions
are those of the steps it replaces bit for bit (the tests hold it to them).

``cache=True``: compiled once per machine, then loaded from ``__pycache__``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._jit import _corner, _tip_and_sides, centre_step
from ._jit_track import _median_into, keep_own_tips, one_pin_per_tip


@njit(cache=True, nogil=True, error_model="numpy")
def _predicted(positions, rest_positions, neighbour_index, pin, last_seen, xs, ys, medians, out, row):
    """`pins._predict._Prediction._predict_from_neighbours` of one pin into `out[row]`, px: its rest position moved
    by the median displacement of its `neighbour_index` neighbours placed in `positions`, else `last_seen`."""
    k = neighbour_index.shape[1]
    for j in range(k):
        other = neighbour_index[pin, j]
        xs[j] = positions[other, 0] - rest_positions[other, 0]
        ys[j] = positions[other, 1] - rest_positions[other, 1]
    _median_into(xs, ys, k, medians, 0)
    for c in range(2):
        shift = medians[0, c]
        out[row, c] = last_seen[pin, c] if shift != shift else rest_positions[pin, c] + shift


@njit(cache=True, nogil=True, error_model="numpy")
def _contrast(image, x, y, half):
    """`pins._jit.window_contrast` of one window at (x, y), px."""
    height, width = image.shape
    cx, cy, _ = _corner(x, y, half, width, height)
    tip, background, _, _ = _tip_and_sides(image, cx, cy, half)
    return tip - background


@njit(cache=True, nogil=True, error_model="numpy")
def disc_offsets(half):
    """`pins._tipfit._disc_offsets(half)`: (x, y) offsets, px, of the pixels of a square of half side `half` no
    farther than `half` from its centre, row by row, (P,) int64 each (integers: the exact test of ``np.hypot``)."""
    side = 2 * half + 1
    gx = np.empty(side * side, np.int64)
    gy = np.empty(side * side, np.int64)
    count = 0
    for y in range(-half, half + 1):
        for x in range(-half, half + 1):
            if x * x + y * y <= half * half:
                gx[count], gy[count] = x, y
                count += 1
    return gx[:count], gy[:count]


@njit(cache=True, nogil=True, error_model="numpy")
def fit_tips(image, positions, last_seen, which, fittable, rest_positions, neighbour_index, origin, half, at_least,
             window_neighbours, tip, reach_cap, tip_ellipses, overlap_px, identity_index, same_sq, margin_sq):
    """`pins._recover._Recovery.fit_tips`' steps (its docstring says what they do) in one call.

    image (h, w) uint8, the crop at `origin` (2,) px, bright pins; positions, last_seen, rest_positions (N, 2) px;
    which (L,) int: the missing pins to look for; fittable (N,) bool; neighbour_index (N, k) (predictions);
    half: the windows' half side, px; at_least (3, N) (the contrast's row 1); window_neighbours (k, N); tip: the
    fit's tip radius, px, and reach_cap ``1.5 tip + 1 + _MARGIN_PX``; tip_ellipses (N, 3); overlap_px (N,);
    identity_index (N, m); same_sq and margin_sq: `_one_pin_per_tip`'s and `keep_own_tips`' bounds.
    Returns (changed, positions): False and `positions` itself when no pin is placed, else True and a copy
    with the pins found, px.
    """
    chosen = np.empty(which.size, np.int64)
    count = 0
    for i in range(which.size):
        if fittable[which[i]]:
            chosen[count] = which[i]
            count += 1
    if count == 0:
        return False, positions
    k = neighbour_index.shape[1]
    xs, ys, medians = np.empty(k), np.empty(k), np.empty((1, 2))
    predicted = np.empty((count, 2))
    for i in range(count):
        _predicted(positions, rest_positions, neighbour_index, chosen[i], last_seen, xs, ys, medians, predicted, i)
    # Windows at the predictions that show a tip of the pin's least contrast.
    shown = np.empty(count, np.int64)
    fits = 0
    for i in range(count):
        if _contrast(image, predicted[i, 0] - origin[0], predicted[i, 1] - origin[1], half) >= at_least[1, chosen[i]]:
            shown[fits] = i
            fits += 1
    if fits == 0:
        return False, positions
    pins = np.empty(fits, np.int64)
    start = np.empty((fits, 2))
    for i in range(fits):
        pins[i] = chosen[shown[i]]
        start[i, 0] = predicted[shown[i], 0] - origin[0]
        start[i, 1] = predicted[shown[i], 1] - origin[1]
    # The neighbours' feet left out (placed, else last seen), the nearest one's distance, the window's reach.
    around = window_neighbours.shape[0]
    neighbours = np.empty((fits, around, 2))
    nearest = np.empty(fits)
    reach = np.empty(fits)
    theta = np.empty((fits, 5))
    widest = -np.inf
    for i in range(fits):
        least = np.inf
        for j in range(around):
            other = window_neighbours[j, pins[i]]
            for c in range(2):
                value = positions[other, c]
                if value != value:
                    value = last_seen[other, c]
                neighbours[i, j, c] = value - origin[c]
            dx, dy = neighbours[i, j, 0] - start[i, 0], neighbours[i, j, 1] - start[i, 1]
            squared = dx * dx + dy * dy
            if squared != squared or least != least:  # (np.minimum.reduce: NaN spreads)
                least = np.nan
            elif squared < least:
                least = squared
        nearest[i] = np.sqrt(least)
        inner = nearest[i] - 0.5 * tip
        reach[i] = inner if inner != inner else min(reach_cap, inner)
        widest = max(widest, reach[i])
        theta[i, 0], theta[i, 1] = start[i, 0], start[i, 1]
        theta[i, 2], theta[i, 3], theta[i, 4] = tip_ellipses[pins[i], 0], tip_ellipses[pins[i], 1], tip_ellipses[pins[i], 2]
    gx, gy = disc_offsets(int(np.ceil(widest)) + 1)
    fitted = centre_step(image, start, reach, neighbours, nearest, theta, gx, gy)
    # Placed where the fit took a step and ends on a tip of the pin's least contrast ...
    moved = np.zeros(fits, np.bool_)
    any_moved = False
    for i in range(fits):
        if fitted[i, 0] != start[i, 0] or fitted[i, 1] != start[i, 1]:
            moved[i] = True
            if np.rint(fitted[i, 0]) != np.rint(start[i, 0]) or np.rint(fitted[i, 1]) != np.rint(start[i, 1]):
                moved[i] = _contrast(image, fitted[i, 0], fitted[i, 1], half) >= at_least[1, pins[i]]
            any_moved = any_moved or moved[i]
    if not any_moved:
        return False, positions
    # ... unless a neighbour is expected (placed, or missing where its neighbours put it) within two tip radii.
    n = positions.shape[0]
    expected = positions.copy()
    row = np.empty((1, 2))
    for pin in range(n):
        if positions[pin, 0] != positions[pin, 0]:
            _predicted(positions, rest_positions, neighbour_index, pin, last_seen, xs, ys, medians, row, 0)
            expected[pin, 0], expected[pin, 1] = row[0, 0], row[0, 1]
    placed = 0
    for i in range(fits):
        if not moved[i]:
            continue
        bound = overlap_px[pins[i]] * overlap_px[pins[i]]
        for j in range(around):
            other = window_neighbours[j, pins[i]]
            dx = expected[other, 0] - origin[0] - fitted[i, 0]
            dy = expected[other, 1] - origin[1] - fitted[i, 1]
            if dx * dx + dy * dy < bound:  # (NaN, a neighbour expected nowhere, compares False)
                moved[i] = False
                break
        placed += moved[i]
    if placed == 0:
        return False, positions
    out = positions.copy()
    found = np.empty(placed, np.int64)
    at = np.empty((placed, 2))
    begun = np.empty((placed, 2))
    error = np.empty(placed)
    m = 0
    for i in range(fits):
        if moved[i]:
            found[m] = pins[i]
            at[m, 0], at[m, 1] = fitted[i, 0] + origin[0], fitted[i, 1] + origin[1]
            begun[m, 0], begun[m, 1] = predicted[shown[i], 0], predicted[shown[i], 1]
            out[found[m], 0], out[found[m], 1] = at[m, 0], at[m, 1]
            dx, dy = at[m, 0] - begun[m, 0], at[m, 1] - begun[m, 1]
            error[m] = dx * dx + dy * dy
            m += 1
    one_pin_per_tip(out, found, error, identity_index, same_sq)
    # ... nor any pin expected nearer to it (a missing pin where its neighbours put it).
    for m in range(placed):
        for c in range(2):
            expected[found[m], c] = begun[m, c] if out[found[m], c] != out[found[m], c] else at[m, c]
    keep_own_tips(out, found, begun, expected, identity_index, margin_sq)
    return True, out
