"""Compiled kernels (Numba) of the tracker's bookkeeping round its window measurements, one call each:
`pins._jit` exports them and `pins._kernels` picks them (issue 20, outcome 9).

The follow passes' judgements (`pins._follow`: which windows settled, which go on, the next chain), the
neighbours' medians, a lost pin's prediction, whether to search there, carried steps and remembered
displacements (`pins._predict`), one pin per tip and pins kept on their own tips (`pins._identity`); the
still pad's in `pins._jit_rest`. Each is the NumPy reference it names, written as a loop over the pins: the
same float64 operations in the same order (a squared norm is ``x * x + y * y``, a median the mean of the
middle one or two finite values), so the results are the reference's bit for bit; on a few hundred
pins a frame the NumPy calls' fixed cost (a few us each), not their arithmetic, set the time.

``cache=True``: compiled once per machine, then loaded from ``__pycache__``.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True, error_model="numpy")
def _like(measures, i, pin, at_least, area_at_most):
    """`pins._refine.Refiner._like_at_rest` of window `i` (column of the (3, L) `measures`) for pin `pin`."""
    return (measures[0, i] >= at_least[0, pin] and measures[1, i] >= at_least[1, pin]
            and measures[2, i] >= at_least[2, pin] and measures[0, i] <= area_at_most[pin])


@njit(cache=True, nogil=True, error_model="numpy")
def follow_first(first, start, measures, which, n, rest_positions, rest_offset, spacing_px, gate_px, fine, reach,
                 at_least, area_at_most, positions):
    """`pins._follow`'s judgement of the first pass: the windows' centroids `first` (L, 2), px, of pins
    `which` (L,) started at `start` (L, 2), px (the first `n` followed from their guesses, the others
    searched for), less the pins' pull at rest (`Refiner._pull`). Pins whose window moved by at most
    `fine` (px^2) onto a tip like at rest are placed in `positions` (N, 2), px, in place.

    Returns the placed centroids (L, 2), px, the windows to re-centre (their rows, increasing) and the
    pins followed from a guess that found no tip near it (rows `far`, < n).
    """
    count = first.shape[0]
    placed_at = np.empty((count, 2))
    again = np.empty(count, np.int64)
    far = np.empty(count, np.int64)
    n_again = 0
    n_far = 0
    for i in range(count):
        pin = which[i]
        dx = start[i, 0] - rest_positions[pin, 0]
        dy = start[i, 1] - rest_positions[pin, 1]
        distance = np.sqrt(dx * dx + dy * dy)
        weight = (spacing_px - distance) / (spacing_px - gate_px)
        weight = max(weight, 0.0) if weight == weight else 0.0  # (np.fmax: NaN to 0)
        weight = min(weight, 1.0)
        x = first[i, 0] - rest_offset[pin, 0] * weight
        y = first[i, 1] - rest_offset[pin, 1] * weight
        placed_at[i, 0] = x
        placed_at[i, 1] = y
        mx = x - start[i, 0]
        my = y - start[i, 1]
        moved = mx * mx + my * my
        done = i < n and moved <= fine and _like(measures, i, pin, at_least, area_at_most)
        if done:
            positions[pin, 0] = x
            positions[pin, 1] = y
        elif np.isfinite(first[i, 0]) and (i >= n or moved <= reach):
            again[n_again] = i
            n_again += 1
        elif i < n:
            far[n_far] = i
            n_far += 1
    return placed_at, again[:n_again], far[:n_far]


@njit(cache=True, nogil=True, error_model="numpy")
def follow_pass(centres, measures, points, start, chain, which, radius, searched, fresh, settled_sq, fine, reach,
                gate_sq, last, at_least, area_at_most, positions):
    """`pins._follow`'s judgement of a re-centring pass: windows `chain` (rows of `start` (L, 2), px, and
    `which` (L,), their pins) re-centred from `points` (C, 2), px, onto `centres` (C, 2), px, with
    their tips' (area, contrast, compactness) `measures` (3, C), judged as the reference judges them (`searched` (C,) bool: searches; `fresh`
    (C,) bool: searches just started; `last`: the last pass). Settled pins are placed in `positions`
    (N, 2), px, in place.

    Returns the rows placed, and the next pass's chain, points, searched and radii (`radius` (L,), px).
    """
    count = chain.shape[0]
    placed = np.empty(count, np.int64)
    going = np.empty(count, np.int64)
    n_placed = 0
    n_going = 0
    for i in range(count):
        row = chain[i]
        pin = which[row]
        sx = centres[i, 0] - points[i, 0]
        sy = centres[i, 1] - points[i, 1]
        ex = centres[i, 0] - start[row, 0]
        ey = centres[i, 1] - start[row, 1]
        moved = sx * sx + sy * sy
        error = ex * ex + ey * ey
        like = _like(measures, i, pin, at_least, area_at_most)
        settled = moved <= settled_sq
        if searched[i]:
            good = settled and error <= gate_sq
        else:
            good = (moved <= fine and error <= reach) or (last and settled and error <= settled_sq)
        ok = like and good
        if ok:
            positions[pin, 0] = centres[i, 0]
            positions[pin, 1] = centres[i, 1]
            placed[n_placed] = row
            n_placed += 1
        elif np.isfinite(centres[i, 0]) and (searched[i] or error <= reach) and (like or fresh[i]):
            going[n_going] = i
            n_going += 1
    going = going[:n_going]
    next_chain = np.empty(n_going, np.int64)
    next_points = np.empty((n_going, 2))
    next_searched = np.empty(n_going, np.bool_)
    next_radius = np.empty(n_going)
    for j in range(n_going):
        i = going[j]
        next_chain[j] = chain[i]
        next_points[j, 0] = centres[i, 0]
        next_points[j, 1] = centres[i, 1]
        next_searched[j] = searched[i]
        next_radius[j] = radius[chain[i]]
    return placed[:n_placed], next_chain, next_points, next_searched, next_radius


@njit(cache=True, nogil=True, error_model="numpy")
def _sort_nan_last(values, count):
    """Sort the first `count` of `values` in place, ascending, NaN last (as `np.sort`; insertion sort: a few)."""
    for i in range(1, count):
        value = values[i]
        j = i - 1
        if value == value:
            while j >= 0 and not (values[j] <= value):  # (a NaN before a number moves up)
                values[j + 1] = values[j]
                j -= 1
        values[j + 1] = value


@njit(cache=True, nogil=True, error_model="numpy")
def _median_into(xs, ys, k, out, row):
    """`pins._predict._median` of one row: the k (x, y) values `xs`, `ys` (sorted in place), into `out[row]`:
    each column's mean of its middle one or two values by the count of finite x, sorted NaN last (with none
    finite, the reference's indices -1 and 0: the mean of the last and first)."""
    count = 0
    for j in range(k):
        if xs[j] == xs[j] and abs(xs[j]) != np.inf:
            count += 1
    _sort_nan_last(xs, k)
    _sort_nan_last(ys, k)
    low = (count - 1) // 2 if count > 0 else k - 1
    high = count // 2
    out[row, 0] = 0.5 * (xs[low] + xs[high])
    out[row, 1] = 0.5 * (ys[low] + ys[high])


