"""Compiled helpers (Numba) of `pins._jit_follow`: the crop blurred over windows' squares (one by one at the crop's
edge, side by side elsewhere, in passes over rows as long as all the squares, which the compiler vectorises), and
the local-maximum tests on them.

``cache=True``: compiled once per machine, then loaded from ``__pycache__``.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True, error_model="numpy")
def _reflect(i, n):
    """Index `i` reflected into [0, n) as OpenCV's BORDER_REFLECT_101 reflects it (n > 1)."""
    while i < 0 or i >= n:
        if i < 0:
            i = -i
        else:
            i = 2 * n - 2 - i
    return i


@njit(cache=True, nogil=True, error_model="numpy")
def blur_square(crop, weights, cx, cy, reach, rows, out):
    """The crop blurred by the separable `weights` over the square of `reach` px round (cx, cy), into `out`
    ((2 reach + 1)^2 used), NaN outside the crop; `rows`: scratch of (2 reach + 1 + taps - 1) x (2 reach + 1)."""
    height, width = crop.shape
    taps = weights.size
    k = taps // 2
    side = 2 * reach + 1
    # Horizontal pass on the rows the vertical one reads (reflected at the crop's edges).
    for r in range(side + taps - 1):
        y = _reflect(cy - reach - k + r, height)
        for c in range(side):
            x = cx - reach + c
            if x < 0 or x >= width:
                continue
            total = 0.0
            if x - k >= 0 and x + k < width:
                for t in range(taps):
                    total += weights[t] * crop[y, x - k + t]
            else:
                for t in range(taps):
                    total += weights[t] * crop[y, _reflect(x - k + t, width)]
            rows[r, c] = total
    for r in range(side):
        y = cy - reach + r
        for c in range(side):
            x = cx - reach + c
            if y < 0 or y >= height or x < 0 or x >= width:
                out[r, c] = np.nan
                continue
            total = 0.0
            for t in range(taps):
                total += weights[t] * rows[r + t, c]
            out[r, c] = total


@njit(cache=True, nogil=True, error_model="numpy")
def extremes(values, side, r0, c0, reach):
    """The least and greatest finite value of `values`' first `side` x `side` in the square of `reach` round
    (r0, c0)."""
    low, high = np.inf, -np.inf
    for r in range(max(r0 - reach, 0), min(r0 + reach + 1, side)):
        for c in range(max(c0 - reach, 0), min(c0 + reach + 1, side)):
            v = values[r, c]
            if v == v:
                low = min(low, v)
                high = max(high, v)
    return low, high


@njit(cache=True, nogil=True, error_model="numpy")
def is_top(values, side, r, c, reach, v):
    """Whether no value of `values`' first `side` x `side` within the square of `reach` round (r, c) exceeds `v`
    (its eight neighbours first: on a slope one of them does)."""
    r0, r1 = max(r - reach, 0), min(r + reach + 1, side)
    c0, c1 = max(c - reach, 0), min(c + reach + 1, side)
    for rr in range(max(r - 1, r0), min(r + 2, r1)):
        for cc in range(max(c - 1, c0), min(c + 2, c1)):
            if values[rr, cc] > v:
                return False
    for rr in range(r0, r1):
        for cc in range(c0, c1):
            if values[rr, cc] > v:
                return False
    return True


@njit(cache=True, nogil=True, error_model="numpy")
def may_hold_two(values, centre, half, square, reach, tip_sq):
    """Whether the window of `half` px round (`centre`, `centre`) in `values` may hold two tips: two local maxima
    within `half` of its centre, more than a tip radius (`tip_sq`, px^2) apart, at or above the middle of the
    darkest and brightest of its square (`square` px round the centre), judged within that square alone (a
    peak's neighbours beyond it unseen: every tip the full test finds, and some more)."""
    side = 2 * square + 1
    low, high = extremes(values, side, centre, centre, square)
    floor = np.float32(0.5) * (np.float32(low) + np.float32(high))
    tops = np.empty((4 * half * half + 4 * half + 1, 2), np.int64)
    found = 0
    half_sq = half * half
    for dy in range(-half, half + 1):
        for dx in range(-half, half + 1):
            if dx * dx + dy * dy > half_sq:
                continue
            r, c = centre + dy, centre + dx
            v = values[r, c]
            if not (v >= floor and is_top(values, side, r, c, reach, v)):
                continue
            for q in range(found):
                if (r - tops[q, 0]) ** 2 + (c - tops[q, 1]) ** 2 > tip_sq:
                    return True
            tops[found, 0], tops[found, 1] = r, c
            found += 1
    return False


