"""Two overlapping tips parted by a fit of two discs (issue 20: windows lagging on squeezed skin).

Ahead of a slide the skin squeezes tips together until they overlap: one blob, on which a window
(a centroid) settles between the two tips, nearer the neighbour's when it lags. Here the blob is
modelled as what the camera sees::

    m(x) = b0 + b1 x + b2 y + A * (1 - (1 - c1(x)) (1 - c2(x)))

two opaque discs of the tips' radius at rest (soft edges: a logistic of the distance beyond the
radius, `_EDGE_PX`) over a plane, their union drawn as one level (a renderer draws overlapping
tips as the brighter one). The linear parameters are solved in closed form for each pair of
centres, and the centres by damped Gauss-Newton, all pairs at once as (L, P) arrays. The blob's
two ends fix both centres where one centroid cannot. Pixels nearer another expected pin than either
of the pair's starts are left out (that pin's tip), as are those beyond a tip radius and 2 px of both.

`part_overlapping` (`pins.track.PinTracker(part_overlaps=True)`, after the follow passes and the snap to
rest) pairs each placed pin with its nearest expected neighbour when that lies within two tip radii
(`Refiner._overlap_px`), starts the fit at where both are (a missing neighbour at its guess or prediction),
and moves the placed ones onto the fit when each fitted centre lies within the gate of its start, nearer its
own start than the other's, and the two at least half a radius apart; a missing neighbour stays missing.

Measured on `bench/bench_slides.py` (8 slides of 3 pitches, seeds 0-5; new against the tracker without it):
realistic skin tactip-331 pin-frames on another pin's tip 20 -> 0, > 3 px off 480 -> 1, lost visible pins per
frame 0.90 -> 0.12; model skin tactip-331 4735 -> 1154 (lost 10.8 -> 6.6), radial-led-120 34 -> 4 (3.41 ->
2.87); its cost is in `pins.track.PinTracker` (`part_overlaps`) and `bench/bench_slides.py`.

On by default since session 17 (follow10), for tips of at least `_SMALLEST_TIP_PX` (3 px): bench_slides, main
ccd37d5 off -> on, seeds 0-5 / held-out 6-11, tactip-331 model skin pin-frames on other tips 4735 -> 1154 / 4585 ->
1446, > 3 px off 12187 -> 5662 / 11607 -> 5669, lost visible pins a frame 10.82 -> 6.55 / 10.88 -> 6.61; realistic
skin 20 -> 0 / 5 -> 0, 480 -> 1 / 483 -> 0, 0.90 -> 0.12 / 0.98 -> 0.13; rest>1, lost@rest, end>1 0 throughout;
bench_phenomena (tactip-331, white-dark-331, seeds 0-2) unchanged, every bar met. radial-led-120 (the real-like
slide video's preset) and small-pad-100 are not fitted: unchanged, the gate costs 0.1 us a frame there.

The NumPy code here is the reference. `part_overlapping` runs the compiled kernel of `pins._jit_pairs` (Numba:
pairing, fits and acceptance in one call a frame) unless ``TACTIP_KERNELS=numpy`` or Numba is missing; the
tests hold it to this code within 1e-9 px.
"""

from __future__ import annotations

import functools

import numpy as np

from ._kernels import compiled
from ._tipfit import _solve

_EDGE_PX = 0.6
_PASSES = 4
_DAMPING = 1e-3
_MARGIN_PX = 2.0
_OTHERS = 4  # other pins nearest a pair whose cells bound its pixels
# Tips smaller than this radius, px, are not fitted: mostly soft edge (0.6 px and the camera's blur), two of
# them overlapping show no ends a fit could find (small-pad-100, tips of 1.25 px: lost visible pins per frame
# 4.99 -> 6.58 on bench_slides' realistic skin with them fitted). radial-led-120's tips of 2 px gain on the
# model skin (pin-frames on other tips 34 -> 4) but not on the realistic one, where the fit is no better than
# the windows (fitted pins 0.20 px off their truth before the fit, 0.22 after, median, seed 2) and loses more
# visible pins on every seed (3.20/2.87/2.19/3.12/2.64/3.43 -> 3.28/2.94/2.45/3.33/2.79/3.69 a frame); tactip-331's
# of 5.75 px gain on both skins. So the fit (on by default in `pins.track.PinTracker`) engages from 3 px, five
# edge widths: between the presets where it does not pay and those where it does (none lies between to tune on).
_SMALLEST_TIP_PX = 3.0
# A fit whose tips rise less than this above the plane, grey levels, found no tips (a flat patch: its rise is the
# sums' rounding, and the centres wander with it).
_LEAST_RISE = 1.0


