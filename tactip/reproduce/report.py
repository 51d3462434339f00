"""What a reproduction returns: rows for JSON and measured figures beside the paper's."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from perception import Dataset, VirtualEnvironment, fit_model

__all__ = ["Comparison", "Report", "collections", "environment", "identity"]


def identity(iterable):
    """No progress display."""
    return iterable


@dataclass(frozen=True)
class Comparison:
    """One figure of the paper: the measured value beside the paper's.

    Attributes
    ----------
    figure : str
        What is compared (paper's figure and condition).
    measured : float
    paper : float or None
        The paper's number (None where the paper gives a trend, not a number).
    unit : str
    fit : bool
        The world was tuned against this figure (`tactip.reproduce.fits`): it reproduces it by
        construction, so it is not a prediction.
    """

    figure: str
    measured: float
    paper: float | None
    unit: str = ""
    fit: bool = False

    def line(self) -> str:
        """One printed line (a fitted figure ends with '(fit)')."""
        paper = "trend" if self.paper is None else f"{self.paper:g}"
        return f"  {self.figure:<58} {self.measured:8.3g}  paper {paper:>6} {self.unit}{' (fit)' if self.fit else ''}".rstrip()


@dataclass(frozen=True)
class Report:
    """A paper's experiment on the simulator.

    Attributes
    ----------
    paper : str
    title : str
    rows : list of dict
        JSON-ready, one per condition.
    comparisons : list of Comparison
    notes : list of str
        What was tuned, what is a prediction, departures from the paper.
    samples : dict of str -> object
        Per-run or per-class samples that only figures draw (distributions, maps, traced contours;
        `tactip.reproduce.figure_samples`), by figure name. Not written to the JSON, whose fields
        stay the rows'.
    """

    paper: str
    title: str
    rows: list[dict]
    comparisons: list[Comparison] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    samples: dict = field(default_factory=dict, repr=False, compare=False)

    def text(self) -> str:
        """The printed report."""
        lines = [f"paper {self.paper}: {self.title}"]
        lines += [c.line() for c in self.comparisons]
        lines += [f"  note: {n}" for n in self.notes]
        return "\n".join(lines)

    def json_rows(self) -> list[dict]:
        """Rows with NaN as None (strict JSON)."""
        def clean(v):
            if isinstance(v, (float, np.floating)):
                return None if math.isnan(v) else float(v)
            if isinstance(v, np.integer):
                return int(v)
            return v
        return [{k: clean(v) for k, v in row.items()} for row in self.rows]


def collections(stimulus, *, seed: int, taps_per_identity: int) -> tuple[Dataset, Dataset]:
    """A training and a test session of a stimulus on the simulated fingertip (`simulate_stimulus_dataset`)."""
    from tactip.taxel.collect import simulate_stimulus_dataset

    return tuple(simulate_stimulus_dataset(stimulus, seed=seed, collection=name, taps_per_identity=taps_per_identity)
                 for name in ("train", "test"))


def environment(stimulus, *, seed: int, taps_per_identity: int, n_locations: int) -> VirtualEnvironment:
    """Train a histogram model on one simulated session of a stimulus and test on another.

    Returns
    -------
    VirtualEnvironment
    """
    train, test = collections(stimulus, seed=seed, taps_per_identity=taps_per_identity)
    return VirtualEnvironment(fit_model(train, n_locations=n_locations), test)
