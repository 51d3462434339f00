"""Is there a pin tip at a point? A matched test of an opaque tip against a curved membrane.

A pin tip is paint: it hides the membrane behind it. Where the light on the membrane is about the
tip's own level (the outermost ring of ``radial-led-120`` under the veil, which lights the membrane
fully and the tips only in part) a tip barely stands above or below its surround on average; what
shows is that the membrane's slope stops at the tip's edge. A test of "core brighter than the ring
round it" misses such a tip (its core mean is -11 to +7 grey from the membrane, noise sigma 5); the
model of what the camera sees does not::

    H1:  m(x) = (1 - c(x)) * s(x) + c(x) * L      H0:  m(x) = s(x)

with ``s`` a quadratic membrane, ``c`` the tip's coverage (an ellipse with a soft edge, the shape of
the pins round the point: foreshortening makes outer tips ellipses) and ``L`` the tip's level. Both
are linear given the point, so each is a least-squares fit, all points at once. The evidence is the
drop in squared residual from H0 to H1 over the noise variance, ``T = (RSS0 - RSS1) / sigma^2``: for
a pin, about its matched-filter SNR squared (6-9 for the faint outer tips of ``radial-led-120``: T
36-80); on bare membrane (H1 one parameter more than H0), at most chi-square with one degree of
freedom at a fixed point, so a threshold for a false-alarm rate follows from the noise alone
(`threshold`). The variance is the larger of the camera's pixel noise and the window's own residual
scatter under H1, so a membrane that no quadratic fits (a reflection's edge, the veil) raises the
bar instead of passing for a tip.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree
from scipy.special import erf
from scipy.stats import chi2

__all__ = ["tip_evidence", "threshold"]

_EDGE_PX = 0.55  # soft edge of the coverage (as `pins._tipfit`): erf of the distance inside / this, px
_SATURATED = 254.0
# H1 has this many parameters more than H0 (the tip's level and dome): the null's degrees of freedom.
_EXTRA = 2
# Another pin's tip and foot reach this far beyond the tip's major semi-axis (the soft edge, blur), px.
_FOOT_PX = 2.0  # pixels this bright show no membrane level (the surround's veil)


def threshold(false_alarm: float, cells: np.ndarray | float) -> np.ndarray:
    """The evidence T above which bare membrane passes for a tip with probability `false_alarm`,
    searched over `cells` independent tip-sized places (Bonferroni over chi-square, one degree of
    freedom).

    >>> round(float(threshold(1e-3, 1.0)), 1)
    10.8
    """
    return chi2.isf(false_alarm / np.maximum(np.asarray(cells, dtype=np.float64), 1.0), _EXTRA)


def tip_evidence(image: np.ndarray, points: np.ndarray, shapes: np.ndarray, pins: np.ndarray,
                 noise_sigma: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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
        membrane (`_FOOT_PX` beyond the major semi-axis); a pin within half a tip radius of a point is that point's own and is not left out.
    noise_sigma : float
        The camera's pixel noise, grey levels: the least variance the test assumes.

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
    inverse = np.linalg.inv(shapes)
    major = np.sqrt(np.linalg.eigvalsh(shapes)[:, 1])
    reach = 1.5 * float(major.max()) + 2.0
    half = int(np.ceil(reach)) + 1
    dy, dx = np.mgrid[-half:half + 1, -half:half + 1]
    dx, dy = dx.ravel().astype(np.float64), dy.ravel().astype(np.float64)
    anchor = np.rint(points)
    x, y = anchor[:, 0, None] + dx[None], anchor[:, 1, None] + dy[None]
    height, width = image.shape
    inside = (x >= 0) & (x <= width - 1) & (y >= 0) & (y <= height - 1)
    values = image[np.clip(y, 0, height - 1).astype(np.intp), np.clip(x, 0, width - 1).astype(np.intp)].astype(np.float64)
    ex, ey = x - points[:, 0, None], y - points[:, 1, None]
    length = np.hypot(ex, ey)
    weight = inside & (length <= (1.5 * major + 2.0)[:, None]) & (values < _SATURATED)
    # Other pins' tips and feet are no membrane.
    if len(pins):
        gap, near = cKDTree(pins).query(points, min(7, len(pins)))
        gap, near = gap.reshape(len(points), -1), near.reshape(len(points), -1)
        others = np.where((gap < 0.5 * major[:, None])[..., None], np.inf, pins[near])
        foot = (major + _FOOT_PX)[:, None]
        for k in range(others.shape[1]):
            weight &= np.hypot(x - others[:, k, 0, None], y - others[:, k, 1, None]) > foot
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
