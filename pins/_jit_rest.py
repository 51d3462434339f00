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
               jitter_floor, at_least, area_at_most, first_count, bound_sq, rate):
    """`pins._rest._AtRest.snap_to_rest`'s judgement of the windows at rest of pins `look` (L,): their
    centroids `centres` (L, 2), px in the crop at `origin`, and `measures` (3, L). Learns the rest scatter
    (`rest_scatter_sq`, `rest_scatter_seen`, in place, as `pins._noise._learn_mean_square` with
    `first_count`, `bound_sq`, `rate`) and returns the positions (N, 2), px (a copy with the pins found at
    rest) and whether any was found (else `positions` itself)."""
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
