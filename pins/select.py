"""Selection of the pins used as tactile elements (paper 002, III-A.3).

The paper uses 40 of the 532 pins, at least 4 mm apart, which keeps the information of the
whole pad while removing the redundancy of neighbouring pins. `select_pins` picks them greedily
from the centre of the pad outwards: each pin, in order of distance from the centre, is taken
if it is at least `min_separation_mm` from every pin already taken. Contact happens at the
centre, so the selection covers the contact region densely and reaches out as far as needed.
The result depends only on the rest positions: the same sensor always gives the same pins.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .errors import PinsError, ShapeError

__all__ = ["select_pins", "median_spacing_px"]


def select_pins(rest_positions: np.ndarray, *, n_pins: int = 40, min_separation_mm: float = 4.0,
                mm_per_px: float, centre: tuple[float, float] | None = None) -> np.ndarray:
    """Indices of `n_pins` pins at least `min_separation_mm` apart, from the centre outwards.

    Parameters
    ----------
    rest_positions : (N, 2) ndarray
        Pin positions (x, y) in the rest frame, px.
    n_pins : int
        How many pins to select (paper: 40).
    min_separation_mm : float
        Smallest distance between two selected pins, mm (paper: 4).
    mm_per_px : float
        Scale of the image at the pad, mm per px (e.g. pad diameter / disc diameter).
    centre : (x, y), optional
        Where the selection starts, px; the mean of the rest positions by default.

    Returns
    -------
    indices : (n_pins,) ndarray of int
        Indices into `rest_positions`, in selection order (nearest the centre first).

    Raises
    ------
    PinsError
        Fewer than `n_pins` pins can be that far apart.

    Examples
    --------
    >>> chosen = select_pins(rest, n_pins=40, min_separation_mm=4.0, mm_per_px=0.096)   # doctest: +SKIP
    >>> features_pins = rest[chosen]                                                   # doctest: +SKIP
    """
    rest = np.asarray(rest_positions, dtype=np.float64)
    if rest.ndim != 2 or rest.shape[1] != 2:
        raise ShapeError(f"rest_positions must have shape (N, 2), got {rest.shape}")
    if not np.isfinite(rest).all():
        raise PinsError("rest_positions must be finite: select pins from a rest frame where every pin was found")
    if int(n_pins) != n_pins or n_pins < 1:
        raise ValueError(f"n_pins must be a positive integer, got {n_pins}")
    if not min_separation_mm >= 0:
        raise ValueError(f"min_separation_mm must be >= 0, got {min_separation_mm}")
    if not mm_per_px > 0:
        raise ValueError(f"mm_per_px must be > 0, got {mm_per_px}")
    middle = rest.mean(axis=0) if centre is None else np.asarray(centre, dtype=np.float64)
    offset = rest - middle
    # Nearest the centre first; ties (symmetric layouts) broken by angle, then index: deterministic.
    order = np.lexsort((np.arctan2(offset[:, 1], offset[:, 0]), np.round(np.hypot(*offset.T), 6)))
    separation_px = min_separation_mm / mm_per_px
    # Pairs closer than the separation (a hair less, so that exactly-min spacing is allowed).
    too_close = cKDTree(rest).query_ball_point(rest, r=separation_px * (1 - 1e-9))
    blocked = np.zeros(len(rest), dtype=bool)
    chosen: list[int] = []
    for index in order:
        if blocked[index]:
            continue
        chosen.append(int(index))
        if len(chosen) == n_pins:
            break
        blocked[too_close[index]] = True
    if len(chosen) < n_pins:
        raise PinsError(f"only {len(chosen)} of {len(rest)} pins are at least {min_separation_mm:g} mm apart; "
                        f"lower n_pins ({n_pins}) or min_separation_mm")
    return np.array(chosen, dtype=np.intp)


def median_spacing_px(points: np.ndarray) -> float:
    """Median distance from each pin to its nearest neighbour, px (NaN with fewer than 2 pins).

    Parameters
    ----------
    points : (N, 2) ndarray
        Pin positions (x, y), px.
    """
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 2:
        raise ShapeError(f"points must have shape (N, 2), got {points.shape}")
    if len(points) < 2:
        return float("nan")
    distance, _ = cKDTree(points).query(points, k=2)
    return float(np.median(distance[:, 1]))
