"""Compiled lattice judgement (Numba): `pins._judge`'s verdict passes, one call a judgement.

`judge_passes` runs `pins._judge._judge_lattice`'s loop of verdict passes (`_verdicts` over `_Neighbourhood`s,
each blob judged against the medians of its nearest kept neighbours and the lattice sites they make, blobs
rejected and rejoining until nothing changes) as loops over the blobs, on a thread without the GIL (the field
search's candidate sets run two at a time). It gives the reference's verdicts, bit for bit, or says it cannot:

- the nearest neighbours are looked up in a grid of cells instead of a KD-tree: the same distances (the square
  root of dx dx + dy dy, as `scipy.spatial.cKDTree` sums them), but of neighbours at equal distances the tree
  may keep another at the k-th place, or put a blob's twin (distance 0) before it: such a tie is reported;
- the mirror images' look-ups are exact (is a member nearer than the tolerance); the reference's bound on
  them only saves work;
- NumPy's ``log`` and ``hypot`` (SIMD: AVX-512 here) and the C library's may differ in the last bit, which
  matters only within `_GUARD` of a threshold. A cosine there is reported. An area ratio there is a ratio of
  small integers (blob areas, px, plus `_AREA_SLACK`; two such ratios differ by 1e-8 at least) equal to the
  threshold's: 9/5, 7/5 or their inverses, whose NumPy logs are passed in (`EXACT_LOG`), as are the thresholds'
  (`LOGS`): on synthetic frames (integer areas) 45 % of random blob sets meet one.

Reported (a status above 0), the caller judges with the reference. ``cache=True``: compiled once per machine.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# `pins._judge`'s constants, imported by value (the kernel compiles them in); the tests hold them equal.
_KEPT, _OFF, _SIZE, _CONTRAST = -1, 1, 2, 3
_NEIGHBOURS = 6
_SIZE_RANGE, _MIN_FILL, _FILL_AREA, _AREA_SLACK = (0.4, 2.2), 0.6, 15.0, 3.0
_MIN_CONTRAST, _MIN_SHARPNESS, _TOO_CLOSE, _LINK, _MIRROR = 0.5, 0.8, 0.6, 1.3, 0.25
_MIN_ANCHORS, _WEAK_CONTRAST, _WEAK_SIZE = 2, (0.5, 0.8), (1.8, 1.4)
_INWARD, _SPREAD, _MIN_PINS = -0.5, 0.8, 4
# Values within this of a threshold are judged with NumPy's arithmetic, or by the reference.
_GUARD = 1e-12
#: NumPy's logs of the size thresholds (as `pins._judge` computes them: its scalar log) ...
LOGS = np.array([np.log(_WEAK_SIZE[0]), np.log(_WEAK_SIZE[1] / _WEAK_SIZE[0])])
#: ... and of the area ratios that can lie within `_GUARD` of them (its array log, as the reference takes it).
EXACT_X = np.array([9.0 / 5.0, 5.0 / 9.0, 7.0 / 5.0, 5.0 / 7.0])
EXACT_LOG = np.log(EXACT_X)


@njit(cache=True, nogil=True, error_model="numpy")
def _median(values, k):
    """`numpy.median` of `values[:k]` (sorted in place): the middle value, or the mean of the two middle ones;
    NaN if any is NaN."""
    for i in range(k):
        if values[i] != values[i]:
            return np.nan
    for i in range(1, k):  # insertion sort: k <= 7
        v = values[i]
        j = i - 1
        while j >= 0 and values[j] > v:
            values[j + 1] = values[j]
            j -= 1
        values[j + 1] = v
    if k % 2:
        return values[k // 2]
    return (values[k // 2 - 1] + values[k // 2]) / 2.0


@njit(cache=True, nogil=True, error_model="numpy")
def _grid(points, members, x0, y0, size, nx, ny, start, order):
    """The members in cells of `size` px from (x0, y0): `order` lists them cell by cell, cell c's from
    ``start[c]`` to ``start[c + 1]``."""
    cells = nx * ny
    start[:] = 0
    for i in range(points.shape[0]):
        if members[i]:
            start[_cell(points[i, 0], points[i, 1], x0, y0, size, nx, ny) + 1] += 1
    for c in range(cells):
        start[c + 1] += start[c]
    fill = start[:cells].copy()
    for i in range(points.shape[0]):
        if members[i]:
            c = _cell(points[i, 0], points[i, 1], x0, y0, size, nx, ny)
            order[fill[c]] = i
            fill[c] += 1


@njit(cache=True, nogil=True, error_model="numpy")
def _cell(x, y, x0, y0, size, nx, ny):
    """The number of the cell of (x, y), px (row by row; a point beyond the grid in its nearest cell)."""
    gx = min(max(int((x - x0) / size), 0), nx - 1)
    gy = min(max(int((y - y0) / size), 0), ny - 1)
    return gy * nx + gx


@njit(cache=True, nogil=True, error_model="numpy")
def _nearest(points, i, want, x0, y0, size, nx, ny, start, order, best_d2, best_id):
    """The `want` nearest members of point i but i itself, ascending (squared distances, numbers), into
    `best_d2`, `best_id` (room for want + 1); returns how many were found and whether a tie could let the
    reference choose others (the want-th and the next at one distance, or a member at distance 0)."""
    qx, qy = points[i, 0], points[i, 1]
    at_cell = _cell(qx, qy, x0, y0, size, nx, ny)
    gx, gy = at_cell % nx, at_cell // nx
    room = want + 1
    found = 0
    eps = 1e-7 * size
    r = 0
    while True:
        for cy in range(gy - r, gy + r + 1):
            if cy < 0 or cy >= ny:
                continue
            ring_row = cy == gy - r or cy == gy + r
            step = 1 if ring_row else 2 * r
            cx = gx - r
            while cx <= gx + r:
                if 0 <= cx < nx:
                    c = cy * nx + cx
                    for s in range(start[c], start[c + 1]):
                        j = order[s]
                        if j == i:
                            continue
                        dx = points[j, 0] - qx
                        dy = points[j, 1] - qy
                        d2 = dx * dx + dy * dy
                        if found == room and d2 >= best_d2[room - 1]:
                            continue
                        at = found if found < room else room - 1
                        while at > 0 and best_d2[at - 1] > d2:
                            best_d2[at] = best_d2[at - 1]
                            best_id[at] = best_id[at - 1]
                            at -= 1
                        best_d2[at] = d2
                        best_id[at] = j
                        if found < room:
                            found += 1
                cx += step
        # Whatever lies beyond the cells searched is at least this far away.
        if gx - r <= 0 and gy - r <= 0 and gx + r >= nx - 1 and gy + r >= ny - 1:
            break
        reach = min(qx - (x0 + (gx - r) * size), x0 + (gx + r + 1) * size - qx,
                    qy - (y0 + (gy - r) * size), y0 + (gy + r + 1) * size - qy) - eps
        if found >= want and reach > 0.0 and best_d2[want - 1] < reach * reach:
            break
        r += 1
    tie = found > want and best_d2[want] == best_d2[want - 1]
    if found > 0 and best_d2[0] == 0.0:
        tie = True
    return min(found, want), tie


@njit(cache=True, nogil=True, error_model="numpy")
def _row_within(points, near, row, want, tx, ty, tolerance):
    """Whether one of the nearest members of point `row` (`near[row, 1:want + 1]`) lies nearer than `tolerance`
    (px) to (tx, ty)."""
    far = tolerance * tolerance * (1.0 + 1e-9)
    for c in range(1, want + 1):
        if _nearer(points, near[row, c], tx, ty, far, tolerance):
            return True
    return False


@njit(cache=True, nogil=True, error_model="numpy")
def _nearer(points, j, tx, ty, far, tolerance):
    """Whether point `j` lies nearer than `tolerance` (px) to (tx, ty): the square root taken only where its squared
    distance is below `far` (`tolerance` squared, a hair wider), the reference's exact test."""
    dx = points[j, 0] - tx
    dy = points[j, 1] - ty
    d2 = dx * dx + dy * dy
    return d2 < far and math.sqrt(d2) < tolerance


