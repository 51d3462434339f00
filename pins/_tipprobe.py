"""Is there a pin tip at a point? A matched test of an opaque tip against a curved membrane.

A pin tip is paint: it hides the membrane behind it. Where the light on the membrane is about the
tip's own level (the outermost ring of ``radial-led-120`` under the veil, which lights the membrane
fully and the tips only in part) a tip barely stands above or below its surround on average; what
shows is that the membrane's slope stops at the tip's edge. A test of "core brighter than the ring
round it" misses such a tip (its core mean is -11 to +7 grey from the membrane, noise sigma 5); the
model of what the camera sees does not::

    H1:  m(x) = (1 - c(x)) * s(x) + c(x) * (L + D * q(x))      H0:  m(x) = s(x)

with ``s`` a quadratic membrane, ``c`` the tip's coverage (an ellipse ``q(x) <= 1`` with a soft edge,
the shape of the pins round the point: foreshortening makes outer tips ellipses) and ``L + D q`` the
tip's own level, domed as `pins._tipfit` models it (a hemispherical tip lit from round it is brighter
at its centre: 25 grey from centre to edge on the faint tips of ``radial-led-120``; without the dome
their evidence fell to half). Both are linear given the point, so each is a least-squares fit, all
points at once. The evidence is the drop in squared residual from H0 to H1 over the noise variance,
``T = (RSS0 - RSS1) / sigma^2``: for a pin, its matched-filter SNR squared (on noise-free renders of
``radial-led-120`` the faint outer tips give T equal to the ideal SNR^2, 20-80 at sigma 5); on bare
membrane (H1 has `_EXTRA` parameters more than H0) chi-square with `_EXTRA` degrees of freedom at a
fixed point, so a threshold for a false-alarm rate follows from the noise alone (`threshold`; on
4056 points of bare membrane of ``radial-led-120``, seeds 0-11, 0.37 % passed chi-square's 0.45 %
point and none its 0.055 % point). The variance is the larger of the camera's pixel noise and the
window's own residual scatter under H1, so a membrane that no quadratic fits (a reflection's edge,
the veil) raises the bar instead of passing for a tip.

`flat_pins` asks the opposite of kept blobs: an LED reflection's flat top at a lattice site stands no
higher above a quadratic fit of the membrane round it than the membrane does (`_core_above_membrane`).
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy.spatial import cKDTree
from scipy.special import chdtri, erf

__all__ = ["flat_pins", "tip_evidence", "threshold"]

_EDGE_PX = 0.55  # soft edge of the coverage (as `pins._tipfit`): erf of the distance inside / this, px
_SATURATED = 254.0  # pixels this bright show no membrane level (the surround's veil)
# H1 has this many parameters more than H0 (the tip's level and dome): the null's degrees of freedom.
_EXTRA = 2
# Another pin's tip and foot reach this far beyond the tip's major semi-axis (the soft edge, blur), px.
_FOOT_PX = 2.0
# A kept pin whose core stands neither this many standard errors above the membrane's fit nor this
# fraction of the contrast of its `_FLAT_NEIGHBOURS` nearest pins is no tip (an LED reflection's flat
# top): `flat_pins`.
_FLAT_SIGNIFICANCE = 2.5
_FLAT_CONTRAST = 0.2
_FLAT_NEIGHBOURS = 6
# The pins whose feet are left out of the membrane round a point: its nearest this many (itself included).
_FOOT_PINS = 7
# The membrane ring round a tip (`flat_pins`): from 1.5 to 3.5 px beyond its edge, or from 0.26 to 0.6
# tip radii where that is more. The px figures were set on tips of 2-6 px; on a frame filmed larger
# (1920x1080: tips of 13 px, their soft edge 2-3 px wide) a 2 px ring caught the tip's edge and fitted a
# bowl under the core: 2-39 of 331 true pins taken for flat tops (0 with the fractions, which are the px
# figures at a 5.7 px tip, tactip-331 at 640x480).
_RING_PX = (1.5, 3.5)
_RING_FRACTION = (0.26, 0.6)
# The membrane ring round a tip leaves out pixels this close to the sensor disc's edge, px (its blur), and
# a tip with no more than this share of its ring on the pad is not judged.
_RIM_PX = 1.0
_RING_ON_PAD = 0.7
# `tip_evidence` fits at most this many window pixels at once (points x pixels; its arrays of 8 basis
# functions then take about 8 x 8 bytes x this = 16 MB, all of its arrays about 80 MB).
_BATCH_PIXELS = 1 << 18


def threshold(false_alarm: float, cells: np.ndarray | float) -> np.ndarray:
    """The evidence T above which bare membrane passes for a tip with probability `false_alarm`,
    searched over `cells` independent tip-sized places (Bonferroni over chi-square with `_EXTRA`
    degrees of freedom: H1's level and dome).

    >>> round(float(threshold(1e-3, 1.0)), 1)
    13.8
    """
    # scipy.stats.chi2.isf's own function (bit for bit), without importing scipy.stats: ~0.25 s of CPU on the
    # main thread of every `tactip replay` and `detect`, inside the pin-field search.
    return chdtri(_EXTRA, false_alarm / np.maximum(np.asarray(cells, dtype=np.float64), 1.0))


def tip_evidence(image: np.ndarray, points: np.ndarray, shapes: np.ndarray, pins: np.ndarray,
                 noise_sigma: float, *, disc: tuple[float, float, float] | None = None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The evidence for an opaque tip at each point (the module docstring), its level and contrast.

    Parameters
    ----------
    image : (H, W) ndarray of float32
        Grey frame (bright tips: invert dark markers first).
    points : (P, 2) ndarray
        Tip centres to test (x, y), px (sub-pixel).
    shapes : (P, 2, 2) ndarray
        Each tip's ellipse: it covers ``{e : e^T shapes^-1 e <= 1}``, px^2 (a circle of radius r:
        ``r^2 I``).
    pins : (N, 2) ndarray
        Pins known round the points, px: pixels near one (its tip and foot) are no
        membrane (`_FOOT_PX` beyond the major semi-axis); a pin within half a tip radius of a point
        is that point's own and is not left out.
    noise_sigma : float
        The camera's pixel noise, grey levels: the least variance the test assumes.
    disc : (cx, cy, radius) px, optional
        The sensor disc: pixels beyond it or within `_RIM_PX` of its edge (its blur) are no membrane (as in
        `flat_pins`). A tip of the outermost ring lies 4-7 px inside the edge, within a window's reach:
        fitted as membrane, the bright surround's rise raised the scatter (the bar) and passed for a tip's
        edge at an empty site. (2 px left out the tips' own pixels where the disc is tight: small-pad-100.)

    Returns
    -------
    evidence : (P,) ndarray
        T = (RSS0 - RSS1) / sigma^2 (nan: too few membrane pixels to fit).
    level : (P,) ndarray
        The tip's fitted level L, grey levels.
    contrast : (P,) ndarray
        L minus the membrane's fitted level at the point, grey levels (negative: a tip darker than the
        membrane lit round it).
    """
    points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    shapes = np.asarray(shapes, dtype=np.float64).reshape(-1, 2, 2)
    if not len(points):
        return np.zeros(0), np.zeros(0), np.zeros(0)
    # Points in batches of at most `_BATCH_PIXELS` window pixels: a 1080p frame's tips are 2-3x wider,
    # their windows 5-9x the pixels and the places searched 5-9x as many (11 GB at once, where 640x480
    # takes 0.1); each point's fit is its own, so batches give the same figures.
    major = np.sqrt(np.linalg.eigvalsh(shapes)[:, 1])
    pixels = len(_disc_offsets(float(1.5 * major.max() + 2.0) + np.sqrt(0.5))[0])
    batch = max(1, _BATCH_PIXELS // pixels)
    if len(points) > batch:
        parts = [_tip_evidence(image, points[k:k + batch], shapes[k:k + batch], pins, noise_sigma, disc)
                 for k in range(0, len(points), batch)]
        return tuple(np.concatenate(column) for column in zip(*parts))
    return _tip_evidence(image, points, shapes, pins, noise_sigma, disc)


def _tip_evidence(image: np.ndarray, points: np.ndarray, shapes: np.ndarray, pins: np.ndarray,
                  noise_sigma: float, disc: tuple[float, float, float] | None = None
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`tip_evidence` on one batch of points (float64 (P, 2) and (P, 2, 2), P >= 1)."""
    inverse = np.linalg.inv(shapes)
    major = np.sqrt(np.linalg.eigvalsh(shapes)[:, 1])
    radius = 1.5 * major + 2.0  # each point's window, px
    reach = float(radius.max())
    # The pixels round each point's nearest pixel that can lie within the widest window of a point up to
    # half a pixel off it (row by row, as a square of them would be).
    dx, dy = _disc_offsets(reach + np.sqrt(0.5))
    anchor = np.rint(points)
    x, y = anchor[:, 0, None] + dx[None], anchor[:, 1, None] + dy[None]
    values, inside = _gather(image, x, y)
    ex, ey = x - points[:, 0, None], y - points[:, 1, None]
    length = np.hypot(ex, ey)
    weight = inside & (length <= radius[:, None]) & (values < _SATURATED)
    if disc is not None:  # beyond the sensor disc (and its edge's blur) lies no membrane
        weight &= np.hypot(x - disc[0], y - disc[1]) <= disc[2] - _RIM_PX
    # Other pins' tips and feet are no membrane.
    if len(pins):
        gap, near = cKDTree(pins).query(points, min(7, len(pins)))
        gap, near = gap.reshape(len(points), -1), near.reshape(len(points), -1)
        others = np.where((gap < 0.5 * major[:, None])[..., None], np.inf, pins[near])
        foot = np.square(major + _FOOT_PX)[:, None]
        for k in range(others.shape[1]):
            weight &= np.square(x - others[:, k, 0, None]) + np.square(y - others[:, k, 1, None]) > foot
    # Only the pixels that count are fitted (about a fifth of the square round the widest window): each
    # point's, in their order, then pixels of weight 0 up to the most any point has.
    used = np.argsort(~weight, axis=1, kind="stable")[:, :int(weight.sum(axis=1).max())]
    weight, values, ex, ey, length = (np.take_along_axis(a, used, axis=1) for a in (weight, values, ex, ey, length))
    q = (inverse[:, 0, 0, None] * ex * ex + 2.0 * inverse[:, 0, 1, None] * ex * ey
         + inverse[:, 1, 1, None] * ey * ey)
    root = np.sqrt(np.maximum(q, 1e-12))
    coverage = 0.5 + 0.5 * erf(length * (1.0 - root) / root / _EDGE_PX)
    scale = reach
    u, v = ex / scale, ey / scale
    surface = np.stack([np.ones_like(u), u, v, u * u, u * v, v * v], axis=1)  # (P, 6, K)
    w = weight.astype(np.float64)
    rss0, _ = _fit(surface, values, w)
    dome = coverage * np.minimum(q, 1.0)
    tip = np.concatenate([surface * (1.0 - coverage)[:, None], coverage[:, None], dome[:, None]], axis=1)  # (P, 8, K)
    rss1, beta = _fit(tip, values, w)
    count = w.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        scatter = np.where(count > 16, rss1 / (count - 8.0), np.nan)
        variance = np.maximum(scatter, float(noise_sigma) ** 2)
        evidence = (rss0 - rss1) / variance
    return evidence, beta[:, 6], beta[:, 6] - beta[:, 0]


def _fit(basis: np.ndarray, values: np.ndarray, weight: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Weighted least squares of `values` (P, K) on `basis` (P, B, K), every point at once: the residual
    sum of squares (P,) and the coefficients (P, B)."""
    weighted = basis * weight[:, None, :]
    normal = weighted @ basis.transpose(0, 2, 1)
    ridge = 1e-9 * np.eye(basis.shape[1])
    beta = np.linalg.solve(normal + ridge, (weighted @ values[..., None]))[..., 0]
    residual = values - np.einsum("pbk,pb->pk", basis, beta)
    return np.sum(weight * residual ** 2, axis=1), beta


def _disc_offsets(reach: float) -> tuple[np.ndarray, np.ndarray]:
    """Integer pixel offsets (dx, dy) within `reach` px of the origin."""
    half = int(np.ceil(reach))
    dy, dx = np.mgrid[-half:half + 1, -half:half + 1]
    inside = np.hypot(dx, dy) <= reach
    return dx[inside].astype(np.float64), dy[inside].astype(np.float64)


def _gather(image: np.ndarray, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Grey levels at integer pixel coordinates (any shape, clipped to the image) and whether inside."""
    height, width = image.shape
    inside = (x >= 0) & (x <= width - 1) & (y >= 0) & (y <= height - 1)
    values = image[np.clip(y, 0, height - 1).astype(np.intp), np.clip(x, 0, width - 1).astype(np.intp)]
    return values.astype(np.float64), inside


def _ring_px(radius_px: float) -> tuple[float, float]:
    """Inner and outer radius of the membrane ring round a tip of `radius_px` (`_core_above_membrane`),
    px: `_RING_PX` beyond the tip, or `_RING_FRACTION` of its radius where that is more."""
    return tuple(radius_px + max(px, fraction * radius_px) for px, fraction in zip(_RING_PX, _RING_FRACTION))


def _core_above_membrane(image: np.ndarray, points: np.ndarray, radius_px: float,
                         pins: np.ndarray, disc: tuple[float, float, float] | None = None
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """How far the core of a tip at each point stands above a quadratic fit of the membrane round it.

    The membrane is the ring `_ring_px` beyond the tip radius (pixels at the foot of another pin of
    `pins` left out, and those beyond `disc`, (cx, cy, radius) px, when given, or within `_RIM_PX` of its
    edge: the casing or the surround; with no more than `_RING_ON_PAD` of the ring on the pad, nan);
    the core is the disc of the tip radius less half a pixel (at least 1 px).

    Returns
    -------
    contrast : (P,) ndarray
        Mean core grey level minus the fit's mean over the core, grey levels (nan: too little membrane).
    error : (P,) ndarray
        Its standard error: the membrane's scatter about the fit (residual standard deviation, grey
        levels) over the square root of the core's pixel count.
    position : (P, 2) ndarray
        Centroid of the core's grey levels above the fit, px (the point where none stands above).
    """
    inner, outer = _ring_px(radius_px)
    dx, dy = _disc_offsets(outer)
    distance = np.hypot(dx, dy)
    used = (distance <= max(radius_px - 0.5, 1.0)) | (distance >= inner)  # the tip's edge: neither
    dx, dy, distance = dx[used], dy[used], distance[used]
    core, ring = distance < inner, distance >= inner
    anchor = np.rint(points)
    x, y = anchor[:, 0, None] + dx[None], anchor[:, 1, None] + dy[None]
    values, inside = _gather(image, x, y)
    # Pixels at another pin's foot (not the pin measured, which sits at its own point) are no membrane.
    gap, near = cKDTree(pins).query(points, min(_FOOT_PINS, len(pins)))
    others = np.where((gap < 0.5 * radius_px)[..., None], np.inf, pins[near]).astype(np.float32)  # (P, F, 2)
    xs, ys = x[:, ring].astype(np.float32), y[:, ring].astype(np.float32)
    other = np.sqrt(np.min((xs[:, :, None] - others[:, None, :, 0]) ** 2 + (ys[:, :, None] - others[:, None, :, 1]) ** 2,
                           axis=2))
    # Saturated pixels (the surround's veil near the rim) show no membrane level.
    weight = np.zeros(values.shape)
    weight[:, ring] = inside[:, ring] & (other > inner) & (values[:, ring] < _SATURATED)
    judged = np.ones(len(points), bool)
    if disc is not None:
        cx, cy, reach = disc
        on_pad = np.hypot(xs - cx, ys - cy) <= reach - _RIM_PX
        weight[:, ring] *= on_pad
        # A ring the disc cuts: a quadratic through one side of a tip (the veil rising to the rim) is no
        # membrane under it (radial-led-120 at 320x240: outer tips 2.1-2.4 px inside the edge, flat by it).
        judged = on_pad.mean(axis=1) > _RING_ON_PAD
    scale = outer
    u, v = dx / scale, dy / scale
    basis = np.stack([np.ones_like(u), u, v, u * u, u * v, v * v], axis=1)  # (K, 6)
    # Weighted least squares for every point at once, as two matrix products over the pixels.
    normal = (weight @ (basis[:, :, None] * basis[:, None, :]).reshape(len(basis), 36)).reshape(-1, 6, 6)
    beta = np.linalg.solve(normal + 1e-9 * np.eye(6), ((weight * values) @ basis)[..., None])[..., 0]
    residual = values - beta @ basis.T
    dof = weight.sum(axis=1) - 6.0
    with np.errstate(invalid="ignore", divide="ignore"):
        variance = np.where((dof >= 6.0) & judged, np.sum(weight * residual ** 2, axis=1) / dof, np.nan)
        # The core mean's standard error, its pixels scattering about the fit as the membrane's do.
        error = np.sqrt(variance / core.sum())
        contrast = np.where(np.isfinite(variance), residual[:, core].mean(axis=1), np.nan)
        above = np.clip(residual[:, core], 0.0, None)
        total = above.sum(axis=1)
        shift = np.column_stack([above @ dx[core], above @ dy[core]]) / total[:, None]
    position = anchor + np.where(total[:, None] > 0, shift, 0.0)
    return contrast, error, position


def flat_pins(grey: np.ndarray, pins: np.ndarray, radius_px: float, *, dark_pins: bool = False,
              disc: tuple[float, float, float] | None = None) -> np.ndarray:
    """Which pins (N,) bool show no tip: a core that stands neither `_FLAT_SIGNIFICANCE` standard errors
    above a quadratic fit of the membrane round it nor `_FLAT_CONTRAST` of its neighbours' contrast.

    The flat top of an LED reflection inside the pad, at a lattice site, is a blob as large and as
    bright above the threshold's neighbourhood mean as a pin, but round it the membrane rises to the
    same level: above the fit it stands 0.7-1.8 standard errors and 0.03-0.08 of its neighbours'
    contrast, where the faintest pins under the veil stand 3.3 and 0.14 (radial-led-120, seeds 0-11).
    A pin whose membrane cannot be fitted (too little of it round the pin) is not judged. Beyond the
    sensor disc (`disc`) lies no membrane: the bright surround round a small pad, taken for membrane, fitted
    a slope under the outermost pins' cores (small-pad-100 under noise 8: a true tip 1.6 standard errors and
    0.18 of its neighbours' contrast above the fit). A blob whose tip the disc's edge cuts (its centre
    within a tip radius of the edge) is no pin either: glare on the casing.

    Parameters
    ----------
    grey : (H, W) ndarray of uint8
        Grey frame.
    pins : (N, 2) ndarray
        Pins (x, y), px.
    radius_px : float
        Pin tip radius, px.
    dark_pins : bool
        Dark markers on a light membrane (the image is inverted).
    disc : (cx, cy, radius) px, optional
        The sensor disc: ring pixels beyond it, or within `_RIM_PX` of its edge (the edge's blur), are not
        membrane.

    Returns
    -------
    flat : (N,) ndarray of bool
        All False for fewer than 7 pins or no radius.
    """
    pins = np.asarray(pins, dtype=np.float64).reshape(-1, 2)
    if len(pins) < 7 or not (np.isfinite(radius_px) and radius_px > 0):
        return np.zeros(len(pins), bool)
    image = grey.astype(np.float32)
    if dark_pins:
        image = 255.0 - image
    contrast, error, _ = _core_above_membrane(image, pins, radius_px, pins, disc)
    _, near = cKDTree(pins).query(pins, min(_FLAT_NEIGHBOURS + 1, len(pins)))
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        # A pin whose neighbours' membranes none could be fitted (all by the rim) has no typical contrast.
        warnings.simplefilter("ignore", RuntimeWarning)
        typical = np.nanmedian(contrast[near[:, 1:]], axis=1)
        flat = (contrast < _FLAT_SIGNIFICANCE * error) & (contrast < _FLAT_CONTRAST * typical)
    if disc is not None:
        # A tip the disc's edge cuts is the casing's glare, not a pin: the lattice's pins lie 3.1-8.0 tip
        # radii inside it on every preset with a disc (seeds 0-2), their blobs' centres (leaning towards a
        # bright rim, radius as measured) at least 1.7 (brown-127 seed 5 tapped: a glare blob 0.9 radii inside).
        cx, cy, reach = disc
        flat |= np.hypot(pins[:, 0] - cx, pins[:, 1] - cy) > reach - radius_px
    return flat
