"""Compiled kernel (Numba) of `pins._pairfit`: the pair fit of overlapping tips, one call a frame.

`part_pairs` is `pins._pairfit.part_overlapping` after its first check (pairing each placed pin with its
nearest expected neighbour within two tip radii, one fit per pair, the fit of two discs over a plane by
damped Gauss-Newton, the acceptance and the writes, in the reference's order), and `fit_pairs` is
`pins._pairfit.fit_tip_pairs`: the same arithmetic as a loop over pairs and pixels. The sums (the normal
equations) run in another order than NumPy's matrix products and the 4 x 4 solves are Gaussian elimination
with partial pivoting as LAPACK's ``gesv``: fits differ from the reference's in the last bits (the tests hold
them within 1e-9 px). One difference: a singular system leaves only its own pair unfitted (NaN), where the
reference gives up on every pair of the call (`numpy.linalg.LinAlgError`); with the reference's ridge on the
diagonal no finite system is singular.

`pins._pairfit` picks it (``TACTIP_KERNELS=numpy``: the NumPy reference) and loads it on the first call that
needs it. ``cache=True``: compiled once per machine (a few seconds), then loaded from ``__pycache__``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._jit import _solve_in_place

# (The reference's constants, by value: `pins._pairfit`'s.)
_EDGE_PX = 0.6
_PASSES = 4
_DAMPING = 1e-3
_MARGIN_PX = 2.0
_OTHERS = 4
_LEAST_RISE = 1.0
_STEP_PX = 1.5  # the largest step of a centre's coordinate in one pass


@njit(cache=True, nogil=True, error_model="numpy")
def _half(first, second, radius_px):
    """Half the side of the square of pixels every pair's fit looks at (the reference's, over all pairs), px."""
    largest = -np.inf
    for i in range(first.shape[0]):
        dx, dy = first[i, 0] - second[i, 0], first[i, 1] - second[i, 1]
        half = 0.5 * np.sqrt(dx * dx + dy * dy)
        if half > largest:  # (nanmax: NaN skipped)
            largest = half
    return int(np.ceil(largest + radius_px + _MARGIN_PX))


@njit(cache=True, nogil=True, error_model="numpy")
def _fit_one(crop, x1, y1, x2, y2, others, radius_px, half, xs, ys, vs, scratch, fit):
    """One pair's fit (`pins._pairfit.fit_tip_pairs` for one row) into `fit` (4,): x1, y1, x2, y2 px, NaN when
    it fails. `others` (k, 2) px (NaN: none); `xs`, `ys`, `vs` (P,), `scratch` (4, P): room for the
    (2 half + 1)^2 pixels."""
    height, width = crop.shape
    mx, my = 0.5 * (x1 + x2), 0.5 * (y1 + y2)
    # The `_OTHERS` others nearest the middle (ties in the order given), NaN ones last.
    k = others.shape[0]
    reach = np.empty(k)
    order = np.empty(k, np.int64)
    for j in range(k):
        dx, dy = others[j, 0] - mx, others[j, 1] - my
        reach[j] = dx * dx + dy * dy
        if not np.isfinite(reach[j]):
            reach[j] = np.inf
        order[j] = j
    for j in range(1, k):  # (insertion sort: stable)
        current, at = order[j], j
        while at > 0 and reach[order[at - 1]] > reach[current]:
            order[at] = order[at - 1]
            at -= 1
        order[at] = current
    nearest = min(_OTHERS, k)
    cx, cy = int(np.rint(mx)), int(np.rint(my))
    bound = (radius_px + _MARGIN_PX) ** 2
    count = 0
    for oy in range(-half, half + 1):
        y = cy + oy
        if y < 0 or y >= height:
            continue
        for ox in range(-half, half + 1):
            x = cx + ox
            if x < 0 or x >= width:
                continue
            dx1, dy1, dx2, dy2 = x - x1, y - y1, x - x2, y - y2
            near = min(dx1 * dx1 + dy1 * dy1, dx2 * dx2 + dy2 * dy2)
            if not near <= bound:
                continue
            nearer = False
            for j in range(nearest):
                ex, ey = x - others[order[j], 0], y - others[order[j], 1]
                if ex * ex + ey * ey < near:  # (NaN: no other)
                    nearer = True
                    break
            if nearer:
                continue
            xs[count], ys[count], vs[count] = x, y, crop[y, x]
            count += 1
    fit[:] = np.nan
    if count == 0:
        return
    mu = np.array([x1, y1, x2, y2])
    a, b, beta, design, jac = np.empty((4, 4)), np.empty(4), np.empty(4), np.empty(4), np.empty(4)
    for _ in range(_PASSES):
        # The plane and the tips' coverage: normal equations (upper triangle, mirrored), solved. Each pixel's
        # distances and coverages kept for the Jacobian's pass.
        a[:] = 0.0
        b[:] = 0.0
        for p in range(count):
            dx1, dy1, dx2, dy2 = xs[p] - mu[0], ys[p] - mu[1], xs[p] - mu[2], ys[p] - mu[3]
            d1, d2 = np.sqrt(dx1 * dx1 + dy1 * dy1), np.sqrt(dx2 * dx2 + dy2 * dy2)
            c1 = 1.0 / (1.0 + np.exp((d1 - radius_px) / _EDGE_PX))
            c2 = 1.0 / (1.0 + np.exp((d2 - radius_px) / _EDGE_PX))
            scratch[0, p], scratch[1, p], scratch[2, p], scratch[3, p] = d1, d2, c1, c2
            design[0], design[1], design[2] = 1.0, xs[p] - mx, ys[p] - my
            design[3] = 1.0 - (1.0 - c1) * (1.0 - c2)
            for r in range(4):
                b[r] += design[r] * vs[p]
                for c in range(r, 4):
                    a[r, c] += design[r] * design[c]
        for r in range(4):
            a[r, r] += 1e-6
            for c in range(r):
                a[r, c] = a[c, r]
        if not _solve_in_place(a, b):
            return
        beta[:] = b
        amplitude = beta[3] / _EDGE_PX
        a[:] = 0.0
        b[:] = 0.0
        for p in range(count):
            dx1, dy1, dx2, dy2 = xs[p] - mu[0], ys[p] - mu[1], xs[p] - mu[2], ys[p] - mu[3]
            d1, d2, c1, c2 = scratch[0, p], scratch[1, p], scratch[2, p], scratch[3, p]
            model = beta[0] + beta[1] * (xs[p] - mx) + beta[2] * (ys[p] - my) + beta[3] * (1.0 - (1.0 - c1) * (1.0 - c2))
            residual = vs[p] - model
            g1 = amplitude * (1.0 - c2) * c1 * (1.0 - c1) / max(d1, 1e-6)
            g2 = amplitude * (1.0 - c1) * c2 * (1.0 - c2) / max(d2, 1e-6)
            jac[0], jac[1], jac[2], jac[3] = g1 * dx1, g1 * dy1, g2 * dx2, g2 * dy2
            for r in range(4):
                b[r] += jac[r] * residual
                for c in range(r, 4):
                    a[r, c] += jac[r] * jac[c]
        for r in range(4):
            a[r, r] += _DAMPING * a[r, r] + 1e-9
            for c in range(r):
                a[r, c] = a[c, r]
        if not _solve_in_place(a, b):
            return
        for r in range(4):
            step = b[r]
            mu[r] += step if step != step else min(max(step, -_STEP_PX), _STEP_PX)
    if np.isfinite(mu[0]) and np.isfinite(mu[1]) and np.isfinite(mu[2]) and np.isfinite(mu[3]) and beta[3] > _LEAST_RISE:
        fit[:] = mu


@njit(cache=True, nogil=True, error_model="numpy")
def fit_pairs(crop, first, second, radius_px, others):
    """`pins._pairfit.fit_tip_pairs`: centres of pairs of overlapping tips (L, 2), (L, 2) px (NaN: failed), from
    the uint8 `crop`, starts `first`, `second` (L, 2) px, the tips' radius px and `others` (L, k, 2) px."""
    n = first.shape[0]
    fit1, fit2 = np.full((n, 2), np.nan), np.full((n, 2), np.nan)
    if n == 0:
        return fit1, fit2
    half = _half(first, second, radius_px)
    side = 2 * half + 1
    xs, ys, vs = np.empty(side * side), np.empty(side * side), np.empty(side * side)
    scratch, fit = np.empty((4, side * side)), np.empty(4)
    for i in range(n):
        _fit_one(crop, first[i, 0], first[i, 1], second[i, 0], second[i, 1], others[i], radius_px, half, xs, ys, vs,
                 scratch, fit)
        fit1[i, 0], fit1[i, 1], fit2[i, 0], fit2[i, 1] = fit[0], fit[1], fit[2], fit[3]
    return fit1, fit2


