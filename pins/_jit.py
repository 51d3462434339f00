"""Compiled kernels (Numba) of the tracker's hot paths, one call a pass: `pins._kernels` picks them.

Each kernel is the NumPy reference it names, written as a loop over the windows: the same
arithmetic, in float64 where the reference sums exact integers in float32 (the same sums), with
the float32 threshold plane rounded as OpenBLAS's ``sgemm`` rounds it (fused multiply-adds in
turn: `_plane_level`). Sums in another order differ in the last bits; the tests hold the kernels
to the reference within 1e-9 px.

``cache=True``: compiled once per machine (a few seconds), then loaded from ``__pycache__``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# (The reference's constants, imported by value: the kernels compile them in.)
_SIDE_RUN = 4  # `pins._window._SIDE_RUN`
_FLAT_RISE = 0.1  # `pins._window._FLAT_RISE`
_PHASES = 4  # `pins._window._PHASES`


@njit(cache=True, nogil=True, error_model="numpy")
def _plane_level(c0, c1, c2, gx, gy):
    """``rint(c0 + c1 gx + c2 gy)`` of float32 coefficients as ``np.dot`` of float32 gives it (two fused
    multiply-adds, each rounded to float32; here each exact in float64, then rounded), float64."""
    first = np.float32(np.float64(c0) + np.float64(c1) * gx)
    return np.rint(np.float64(np.float32(np.float64(first) + np.float64(c2) * gy)))


@njit(cache=True, nogil=True, error_model="numpy")
def window_measure(image, points, radius_px, half, threshold_fraction, above_mean, least_contrast,
                   masks, n_phases, top, sides, runs):
    """`pins._window.WindowCentroids._measure` (its NumPy reference: `_measure_numpy`), a loop over the windows.

    image (H, W) uint8; points (N, 2) float64, px; radius_px (N,) float64, px; the window's settings
    (half side, threshold fraction, above the mean, least contrast); masks (radius x phase y x
    phase x, P) uint8; n_phases; the five centre pixels `top` and the sides' runs `sides` (side, run,
    pixel) as indices into a window's P pixels; runs per side. Returns the centroids (N, 2), px (NaN
    where the window does not fit in the image or the point is not finite) and (area, contrast,
    compactness) (3, N). A window that does not fit is measured at the image's corner, as there.
    """
    n = points.shape[0]
    height, width = image.shape
    side = 2 * half + 1
    pixels = side * side
    n_radii = masks.shape[0] // (n_phases * n_phases)
    middle_phase = n_phases // 2
    centres = np.empty((n, 2))
    measures = np.empty((3, n))
    grey = np.empty(pixels)
    for i in range(n):
        px, py = points[i, 0], points[i, 1]
        if not (np.isfinite(px) and np.isfinite(py)):
            centres[i, 0] = centres[i, 1] = np.nan
            measures[0, i] = measures[1, i] = measures[2, i] = np.nan
            continue
        ax, ay = np.rint(px), np.rint(py)
        fits = ax - half >= 0 and ay - half >= 0 and ax - half <= width - side and ay - half <= height - side
        cx, cy = (int(ax) - half, int(ay) - half) if fits else (0, 0)
        total = 0.0
        for r in range(side):
            for c in range(side):
                value = np.float64(image[cy + r, cx + c])
                grey[r * side + c] = value
                total += value
        tip = 0.0
        for k in range(top.size):
            tip += grey[top[k]]
        tip /= top.size
        # The darkest run of each side (left, right, top, bottom); the plane through them.
        darkest = np.empty(4)
        for s in range(4):
            least = np.inf
            for run in range(runs):
                start = (s * runs + run) * _SIDE_RUN
                summed = 0.0
                for j in range(_SIDE_RUN):
                    summed += grey[sides[start + j]]
                least = min(least, summed)
            darkest[s] = least
        background = (darkest[0] + darkest[1] + darkest[2] + darkest[3]) * (0.25 / _SIDE_RUN)
        rise_x = (darkest[1] - darkest[0]) * (0.5 / _SIDE_RUN)
        rise_y = (darkest[3] - darkest[2]) * (0.5 / _SIDE_RUN)
        contrast = tip - background
        shrink = _FLAT_RISE * contrast / np.sqrt(rise_x * rise_x + rise_y * rise_y)
        sloped = shrink < 1.0 and contrast > least_contrast
        positive = max(contrast, 0.0)
        lift = threshold_fraction * positive
        if above_mean:
            lift = min(max(lift, total / pixels - background), positive)
        level = background + lift
        if sloped:
            factor = (1.0 - max(shrink, 0.0)) / half
            c0, c1, c2 = np.float32(level), np.float32(rise_x * factor), np.float32(rise_y * factor)
        else:
            c0, c1, c2 = np.float32(np.rint(level)), np.float32(0.0), np.float32(0.0)
        # The mask of the point's quarter-pixel phase and its radius (NaN: the widest).
        qx = int(np.rint((px - ax) * _PHASES)) + middle_phase
        qy = int(np.rint((py - ay) * _PHASES)) + middle_phase
        quarter = np.rint(radius_px[i] * _PHASES)
        if not quarter <= n_radii:  # (NaN too)
            quarter = np.float64(n_radii)
        elif quarter < 1.0:
            quarter = 1.0
        mask = masks[qx + n_phases * qy + n_phases * n_phases * (int(quarter) - 1)]
        mass = sum_x = sum_y = sum_r2 = 0.0
        for r in range(side):
            gy = np.float64(r - half)
            for c in range(side):
                k = r * side + c
                if mask[k] == 0:
                    continue
                gx = np.float64(c - half)
                weight = grey[k] - _plane_level(c0, c1, c2, gx, gy)
                if weight > 0.0:
                    mass += weight
                    sum_x += weight * gx
                    sum_y += weight * gy
                    sum_r2 += weight * (gx * gx + gy * gy)
        offset_x, offset_y = sum_x / mass, sum_y / mass
        area = mass / (tip - level)
        spread = sum_r2 / mass - (offset_x * offset_x + offset_y * offset_y)
        measures[0, i] = area
        measures[1, i] = contrast
        measures[2, i] = area / (2 * math.pi * spread)
        if fits:
            centres[i, 0], centres[i, 1] = ax + offset_x, ay + offset_y
        else:
            centres[i, 0] = centres[i, 1] = np.nan
    return centres, measures


_EDGE_PX = 0.55  # `pins._tipfit._EDGE_PX`
_REACH_PX = 0.8  # `pins._tipfit._REACH_PX`
_RIDGE = 1e-6  # `pins._tipfit._RIDGE`'s diagonal
_ERF_SLOPE = 1.0 / (math.sqrt(math.pi) * _EDGE_PX)  # `pins._tipfit._ERF_SLOPE`


@njit(cache=True, nogil=True, error_model="numpy")
def _solve_in_place(a, b):
    """Solve ``a x = b`` (M, M) and (M,) float64 by Gaussian elimination with partial pivoting, as LAPACK's
    ``gesv`` does (`np.linalg.solve`); `a` and `b` are overwritten, `b` with x. A zero pivot gives inf/NaN."""
    m = b.size
    for col in range(m):
        pivot = col
        for row in range(col + 1, m):
            if abs(a[row, col]) > abs(a[pivot, col]):
                pivot = row
        if pivot != col:
            for k in range(m):
                a[col, k], a[pivot, k] = a[pivot, k], a[col, k]
            b[col], b[pivot] = b[pivot], b[col]
        for row in range(col + 1, m):
            factor = a[row, col] / a[col, col]
            for k in range(col + 1, m):
                a[row, k] -= factor * a[col, k]
            b[row] -= factor * b[col]
    for row in range(m - 1, -1, -1):
        total = b[row]
        for k in range(row + 1, m):
            total -= a[row, k] * b[k]
        b[row] = total / a[row, row]


@njit(cache=True, nogil=True, error_model="numpy")
def _clip_step(step):
    """A step clipped to [-0.5, 0.5] px; NaN stays NaN (as ``np.minimum(np.maximum(step, -0.5), 0.5)``)."""
    return step if step != step else min(max(step, -0.5), 0.5)


@njit(cache=True, nogil=True, error_model="numpy")
def centre_step(image, start, reach, neighbours, nearest, theta, gx, gy):
    """`pins._tipfit._centre_step` on the windows `pins._tipfit._Windows` would gather, in one loop over them.

    image (H, W) grey levels; start (N, 2) float64, px; reach (N,) px; neighbours (N, k, 2) px and the
    nearest's distance (N,) px (pixels nearer a neighbour than half that are left out); theta (N, 5)
    (centre, Q_xx, Q_xy, Q_yy); gx, gy (P,) int: the offsets of the window's disc (`_disc_offsets`).
    Returns the centres (N, 2), px, as `_centre_step` does.
    """
    n = start.shape[0]
    height, width = image.shape
    pixels = gx.size
    out = np.empty((n, 2))
    # Per window: each pixel's weight (usable and within reach), grey level and offsets from the centre.
    weight = np.empty(pixels, np.bool_)
    values = np.empty(pixels)
    # Per pixel, from the first pass for the second: offsets from the centre, q, its root, the length
    # and the edge's argument, the coverage.
    kept = np.empty((pixels, 7))
    products = np.empty((8, 9))
    basis = np.empty(9)
    normal = np.empty((8, 8))
    beta = np.empty(8)
    for i in range(n):
        ax, ay = np.rint(start[i, 0]), np.rint(start[i, 1])
        mu_x, mu_y = theta[i, 0], theta[i, 1]
        q_xx, q_xy, q_yy = theta[i, 2], theta[i, 3], theta[i, 4]
        apart = (0.5 * nearest[i]) ** 2
        products[:] = 0.0
        for p in range(pixels):
            x, y = ax + gx[p], ay + gy[p]
            ix, iy = int(x), int(y)
            inside = 0 <= ix < width and 0 <= iy < height
            values[p] = np.float64(image[min(max(iy, 0), height - 1), min(max(ix, 0), width - 1)])
            usable = inside
            if usable:
                for k in range(neighbours.shape[1]):
                    dx, dy = x - neighbours[i, k, 0], y - neighbours[i, k, 1]
                    if not dx * dx + dy * dy > apart:
                        usable = False
                        break
            ex, ey = x - mu_x, y - mu_y
            weight[p] = usable and math.sqrt(ex * ex + ey * ey) <= reach[i]
            if not weight[p]:
                continue
            q = max(ex * (q_xx * ex + q_xy * ey) + ey * (q_xy * ex + q_yy * ey), 1e-12)
            root = math.sqrt(q)
            length = math.sqrt(ex * ex + ey * ey)
            edge = length * (1.0 - root) / root / _EDGE_PX
            coverage = 0.5 + 0.5 * math.erf(edge)
            kept[p, 0], kept[p, 1], kept[p, 2], kept[p, 3] = ex, ey, q, root
            kept[p, 4], kept[p, 5], kept[p, 6] = length, edge, coverage
            bare = 1.0 - coverage
            basis[0], basis[1], basis[2] = bare, ex * bare, ey * bare
            basis[3], basis[4], basis[5] = ex * ex * bare, ex * ey * bare, ey * ey * bare
            basis[6], basis[7], basis[8] = coverage, coverage * min(q, 1.0), values[p]
            for k in range(8):
                for m in range(k, 9):
                    products[k, m] += basis[k] * basis[m]
        # The linear parameters (quadratic membrane, the tip's level and dome) in closed form.
        for k in range(8):
            for m in range(k):
                normal[k, m] = products[m, k]
            for m in range(k, 8):
                normal[k, m] = products[k, m]
            normal[k, k] += _RIDGE
            beta[k] = products[k, 8]
        _solve_in_place(normal, beta)
        # The centre's Gauss-Newton step: J^T J and J^T r of d m / d mu (x, y).
        a = b = d = g0 = g1 = 0.0
        for p in range(pixels):
            if not weight[p]:
                continue
            ex, ey, q, root = kept[p, 0], kept[p, 1], kept[p, 2], kept[p, 3]
            length, edge, coverage = kept[p, 4], kept[p, 5], kept[p, 6]
            qex, qey = q_xx * ex + q_xy * ey, q_xy * ex + q_yy * ey
            dome = min(q, 1.0)
            surface = beta[0] + beta[1] * ex + beta[2] * ey + beta[3] * ex * ex + beta[4] * ex * ey + beta[5] * ey * ey
            rise = beta[6] + beta[7] * dome - surface
            slope = rise * math.exp(-(edge * edge)) * _ERF_SLOPE
            by_q = slope * (length / (-2.0 * q * root)) + (beta[7] * coverage if q < 1.0 else 0.0)
            inward = slope * (1.0 - 1.0 / root) / max(length, 1e-9)
            j0 = ex * inward - 2.0 * qex * by_q
            j1 = ey * inward - 2.0 * qey * by_q
            residual = values[p] - (surface + coverage * rise)
            a += j0 * j0
            b += j0 * j1
            d += j1 * j1
            g0 += j0 * residual
            g1 += j1 * residual
        a, d = a * (1.0 + 1e-3) + 1e-9, d * (1.0 + 1e-3) + 1e-9
        det = a * d - b * b
        new_x = mu_x + _clip_step((d * g0 - b * g1) / det)
        new_y = mu_y + _clip_step((a * g1 - b * g0) / det)
        dx, dy = new_x - start[i, 0], new_y - start[i, 1]
        if dx * dx + dy * dy <= _REACH_PX ** 2:
            out[i, 0], out[i, 1] = new_x, new_y
        else:
            out[i, 0], out[i, 1] = mu_x, mu_y
    return out