def fit_tip_pairs(crop: np.ndarray, first: np.ndarray, second: np.ndarray, radius_px: float,
                  others: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centres of pairs of overlapping tips, fitted as two discs over a plane: (L, 2), (L, 2) px (NaN: failed).

    Parameters
    ----------
    crop : (h, w) ndarray of uint8
        Bright pins.
    first, second : (L, 2) ndarray
        Starting centres (x, y) of each pair's two tips, px in `crop`.
    radius_px : float
        The tips' radius, px.
    others : (L, k, 2) ndarray
        Other pins expected nearby, px in `crop` (NaN: none): pixels nearer to them than to the pair are left out.
    """
    middle = 0.5 * (first + second)
    half = int(np.ceil(np.nanmax(0.5 * np.linalg.norm(first - second, axis=1)) + radius_px + _MARGIN_PX))
    gx, gy = _grid(half)
    corner = np.rint(middle).astype(np.intp)
    x = corner[:, :1] + gx  # (L, P)
    y = corner[:, 1:] + gy
    h, w = crop.shape
    inside = (x >= 0) & (x < w) & (y >= 0) & (y < h)
    values = crop[np.minimum(np.maximum(y, 0), h - 1), np.minimum(np.maximum(x, 0), w - 1)].astype(np.float64)
    xf, yf = x.astype(np.float64), y.astype(np.float64)

    def squared(points):  # (L, 2) -> (L, P), px^2
        dx, dy = xf - points[:, :1], yf - points[:, 1:]
        dx *= dx
        dy *= dy
        dx += dy
        return dx

    near = np.minimum(squared(first), squared(second))
    keep = inside & (near <= (radius_px + _MARGIN_PX) ** 2)
    # Only the few others nearest the pair can reach its pixels (each a pass over the (L, P) arrays).
    reach = _sq(others - middle[:, None, :])
    order = np.argsort(np.where(np.isfinite(reach), reach, np.inf), axis=1)[:, :_OTHERS]
    others = np.take_along_axis(others, order[..., None], axis=1)
    closest = squared(others[:, 0])
    for j in range(1, others.shape[1]):
        np.fmin(closest, squared(others[:, j]), out=closest)
    keep &= ~(closest < near)  # (NaN, no other, compares False)
    # Only the kept pixels (two discs' worth of a square patch, about a third of it) go on: each pair's first,
    # padded to the most any pair keeps.
    most = int(np.count_nonzero(keep, axis=1).max())
    if most == 0:
        return np.full_like(first, np.nan), np.full_like(second, np.nan)
    order = np.argsort(~keep, axis=1, kind="stable")[:, :most]
    keep, values, xf, yf = (np.take_along_axis(v, order, axis=1) for v in (keep, values, xf, yf))
    weight = keep.astype(np.float64)[..., None]
    mu = np.concatenate([first, second], axis=1)  # (L, 4)
    # The design (L, P, 4): a plane and the tips' coverage (the last column, new each pass); the Jacobian likewise.
    design = np.empty(xf.shape + (4,))
    design[..., 0] = 1.0
    np.subtract(xf, middle[:, :1], out=design[..., 1])
    np.subtract(yf, middle[:, 1:], out=design[..., 2])
    jac = np.empty(xf.shape + (4,))
    ridge, eye = 1e-6 * np.eye(4), np.eye(4)
    try:
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            for _ in range(_PASSES):
                dx1, dy1, dx2, dy2 = xf - mu[:, :1], yf - mu[:, 1:2], xf - mu[:, 2:3], yf - mu[:, 3:]
                d1, d2 = np.sqrt(dx1 * dx1 + dy1 * dy1), np.sqrt(dx2 * dx2 + dy2 * dy2)
                c1 = 1.0 / (1.0 + np.exp((d1 - radius_px) / _EDGE_PX))  # (exp overflows to inf: c 0)
                c2 = 1.0 / (1.0 + np.exp((d2 - radius_px) / _EDGE_PX))
                np.subtract(1.0, (1.0 - c1) * (1.0 - c2), out=design[..., 3])
                weighted = np.swapaxes(design * weight, 1, 2)  # (L, 4, P)
                beta = (_solve(weighted @ design + ridge, weighted @ values[..., None]))[..., 0]
                residual = values - (design @ beta[..., None])[..., 0]
                amplitude = beta[:, 3:] / _EDGE_PX
                # d cover / d mu: (1 - c_other) * c (1 - c) / edge * (x - mu) / d
                g1 = amplitude * (1.0 - c2) * c1 * (1.0 - c1) / np.maximum(d1, 1e-6)
                g2 = amplitude * (1.0 - c1) * c2 * (1.0 - c2) / np.maximum(d2, 1e-6)
                np.multiply(g1, dx1, out=jac[..., 0])
                np.multiply(g1, dy1, out=jac[..., 1])
                np.multiply(g2, dx2, out=jac[..., 2])
                np.multiply(g2, dy2, out=jac[..., 3])
                weighted = np.swapaxes(jac * weight, 1, 2)  # (L, 4, P)
                jtj = weighted @ jac
                jtj += (_DAMPING * jtj.diagonal(axis1=1, axis2=2))[:, :, None] * eye + 1e-9 * eye
                step = _solve(jtj, weighted @ residual[..., None])[..., 0]
                mu = mu + np.minimum(np.maximum(step, -1.5), 1.5)
    except np.linalg.LinAlgError:  # (a singular system: no fit)
        return np.full_like(first, np.nan), np.full_like(second, np.nan)
    bad = ~np.isfinite(mu).all(axis=1) | ~(beta[:, 3] > _LEAST_RISE)
    mu[bad] = np.nan
    return mu[:, :2], mu[:, 2:]


@functools.lru_cache(maxsize=None)
def _grid(half: int) -> tuple[np.ndarray, np.ndarray]:
    """Offsets (x, y) of a square of side 2 half + 1 px, flattened: (P,), (P,) of int."""
    offsets = np.arange(-half, half + 1)
    gx, gy = np.meshgrid(offsets, offsets)
    return gx.ravel(), gy.ravel()


def part_overlapping(refiner, crop: np.ndarray, positions: np.ndarray, expected: np.ndarray) -> np.ndarray:
    """Placed pins whose tips overlap a neighbour's (expected within two tip radii) moved onto a fit of the two tips.

    `refiner`: the `pins._refine.Refiner`; `positions` (N, 2) px (NaN: missing), `expected` (N, 2) px where
    every pin is expected (missing ones at their guesses or predictions). Returns `positions` or a copy, px.
    """
    if not refiner.tip_fit_radius_px >= _SMALLEST_TIP_PX:
        return positions
    kernels = compiled("_jit_pairs")
    if kernels is not None:  # (one call: pairing, fits, acceptance)
        return kernels.part_pairs(crop, positions, expected, refiner._window_neighbours, refiner._overlap_px,
                                  float(refiner.tip_fit_radius_px), float(refiner.gate_px), refiner.origin)
    at = np.where(np.isfinite(positions), positions, expected)
    placed = np.flatnonzero(np.isfinite(positions[:, 0]))
    if not placed.size:
        return positions
    around = refiner._window_neighbours[:, placed].T  # (L, k)
    gap = _sq(at[around] - at[placed][:, None, :])  # px^2 (NaN compares False)
    close = gap < (refiner._overlap_px[placed] ** 2)[:, None]
    if not np.count_nonzero(close):  # (most frames: no two tips overlap)
        return positions
    rows = np.flatnonzero(np.logical_or.reduce(close, axis=1))
    nearest = np.argmin(np.where(close[rows], gap[rows], np.inf), axis=1)
    first, second = placed[rows], around[rows, nearest]
    # One fit per pair.
    key = np.minimum(first, second) * len(positions) + np.maximum(first, second)
    _, unique = np.unique(key, return_index=True)
    first, second = first[unique], second[unique]
    neighbours = np.concatenate([refiner._window_neighbours[:, first].T, refiner._window_neighbours[:, second].T], axis=1)
    others = at[neighbours] - refiner.origin
    others[(neighbours == first[:, None]) | (neighbours == second[:, None])] = np.nan
    start1, start2 = at[first] - refiner.origin, at[second] - refiner.origin
    fit1, fit2 = fit_tip_pairs(crop, start1, start2, refiner.tip_fit_radius_px, others)
    gate = refiner.gate_px ** 2
    with np.errstate(invalid="ignore"):
        ok = (_sq(fit1 - start1) <= gate) & (_sq(fit2 - start2) <= gate)
        ok &= _sq(fit1 - start1) + _sq(fit2 - start2) <= _sq(fit1 - start2) + _sq(fit2 - start1)
        ok &= _sq(fit1 - fit2) >= (0.5 * refiner.tip_fit_radius_px) ** 2
    if not ok.any():
        return positions
    positions = positions.copy()
    positions[first[ok]] = fit1[ok] + refiner.origin
    both = ok & np.isfinite(positions[second, 0])
    positions[second[both]] = fit2[both] + refiner.origin
    return positions


def _sq(v: np.ndarray) -> np.ndarray:
    return v[..., 0] ** 2 + v[..., 1] ** 2