@njit(cache=True, nogil=True, error_model="numpy")
def _member_within(tx, ty, tolerance, x0, y0, size, nx, ny, start, order, points):
    """Whether a member lies nearer than `tolerance` (px) to (tx, ty): the reference's nearest-member distance
    below it."""
    # (Cells as `_cell` numbers them, a millionth of a cell wider on each side against rounding.)
    gx0 = max(int(math.floor((tx - tolerance - x0) / size - 1e-6)), 0)
    gx1 = min(int(math.floor((tx + tolerance - x0) / size + 1e-6)), nx - 1)
    gy0 = max(int(math.floor((ty - tolerance - y0) / size - 1e-6)), 0)
    gy1 = min(int(math.floor((ty + tolerance - y0) / size + 1e-6)), ny - 1)
    # Squared distances beyond this are beyond `tolerance` (the square root taken only near it: the exact test).
    far = tolerance * tolerance * (1.0 + 1e-9)
    for cy in range(gy0, gy1 + 1):
        for cx in range(gx0, gx1 + 1):
            c = cy * nx + cx
            for s in range(start[c], start[c + 1]):
                if _nearer(points, order[s], tx, ty, far, tolerance):
                    return True
    return False


@njit(cache=True, nogil=True, error_model="numpy")
def _pass(points, members, before, k_before, whole, valid, areas, fills, contrasts, sharpness, strength, logs,
          exact_x, exact_log, grid, start, order, dist, near, pitch, link, verdict):
    """One `pins._judge._verdicts` pass against `members`: fills `verdict` and the neighbourhood's `dist`,
    `near`, `pitch`, `link` (k columns used, k - 1 of `link`); returns (k, 0, or why the reference must judge:
    1 a tie between neighbours, 2 a size log-ratio at its threshold, 3 a cosine at its threshold).

    `before`, `k_before`: the members and k of the last pass. A point's row (`dist`, `near`) stays, as
    `pins._judge._Neighbourhood` keeps it, while `valid` and none of its nearest members was removed (members
    added or k changed: every row looked up again). The members are judged first; the others' verdicts count
    only in a pass that removes no member (`judge_passes` then lets them rejoin) or when `whole`: when a member
    fails and not `whole`, they are left unjudged (their verdicts stale)."""
    x0, y0, size, nx, ny = grid[0], grid[1], grid[2], int(grid[3]), int(grid[4])
    n = points.shape[0]
    m = 0
    added = False
    for i in range(n):
        if members[i]:
            m += 1
            if not before[i]:
                added = True
    k = min(_NEIGHBOURS + 1, m)
    if added or k != k_before:
        valid[:] = False
    _grid(points, members, x0, y0, size, nx, ny, start, order)
    best_d2 = np.empty(k)
    best_id = np.empty(k, np.int64)
    values = np.empty(k)
    reach = np.empty(n)
    towards = np.empty((k - 1, 2))
    # The members' centroid (`beyond_ring`'s outward directions), summed in order as NumPy's mean.
    mean_x, mean_y = 0.0, 0.0
    for i in range(n):
        if members[i]:
            mean_x += points[i, 0]
            mean_y += points[i, 1]
    mean_x /= m
    mean_y /= m
    for side in range(2):  # the members, then the others
        for i in range(n):
            if members[i] == (side == 0) and _row(points, members, i, k, valid, grid, start, order, dist, near,
                                                   best_d2, best_id):
                return k, 1
        # Local pitch and reach: medians over the point and its neighbours of their nearest and second-nearest
        # distances; then the links.
        for i in range(n):
            if members[i] == (side == 0):
                for c in range(k):
                    values[c] = dist[near[i, c], 1]
                pitch[i] = _median(values, k)
                for c in range(k):
                    values[c] = dist[near[i, c], min(2, k - 1)]
                reach[i] = _median(values, k)
        for i in range(n):
            if members[i] == (side == 0):
                for c in range(k - 1):
                    link[i, c] = dist[i, c + 1] <= _LINK * max(reach[i], reach[near[i, c + 1]])
        failed = False
        for i in range(n):
            if members[i] == (side == 0):
                refer, verdict[i] = _verdict(points, i, k, areas, fills, contrasts, sharpness, strength, logs, exact_x,
                                             exact_log, grid, start, order, dist, near, pitch, link, values, towards,
                                             mean_x, mean_y)
                if refer:
                    return k, refer
                failed |= side == 0 and verdict[i] != _KEPT
        if failed and not whole:
            break
    return k, 0