@njit(cache=True, nogil=True, error_model="numpy")
def neighbour_median(values, index):
    """`pins._predict._median` of ``values[index]``: each row's median of the (N, 2) `values` at its
    (L, k) `index`, over those with finite x; (L, 2), NaN where none."""
    rows, k = index.shape
    out = np.empty((rows, 2))
    xs = np.empty(k)
    ys = np.empty(k)
    for i in range(rows):
        for j in range(k):
            xs[j] = values[index[i, j], 0]
            ys[j] = values[index[i, j], 1]
        _median_into(xs, ys, k, out, i)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def displacement_median(positions, rest_positions, index):
    """`neighbour_median` of the displacements ``positions - rest_positions`` (N, 2), px, without forming them."""
    rows, k = index.shape
    out = np.empty((rows, 2))
    xs = np.empty(k)
    ys = np.empty(k)
    for i in range(rows):
        for j in range(k):
            pin = index[i, j]
            xs[j] = positions[pin, 0] - rest_positions[pin, 0]
            ys[j] = positions[pin, 1] - rest_positions[pin, 1]
        _median_into(xs, ys, k, out, i)
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def displacement_nanmedian(positions, rest_positions, index):
    """`pins.segment.nanmedian_rows` of the displacements ``positions - rest_positions`` (N, 2), px, gathered at
    each row of the (L, k) `index`, per axis: (L, 2), px, the mean of the middle one or two values that are not
    NaN (infinities count, as there), NaN where every one is; `pins.segment.NeighbourMedians`' one frame."""
    rows, k = index.shape
    out = np.empty((rows, 2))
    values = np.empty(k)
    for i in range(rows):
        for axis in range(2):
            count = 0
            for j in range(k):
                pin = index[i, j]
                value = positions[pin, axis] - rest_positions[pin, axis]
                values[j] = value
                if value == value:
                    count += 1
            if count == 0:
                out[i, axis] = np.nan
                continue
            _sort_nan_last(values, k)
            out[i, axis] = (values[(count - 1) // 2] + values[count // 2]) / 2
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def predict(positions, rest_positions, then, index, which, last_seen):
    """`pins._predict._Prediction._predict`: where lost pins `which` (L,) should be, px (L, 2), from their
    neighbours at (L, k) `index` placed in `positions` (N, 2), px, and `then` (N, k, 2), px (their
    displacements when each pin was last placed)."""
    rows, k = index.shape
    out = np.empty((rows, 2))
    medians = np.empty((3, 2))
    now_x, now_y = np.empty(k), np.empty(k)
    both_x, both_y = np.empty(k), np.empty(k)
    then_x, then_y = np.empty(k), np.empty(k)
    for i in range(rows):
        pin = which[i]
        for j in range(k):
            other = index[i, j]
            x = positions[other, 0] - rest_positions[other, 0]
            y = positions[other, 1] - rest_positions[other, 1]
            tx, ty = then[pin, j, 0], then[pin, j, 1]
            now_x[j], now_y[j] = x, y
            if np.isfinite(x) and np.isfinite(tx):
                both_x[j], both_y[j], then_x[j], then_y[j] = x, y, tx, ty
            else:
                both_x[j] = both_y[j] = then_x[j] = then_y[j] = np.nan
        _median_into(now_x, now_y, k, medians, 0)
        _median_into(both_x, both_y, k, medians, 1)
        _median_into(then_x, then_y, k, medians, 2)
        for c in range(2):
            carried = last_seen[pin, c] + (medians[1, c] - medians[2, c])
            if carried == carried and abs(carried) != np.inf:
                out[i, c] = carried
            elif medians[0, c] != medians[0, c]:
                out[i, c] = last_seen[pin, c]
            else:
                out[i, c] = rest_positions[pin, c] + medians[0, c]
    return out


@njit(cache=True, nogil=True)
def _unplace(positions, found, yields):
    """Rows `found[i]` of `positions` (N, 2), px, set NaN (unplaced) where `yields[i]`, in place."""
    for i in range(found.shape[0]):
        if yields[i]:
            positions[found[i], 0] = np.nan
            positions[found[i], 1] = np.nan


@njit(cache=True, nogil=True, error_model="numpy")
def one_pin_per_tip(positions, found, error, near, same_sq):
    """`pins._refine.Refiner._one_pin_per_tip`: found pins `found` (F,) within `same_sq` (px^2) of a pin among
    their (N, m) `near` that is placed otherwise, or found and no farther from its prediction (squared
    distances `error` (F,), px^2), unplaced (NaN) in `positions` (N, 2), px, in place; all judged first."""
    count = found.shape[0]
    rank = np.full(positions.shape[0], -1.0)
    for i in range(count):
        rank[found[i]] = error[i]
    yields = np.zeros(count, np.bool_)
    for i in range(count):
        pin = found[i]
        px, py = positions[pin, 0], positions[pin, 1]
        for j in range(near.shape[1]):
            other = near[pin, j]
            dx = positions[other, 0] - px
            dy = positions[other, 1] - py
            if dx * dx + dy * dy < same_sq and rank[other] <= error[i]:
                yields[i] = True
                break
    _unplace(positions, found, yields)


@njit(cache=True, nogil=True, error_model="numpy")
def keep_own_tips(positions, found, start, expected, near, margin_sq):
    """`pins._identity.keep_own_tips`: found pins `found` (F,), expected at `start` (F, 2), px, whose tips in
    `positions` (N, 2), px, lie nearer another pin's expected position (among their (N, m) `near`: a placed
    pin's place, another found pin's start, else `expected` (N, 2), px; a missing pin's `margin_sq` times
    nearer) than their own start, unplaced (NaN) in place; all judged first."""
    n = positions.shape[0]
    slot = np.full(n, -1, np.int64)  # each placed found pin's row (the last one, as ``at[found] = start``)
    count = found.shape[0]
    for i in range(count):
        if np.isfinite(positions[found[i], 0]):
            slot[found[i]] = i
    yields = np.zeros(count, np.bool_)
    for i in range(count):
        pin = found[i]
        tx, ty = positions[pin, 0], positions[pin, 1]
        if not np.isfinite(tx):
            continue
        ox, oy = tx - start[i, 0], ty - start[i, 1]
        own = ox * ox + oy * oy
        for j in range(near.shape[1]):
            other = near[pin, j]
            if slot[other] >= 0:
                ax, ay = start[slot[other], 0], start[slot[other], 1]
            else:
                ax, ay = positions[other, 0], positions[other, 1]
                if not np.isfinite(ax):
                    ax = expected[other, 0]
                if not np.isfinite(ay):
                    ay = expected[other, 1]
            dx, dy = ax - tx, ay - ty
            distance = dx * dx + dy * dy
            if positions[other, 0] != positions[other, 0]:
                distance = distance / margin_sq
            if distance < own:
                yields[i] = True
                break
    _unplace(positions, found, yields)


@njit(cache=True, nogil=True, error_model="numpy")
def carried_velocity(velocity, still, bound_sq, index, agree_sq):
    """`pins._predict._Prediction.carried_velocity` in place on `velocity` (N, 2), px: `still` (N,) pins'
    steps zeroed unless their (N, k) `index` neighbours' median step lies beyond `bound_sq` (N,), px^2;
    then their own step where within `agree_sq` times that median's square of it, else the median."""
    n, k = index.shape
    active = np.empty(n, np.bool_)
    anything = False
    for i in range(n):
        x, y = velocity[i, 0], velocity[i, 1]
        active[i] = (not still[i] or x * x + y * y > bound_sq[i]) and x == x and abs(x) != np.inf
        anything = anything or active[i]
    if anything:
        # Still pins near a step beyond noise: their neighbours' medians, of the steps as they are.
        which = np.empty(n, np.int64)
        count = 0
        for i in range(n):
            if still[i]:
                near = active[i]
                for j in range(k):
                    near = near or active[index[i, j]]
                if near:
                    which[count] = i
                    count += 1
        around = np.empty((count, 2))
        own = np.empty((count, 2))
        xs = np.empty(k)
        ys = np.empty(k)
        for r in range(count):
            i = which[r]
            own[r, 0], own[r, 1] = velocity[i, 0], velocity[i, 1]
            for j in range(k):
                xs[j] = velocity[index[i, j], 0]
                ys[j] = velocity[index[i, j], 1]
            _median_into(xs, ys, k, around, r)
    for i in range(n):
        if still[i]:
            velocity[i, 0] = 0.0
            velocity[i, 1] = 0.0
    if anything:
        for r in range(count):
            i = which[r]
            ax, ay = around[r, 0], around[r, 1]
            size = ax * ax + ay * ay
            if size > bound_sq[i]:
                dx, dy = own[r, 0] - ax, own[r, 1] - ay
                if dx * dx + dy * dy <= agree_sq * size:
                    velocity[i, 0], velocity[i, 1] = own[r, 0], own[r, 1]
                else:
                    velocity[i, 0], velocity[i, 1] = ax, ay


@njit(cache=True, nogil=True, error_model="numpy")
def remember(positions, rest_positions, index, then):
    """`pins._predict._Prediction.remember`: for each pin placed in (N, 2) `positions`, px, its (N, k) `index`
    neighbours' displacements from `rest_positions`, px, into `then` (N, k, 2), in place."""
    n, k = index.shape
    for i in range(n):
        if np.isfinite(positions[i, 0]):
            for j in range(k):
                other = index[i, j]
                then[i, j, 0] = positions[other, 0] - rest_positions[other, 0]
                then[i, j, 1] = positions[other, 1] - rest_positions[other, 1]


@njit(cache=True, nogil=True, error_model="numpy")
def trusted(positions, index, which, still, predicted, last_seen, least, gate_sq):
    """`pins._predict._Prediction._trusted`: whether pins `which` (L,) may be searched for at their
    `predicted` (L, 2), px: at least `least` of their (N, k) `index` neighbours placed in `positions`
    (N, 2), px; or at least two, none of them moved (`still` (N,) bool) and the prediction within
    `gate_sq`, px^2, of where the pin was last seen (`last_seen` (N, 2), px). (L,) bool."""
    rows = which.shape[0]
    k = index.shape[1]
    out = np.empty(rows, np.bool_)
    for r in range(rows):
        pin = which[r]
        count = 0
        moved = False
        for j in range(k):
            other = index[pin, j]
            if np.isfinite(positions[other, 0]):
                count += 1
                moved = moved or not still[other]
        out[r] = count >= least
        if not out[r] and count >= 2 and not moved:
            dx = predicted[r, 0] - last_seen[pin, 0]
            dy = predicted[r, 1] - last_seen[pin, 1]
            out[r] = dx * dx + dy * dy <= gate_sq
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def settle(positions, velocity, lost_run, retire_after, last_seen):
    """`pins._predict.settle`: the steps to carry (N, 2), px (`velocity`'s, NaN as 0), lost pins (N,) (`positions`
    (N, 2), px, not finite), their runs of frames lost (N,) int64 and the retired ones (runs beyond `retire_after`);
    `last_seen` (N, 2), px, takes the found pins' positions, in place."""
    n = positions.shape[0]
    carried = np.empty((n, 2))
    lost = np.empty(n, np.bool_)
    run = np.empty(n, np.int64)
    retired = np.empty(n, np.bool_)
    for i in range(n):
        for c in range(2):
            step = velocity[i, c]
            carried[i, c] = 0.0 if step != step else step
        x, y = positions[i, 0], positions[i, 1]
        found = np.isfinite(x) and np.isfinite(y)
        lost[i] = not found
        run[i] = 0 if found else lost_run[i] + 1
        retired[i] = run[i] > retire_after
        if found:
            last_seen[i, 0], last_seen[i, 1] = x, y
    return carried, lost, run, retired
