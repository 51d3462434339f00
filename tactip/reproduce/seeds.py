"""Each paper's headline claim judged over many seeds, from an interval and never from one seed.

A claim is a function of one run's rows (`Report.rows`) that gives its *margin*: how far the
simulated world is on the claim's side (> 0: the claim holds on that run; exactly 0 holds too for a
claim of "no larger than", `TIES_HOLD`), in the unit the claim names. Over N seeds, `judge_claim` takes the margins' mean and its 95 % interval (Student t), and says

- **holds** when there are at least two seeds, the whole interval lies above 0 and every seed's
  margin is above 0 (for a `TIES_HOLD` claim: at or above 0);
- **partly holds** when the mean is above 0 but the interval reaches 0 or a seed fails;
- **fails** when the mean is below 0, or at 0 for a claim that 0 does not satisfy.

Claims (the issue's bars for paper comparisons):

- 000: active perception's localisation error is no larger than passive's at every class count
  (the skin's Table III, fixated at the paper's 37 mm; the margin is the smallest passive - active, mm);
- 001: with a deadline of 5 taps the position error is lower and the shape error at most 5 % higher
  than without one, at every threshold >= 0.99 (the smallest of the relative margins; where some
  deadline runs never decide, minus the fraction that never decides);
- 002: width error at 10 mean taps, active < random < stationary (the smaller gap, mm); active is Fig. 9's
  active row, fixated where the paper fixated (the Fig. 10 sweep's best on the test collection); the
  station's own fixation, chosen on held-out training taps, is judged beside it as a variant (`VARIANTS`);
- 003: strongly active <= half of passive and weakly active < passive (the smaller margin, classes);
- 004: at threshold 0.5, the adaptive prior's angle error <= 0.9 x active's, with the contour closed
  in at least half of the adaptive runs (the angle margin, deg; negative when the contour is open).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from perception.choices import POLICIES

__all__ = ["CLAIMS", "TIES_HOLD", "VARIANTS", "ClaimVerdict", "judge_claim", "claim_margin"]


def _000(rows) -> float:
    skin = {(r["classes"], r["policy"]): r["error_mm"] for r in rows if r["sensor"] == "skin"}
    return min(skin[n, "passive"] - skin[n, "active"] for n, policy in skin if policy == "passive")


def _001(rows) -> float:
    margins = []
    for top in sorted({r["threshold"] for r in rows if r["threshold"] >= 0.99}):
        at = {r["deadline"]: r for r in rows if r["threshold"] == top}
        none, five = at[None], at[5]
        if five["shape_error_mm"] is None or not np.isfinite(five["shape_error_mm"]):
            margins.append(-max(five["forced_fraction"], 1e-9))     # runs that never decide: no comparison
            continue
        position = (none["position_error_mm"] - five["position_error_mm"]) / none["position_error_mm"]
        shape = 0.05 - (five["shape_error_mm"] - none["shape_error_mm"]) / none["shape_error_mm"]
        margins.append(min(position, shape))
    return min(margins)


def _002(rows) -> float:
    at_10 = {}
    for policy in POLICIES:
        mine = sorted((r for r in rows if r["policy"] == policy), key=lambda r: r["mean_taps"])
        at_10[policy] = float(np.interp(10.0, [r["mean_taps"] for r in mine], [r["width_error_mm"] for r in mine]))
    return min(at_10["random"] - at_10["active"], at_10["stationary"] - at_10["random"])


def _002_station_fixation(rows) -> list[dict]:
    """002's rows with the variant (active perception at the station's own fixation) read as the active policy."""
    from tactip.reproduce.p002 import STATION_FIXATION

    return [dict(r, policy="active") if r["policy"] == STATION_FIXATION else r for r in rows if r["policy"] != "active"]


def _003(rows) -> float:
    error = {move: np.mean([r["texture_error_classes"] for r in rows if r["move_threshold"] == move])
             for move in (1.5, 0.999, 0.05)}
    return float(min(0.5 * error[1.5] - error[0.05], error[1.5] - error[0.999]))


def _004(rows) -> float:
    at = {r["method"]: r for r in rows if r["threshold"] == 0.5}
    margin = 0.9 * at["active"]["angle_error_deg"] - at["adaptive"]["angle_error_deg"]
    return margin if at["adaptive"]["closed_contour"] >= 0.5 else -abs(margin) - 1e-9


#: The headline claim of each paper: (what it says, margin unit, margin of one run's rows).
CLAIMS: dict[str, tuple[str, str, Callable]] = {
    "000": ("skin (Table III): active error <= passive error at every class count", "mm", _000),
    "001": ("theta >= 0.99: deadline 5 lowers the position error, shape error at most 5 % higher",
            "fraction", _001),
    "002": ("width error at 10 taps: active < random < stationary", "mm", _002),
    "003": ("strongly active <= half of passive, weakly active < passive", "classes", _003),
    "004": ("threshold 0.5: adaptive angle error <= 0.9 x active, contour closed", "deg", _004),
}


#: Variants judged beside a paper's claim, never instead of it: paper -> ((name, rows -> the rows the claim
#: then reads), ...). 002: active perception at the fixation the station chose on its held-out training taps.
VARIANTS: dict[str, tuple[tuple[str, Callable], ...]] = {
    "002": (("active (fixation from training taps)", _002_station_fixation),),
}


#: Claims of "no larger than" (000: active <= passive; 004: adaptive <= 0.9 x active), which a margin of
#: exactly 0 satisfies. The others hold only above 0: 001 and 002 say "lowers" and "<", and 003's
#: margin is the smaller of a "<=" and a "<".
TIES_HOLD = frozenset({"000", "004"})


def claim_margin(paper: str, rows: list[dict]) -> float:
    """The margin by which one run's rows are on the side of ``paper``'s claim (> 0: it holds)."""
    if paper not in CLAIMS:
        raise ValueError(f"no claim for paper {paper!r}; choose from {', '.join(CLAIMS)}")
    return float(CLAIMS[paper][2](rows))


@dataclass(frozen=True)
class ClaimVerdict:
    """A claim judged over seeds.

    Attributes
    ----------
    paper, claim, unit : str
    seeds : tuple of int
    margins : (N,) ndarray
        Each seed's margin (> 0: the claim holds on that seed; 0 too where ``ties_hold``).
    mean : float
    interval : (float, float)
        95 % interval of the mean margin (Student t; the single value for one seed).
    verdict : {"holds", "partly holds", "fails"}
    ties_hold : bool
        Whether a margin of exactly 0 satisfies the claim (`TIES_HOLD`).
    """

    paper: str
    claim: str
    unit: str
    seeds: tuple
    margins: np.ndarray
    mean: float
    interval: tuple
    verdict: str
    ties_hold: bool = False

    def held(self) -> np.ndarray:
        """(N,) bool: the seeds on which the claim holds."""
        return self.margins >= 0 if self.ties_hold else self.margins > 0

    def line(self) -> str:
        """One printed line."""
        held = int(self.held().sum())
        return (f"  claim: {self.claim}: {self.verdict} (margin {self.mean:.3g} {self.unit}, 95 % interval "
                f"{self.interval[0]:.3g} to {self.interval[1]:.3g}; held on {held} of {len(self.margins)} seeds)")

    def json(self) -> dict:
        """JSON-ready fields."""
        return {"paper": self.paper, "claim": self.claim, "unit": self.unit, "seeds": list(self.seeds),
                "margins": [float(m) for m in self.margins], "mean": self.mean, "interval": list(self.interval),
                "verdict": self.verdict}


def judge_claim(paper: str, rows_per_seed: dict[int, list[dict]]) -> ClaimVerdict:
    """Judge ``paper``'s claim from the rows of one run per seed.

    Parameters
    ----------
    paper : str
    rows_per_seed : dict of int -> list of dict
        Each seed's `Report.rows`.

    Returns
    -------
    ClaimVerdict
    """
    from scipy import stats

    seeds = tuple(sorted(rows_per_seed))
    if not seeds:
        raise ValueError("no seeds to judge a claim on")
    margins = np.array([claim_margin(paper, rows_per_seed[s]) for s in seeds])
    mean = float(margins.mean())
    if len(margins) > 1:
        half = float(stats.t.ppf(0.975, len(margins) - 1) * margins.std(ddof=1) / np.sqrt(len(margins)))
    else:
        half = 0.0
    interval = (mean - half, mean + half)
    ties_hold = paper in TIES_HOLD
    held = margins >= 0 if ties_hold else margins > 0
    above = (lambda value: value >= 0) if ties_hold else (lambda value: value > 0)
    if not above(mean):
        verdict = "fails"
    elif len(margins) >= 2 and above(interval[0]) and held.all():   # one seed is not a claim
        verdict = "holds"
    else:
        verdict = "partly holds"
    claim, unit, _ = CLAIMS[paper]
    return ClaimVerdict(paper, claim, unit, seeds, margins, mean, interval, verdict, ties_hold)