@njit(cache=True, nogil=True, error_model="numpy")
def _row(points, members, i, k, valid, grid, start, order, dist, near, best_d2, best_id):
    """Point i's row (itself at distance 0, then its k - 1 nearest members, as `_Neighbourhood` puts it), looked
    up unless `valid` and none of its members removed; returns whether a tie leaves it to the reference."""
    want = k - 1
    if valid[i]:
        kept = True
        for c in range(want):
            if not members[near[i, c + 1]]:
                kept = False
                break
        if kept:
            return False
    x0, y0, size, nx, ny = grid[0], grid[1], grid[2], int(grid[3]), int(grid[4])
    found, tie = _nearest(points, i, want, x0, y0, size, nx, ny, start, order, best_d2, best_id)
    if tie or found < want:
        return True
    dist[i, 0] = 0.0
    near[i, 0] = i
    for c in range(want):
        dist[i, c + 1] = math.sqrt(best_d2[c])
        near[i, c + 1] = best_id[c]
    valid[i] = True
    return False


@njit(cache=True, nogil=True, error_model="numpy")
def _verdict(points, i, k, areas, fills, contrasts, sharpness, strength, logs, exact_x, exact_log, grid, start,
             order, dist, near, pitch, link, values, towards, mean_x, mean_y):
    """Point i's verdict against the medians of its row and the lattice sites its linked members make: (0, or why
    the reference must judge (2, 3: see `_pass`); -1 kept, or why not). `values`, `towards`: scratch."""
    x0, y0, size, nx, ny = grid[0], grid[1], grid[2], int(grid[3]), int(grid[4])
    want = k - 1
    for c in range(k):
        values[c] = areas[near[i, c]]
    area_ref = _median(values, k) + _AREA_SLACK
    for c in range(k):
        values[c] = contrasts[near[i, c]]
    contrast_ref = _median(values, k)
    for c in range(k):
        values[c] = fills[near[i, c]]
    fill_ref = _median(values, k)
    for c in range(k):
        values[c] = sharpness[near[i, c]]
    sharp_ref = _median(values, k)
    area = areas[i] + _AREA_SLACK
    v = _KEPT
    for c in range(want):
        if dist[i, c + 1] < _TOO_CLOSE * pitch[i] and strength[near[i, c + 1]] > strength[i]:
            v = _OFF
            break
    if contrasts[i] < _MIN_CONTRAST * contrast_ref or sharpness[i] < _MIN_SHARPNESS * sharp_ref:
        v = _CONTRAST
    if (area < _SIZE_RANGE[0] * area_ref or area > _SIZE_RANGE[1] * area_ref
            or (fills[i] < _MIN_FILL * fill_ref and area_ref >= _FILL_AREA)):
        v = _SIZE
    if v != _KEPT:
        return 0, v
    # Lattice sites: linked neighbours j with a member at the mirror image through j (2 j - p), and the
    # lines through the point (a member at 2 p - j), each counted once.
    through, between = 0, 0
    for c in range(want):
        if not link[i, c]:
            continue
        j = near[i, c + 1]
        tolerance = _MIRROR * dist[i, c + 1]
        # (A member there is most often one of the nearest members of j, or of the point: those first.)
        tx, ty = 2.0 * points[j, 0] - points[i, 0], 2.0 * points[j, 1] - points[i, 1]
        if (_row_within(points, near, j, want, tx, ty, tolerance)
                or _member_within(tx, ty, tolerance, x0, y0, size, nx, ny, start, order, points)):
            through += 1
        tx, ty = 2.0 * points[i, 0] - points[j, 0], 2.0 * points[i, 1] - points[j, 1]
        if (_row_within(points, near, i, want, tx, ty, tolerance)
                or _member_within(tx, ty, tolerance, x0, y0, size, nx, ny, start, order, points)):
            between += 1
    anchors = through + (between + 1) // 2
    strict = min(max(_MIN_ANCHORS - anchors, 0), _MIN_ANCHORS) / _MIN_ANCHORS
    ratio = contrasts[i] / contrast_ref
    if anchors < _MIN_ANCHORS:
        unlike = ratio < _WEAK_CONTRAST[0] + strict * (_WEAK_CONTRAST[1] - _WEAK_CONTRAST[0])
        if not unlike:
            x = area / area_ref
            size_log = abs(math.log(x))
            size_limit = logs[0] + strict * logs[1]
            if abs(size_log - size_limit) <= _GUARD:
                # At the threshold: NumPy's own log, known for the ratios that can lie there (see the module).
                for e in range(exact_x.size):
                    if exact_x[e] == x:
                        size_log = abs(exact_log[e])
                        break
                else:
                    return 2, v
            unlike = size_log > size_limit
        if unlike:
            return 0, _OFF
    if not ratio < _WEAK_CONTRAST[1]:
        return 0, v
    # A faint blob beyond the outer ring: linked only to members inward, and from two directions.
    ox, oy = points[i, 0] - mean_x, points[i, 1] - mean_y
    norm = max(math.hypot(ox, oy), 1e-9)
    ox /= norm
    oy /= norm
    for c in range(want):
        j = near[i, c + 1]
        tx, ty = points[j, 0] - points[i, 0], points[j, 1] - points[i, 1]
        norm = max(math.hypot(tx, ty), 1e-9)
        towards[c, 0] = tx / norm
        towards[c, 1] = ty / norm
        if link[i, c]:
            cos = towards[c, 0] * ox + towards[c, 1] * oy
            if abs(cos - _INWARD) <= _GUARD:
                return 3, v
            if not cos < _INWARD:  # a link outward: not beyond the ring
                return 0, v
    for a in range(want):
        if not link[i, a]:
            continue
        for b in range(want):
            if not link[i, b]:
                continue
            cos = towards[a, 0] * towards[b, 0] + towards[a, 1] * towards[b, 1]
            if abs(cos - _SPREAD) <= _GUARD:
                return 3, v
            if cos < _SPREAD:
                return 0, _OFF
    return 0, v


