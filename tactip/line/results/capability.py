"""Process capability of a gap from its stored width estimates: Cp and Cpk.

With the specification limits LSL = nominal - tolerance and USL = nominal + tolerance (mm), the
sample mean mu and sample standard deviation sigma (ddof 1) of the estimated widths:

    Cp  = (USL - LSL) / (6 sigma)
    Cpk = min(USL - mu, mu - LSL) / (3 sigma)

Cp says how wide the spread is against the tolerance band; Cpk also charges the offset of the mean
from the nominal. 1.33 is the usual bar for a capable process.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

__all__ = ["Capability", "process_capability"]


@dataclass(frozen=True)
class Capability:
    """Cp and Cpk of ``n`` width estimates (mm) against ``nominal`` +- ``tolerance`` (mm).

    ``cp`` and ``cpk`` are None when they are undefined: fewer than two estimates, or no spread.
    """

    n: int
    mean_mm: float | None
    sigma_mm: float | None
    cp: float | None
    cpk: float | None
    nominal_mm: float
    tolerance_mm: float

    def as_dict(self) -> dict:
        """JSON-ready fields."""
        return dict(n=self.n, mean_mm=self.mean_mm, sigma_mm=self.sigma_mm, cp=self.cp, cpk=self.cpk,
                    nominal_mm=self.nominal_mm, tolerance_mm=self.tolerance_mm)


def process_capability(widths_mm: Sequence[float], *, nominal_mm: float, tolerance_mm: float) -> Capability:
    """Cp and Cpk of the estimated widths of one gap (see the module docstring).

    Parameters
    ----------
    widths_mm : (N,) array_like of float
        Estimated widths of the gap's decided inspections, mm.
    nominal_mm, tolerance_mm : float
        Nominal width and its tolerance (> 0), mm: the specification is nominal +- tolerance.

    Returns
    -------
    Capability

    Examples
    --------
    >>> c = process_capability([0.9, 1.0, 1.1], nominal_mm=1.0, tolerance_mm=0.3)
    >>> round(c.cp, 3), round(c.cpk, 3)
    (1.0, 1.0)
    """
    if not tolerance_mm > 0:
        raise ValueError(f"tolerance_mm must be > 0, got {tolerance_mm!r}")
    widths = np.asarray(widths_mm, dtype=float).ravel()
    widths = widths[np.isfinite(widths)]
    n = int(widths.size)
    if n == 0:
        return Capability(0, None, None, None, None, float(nominal_mm), float(tolerance_mm))
    mean = float(widths.mean())
    if n < 2:
        return Capability(n, mean, None, None, None, float(nominal_mm), float(tolerance_mm))
    sigma = float(widths.std(ddof=1))
    if sigma <= 0:
        return Capability(n, mean, 0.0, None, None, float(nominal_mm), float(tolerance_mm))
    usl, lsl = nominal_mm + tolerance_mm, nominal_mm - tolerance_mm
    # Cp = (USL - LSL) / 6 sigma;  Cpk = min(USL - mu, mu - LSL) / 3 sigma
    cp = (usl - lsl) / (6.0 * sigma)
    cpk = min(usl - mean, mean - lsl) / (3.0 * sigma)
    return Capability(n, mean, sigma, float(cp), float(cpk), float(nominal_mm), float(tolerance_mm))
