"""What each simulated world was tuned on: every fitted parameter beside the paper's figure it was fitted to.

A figure a parameter was tuned against is a *fit*: the world was made to reproduce it, so it tests
nothing. Every other figure of the paper is a *prediction*. `reproduce` marks the comparisons of fitted
figures (`Comparison.fit`) and lists the fits in each report's notes.

Example
-------
>>> [f.parameter for f in FITS["002"]]
['tactip.sim._pad.MEMBRANE_RHO_MM']
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

__all__ = ["Fit", "FITS", "mark_fits"]


@dataclass(frozen=True)
class Fit:
    """One parameter tuned against one of a paper's figures.

    Attributes
    ----------
    parameter : str
        Where it lives (module.name or class.attribute).
    value : str
        Its value, with units (and what it was before tuning, where known).
    figure : str
        The paper's figure it was tuned on.
    marks : tuple of str
        Beginnings of the comparison names of that figure (`Comparison.figure`).
    """

    parameter: str
    value: str
    figure: str
    marks: tuple

    def line(self) -> str:
        """One printed line."""
        return f"fit: {self.parameter} = {self.value}, tuned on {self.figure}"


#: Paper -> its world's fits.
FITS: dict[str, tuple[Fit, ...]] = {
    "000": (Fit("tactip.taxel.sim.TaxelSimulator white_noise_counts, common_noise_counts", "0.5, 0.3 counts",
                "Table II (fingertip, active error <= 0.2 mm at 300 classes on seeds 0-9)", ("Table II ",)),),
    "001": (Fit("tactip.reproduce.stimuli.Rods session_depth_mm, session_tilt, session_shift_mm",
                "0.1 mm, 0.03 mm/mm, 0.15 mm", "Fig. 4 black (fixed position: ~2.2 mm shape, ~0.6 mm position)",
                ("Fig. 4 fixed",)),),
    "002": (Fit("tactip.sim._pad.MEMBRANE_RHO_MM", "1 mm (was 8 mm)",
                "Fig. 9 (width error of active, random, stationary perception)", ("Fig. 9",)),),
    "003": (Fit("tactip.reproduce.stimuli.Textures onset_mm, saturation_mm, signature, grain_height, tap_speed_mm_s",
                "0.2 mm, 1.5 mm, 0.6, 0.3, 8 mm/s",
                "Figs 5 and 6B (passive perception at one depth and over depth)", ("Fig. 5", "Fig. 6B")),),
    "004": (Fit("tactip.reproduce.stimuli.Edge pad_radius_mm, ridge, edge_mm, ridge_mm", "6 mm, 1.0, 0.25 mm, 0.5 mm",
                "passive perception and the active single-decision angle error (~4 deg, Fig. 7A active)",
                ("Fig. 7A active",)),),
}


def mark_fits(report):
    """``report`` with its fitted comparisons marked and its fits listed in the notes.

    Parameters
    ----------
    report : tactip.reproduce.Report

    Returns
    -------
    Report
    """
    fits = FITS.get(report.paper, ())
    marks = tuple(m for f in fits for m in f.marks)
    comparisons = [dataclasses.replace(c, fit=True) if c.figure.startswith(marks) else c for c in report.comparisons]
    return dataclasses.replace(report, comparisons=comparisons, notes=list(report.notes) + [f.line() for f in fits])