@njit(cache=True, nogil=True, error_model="numpy")
def judge_passes(points, areas, fills, contrasts, sharpness, logs, exact_x, exact_log):
    """`pins._judge._judge_lattice`'s verdict passes on blobs at `points` (N, 2), px, with their areas (px),
    fills, contrasts (floored at 1e-6) and sharpness, (N,) float64 each (N >= `_MIN_PINS`). `logs`, `exact_x`,
    `exact_log`: NumPy's logs (`LOGS`, `EXACT_X`, `EXACT_LOG`: see the module).

    Returns (reason per blob, -1 kept; the active blobs after the passes; the last pass's neighbourhood:
    dist (N, 7), near (N, 7), pitch (N,), link (N, 6), of which k and k - 1 columns are used; k; status), status
    0, or why the reference must judge: `_pass`'s 1-3, or 4 fewer than `_MIN_PINS` members left for the last
    pass (see the module).
    """
    n = points.shape[0]
    reason = np.full(n, _KEPT, np.int64)
    active = np.ones(n, np.bool_)
    rejoined = np.zeros(n, np.bool_)
    strength = contrasts * areas
    width = _NEIGHBOURS + 1
    dist = np.zeros((n, width))
    near = np.zeros((n, width), np.int64)
    pitch = np.zeros(n)
    link = np.zeros((n, width - 1), np.bool_)
    verdict = np.full(n, _KEPT, np.int64)
    # Cells of about two blobs each over the blobs' bounding box.
    x0, y0 = points[:, 0].min(), points[:, 1].min()
    span_x, span_y = points[:, 0].max() - x0, points[:, 1].max() - y0
    size = max(math.sqrt(max(span_x * span_y, 1.0) * 2.0 / n), 1e-3)
    nx = min(int(span_x / size) + 1, 4096)
    ny = min(int(span_y / size) + 1, 4096)
    size = max(size, span_x / nx * (1.0 + 1e-9), span_y / ny * (1.0 + 1e-9))
    grid = np.array([x0, y0, size, nx, ny], np.float64)
    start = np.zeros(nx * ny + 1, np.int64)
    order = np.zeros(n, np.int64)
    k = 0
    before = np.zeros(n, np.bool_)  # the last pass's members (none: every row looked up)
    valid = np.zeros(n, np.bool_)
    while True:
        cut = False
        for _ in range(8):
            if active.sum() < _MIN_PINS:
                cut = True
                break
            k, refer = _pass(points, active, before, k, False, valid, areas, fills, contrasts, sharpness, strength,
                             logs, exact_x, exact_log, grid, start, order, dist, near, pitch, link, verdict)
            before[:] = active
            if refer:
                return reason, active, dist, near, pitch, link, k, refer
            out = False
            for i in range(n):
                if active[i] and verdict[i] != _KEPT:
                    reason[i] = verdict[i]
                    active[i] = False
                    out = True
            if not out:
                cut = True
                break
        if not cut:
            if active.sum() < _MIN_PINS:
                return reason, active, dist, near, pitch, link, k, 4
            k, refer = _pass(points, active, before, k, True, valid, areas, fills, contrasts, sharpness, strength,
                             logs, exact_x, exact_log, grid, start, order, dist, near, pitch, link, verdict)
            before[:] = active
            if refer:
                return reason, active, dist, near, pitch, link, k, refer
        if active.sum() < _MIN_PINS:
            break
        back = False
        for i in range(n):
            if not active[i] and not rejoined[i] and verdict[i] == _KEPT:
                reason[i] = _KEPT
                active[i] = True
                rejoined[i] = True
                back = True
        if not back:
            break
    return reason, active, dist, near, pitch, link, k, 0


@njit(cache=True, nogil=True, error_model="numpy")
def field_core(near, link, active, k, least, share):
    """`pins._judge._judge_lattice`'s field: the active blobs in linked groups (`near`, `link`: `judge_passes`'s
    last pass, the active blobs' rows) of at least `least` blobs and `share` of the largest group's, as
    `scipy.sparse.csgraph.connected_components` of the links (undirected) groups them; per active blob, in order."""
    n = active.shape[0]
    parent = np.arange(n)
    for i in range(n):
        if not active[i]:
            continue
        for c in range(k - 1):
            if link[i, c]:
                a, b = _root(parent, i), _root(parent, near[i, c + 1])
                if a != b:
                    parent[max(a, b)] = min(a, b)
    size = np.zeros(n, np.int64)
    for i in range(n):
        if active[i]:
            size[_root(parent, i)] += 1
    largest = size.max()
    index = np.flatnonzero(active)
    core = np.empty(index.size, np.bool_)
    for at in range(index.size):
        core[at] = size[_root(parent, index[at])] >= max(least, share * largest)
    return core


@njit(cache=True, nogil=True, error_model="numpy")
def _root(parent, i):
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i
