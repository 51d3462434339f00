"""The lattice judge of `pins.find_pin_field`: which blobs of one candidate set form the pin lattice.

Each blob is judged against the medians of its nearest neighbours (size, contrast, sharpness) and
against the lattice sites its neighbours make (mirror images), iterated until nothing changes, and
then the linked groups of kept blobs make the field (see `pins.lattice`, steps 3 and 4).

A blob beyond the field's outer ring, linked to it only from inside and from two directions
(`_Neighbourhood.beyond_ring`), sits at a site of a ring that has no pins; it stays only with the contrast an
unanchored blob needs (brown-127's skin highlights lit by the casing glare: 0.50-0.89 of their neighbours').
One kind of glare blob is left: one beyond a corner of the outer ring, where a true corner pin's edges run at
120 degrees too (brown-127 seed 11: contrast 0.80-0.86, as the pins').
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from . import _kernels
from .detect import Blobs, DetectionParams
from .disc import SensorDisc


#: Why a candidate blob was rejected, in `PinField.rejected_reason`.
REJECTION_REASONS = ("outside field", "off lattice", "size", "contrast")
_OUTSIDE, _OFF, _SIZE, _CONTRAST = range(4)
_KEPT = -1

_NEIGHBOURS = 6
# Lattice consistency: fractions of the neighbours' medians (areas compared with `_AREA_SLACK` px
# added, fills only for areas of `_FILL_AREA` px or more) and of the local pitch.
_SIZE_RANGE = (0.4, 2.2)
_MIN_FILL = 0.6
_FILL_AREA = 15.0
_MIN_CONTRAST = 0.5
_MIN_SHARPNESS = 0.8
# Below this tip radius, px, the steepest slope depends on where the pixel grid cuts the tip.
_SHARP_RADIUS = 2.0
# The blurred casing edge reaches this many blur sigmas into the disc (the blur's kernel half-width).
_EDGE_REACH = 2.5
_TOO_CLOSE = 0.6
_LINK = 1.3
# Lattice sites: a mirror image within this fraction of the link length anchors a blob; a blob with
# fewer than `_MIN_ANCHORS` must have at least these contrast ratios and at most these area ratios
# to its neighbours' medians (with one anchor, with none).
_MIRROR = 0.25
_MIN_ANCHORS = 2
_WEAK_CONTRAST = (0.5, 0.8)
_WEAK_SIZE = (1.8, 1.4)
# Beyond the outer ring: a blob whose linked neighbours all lie inward (each more than `_INWARD` from its
# outward direction: cos below -0.5) and from two directions (at least `_SPREAD` apart: cos below 0.8; a
# radial spoke's end is linked along its spoke alone) has no ring of its own; it must stand at least the
# unanchored contrast ratio (`_WEAK_CONTRAST[1]`) to its neighbours' median.
_INWARD = -0.5
_SPREAD = 0.8
_MIN_PINS = 4
# Fewest pins that make a pin field (TacTips have 100-1000).
_MIN_FIELD = 10
_AREA_SLACK = 3.0
# Linked groups of at least this fraction of the largest make the field; isolated blobs within
# `_HULL_MARGIN` pitches of its hull stay.
_MIN_GROUP = 0.1
_HULL_MARGIN = 0.3
# Rejected blobs this many pitches beyond the field's hull are reported as outside the field.
_OUTSIDE_MARGIN = 0.5


def _sharpness(grey: np.ndarray, blobs: Blobs, params: DetectionParams, cache: dict | None = None,
               disc: SensorDisc | None = None) -> np.ndarray:
    """Steepest grey-level slope near each blob over its contrast, 1/px.

    A pin tip is a disc with a sharp edge; glare, light patches of skin and shadows are smooth. On
    tips smaller than `_SHARP_RADIUS` the slope depends on where the pixel grid cuts the tip: all ones.
    `cache` keeps the slope image per blur between candidate sets. Within `_EDGE_REACH` blur sigmas
    (plus the Sobel's pixel) of the rim of `disc` the slope is the casing's edge, not the blob's
    (a soft skin highlight or glare just inside the rim would look as sharp as a pin): it is left out.
    """
    n = len(blobs.centres)
    radius = float(np.sqrt(np.median(blobs.areas) / np.pi)) if n else 0.0
    if radius < _SHARP_RADIUS:
        return np.ones(n)
    sigma = max(params.blur_sigma_px, 0.5)
    cache = {} if cache is None else cache
    if sigma not in cache:
        smooth = cv2.GaussianBlur(grey, (0, 0), sigma).astype(np.float32)
        gx = cv2.Sobel(smooth, cv2.CV_32F, 1, 0, ksize=3, scale=0.125)
        gy = cv2.Sobel(smooth, cv2.CV_32F, 0, 1, ksize=3, scale=0.125)
        cache[sigma] = cv2.magnitude(gx, gy)
    slope = cache[sigma]
    # The steepest slope within the tip radius (plus a pixel and a half) of each centre.
    reach = int(np.ceil(radius + 1.5))
    dy, dx = np.mgrid[-reach:reach + 1, -reach:reach + 1]
    inside = dx**2 + dy**2 <= (radius + 1.5) ** 2
    dx, dy = dx[inside], dy[inside]
    x = np.rint(blobs.centres[:, 0]).astype(np.intp)
    y = np.rint(blobs.centres[:, 1]).astype(np.intp)
    height, width = grey.shape
    if n and x.min() >= reach and y.min() >= reach and x.max() < width - reach and y.max() < height - reach:
        # Every disc of pixels inside the image: one flat gather (no clipping).
        slopes = slope.ravel().take((y * width + x)[:, None] + (dy * width + dx))
    else:
        slopes = slope[np.clip(y[:, None] + dy, 0, height - 1), np.clip(x[:, None] + dx, 0, width - 1)]
    if disc is not None and not disc.whole_frame:
        # Only the blobs within reach of the casing's blurred edge: their pixels there left out.
        limit = disc.radius_px - _EDGE_REACH * sigma - 1.5
        rim = np.flatnonzero(np.hypot(x - disc.cx, y - disc.cy) > limit - reach)
        if rim.size:
            beyond = np.hypot(x[rim, None] + dx - disc.cx, y[rim, None] + dy - disc.cy) > limit
            slopes[rim] = np.where(beyond, 0.0, slopes[rim])
    steepest = slopes.max(axis=1)
    return steepest / np.maximum(blobs.contrasts, 1e-6)


def _judge_lattice(blobs: Blobs, sharpness: np.ndarray) -> tuple[np.ndarray, float]:
    """Which blobs form a lattice: (reason per blob, -1 for kept; median pitch of the kept, px)."""
    n = len(blobs.centres)
    reason = np.full(n, _KEPT, dtype=np.int64)
    if n < _MIN_PINS:
        reason[:] = _OFF
        return reason, np.nan
    centres = blobs.centres
    reason, index, core, pitches, nearest = _compiled_passes(blobs, sharpness) or _passes(blobs, sharpness)
    if len(index) < _MIN_PINS:
        reason[index] = _OFF
        return reason, np.nan
    if core.sum() < _MIN_FIELD:
        # A handful of blobs (glare round the rim of a pad without pins) is no pin field.
        reason[index] = _OFF
        return reason, np.nan
    hull = cv2.convexHull(centres[index[core]].astype(np.float32))
    pitch = float(np.median(pitches[core]))
    loose = index[~core]
    reason[loose[_beyond(hull, centres[loose], _HULL_MARGIN * pitch)]] = _OUTSIDE
    # Whatever else was rejected beyond the field (glare round the rim) is outside it, first of all.
    kept = reason == _KEPT
    rejected = np.flatnonzero(~kept)
    reason[rejected[_beyond(hull, centres[rejected], _OUTSIDE_MARGIN * pitch)]] = _OUTSIDE
    kept = reason == _KEPT
    if np.array_equal(np.flatnonzero(kept), index) and len(index) >= 2:
        # None of the active blobs left as outside: their nearest-neighbour distances are looked up already.
        return reason, float(np.median(nearest))
    return reason, float(_median_nn(centres[kept]))


def _passes(blobs: Blobs, sharpness: np.ndarray) -> tuple:
    """`_judge_lattice`'s verdict passes and the field's groups (the reference): reason per blob, the active
    blobs' numbers and, when there are `_MIN_PINS` of them, per active blob whether its group makes the field's
    core, its local pitch and its nearest active neighbour's distance, px (else None each)."""
    n = len(blobs.centres)
    reason = np.full(n, _KEPT, dtype=np.int64)
    # Photometry and spacing, iterated: removing an impostor changes its neighbours' medians. Then
    # the blobs rejected are judged again against the blobs kept, because a pin first judged among
    # impostors (skin highlights and specks round the spoke ends or the lone centre pin of a radial
    # layout make it look unlike its neighbours) must come back once they are gone; those that pass
    # rejoin and the iteration runs again, each blob rejoining at most once (else pairs of blobs
    # could take turns).
    active = np.ones(n, bool)
    rejoined = np.zeros(n, bool)
    hood = None   # the last pass's neighbourhood: the next one looks up again only what a removal changed
    while True:
        for _ in range(8):
            if active.sum() < _MIN_PINS:
                break
            verdict, hood = _verdicts(blobs, sharpness, active, hood)
            out = active & (verdict != _KEPT)
            if not out.any():
                break
            reason[out] = verdict[out]
            active &= ~out
        else:
            verdict, hood = _verdicts(blobs, sharpness, active, hood)
        if active.sum() < _MIN_PINS:
            break
        back = ~active & ~rejoined & (verdict == _KEPT)
        if not back.any():
            break
        reason[back] = _KEPT
        active |= back
        rejoined |= back
    index = np.flatnonzero(active)
    if len(index) < _MIN_PINS:
        return reason, index, None, None, None
    # The field: groups of blobs joined by lattice links. The last pass judged every blob among the active
    # ones: its rows for them are the active blobs' own neighbourhood (the same tree, the same look-ups), no
    # tree built again.
    hood = hood.among_members()
    groups, label = connected_components(hood.graph(), directed=False)
    sizes = np.bincount(label, minlength=groups)
    core = (sizes >= max(_MIN_PINS, _MIN_GROUP * sizes.max()))[label]
    return reason, index, core, hood.pitch, hood.dist[:, 1]


def _compiled_passes(blobs: Blobs, sharpness: np.ndarray) -> tuple | None:
    """`_passes` by the compiled kernels (`pins._jit_judge.judge_passes` and `field_core`: one call each, without
    the GIL), or None where the reference must judge: NumPy's code chosen (`pins._kernels`), Numba missing, or
    the kernel unsure (a tie between neighbours, a value at a threshold)."""
    kernels = _kernels.compiled("_jit_judge")
    if kernels is None or blobs.contrasts.dtype != np.float64:
        return None
    reason, active, dist, near, pitch, link, k, status = kernels.judge_passes(
        np.ascontiguousarray(blobs.centres, dtype=np.float64), blobs.areas.astype(np.float64),
        np.ascontiguousarray(blobs.fills, dtype=np.float64), np.maximum(blobs.contrasts, 1e-6),
        np.ascontiguousarray(sharpness, dtype=np.float64), *_judge_logs(kernels))
    if status:
        return None
    index = np.flatnonzero(active)
    if len(index) < _MIN_PINS:
        return reason, index, None, None, None
    core = kernels.field_core(near, link, active, k, _MIN_PINS, _MIN_GROUP)
    return reason, index, core, pitch[index], dist[index, 1]


def _judge_logs(kernels=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """NumPy's logs that `pins._jit_judge.judge_passes` takes (its thresholds', and of the ratios that can meet them)."""
    kernels = kernels or _kernels.compiled("_jit_judge")
    return kernels.LOGS, kernels.EXACT_X, kernels.EXACT_LOG


def _verdicts(blobs: Blobs, sharpness: np.ndarray, members: np.ndarray,
              previous: _Neighbourhood | None = None) -> tuple[np.ndarray, _Neighbourhood]:
    """Each blob judged against its nearest `members` (bool per blob): -1 (a lattice site) or why not;
    and the `_Neighbourhood` it was judged in (`previous`: the last pass's, see `_Neighbourhood`)."""
    n = len(blobs.centres)
    areas = blobs.areas.astype(np.float64)
    fills = blobs.fills
    contrasts = np.maximum(blobs.contrasts, 1e-6)
    strength = contrasts * areas
    hood = _Neighbourhood(blobs.centres, members, previous)
    # Medians over the blob and its neighbours. Areas compared with a little slack: a 1 px tip
    # covers 3-7 px.
    near = hood.near
    area_ref, contrast_ref, fill_ref, sharp_ref = _row_median(np.stack([areas, contrasts, fills, sharpness])[:, near])
    area_ref = area_ref + _AREA_SLACK
    area = areas + _AREA_SLACK
    verdict = np.full(n, _KEPT)
    # Of two blobs much closer than the local pitch, the weaker is not a lattice site.
    close = (hood.dist[:, 1:] < _TOO_CLOSE * hood.pitch[:, None]) & (strength[near[:, 1:]] > strength[:, None])
    verdict[close.any(axis=1)] = _OFF
    verdict[(contrasts < _MIN_CONTRAST * contrast_ref) | (sharpness < _MIN_SHARPNESS * sharp_ref)] = _CONTRAST
    # (The fill of a blob of a few pixels says nothing of its shape.)
    verdict[(area < _SIZE_RANGE[0] * area_ref) | (area > _SIZE_RANGE[1] * area_ref)
            | ((fills < _MIN_FILL * fill_ref) & (area_ref >= _FILL_AREA))] = _SIZE
    # Lattice sites: a blob on the lattice is a mirror image of a neighbour through another one
    # (interior pins have six such pairs, rim pins and the ends of radial spokes at least one). A
    # blob with fewer than two must look just like its neighbours to stay.
    anchors = hood.anchors()
    strict = np.clip(_MIN_ANCHORS - anchors, 0, _MIN_ANCHORS) / _MIN_ANCHORS
    ratio = contrasts / contrast_ref
    unlike = ((ratio < _WEAK_CONTRAST[0] + strict * (_WEAK_CONTRAST[1] - _WEAK_CONTRAST[0]))
              | (np.abs(np.log(area / area_ref)) > np.log(_WEAK_SIZE[0]) + strict * np.log(_WEAK_SIZE[1] / _WEAK_SIZE[0])))
    verdict[(anchors < _MIN_ANCHORS) & unlike & (verdict == _KEPT)] = _OFF
    # A lattice site beyond the outer ring, lit skin there (casing glare): anchored from inside alone.
    faint = np.flatnonzero((ratio < _WEAK_CONTRAST[1]) & (verdict == _KEPT))
    verdict[faint[hood.beyond_ring(faint)]] = _OFF
    return verdict, hood


def _beyond(hull: np.ndarray, points: np.ndarray, margin: float) -> np.ndarray:
    """Which points lie farther than `margin` (px) outside a convex hull."""
    return np.array([cv2.pointPolygonTest(hull, (float(x), float(y)), True) < -margin for x, y in points],
                    dtype=bool)


class _Neighbourhood:
    """Nearest neighbours among member points (each point first), local pitch, links and mirror anchors.

    Every point, member or not, gets its nearest members as neighbours (a point is never its own
    neighbour), so that blobs rejected so far can be judged against the blobs kept.

    `previous`, the neighbourhood of the same points among more members (the judge's last pass, which
    removed a few), saves the tree look-ups whose answers cannot have changed: a point's nearest
    members, unless one of them was removed; a mirror image's nearest member, unless the point's
    neighbours changed, that member was removed, or none was found within a smaller bound. The
    answers are the ones a new look-up gives (the same members at the same distances).
    """

    def __init__(self, points: np.ndarray, members: np.ndarray | None = None,
                 previous: _Neighbourhood | None = None):
        self.points = points
        n = len(points)
        self.members = np.ones(n, bool) if members is None else members.copy()   # the caller's may change after
        index = np.flatnonzero(self.members)
        self.index = index
        self.tree = cKDTree(points[index])
        k = min(_NEIGHBOURS + 1, len(index))
        if (previous is None or previous.k != k or previous.points is not points
                or (self.members & ~previous.members).any()):
            previous = None
        self._previous = previous
        if previous is None:
            self.changed = np.ones(n, bool)
            raw_dist, raw_near = self._nearest(points, k)
        else:
            self.removed = previous.members & ~self.members
            self.changed = self.removed[previous.raw_near].any(axis=1)
            raw_dist, raw_near = previous.raw_dist.copy(), previous.raw_near.copy()
            if self.changed.any():
                raw_dist[self.changed], raw_near[self.changed] = self._nearest(points[self.changed], k)
        self.k, self.raw_dist, self.raw_near = k, raw_dist, raw_near
        dist, near = raw_dist.copy(), raw_near.copy()
        if not self.members.all():
            # A point outside the members is not found first: put it first, before its k - 1 nearest.
            outside = ~self.members
            dist[outside] = np.column_stack([np.zeros(outside.sum()), dist[outside, :-1]])
            near[outside] = np.column_stack([np.flatnonzero(outside), near[outside, :-1]])
        self.dist, self.near = dist, near
        # Local pitch: median nearest-neighbour distance of the point and its neighbours. Links
        # reach a little beyond the second-nearest distance instead: near the rim of a hemispherical
        # pad the pins are foreshortened towards the centre, closer in the radial direction than
        # along the rim.
        self.pitch, reach = _row_median(self.dist[:, [1, min(2, k - 1)]].T[:, self.near])
        self.link = self.dist[:, 1:] <= _LINK * np.maximum(reach[:, None], reach[self.near[:, 1:]])
        self._mirrors = {}

    def _nearest(self, queries: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
        """The `k` nearest members of each query point: distances (px) and point numbers, (M, k) each."""
        dist, near = self.tree.query(queries, k)
        return dist.reshape(len(queries), k), self.index[near.reshape(len(queries), k)]

    def _mirror_distances(self, kind: str, targets: np.ndarray, bound: float, wanted: np.ndarray) -> np.ndarray:
        """Distance (px) from each `wanted` target (n, k - 1, 2) to its nearest member, looked up again only
        where `previous` cannot answer; NaN where not wanted. inf where no member lies within `bound`; a
        distance kept from a pass with a larger bound may exceed this one's, which is the same to the
        callers: they compare it with tolerances within `bound`."""
        shape = targets.shape[:2]
        cached = self._previous._mirrors.get(kind) if self._previous is not None else None
        if cached is None:
            dist, found, bounds, have = np.full(shape, np.nan), np.full(shape, -1), np.zeros(shape), np.zeros(shape, bool)
        else:
            dist, found, bounds, have = (a.copy() for a in cached)
            have[self.changed] = False
            have &= ~((found >= 0) & self.removed[np.maximum(found, 0)])
            have &= ~((found < 0) & (bounds < bound))
        todo = wanted & ~have
        if todo.any():
            d, i = self.tree.query(targets[todo], distance_upper_bound=bound)
            inside = np.isfinite(d)
            dist[todo] = d
            found[todo] = np.where(inside, self.index[np.minimum(i, len(self.index) - 1)], -1)
            bounds[todo] = bound
            have |= todo
        self._mirrors[kind] = (dist, found, bounds, have)
        return np.where(wanted, dist, np.nan)

    def anchors(self) -> np.ndarray:
        """Per point: linked neighbours j with a point at the mirror image through j, plus the lines
        through the point (pairs of linked neighbours j, 2 p - j)."""
        points, neighbours = self.points, self.near[:, 1:]
        n, k = neighbours.shape
        others = points[neighbours]
        tolerance = _MIRROR * self.dist[:, 1:]
        bound = float(tolerance.max()) if tolerance.size else 0.0
        # Mirror images of the point through each neighbour j (2 j - p) ...
        through = self._mirror_distances("through", 2.0 * others - points[:, None, :], bound, np.ones((n, k), bool))
        # ... and of each neighbour j through the point (2 p - j): the first kind seen from j, when p is
        # one of j's neighbours (the same numbers: looked up, not queried again).
        back = neighbours[neighbours] == np.arange(n)[:, None, None]  # (n, k, k): p among j's neighbours
        mutual = back.any(axis=2)
        beyond = np.empty((n, k))
        beyond[mutual] = through[neighbours[mutual], back.argmax(axis=2)[mutual]]
        if not mutual.all():
            lone = ~mutual
            beyond[lone] = self._mirror_distances("beyond", 2.0 * points[:, None, :] - others, bound, lone)[lone]
        # A point between two neighbours j and 2 p - j is seen from both: one line, counted once (else
        # the midpoint of two pins of a radial layout's diverging spokes, a reflection there, would
        # have two anchors from one pair).
        between = np.sum(self.link & (beyond < tolerance), axis=1)
        self._previous = None   # its answers are carried over: no chain of every pass's neighbourhood
        return np.sum(self.link & (through < tolerance), axis=1) + (between + 1) // 2

    def beyond_ring(self, which: np.ndarray | None = None) -> np.ndarray:
        """Per point (or per point of the index array `which`): whether it lies beyond the field's outer
        ring, linked to members only inward.

        Each linked neighbour lies inward (its direction more than 120 degrees from the point's outward
        direction, away from the members' centroid: cos below `_INWARD`), and the links come from two
        directions at least `_SPREAD` apart (cos below it). An outer-ring pin has ring neighbours beside it
        (a hexagon's corner: its edges at 120 degrees, cos -0.5, foreshortened towards the rim to -0.45);
        a lattice site beyond the ring (between two ring pins, at 150 degrees, cos -0.52 to -0.85 on
        brown-127's webcam frames) has none; a radial spoke's end is linked along its spoke alone.
        """
        which = np.arange(len(self.points)) if which is None else which
        points, neighbours, link = self.points[which], self.near[which, 1:], self.link[which]
        outward = points - self.points[self.members].mean(axis=0)
        outward /= np.maximum(np.hypot(outward[:, 0], outward[:, 1]), 1e-9)[:, None]
        towards = self.points[neighbours] - points[:, None, :]
        towards /= np.maximum(np.hypot(towards[..., 0], towards[..., 1]), 1e-9)[..., None]
        inward = np.all(~link | (np.einsum("nkj,nj->nk", towards, outward) < _INWARD), axis=1)
        spread = np.einsum("nkj,nlj->nkl", towards, towards)
        apart = np.any(link[:, :, None] & link[:, None, :] & (spread < _SPREAD), axis=(1, 2))
        return inward & apart

    def graph(self) -> coo_matrix:
        """Sparse adjacency of the lattice links."""
        n, k = self.near.shape
        rows = np.repeat(np.arange(n), k - 1)[self.link.ravel()]
        cols = self.near[:, 1:].ravel()[self.link.ravel()]
        return coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))

    def among_members(self) -> _Neighbourhood:
        """The neighbourhood of the members alone, numbered among themselves (as `_Neighbourhood` of
        ``points[members]`` gives it: each member's nearest members are the same look-ups)."""
        index = self.index
        number = np.full(len(self.points), -1)
        number[index] = np.arange(len(index))
        hood = object.__new__(_Neighbourhood)
        hood.points = self.points[index]
        hood.members = np.ones(len(index), bool)
        hood.index = np.arange(len(index))
        hood.tree = self.tree
        hood.k, hood._previous, hood._mirrors = self.k, None, {}
        hood.raw_dist, hood.raw_near = self.raw_dist[index], number[self.raw_near[index]]
        hood.dist, hood.near = hood.raw_dist, hood.raw_near
        hood.pitch, hood.link = self.pitch[index], self.link[index]
        return hood


def _row_median(values: np.ndarray) -> np.ndarray:
    """Median along the last axis, as `numpy.median` gives it (a partition alone for an odd count, 5x faster)."""
    k = values.shape[-1]
    if k % 2 == 0 or np.isnan(values).any():
        return np.median(values, axis=-1)
    return np.partition(values, k // 2, axis=-1)[..., k // 2]


def _median_nn(centres: np.ndarray) -> float:
    if len(centres) < 2:
        return np.nan
    dist, _ = cKDTree(centres).query(centres, 2)
    return float(np.median(dist[:, 1]))