@njit(cache=True, nogil=True, error_model="numpy")
def _horizontal(source, out, weights, columns):
    """The horizontal pass of a separable blur over whole rows: ``out[r, j]`` = sum over t of ``weights[t] *
    source[r, j + t]``, j < `columns` (one long loop a row, which the compiler vectorises)."""
    taps = weights.size
    for r in range(out.shape[0]):
        line = source[r]
        target = out[r, :columns]
        w = weights[0]
        for j in range(columns):
            target[j] = w * line[j]
        for t in range(1, taps):
            w = weights[t]
            shifted = line[t:t + columns]
            for j in range(columns):
                target[j] += w * shifted[j]


@njit(cache=True, nogil=True, error_model="numpy")
def _vertical(source, out, weights, columns):
    """The vertical pass: ``out[r, j]`` = sum over t of ``weights[t] * source[r + t, j]``, j < `columns`."""
    taps = weights.size
    for r in range(out.shape[0]):
        target = out[r, :columns]
        line = source[r, :columns]
        w = weights[0]
        for j in range(columns):
            target[j] = w * line[j]
        for t in range(1, taps):
            w = weights[t]
            line = source[r + t, :columns]
            for j in range(columns):
                target[j] += w * line[j]


@njit(cache=True, nogil=True, error_model="numpy")
def blurred_squares(crop, xs, ys, reach, weights, pad):
    """The crop blurred by `weights` over the squares of `reach` px round (xs[q], ys[q]) (each inside the crop
    with its blur's reach), side by side: returns the blurred rows ((2 reach + 1, span), float32) and the columns
    a square takes (`block`); square q's first column is ``pad + q * block``, and the `pad` columns before the
    first and those between squares hold -inf. One pair of passes over rows as long as all the squares
    (`_horizontal`, `_vertical`), which the compiler vectorises, where a square alone has too few columns."""
    width = crop.shape[1]
    taps = weights.size
    k = taps // 2
    side = 2 * reach + 1
    extent = side + taps - 1  # a square's pixels with its blur's reach, each way
    block = max(extent, side + pad)
    count = xs.shape[0]
    span = pad + count * block
    # (Columns outside the squares' pixels are left as they are: only the columns between squares read them.)
    pixels = np.empty((extent, span + taps), np.float32)
    flat = crop.ravel()
    into = pixels.ravel()
    stride = np.uint64(span + taps)
    for q in range(count):
        # (Unsigned indices: no test for negative ones in the inner loop.)
        base = np.uint64((ys[q] - reach - k) * width + xs[q] - reach - k)
        j0 = np.uint64(pad + q * block)
        for r in range(extent):
            source = base + np.uint64(r * width)
            target = j0 + np.uint64(r) * stride
            for c in range(extent):
                into[target + np.uint64(c)] = flat[source + np.uint64(c)]
    # Down the columns first (every column of a square's pixels is needed across), then across.
    down = np.empty((side, span + taps), np.float32)
    _vertical(pixels, down, weights, span + taps)
    blurred = np.empty((side, span), np.float32)
    _horizontal(down, blurred, weights, span)
    for r in range(side):
        line = blurred[r]
        for j in range(pad):
            line[j] = -np.inf
        for q in range(count):
            j0 = pad + q * block
            for j in range(j0 + side, j0 + block):
                line[j] = -np.inf
    return blurred, block