@njit(cache=True, nogil=True, error_model="numpy")
def part_pairs(crop, positions, expected, neighbours, overlap_px, radius_px, gate_px, origin):
    """`pins._pairfit.part_overlapping` after its check of the tips' radius: `positions` (N, 2) px (NaN:
    missing) with the placed pins of overlapping pairs moved onto their fits (a copy), given `expected` (N, 2)
    px, the refiner's window neighbours (k, N), its overlap distances (N,) px, the tips' radius, the gate and
    the crop's origin (2,), px."""
    n, k = positions.shape[0], neighbours.shape[0]
    out = positions.copy()
    at = np.empty((n, 2))
    for i in range(n):
        placed = np.isfinite(positions[i, 0])
        at[i, 0] = positions[i, 0] if placed else expected[i, 0]
        at[i, 1] = positions[i, 1] if placed else expected[i, 1]
    # Each placed pin with its nearest neighbour expected within its overlap distance; one pair per key.
    keys, rows, nearest = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.int64)
    pairs = 0
    for i in range(n):
        if not np.isfinite(positions[i, 0]):
            continue
        best, gap = -1, np.inf
        for j in range(k):
            other = neighbours[j, i]
            dx, dy = at[other, 0] - at[i, 0], at[other, 1] - at[i, 1]
            squared = dx * dx + dy * dy
            if squared < overlap_px[i] * overlap_px[i] and squared < gap:  # (NaN compares False)
                best, gap = other, squared
        if best >= 0:
            keys[pairs], rows[pairs], nearest[pairs] = min(i, best) * n + max(i, best), i, best
            pairs += 1
    if pairs == 0:
        return out
    # One fit per pair, in the order of their keys, each from the first row (lowest placed pin) that made it.
    order = np.argsort(keys[:pairs], kind="mergesort")
    first, second = np.empty(pairs, np.int64), np.empty(pairs, np.int64)
    m = 0
    for r in range(pairs):
        row = order[r]
        if r == 0 or keys[row] != keys[order[r - 1]]:
            first[m], second[m] = rows[row], nearest[row]
            m += 1
    start1, start2 = np.empty((m, 2)), np.empty((m, 2))
    others = np.empty((m, 2 * k, 2))
    for p in range(m):
        a, b = first[p], second[p]
        for c in range(2):
            start1[p, c] = at[a, c] - origin[c]
            start2[p, c] = at[b, c] - origin[c]
        for j in range(2 * k):
            other = neighbours[j, a] if j < k else neighbours[j - k, b]
            for c in range(2):
                others[p, j, c] = np.nan if other == a or other == b else at[other, c] - origin[c]
    fit1, fit2 = fit_pairs(crop, start1, start2, radius_px, others)
    gate = gate_px * gate_px
    least = (0.5 * radius_px) ** 2
    ok = np.zeros(m, np.bool_)
    for p in range(m):
        own1 = (fit1[p, 0] - start1[p, 0]) ** 2 + (fit1[p, 1] - start1[p, 1]) ** 2
        own2 = (fit2[p, 0] - start2[p, 0]) ** 2 + (fit2[p, 1] - start2[p, 1]) ** 2
        cross = ((fit1[p, 0] - start2[p, 0]) ** 2 + (fit1[p, 1] - start2[p, 1]) ** 2
                 + (fit2[p, 0] - start1[p, 0]) ** 2 + (fit2[p, 1] - start1[p, 1]) ** 2)
        apart = (fit1[p, 0] - fit2[p, 0]) ** 2 + (fit1[p, 1] - fit2[p, 1]) ** 2
        ok[p] = own1 <= gate and own2 <= gate and own1 + own2 <= cross and apart >= least
    for p in range(m):  # (the reference's writes: every first pin, then the placed second pins)
        if ok[p]:
            out[first[p], 0], out[first[p], 1] = fit1[p, 0] + origin[0], fit1[p, 1] + origin[1]
    for p in range(m):
        if ok[p] and np.isfinite(out[second[p], 0]):
            out[second[p], 0], out[second[p], 1] = fit2[p, 0] + origin[0], fit2[p, 1] + origin[1]
    return out


__all__ = ["fit_pairs", "part_pairs"]
