"""Compiled kernels (Numba) of the tracker's hot paths, one call a pass: `pins._kernels` picks them.

Each kernel is the NumPy reference it names, written as a loop over the windows: the same
arithmetic, with integer sums where the reference sums whole grey levels in float32 (exact there
too), and the window's float32 threshold plane rounded as OpenBLAS's ``sgemm`` rounds it on this
machine (``c0 + c1 x + c2 y`` by two fused multiply-adds, each rounded to float32; here each exact
in float64, then rounded): the window measurements come out bit for bit the reference's. The tip
fit's sums and its 8 x 8 solve run in another order than NumPy's and LAPACK's and differ in the
last bits (~1e-14 px). The tests hold the kernels to the reference within 1e-9 px.

The tracker's bookkeeping kernels (`pins._jit_track`) are exported here too, so that `pins._kernels`
hands out one module; `follow_passes` runs the follow passes' re-centring rounds with their window
measurements in one call.

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
def _corner(x, y, half, width, height):
    """The window's corner (column, row) at the point (x, y), px, and whether the window fits in the
    image (else the image's corner, (0, 0), as the reference measures it there)."""
    side = 2 * half + 1
    ax, ay = np.rint(x), np.rint(y)
    if ax - half >= 0 and ay - half >= 0 and ax - half <= width - side and ay - half <= height - side:
        return int(ax) - half, int(ay) - half, True
    return 0, 0, False


@njit(cache=True, nogil=True, error_model="numpy")
def _tip_and_sides(image, cx, cy, half):
    """A window's tip (the mean of its five centre pixels) and the plane through the darkest runs of
    `_SIDE_RUN` pixels along its sides (left, right, top, bottom; `pins._window`'s ``_sides``, the
    runs end to end along the middle of each side): its level at the centre and its rise across half
    the window (x, y), grey levels. Sums of whole grey levels: exact, as the reference's."""
    side = 2 * half + 1
    middle_x, middle_y = cx + half, cy + half
    tip = (np.int64(image[middle_y, middle_x]) + np.int64(image[middle_y, middle_x - 1])
           + np.int64(image[middle_y, middle_x + 1]) + np.int64(image[middle_y - 1, middle_x])
           + np.int64(image[middle_y + 1, middle_x])) / 5.0
    runs = side // _SIDE_RUN
    first = (side - runs * _SIDE_RUN) // 2
    darkest = np.empty(4, np.int64)  # left, right, top, bottom
    for s in range(4):
        least = np.int64(1) << 40
        for run in range(runs):
            summed = np.int64(0)
            for j in range(_SIDE_RUN):
                along = first + run * _SIDE_RUN + j
                if s == 0:
                    summed += image[cy + along, cx]
                elif s == 1:
                    summed += image[cy + along, cx + side - 1]
                elif s == 2:
                    summed += image[cy, cx + along]
                else:
                    summed += image[cy + side - 1, cx + along]
            least = min(least, summed)
        darkest[s] = least
    background = np.float64(darkest[0] + darkest[1] + darkest[2] + darkest[3]) * (0.25 / _SIDE_RUN)
    rise_x = np.float64(darkest[1] - darkest[0]) * (0.5 / _SIDE_RUN)
    rise_y = np.float64(darkest[3] - darkest[2]) * (0.5 / _SIDE_RUN)
    return tip, background, rise_x, rise_y


@njit(cache=True, nogil=True, error_model="numpy")
def window_contrast(image, points, half):
    """`pins._window.WindowCentroids.contrast`: the tips' contrast (N,), grey levels, of the windows at
    `points` (N, 2), px, in the uint8 `image` (a window that does not fit: at the image's corner)."""
    n = points.shape[0]
    height, width = image.shape
    out = np.empty(n)
    for i in range(n):
        cx, cy, _ = _corner(points[i, 0], points[i, 1], half, width, height)
        tip, background, _, _ = _tip_and_sides(image, cx, cy, half)
        out[i] = tip - background
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def window_measure(image, points, radius_px, half, threshold_fraction, above_mean, least_contrast):
    """`pins._window.WindowCentroids._measure` (its NumPy reference: `_measure_numpy`), a loop over the windows.

    image (H, W) uint8; points (N, 2) float64, px; radius_px (N,) float64, px; the windows' settings
    (half side, threshold fraction, above the mean, least contrast). Returns the centroids (N, 2), px
    (NaN where the window does not fit in the image or the point is not finite) and (area, contrast,
    compactness) (3, N). A window that does not fit is measured at the image's corner, as there. The
    disc masks are the reference's (``_masks``): pixels within the quarter-px radius of the point's
    quarter-px phase (squares of quarters: exact).
    """
    n = points.shape[0]
    height, width = image.shape
    side = 2 * half + 1
    pixels = side * side
    widest = int((half + 0.5) * _PHASES)  # the masks' radii: 1 .. widest quarter px
    centres = np.empty((n, 2))
    measures = np.empty((3, n))
    across, dx2 = np.empty(side), np.empty(side)
    for i in range(n):
        px, py = points[i, 0], points[i, 1]
        if not (np.isfinite(px) and np.isfinite(py)):
            centres[i, 0] = centres[i, 1] = np.nan
            measures[0, i] = measures[1, i] = measures[2, i] = np.nan
            continue
        ax, ay = np.rint(px), np.rint(py)
        cx, cy, fits = _corner(px, py, half, width, height)
        tip, background, rise_x, rise_y = _tip_and_sides(image, cx, cy, half)
        contrast = tip - background
        shrink = _FLAT_RISE * contrast / np.sqrt(rise_x * rise_x + rise_y * rise_y)
        sloped = shrink < 1.0 and contrast > least_contrast
        positive = max(contrast, 0.0)
        lift = threshold_fraction * positive
        if above_mean:
            total = np.int64(0)
            for r in range(side):
                for c in range(side):
                    total += image[cy + r, cx + c]
            lift = min(max(lift, total / pixels - background), positive)
        level = background + lift
        # The mask: the point's quarter-px phase (x, y) and its radius in quarter px (NaN: the widest).
        phase_x, phase_y = np.rint((px - ax) * _PHASES) / _PHASES, np.rint((py - ay) * _PHASES) / _PHASES
        quarter = np.rint(radius_px[i] * _PHASES)
        if not quarter <= widest:  # (NaN too)
            quarter = np.float64(widest)
        elif quarter < 1.0:
            quarter = 1.0
        reach = (quarter / _PHASES) ** 2
        # Each pixel weighs its grey level above the threshold, in whole grey levels (a flat threshold
        # rounded, a sloped plane rounded pixel by pixel): integer sums, exact as the reference's.
        if sloped:
            factor = (1.0 - max(shrink, 0.0)) / half
            c0, c1, c2 = np.float32(level), np.float32(rise_x * factor), np.float32(rise_y * factor)
        else:
            c0 = c1 = c2 = np.float32(0.0)
        flat = np.int64(np.rint(level))
        # Per column: the plane's first fused multiply-add (c0 + c1 x, rounded to float32 as ``sgemm`` does;
        # the product exact in float64) and the squared distance from the phase in x.
        for c in range(side):
            across[c] = np.float64(np.float32(np.float64(c0) + np.float64(c1) * (c - half)))
            dx2[c] = (c - half - phase_x) ** 2
        mass = sum_x = sum_y = sum_r2 = np.int64(0)
        for r in range(side):
            dy = r - half
            dy2 = (dy - phase_y) ** 2
            down = np.float64(c2) * dy
            for c in range(side):
                dx = c - half
                threshold = flat
                if sloped:
                    threshold = np.int64(np.rint(np.float64(np.float32(across[c] + down))))
                inside = np.int64(dy2 + dx2[c] <= reach)
                weight = max(np.int64(image[cy + r, cx + c]) - threshold, 0) * inside
                mass += weight
                sum_x += weight * dx
                sum_y += weight * dy
                sum_r2 += weight * (dx * dx + dy * dy)
        offset_x, offset_y = sum_x / mass, sum_y / mass  # (int64 / int64: float64, NaN for no mass)
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
    ``gesv`` does (`np.linalg.solve`); `a` and `b` are overwritten, `b` with x. A zero pivot gives inf/NaN
    and False (singular); True otherwise."""
    m = b.size
    regular = True
    for col in range(m):
        pivot = col
        for row in range(col + 1, m):
            if abs(a[row, col]) > abs(a[pivot, col]):
                pivot = row
        if a[pivot, col] == 0.0:
            regular = False
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
    return regular


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


# The tracker's bookkeeping round its window measurements (`pins._follow`, `pins._predict`, `pins._identity`,
# `pins._rest`), and the follow passes with their window measurements (`follow_passes`, below).
from ._jit_rest import observe_still, rest_judge, rest_look  # noqa: E402
from ._jit_track import (carried_velocity, displacement_median, follow_first, follow_pass,  # noqa: E402
                         keep_own_tips, neighbour_median, one_pin_per_tip, predict, remember, settle, trusted)

# (Named here: the kernels `pins._kernels` hands out with this module.)
_TRACK_KERNELS = (carried_velocity, displacement_median, follow_first, follow_pass, keep_own_tips, neighbour_median,
                  observe_still, one_pin_per_tip, predict, remember, rest_judge, rest_look, settle, trusted)


@njit(cache=True, nogil=True, error_model="numpy")
def follow_passes(image, origin, half, threshold_fraction, above_mean, least_contrast, points, start, chain, which,
                  radius, searched, fresh, settled_sq, fine, reach, gate_sq, passes, at_least, area_at_most, positions):
    """`pins._follow`'s re-centring passes in one call: up to `passes` rounds of `window_measure` (the windows'
    settings as there; `image` the crop at `origin` (2,), px) of the windows `chain` from `points` (C, 2),
    px, each judged by `pins._jit_track.follow_pass` (its arguments as there; `fresh` for the first round
    only; the last round its last pass). Returns the rows placed, in the order the passes placed them."""
    placed = np.empty(chain.shape[0], np.int64)
    count = 0
    chain_radius = np.empty(chain.shape[0])
    for i in range(chain.shape[0]):
        chain_radius[i] = radius[chain[i]]
    none = np.zeros(chain.shape[0], np.bool_)
    for round_ in range(passes):
        if chain.shape[0] == 0:
            break
        local = np.empty(points.shape)
        for i in range(points.shape[0]):
            local[i, 0] = points[i, 0] - origin[0]
            local[i, 1] = points[i, 1] - origin[1]
        centres, measures = window_measure(image, local, chain_radius, half, threshold_fraction, above_mean,
                                           least_contrast)
        for i in range(centres.shape[0]):
            centres[i, 0] += origin[0]
            centres[i, 1] += origin[1]
        ok, chain, points, searched, chain_radius = follow_pass(
            centres, measures, points, start, chain, which, radius, searched, fresh if round_ == 0 else none,
            settled_sq, fine, reach, gate_sq, round_ == passes - 1, at_least, area_at_most, positions)
        placed[count:count + ok.shape[0]] = ok
        count += ok.shape[0]
    return placed[:count]
