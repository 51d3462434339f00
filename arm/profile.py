"""Trapezoidal velocity profiles of straight moves: how long a move takes and where it is meanwhile.

Both the simulated arm (to time and interpolate its moves) and the UR backend (to set its move watchdog)
use them.

Example
-------
>>> round(trapezoid_duration(30.0, 20.0, 100.0), 3)    # 30 mm at 20 mm/s, 100 mm/s^2
1.7
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["trapezoid_duration", "trapezoid_fraction"]


def trapezoid_duration(distance_mm: float, speed_mm_s: float, acceleration_mm_s2: float) -> float:
    """Duration of a straight move with a trapezoidal velocity profile, s.

    Accelerate at ``a`` up to ``v``, cruise, decelerate at ``a``; a move too short to reach ``v`` has a
    triangular profile and lasts ``2 sqrt(d / a)``.
    """
    d, v, a = float(distance_mm), float(speed_mm_s), float(acceleration_mm_s2)
    if d <= 0:
        return 0.0
    if d >= v * v / a:
        return d / v + v / a
    return 2.0 * math.sqrt(d / a)


def trapezoid_fraction(t_s, distance_mm: float, speed_mm_s: float, acceleration_mm_s2: float) -> np.ndarray:
    """Fraction of the distance covered at times ``t_s`` (array_like, s) of a trapezoidal move, in [0, 1]."""
    t = np.asarray(t_s, dtype=float)
    d, v, a = float(distance_mm), float(speed_mm_s), float(acceleration_mm_s2)
    if d <= 0:
        return np.ones_like(t)
    total = trapezoid_duration(d, v, a)
    peak = min(v, math.sqrt(d * a))          # top speed actually reached
    ramp = peak / a
    t = np.clip(t, 0.0, total)
    rising = 0.5 * a * t**2
    cruising = 0.5 * a * ramp**2 + peak * (t - ramp)
    remaining = total - t
    falling = d - 0.5 * a * remaining**2
    covered = np.where(t < ramp, rising, np.where(t <= total - ramp, cruising, falling))
    return np.clip(covered / d, 0.0, 1.0)
