"""Compiled kernel (Numba) of `pins._follow._Following._part_tips`: tips in the re-centred follow windows that hold two
or more, assigned one-to-one, in one call with the re-measurement after it (issue 20, outcomes 2 and 9);
`pins._kernels.compiled("_jit_follow")` picks it, `pins._follow` keeps the NumPy reference.

The reference blurs, erodes and dilates the whole part of the crop round the windows (OpenCV; that part's noise held
~840 local maxima a frame) and then loops in Python over the windows with two tips. Here a first look blurs only
each window's own square (`half` px round its centre; about 1 window in 10 passes it on the slide video) and asks
for two local maxima within the square, more than a tip radius apart, at or above its floor: a superset of the
reference's test (a peak's neighbours beyond the square unseen). Only those windows are blurred again over squares
twice as wide, and judged as the reference judges them (full neighbourhoods, the peaks' own rise). The squares are
laid side by side so that each blur pass is one loop over rows as long as all of them (vectorised: a square alone
has too few columns; `pins._jit_squares`), those within the blur's reach of the crop's edge blurred one by one
(reflected there as OpenCV reflects). The blur is OpenCV's Gaussian (its kernel size and float32 weights) summed in
float32 in another order, and it reads the crop's own pixels where the reference reflects them at its part's edge
(2 half beyond the outermost window): a peak at a threshold or there may fall the other way (radial-led-120 through
two slides, seed 1: 1 pin-frame of 8160 placed 0.016 px apart). The assignment is the least sum of squared
distances over every one-to-one pairing (a depth-first search, few rows and columns) where the reference calls
`scipy.optimize.linear_sum_assignment`: the same unless two pairings tie.

``cache=True``: compiled once per machine, then loaded from ``__pycache__``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._jit import window_measure
from ._jit_squares import blur_square, blurred_squares, extremes, is_top, may_hold_two


@njit(cache=True, nogil=True, error_model="numpy")
def _first_look(crop, origin, positions, pins, half, maximum_reach, weights, tip_sq, rows, values):
    """Which windows (at the finite `positions` of `pins`, inside the crop) may hold two tips, on the crop blurred
    over each window's square of `half` px: two local maxima within `half` of its centre, more than a tip radius
    (`tip_sq`, px^2) apart, at or above the middle of the darkest and brightest of its square, judged within that
    square alone (a peak's neighbours beyond it unseen: every pair of tips the full test finds, and some more).
    The squares inside the crop with their blur's reach are blurred side by side (`blurred_squares`), the others
    one by one (`blur_square`, with the scratch `rows` and `values`)."""
    height, width = crop.shape
    count = pins.shape[0]
    k = weights.size // 2
    side = 2 * half + 1
    reach = maximum_reach
    look = np.zeros(count, np.bool_)
    slot = np.full(count, -1, np.int64)
    xs = np.empty(count, np.int64)
    ys = np.empty(count, np.int64)
    inside = 0
    for i in range(count):
        x, y = positions[pins[i], 0] - origin[0], positions[pins[i], 1] - origin[1]
        if not (np.isfinite(x) and np.isfinite(y)):
            continue
        cx, cy = int(np.rint(x)), int(np.rint(y))
        if cx < 0 or cy < 0 or cx >= width or cy >= height:
            continue
        if cx - half - k >= 0 and cy - half - k >= 0 and cx + half + k < width and cy + half + k < height:
            xs[inside], ys[inside] = cx, cy
            slot[i] = inside
            inside += 1
        else:
            blur_square(crop, weights, cx, cy, half, rows, values)
            look[i] = may_hold_two(values, half, half, half, reach, tip_sq)
    if inside == 0:
        return look
    blurred, block = blurred_squares(crop, xs[:inside], ys[:inside], half, weights, reach)
    span = blurred.shape[1]
    # The greatest value within `reach` of each pixel, inside its square: along the rows, then down the columns.
    along = np.empty((side, span), np.float32)
    for r in range(side):
        line = blurred[r]
        target = along[r]
        for j in range(span):
            target[j] = line[j]
        for t in range(1, reach + 1):
            left = line[:span - t]
            right = line[t:]
            ahead = target[:span - t]
            for j in range(span - t):
                ahead[j] = max(ahead[j], right[j])
            behind = target[t:]
            for j in range(span - t):
                behind[j] = max(behind[j], left[j])
    greatest = np.empty((side, span), np.float32)
    # The darkest and brightest of each column of the squares.
    low = np.empty(span, np.float32)
    high = np.empty(span, np.float32)
    for j in range(span):
        low[j] = np.inf
        high[j] = -np.inf
    for r in range(side):
        target = greatest[r]
        line = along[max(r - reach, 0)]
        for j in range(span):
            target[j] = line[j]
        for rr in range(max(r - reach, 0) + 1, min(r + reach, side - 1) + 1):
            line = along[rr]
            for j in range(span):
                target[j] = max(target[j], line[j])
        line = blurred[r]
        for j in range(span):
            low[j] = min(low[j], line[j])
            high[j] = max(high[j], line[j])
    half_sq = half * half
    tops = np.empty((side * side, 2), np.int64)
    for i in range(count):
        if slot[i] < 0:
            continue
        j0 = reach + slot[i] * block
        darkest, brightest = np.inf, -np.inf
        for c in range(side):
            darkest = min(darkest, low[j0 + c])
            brightest = max(brightest, high[j0 + c])
        floor = np.float32(0.5) * (np.float32(darkest) + np.float32(brightest))
        found = 0
        for r in range(side):
            dy = r - half
            line = blurred[r, j0:j0 + side]
            most = greatest[r, j0:j0 + side]
            for c in range(side):
                v = line[c]
                if not (v >= floor and v >= most[c]):
                    continue
                dx = c - half
                if dx * dx + dy * dy > half_sq:
                    continue
                for q in range(found):
                    if (r - tops[q, 0]) ** 2 + (c - tops[q, 1]) ** 2 > tip_sq:
                        look[i] = True
                        break
                if look[i]:
                    break
                tops[found, 0], tops[found, 1] = r, c
                found += 1
            if look[i]:
                break
    return look


@njit(cache=True, nogil=True, error_model="numpy")
def _assigned(expected, count, peaks, n_peaks):
    """The peak assigned to row 0 of `expected` ((count, 2), px) when rows and `peaks` ((n_peaks, 2), px) are
    paired one-to-one at the least sum of squared distances (every row or every peak paired, whichever are
    fewer), or -1 when row 0 stays unpaired."""
    cost = np.empty((count, n_peaks))
    for i in range(count):
        for j in range(n_peaks):
            dx = expected[i, 0] - peaks[j, 0]
            dy = expected[i, 1] - peaks[j, 1]
            cost[i, j] = dx * dx + dy * dy
    rows_fewer = count <= n_peaks
    small = count if rows_fewer else n_peaks
    large = n_peaks if rows_fewer else count
    # Depth-first over the smaller side: element s takes a free element of the larger side.
    choice = np.full(small, -1, np.int64)
    best_choice = np.full(small, -1, np.int64)
    taken = np.zeros(large, np.bool_)
    best = np.inf
    total = 0.0
    s = 0
    while s >= 0:
        # Free the element s held, then try the next one of the larger side.
        if choice[s] >= 0:
            taken[choice[s]] = False
            total -= cost[s, choice[s]] if rows_fewer else cost[choice[s], s]
        nxt = choice[s] + 1
        while nxt < large and taken[nxt]:
            nxt += 1
        if nxt >= large:
            choice[s] = -1
            s -= 1
            continue
        step = cost[s, nxt] if rows_fewer else cost[nxt, s]
        choice[s] = nxt
        taken[nxt] = True
        total += step
        if total >= best:
            continue  # (no cheaper pairing below: costs are >= 0)
        if s == small - 1:
            best = total
            best_choice[:] = choice
            continue
        s += 1
    if rows_fewer:
        return best_choice[0]
    for j in range(small):
        if best_choice[j] == 0:
            return j
    return -1


@njit(cache=True, nogil=True, error_model="numpy")
def part_tips(crop, origin, positions, filled, pins, start, half, tip_px, maximum_reach, weights, spacing_px,
              held_from):
    """`pins._follow._Following._part_tips` up to its windows' re-measurement: the windows at the `positions`
    ((N, 2), px in the frame) of `pins` (F,) (guesses `start` (F, 2), px; NaN positions skipped) whose square of
    `half` px holds two or more tips (local maxima of the crop blurred by `weights` over `maximum_reach` px,
    within `half` px of the window's centre, that reach half-way from the darkest to the brightest of the
    window's square and of their own, one per `tip_px`), their tips assigned one-to-one to the pin's guess and
    the other pins' expected places near the tip (within 1.5 `half`: a position, else `filled`).

    Returns the rows (of `pins`) whose pin is re-measured, the tips they were assigned ((M, 2), px in the frame)
    and the windows' radii there (half the distance to the next tip, within [1.5, 0.55 `spacing_px`]), and the
    rows whose pin was assigned no tip (to be unplaced). Rows from `held_from` on (first-pass pins) assigned no tip
    are left as they are, and those assigned a tip farther than `tip_px` from their position are unplaced.
    """
    height, width = crop.shape
    count = pins.shape[0]
    taps = weights.size
    # The pixels a peak's tests read: its neighbourhood (`maximum_reach`) and its own square (`half`).
    most = half + max(half, maximum_reach)
    columns = 2 * most + 1
    values = np.empty((2 * half + 1, columns), np.float32)
    rows = np.empty((2 * most + taps, columns), np.float32)
    wide_values_edge = np.empty((2 * most + 1, columns), np.float32)
    peak_r = np.empty((2 * half + 1) ** 2, np.int64)
    peak_c = np.empty((2 * half + 1) ** 2, np.int64)
    peak_v = np.empty((2 * half + 1) ** 2, np.float32)
    kept = np.empty((2 * half + 1) ** 2, np.int64)
    peaks = np.empty(((2 * half + 1) ** 2, 2))
    expected = np.empty((positions.shape[0] + 1, 2))
    at = np.empty((0, 2))  # the expected places, made when a window first needs them
    moved = np.empty(count, np.int64)
    aims = np.empty((count, 2))
    radii = np.empty(count)
    unplaced = np.empty(count, np.int64)
    n_moved = 0
    n_unplaced = 0
    tip_sq = tip_px * tip_px
    half_sq = half * half
    others_sq = (1.5 * half) ** 2
    # A first look, over each window's own square alone: its local maxima (judged within the square) at or above
    # its floor, two of them more than a tip radius apart, or no two tips (about one window in ten passes).
    look = _first_look(crop, origin, positions, pins, half, maximum_reach, weights, tip_sq, rows, values)
    # The windows that may hold two tips, again over squares twice as wide: the peaks' full neighbourhoods and their
    # own squares (side by side where they lie inside the crop with their blur's reach, else one by one).
    k = taps // 2
    xs = np.empty(count, np.int64)
    ys = np.empty(count, np.int64)
    slot = np.full(count, -1, np.int64)
    inside = 0
    for i in range(count):
        if look[i]:
            cx = int(np.rint(positions[pins[i], 0] - origin[0]))
            cy = int(np.rint(positions[pins[i], 1] - origin[1]))
            if cx - most - k >= 0 and cy - most - k >= 0 and cx + most + k < width and cy + most + k < height:
                xs[inside], ys[inside] = cx, cy
                slot[i] = inside
                inside += 1
    if inside:
        squares, block = blurred_squares(crop, xs[:inside], ys[:inside], most, weights, 0)
    else:
        squares, block = np.empty((2 * most + 1, 0), np.float32), 0
    for i in range(count):
        if not look[i]:
            continue
        tip_x, tip_y = positions[pins[i], 0], positions[pins[i], 1]
        cx = int(np.rint(tip_x - origin[0]))
        cy = int(np.rint(tip_y - origin[1]))
        if slot[i] >= 0:
            wide_values = squares[:, slot[i] * block:slot[i] * block + 2 * most + 1]
        else:
            blur_square(crop, weights, cx, cy, most, rows, wide_values_edge)
            wide_values = wide_values_edge[:, :2 * most + 1]
        low, high = extremes(wide_values, 2 * most + 1, most, most, half)
        floor = np.float32(0.5) * (np.float32(low) + np.float32(high))  # (float32, as the reference's)
        # Local maxima within `half` of the centre at or above the window's floor, each rising half-way from the
        # darkest to the brightest of its own square.
        m = 0
        for dy in range(-half, half + 1):
            for dx in range(-half, half + 1):
                if dx * dx + dy * dy > half_sq:
                    continue
                r, c = most + dy, most + dx
                v = wide_values[r, c]
                if not (v >= floor and is_top(wide_values, 2 * most + 1, r, c, maximum_reach, v)):
                    continue  # (NaN outside the crop)
                p_low, p_high = extremes(wide_values, 2 * most + 1, r, c, half)
                if v >= np.float32(0.5) * (np.float32(p_low) + np.float32(p_high)) and p_high > p_low:
                    peak_r[m], peak_c[m], peak_v[m] = dy, dx, v
                    m += 1
        if m < 2:
            continue
        # One peak per tip: the brightest of peaks within a tip radius of each other (ties in raster order).
        order = np.argsort(-peak_v[:m], kind="mergesort")
        n_kept = 0
        for j in order:
            ok = True
            for q in range(n_kept):
                ddx = peak_c[kept[q]] - peak_c[j]
                ddy = peak_r[kept[q]] - peak_r[j]
                if ddx * ddx + ddy * ddy <= tip_sq:
                    ok = False
                    break
            if ok:
                kept[n_kept] = j
                n_kept += 1
        if n_kept < 2:
            continue
        for q in range(n_kept):
            peaks[q, 0] = cx + peak_c[kept[q]] + origin[0]
            peaks[q, 1] = cy + peak_r[kept[q]] + origin[1]
        # The pin's guess and every other pin's expected place near its tip.
        if at.shape[0] == 0:
            at = np.where(np.isfinite(positions), positions, filled)
            for j in range(count):
                at[pins[j], 0], at[pins[j], 1] = start[j, 0], start[j, 1]
        expected[0, 0], expected[0, 1] = start[i, 0], start[i, 1]
        rows_count = 1
        for other in range(at.shape[0]):
            if other == pins[i]:
                continue
            ox = at[other, 0] - tip_x
            oy = at[other, 1] - tip_y
            if ox * ox + oy * oy <= others_sq:
                expected[rows_count, 0], expected[rows_count, 1] = at[other, 0], at[other, 1]
                rows_count += 1
        mine = _assigned(expected, rows_count, peaks, n_kept)
        if mine < 0:
            if i < held_from:
                unplaced[n_unplaced] = i
                n_unplaced += 1
            continue
        if i >= held_from:
            ax = peaks[mine, 0] - tip_x
            ay = peaks[mine, 1] - tip_y
            if ax * ax + ay * ay > tip_sq:  # (another pin's tip: LK decides)
                unplaced[n_unplaced] = i
                n_unplaced += 1
                continue
        gap_sq = np.inf
        for q in range(n_kept):
            if q != mine:
                gx = peaks[q, 0] - peaks[mine, 0]
                gy = peaks[q, 1] - peaks[mine, 1]
                gap_sq = min(gap_sq, gx * gx + gy * gy)
        moved[n_moved] = i
        aims[n_moved, 0], aims[n_moved, 1] = peaks[mine, 0], peaks[mine, 1]
        radii[n_moved] = max(min(0.5 * np.sqrt(gap_sq), 0.55 * spacing_px), 1.5)
        n_moved += 1
    return moved[:n_moved], aims[:n_moved], radii[:n_moved], unplaced[:n_unplaced]



@njit(cache=True, nogil=True, error_model="numpy")
def part_tips_measured(crop, origin, positions, filled, pins, start, half, tip_px, maximum_reach, weights, spacing_px,
                       reach_sq, window_half, threshold_fraction, above_mean, least_contrast, held_from):
    """`part_tips` and the re-measurement after it, in place in `positions` (the pins assigned no tip unplaced,
    the others re-measured by `pins._jit.window_measure` at their tips and kept within `reach_sq`, px^2, of their
    guesses, else unplaced), for windows that are `pins._window.WindowCentroids` of `window_half`,
    `threshold_fraction`, `above_mean` and `least_contrast`; rows from `held_from` on as `part_tips` says."""
    moved, aims, radii, unplaced = part_tips(crop, origin, positions, filled, pins, start, half, tip_px,
                                             maximum_reach, weights, spacing_px, held_from)
    for j in range(unplaced.shape[0]):
        positions[pins[unplaced[j]], 0] = np.nan
        positions[pins[unplaced[j]], 1] = np.nan
    if moved.shape[0] == 0:
        return
    for j in range(moved.shape[0]):
        aims[j, 0] -= origin[0]
        aims[j, 1] -= origin[1]
    centres, _ = window_measure(crop, aims, radii, window_half, threshold_fraction, above_mean, least_contrast)
    for j in range(moved.shape[0]):
        row = moved[j]
        x = centres[j, 0] + origin[0]
        y = centres[j, 1] + origin[1]
        dx = x - start[row, 0]
        dy = y - start[row, 1]
        if np.isfinite(x) and dx * dx + dy * dy <= reach_sq:
            positions[pins[row], 0] = x
            positions[pins[row], 1] = y
        else:
            positions[pins[row], 0] = np.nan
            positions[pins[row], 1] = np.nan


@njit(cache=True, nogil=True, error_model="numpy")
def first_pass_parted(positions, which, n, placed, neighbours):
    """`pins._follow._Following._first_pass_parted`'s rows: of the first `n` rows of `which` (pins, into `positions`
    (N, 2), px), those at finite positions, not in `placed` (rows re-centred), with a pin of `neighbours` ((k, N):
    each pin's window neighbours) at NaN. In one pass, where the NumPy version's dozen calls cost 0.06 ms a frame
    (tactip-331 slides, 3 % of the tracker's CPU)."""
    skip = np.zeros(n, np.bool_)
    for j in range(placed.shape[0]):
        if placed[j] < n:
            skip[placed[j]] = True
    rows = np.empty(n, np.int64)
    count = 0
    for row in range(n):
        if skip[row]:
            continue
        pin = which[row]
        if not np.isfinite(positions[pin, 0]):
            continue
        for k in range(neighbours.shape[0]):
            if np.isnan(positions[neighbours[k, pin], 0]):
                rows[count] = row
                count += 1
                break
    return rows[:count]

