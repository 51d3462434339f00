"""Paper 001 on the simulated fingertip: rod shape and position, 'boredom' deadline (Figs 4-7).

Five rods (4-12 mm, `tactip.reproduce.stimuli.Rods`), a 16 mm sweep of 320 taps per rod in each of
two sessions (training, test), 16 position classes of 1 mm x 5 shape classes = 80 joint classes,
a histogram model (100 bins). Monte Carlo as in the paper: passive perception from a random
(shape, position) class, the joint stop rule (eq. 3), and with a deadline D (eq. 4) a null
decision that discards the evidence and moves the finger to a position drawn uniformly over the
range; reaction times count the taps before the null decisions. No cap on the taps beyond
``MAX_TAPS`` (runs reaching it are reported as ``forced_fraction``, apart from the decisions).

Tuned: the session-to-session differences of the rods (`Rods` docstring) against the fixed-
position errors (Fig. 4 black: ~2.2 mm shape, ~0.6 mm position at theta >= 0.9). Predictions:
everything with a deadline.
"""

from __future__ import annotations

import functools

import numpy as np

from _shared import map_pieces
from perception import StationaryPolicy, monte_carlo

from tactip.reproduce.report import Comparison, Report, environment

__all__ = ["THRESHOLDS", "DEADLINES", "run"]

#: Belief thresholds (the paper's range starts at 0.05; with deadline 5 and theta >= 0.9 almost every
#: attempt times out on the simulated rods, see the report's notes).
THRESHOLDS = (0.05, 0.2, 0.5, 0.7, 0.8)
QUICK_THRESHOLDS = (0.2, 0.5, 0.7)
#: Fixed perception (no deadline) also at higher thresholds, to match the deadline runs' longer reaction times.
FIXED_EXTRA = (0.9, 0.99)
#: Deadlines D of Figs 4-7 (None: fixed perception, no deadline).
DEADLINES = (None, 5, 10)
MAX_TAPS = 1000


def _deadline_run(deadline, *, env, thresholds, quick: bool, runs: int, seed: int):
    """The runs with one deadline (None: fixed position), a piece of `run` (module level: it travels to a worker)."""
    levels = thresholds + (FIXED_EXTRA if deadline is None and not quick else ())
    return monte_carlo(env, StationaryPolicy(), thresholds=levels, runs=runs, seed=seed + 1, deadline=deadline,
                       max_taps=MAX_TAPS, decision_rule="joint", shift_mode="uniform")


def run(*, quick: bool = False, seed: int = 0, progress=None, map_fn=None) -> Report:
    """The experiment of paper 001; rows per deadline and threshold (see the module docstring)."""
    from tactip.reproduce.stimuli import make_stimulus

    env = environment(make_stimulus("rods"), seed=seed, taps_per_identity=320, n_locations=16)
    thresholds = QUICK_THRESHOLDS if quick else THRESHOLDS
    runs = 400 if quick else 2500
    rows, results = [], {}
    pieces = map_pieces(functools.partial(_deadline_run, env=env, thresholds=thresholds, quick=quick, runs=runs,
                                          seed=seed), list(DEADLINES), map_fn=map_fn, progress=progress)
    for deadline, result in zip(DEADLINES, pieces):
        results[deadline] = result
        for k, threshold in enumerate(result.thresholds):
            rows.append({"deadline": deadline, "threshold": float(threshold),
                         "shape_error_mm": float(result.decided_identity_error[k]),
                         "position_error_mm": float(result.decided_location_error[k]),
                         "reaction_taps": float(result.mean_taps[k]), "null_fraction": float(result.null_fraction[k]),
                         "forced_fraction": float(result.forced[k])})
    fixed, short = results[None], results[5]
    comparisons = [
        Comparison(f"Fig. 4 fixed, theta {fixed.thresholds[-1]:g}: shape error", fixed.decided_identity_error[-1],
                   2.2, "mm"),
        Comparison(f"Fig. 4 fixed, theta {fixed.thresholds[-1]:g}: position error", fixed.decided_location_error[-1],
                   0.6, "mm"),
        Comparison(f"Fig. 4 deadline 5, theta {short.thresholds[-1]:g}: shape error", short.decided_identity_error[-1],
                   1.4, "mm"),
        Comparison(f"Fig. 4 deadline 5, theta {short.thresholds[-1]:g}: position error",
                   short.decided_location_error[-1], 0.1, "mm"),
    ]
    # Fig. 5: errors at matched mean reaction time (the fixed curve interpolated at deadline 5's times)
    for k in range(len(short.thresholds)):
        taps = short.mean_taps[k]
        if short.null_fraction[k] > 0.1 and fixed.mean_taps[0] <= taps <= fixed.mean_taps[-1]:
            for name, error, paper_error in (("shape", "decided_identity_error", None),
                                             ("position", "decided_location_error", None)):
                matched = np.interp(taps, fixed.mean_taps, getattr(fixed, error))
                comparisons.append(Comparison(f"Fig. 5 at {taps:.1f} taps: {name} error D=5 / fixed",
                                              getattr(short, error)[k] / matched, paper_error, "ratio"))
    comparisons += [Comparison(f"Fig. 6 null fraction, D={d}, theta {short.thresholds[-1]:g}",
                               results[d].null_fraction[-1], None) for d in (5, 10)]
    notes = [f"{runs} runs per condition; simulated sensor seed {seed}; joint stop rule (eq. 3).",
             "tuned: rod session differences against Fig. 4 black (fixed position); deadline rows are predictions.",
             f"forced_fraction: runs still undecided after {MAX_TAPS} taps (the paper has no cap)."]
    return Report("001", "embodied hyperacuity: rod shape x position, deadline and random relocation", rows,
                  comparisons, notes)
