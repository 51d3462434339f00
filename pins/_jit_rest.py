"""Compiled kernels (Numba) of the still pad's bookkeeping: the still steps' learnt scatter and snap to rest
(`pins._rest`), as `pins._jit_track` compiles the rest of the tracker's; `pins._jit` exports them.

Each is the NumPy reference it names, the same float64 operations in the same order: bit for bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._jit_track import _like, _median_into


@njit(cache=True, nogil=True, error_model="numpy")
def rest_look(positions, rest_positions, search, index, drift_sq, still_sq, still_share, gate_sq, jitter_sq,
              between_share):
    """`pins._rest._AtRest.snap_to_rest`'s checks of a pad back at rest: each pin's squared distance from
    rest (N,), px^2 (NaN where missing), the pins to look for at rest (drifted beyond `drift_sq`, or missing
    and searched for: `search` (N,) bool), and whether to look: some pin is, at least `still_share` of the
    placed pins lie within `still_sq` of rest, and at most `between_share` of them between that and
    `gate_sq` (a pin within `jitter_sq` whose (N, k) `index` neighbours' median displacement lies within
    `still_sq` is a faint tip's jitter, not motion)."""
    n, k = index.shape
    distance = np.empty(n)
    look = np.empty(n, np.int64)
    wanted = 0
    still = 0
    placed = 0
    for i in range(n):
        dx = positions[i, 0] - rest_positions[i, 0]
        dy = positions[i, 1] - rest_positions[i, 1]
        d = dx * dx + dy * dy
        distance[i] = d
        if d > drift_sq or (d != d and search[i]):
            look[wanted] = i
            wanted += 1
        if d <= still_sq:
            still += 1
        if d == d and abs(d) != np.inf:
            placed += 1
    if wanted == 0 or still < still_share * placed:
        return distance, look[:0], False
    between = 0
    xs = np.empty(k)
    ys = np.empty(k)
    around = np.empty((1, 2))
    for i in range(n):
        d = distance[i]
        if d <= still_sq or d > gate_sq or d != d or abs(d) == np.inf:
            continue
        if d <= jitter_sq:
            for j in range(k):
                other = index[i, j]
                xs[j] = positions[other, 0] - rest_positions[other, 0]
                ys[j] = positions[other, 1] - rest_positions[other, 1]
            _median_into(xs, ys, k, around, 0)
            if around[0, 0] * around[0, 0] + around[0, 1] * around[0, 1] <= still_sq:
                continue
        between += 1
    if between > between_share * placed:
        return distance, look[:0], False
    return distance, look[:wanted], True


@njit(cache=True, nogil=True, error_model="numpy")
def _nan_max(a, b):
    """`np.maximum` of two floats: NaN when either is."""
    if a != a or b != b:
        return np.nan
    return a if a >= b else b


@njit(cache=True, nogil=True, error_model="numpy")
def rest_judge(centres, measures, look, positions, distance, rest_positions, rest_offset, origin, index, guess_sq,
               calm_sq, settled_px, gate_sq, jitter_sq, rest_scatter_sq, rest_scatter_seen, noise_scatter_sq,
               jitter_floor, at_least, area_at_most, first_count, bound_sq, rate, odd_neighbours):
    """`pins._rest._AtRest.snap_to_rest`'s judgement of the windows at rest of pins `look` (L,): their
    centroids `centres` (L, 2), px in the crop at `origin`, and `measures` (3, L). Learns the rest scatter
    (`rest_scatter_sq`, `rest_scatter_seen`, in place, as `pins._noise._learn_mean_square` with
    `first_count`, `bound_sq`, `rate`) and returns the positions (N, 2), px (a copy with the pins found at
    rest) and whether any was found (else `positions` itself). A pin is quiet only among neighbours that agree as a
    still membrane's do: each within `guess_sq` of their median or `calm_sq` times its scatter in noise (or beyond
    `gate_sq` of rest: on another tip), all but `odd_neighbours[pin]` ((N,) int) of them."""
    count = look.shape[0]
    k = index.shape[1]
    xs = np.empty(k)
    ys = np.empty(k)
    shift = np.empty((count, 2))
    placed = np.empty((count, 2))
    found = np.zeros(count, np.bool_)
    anything = False
    for r in range(count):
        pin = look[r]
        cx = centres[r, 0] + (origin[0] - rest_offset[pin, 0])
        cy = centres[r, 1] + (origin[1] - rest_offset[pin, 1])
        for j in range(k):
            other = index[pin, j]
            xs[j] = positions[other, 0] - rest_positions[other, 0]
            ys[j] = positions[other, 1] - rest_positions[other, 1]
        _median_into(xs, ys, k, shift, r)
        sx, sy = shift[r, 0], shift[r, 1]
        quiet = sx * sx + sy * sy <= guess_sq
        if quiet:  # (`pins._rest._AtRest._neighbours_agree`: the neighbours agree as a still membrane's do)
            apart = 0
            for j in range(k):
                other = index[pin, j]
                mx = positions[other, 0] - rest_positions[other, 0]  # (xs, ys: sorted by the median)
                my = positions[other, 1] - rest_positions[other, 1]
                ex, ey = mx - sx, my - sy
                noise = _nan_max(_nan_max(jitter_sq[other], noise_scatter_sq[other]), jitter_floor)
                if ex * ex + ey * ey > _nan_max(guess_sq, calm_sq * noise) and mx * mx + my * my <= gate_sq:
                    apart += 1  # (beyond the gate: on another tip)
            quiet = apart <= odd_neighbours[pin]
        rx, ry = rest_positions[pin, 0], rest_positions[pin, 1]
        ex = (cx - rx) - sx
        ey = (cy - ry) - sy
        residual = ex * ex + ey * ey
        scatter = _nan_max(_nan_max(jitter_sq[pin], rest_scatter_sq[pin]), _nan_max(noise_scatter_sq[pin], jitter_floor))
        calm = quiet and residual <= calm_sq * scatter
        bound = 2.0 * settled_px if calm else settled_px
        if calm:
            like = measures[1, r] >= at_least[1, pin]
        else:
            like = _like(measures, r, pin, at_least, area_at_most)
        dx, dy = cx - rx, cy - ry
        ok = dx * dx + dy * dy <= bound * bound and like
        ok = ok and (calm or not (distance[pin] <= gate_sq))
        found[r] = ok
        if ok:
            anything = True
            if calm:
                placed[r, 0], placed[r, 1] = rx + sx, ry + sy
            else:
                placed[r, 0], placed[r, 1] = cx, cy
        # The rest scatter learnt after the test (`pins._noise._learn_mean_square`).
        so_far, seen = rest_scatter_sq[pin], rest_scatter_seen[pin]
        first = seen < first_count
        if quiet and ok and (first or residual <= bound_sq * so_far):
            rest_scatter_sq[pin] = so_far + (1.0 / (seen + 1.0) if first else rate) * (residual - so_far)
            rest_scatter_seen[pin] = seen + 1.0
        else:
            rest_scatter_sq[pin] = so_far + 0.0
    if not anything:
        return positions, False
    out = positions.copy()
    for r in range(count):
        if found[r]:
            out[look[r], 0], out[look[r], 1] = placed[r, 0], placed[r, 1]
    return out, True


@njit(cache=True, nogil=True, error_model="numpy")
def observe_still(steps, settled_sq, mean_sq, seen, first_count, bound_sq, rate):
    """`pins._rest._AtRest.observe_still`'s learning (`pins._noise._learn_mean_square` over every pin):
    half the square of each still step (within `settled_sq`, px^2) of (N, 2) `steps`, px, updates the
    running mean squares `mean_sq` (N,), px^2, and their counts `seen` (N,) in place (the first
    `first_count` averaged, later ones with weight `rate` within `bound_sq` times the mean so far).
    Returns which steps were still (N,) bool."""
    n = steps.shape[0]
    still = np.empty(n, np.bool_)
    for i in range(n):
        x, y = steps[i, 0], steps[i, 1]
        half = x * x + y * y
        still[i] = half <= settled_sq
        half *= 0.5
        so_far, count = mean_sq[i], seen[i]
        first = count < first_count
        learn = still[i] and (first or half <= bound_sq * so_far)
        if learn:
            mean_sq[i] = so_far + (1.0 / (count + 1.0) if first else rate) * (half - so_far)
            seen[i] = count + 1.0
        else:
            mean_sq[i] = so_far + 0.0
    return still


@njit(cache=True, nogil=True, error_model="numpy")
def probe_matches(crop, probe_index, probe_rest, bound, need):
    """`pins._return.RestMatch._probe_matches`: whether at least `need` of the probe pins' windows match the rest
    frame, their mean absolute difference within `bound` grey levels. `crop` the frame's crop flattened (uint8),
    `probe_index` (P, m) its windows' pixels, `probe_rest` (P, m) the rest frame's there (int16). Stops as soon as
    the answer is known (most frames of a contact: after a few windows)."""
    probes, m = probe_index.shape
    matches = 0
    for p in range(probes):
        total = 0
        for j in range(m):
            total += abs(np.int64(crop[probe_index[p, j]]) - np.int64(probe_rest[p, j]))
        if total / m <= bound:
            matches += 1
            if matches >= need:
                return True
        elif matches + probes - 1 - p < need:
            return False
    return matches >= need


@njit(cache=True, nogil=True, error_model="numpy")
def draw_bounds(still, steady, here, judged, rest_least, learnt_least, learnt_most, area_rest, contrast_still,
                contrast_moving, pair):
    """`pins._rest._AtRest._draw_bounds`: each pin's bounds from below (3, N) and on its area from above (N,) for
    pins `still` (N,) bool in the last frame, faint tips `steady` there and on a pad at rest round them (`here`):
    a faint tip still or steady there has its learnt bounds (`learnt_least`, `learnt_most` where `judged`), any
    other its rest frame's (`rest_least`; with `pair`, a codec's still pair seen, the contrast's bound of a still
    or a moving pin: `contrast_still`, `contrast_moving`), and a tip judged by its contrast alone (not `judged`)
    an area bound only while still (else -inf)."""
    n = still.shape[0]
    at_least = np.empty((3, n))
    area = np.empty(n)
    for i in range(n):
        mine = (still[i] or steady[i]) and here[i]
        if mine:
            at_least[0, i], at_least[1, i], at_least[2, i] = learnt_least[0, i], learnt_least[1, i], learnt_least[2, i]
        else:
            at_least[0, i], at_least[2, i] = rest_least[0, i], rest_least[2, i]
            if pair:
                at_least[1, i] = contrast_still[i] if still[i] else contrast_moving[i]
            else:
                at_least[1, i] = rest_least[1, i]
        if mine and judged[i]:
            area[i] = learnt_most[i]
        elif judged[i] or still[i]:
            area[i] = area_rest[i]
        else:
            area[i] = -np.inf
    return at_least, area


@njit(cache=True, nogil=True, error_model="numpy")
def faint_steady(steps, faint, index, guess_sq, settled_sq, steady):
    """`pins._rest._AtRest.observe_still`'s faint tips: each faint tip (`faint` (F,) pins) whose (N, 2) step, px,
    lies within `settled_sq` but not `guess_sq` (px^2), or is NaN (lost), among neighbours (`index` (N, k)) whose
    median step lies within `guess_sq` is steady; written into `steady` (N,) bool; returns whether any changed."""
    k = index.shape[1]
    xs, ys = np.empty(k), np.empty(k)
    median = np.empty((1, 2))
    changed = False
    for f in range(faint.shape[0]):
        pin = faint[f]
        x, y = steps[pin, 0], steps[pin, 1]
        own = x * x + y * y
        now = not (own <= guess_sq) and not (own > settled_sq)
        if now:
            for j in range(k):
                xs[j] = steps[index[pin, j], 0]
                ys[j] = steps[index[pin, j], 1]
            _median_into(xs, ys, k, median, 0)
            now = median[0, 0] * median[0, 0] + median[0, 1] * median[0, 1] <= guess_sq
        if now != steady[pin]:
            steady[pin] = now
            changed = True
    return changed


@njit(cache=True, nogil=True, error_model="numpy")
def faint_here(positions, rest_positions, faint, index, near_sq, share, guess_sq, judged, seen, readings, here):
    """`pins._rest._AtRest._learn_levels`' checks: on a pad at rest (at least `share` of the (N, 2) `positions`,
    px, within `near_sq` of rest, px^2), each faint tip (`faint` (F,)) whose neighbours' (`index` (N, k)) median
    displacement lies within `guess_sq` is at rest there (`here` (N,) bool, written; all False off a pad at
    rest); returns the faint tips that read their windows: at rest there, placed within `near_sq` of rest (or
    lost and not `judged` by all three measures), with fewer than `readings` readings of their contrast (`seen`)."""
    n, k = index.shape
    near = 0
    for i in range(n):
        dx = positions[i, 0] - rest_positions[i, 0]
        dy = positions[i, 1] - rest_positions[i, 1]
        if dx * dx + dy * dy <= near_sq:
            near += 1
    read = np.empty(faint.shape[0], np.int64)
    count = 0
    if near < share * n:
        for f in range(faint.shape[0]):
            here[faint[f]] = False
        return read[:0]
    xs, ys = np.empty(k), np.empty(k)
    median = np.empty((1, 2))
    for f in range(faint.shape[0]):
        pin = faint[f]
        for j in range(k):
            other = index[pin, j]
            xs[j] = positions[other, 0] - rest_positions[other, 0]
            ys[j] = positions[other, 1] - rest_positions[other, 1]
        _median_into(xs, ys, k, median, 0)
        at_rest = median[0, 0] * median[0, 0] + median[0, 1] * median[0, 1] <= guess_sq
        here[pin] = at_rest
        dx = positions[pin, 0] - rest_positions[pin, 0]
        dy = positions[pin, 1] - rest_positions[pin, 1]
        away = dx * dx + dy * dy
        if at_rest and (away <= near_sq or (away != away and not judged[pin])) and seen[pin] < readings:
            read[count] = pin
            count += 1
    return read[:count]
