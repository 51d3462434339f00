"""Paper 001 on the simulated fingertip: rod shape and position, 'boredom' deadline (Figs 4-7).

Five rods (4-12 mm, `tactip.reproduce.stimuli.Rods`), a 16 mm sweep of 320 taps per rod in each of
two sessions (training, test), 16 position classes of 1 mm x 5 shape classes = 80 joint classes,
a histogram model (100 bins). Monte Carlo as in the paper, at the paper's thresholds (0.05 up to
0.99999): passive perception from a random (shape, position) class, the joint stop rule (eq. 3),
and with a deadline D (eq. 4) a null decision that discards the evidence and moves the finger to a
position drawn uniformly over the range; reaction times count the taps before the null decisions.
Neither has a cap on the taps (the paper has none):

- fixed perception (no deadline) runs `perception.monte_carlo` with ``max_taps=None``;
- with a deadline, a run is a sequence of independent attempts (each starts from the flat prior at a
  uniformly drawn position, on the run's rod), so its decision is the decision of an attempt that
  reaches the threshold, and its reaction time is ``D (1 - p) / p`` taps of null attempts plus the
  taps of the deciding one, ``p`` the rod's chance that an attempt decides. `deadline_runs` measures
  each rod's attempts (``perception.monte_carlo`` capped at D taps) and composes the runs from them:
  the same expectations as the direct Monte Carlo with ``deadline=D`` (tests compare the two), with
  no cap. A rod none of whose attempts decides never decides: its runs are counted in
  ``forced_fraction``, the reaction time is infinite (None) and so are the means over all runs
  (the errors are None; the report gives the errors of the runs that decide beside them).

Tuned: the session-to-session differences of the rods (`Rods` docstring) against the fixed-
position errors (Fig. 4 black: ~2.2 mm shape, ~0.6 mm position at theta >= 0.9). Predictions:
everything with a deadline.

The simulated rods give little evidence per tap: fixed perception needs ~44 taps to reach 0.99 (and
~30 without any session difference), where the paper's errors reach their minimum within 5-10
taps. A 5-tap attempt must raise one of 80 beliefs from 1/80 to 0.99 (about 9 nats); in this world
most rods never get there (seed 0: the 4, 6 and 10 mm rods decide in none of thousands of attempts
at theta 0.99), so at the paper's highest thresholds deadline 5 leaves runs that never decide.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from _shared import map_pieces
from perception import StationaryPolicy, monte_carlo

from tactip.reproduce.report import Comparison, Report, environment

__all__ = ["THRESHOLDS", "QUICK_THRESHOLDS", "DEADLINES", "DeadlineRuns", "deadline_runs", "run"]

#: Belief thresholds of Figs 4-7 (0.05 to 0.99999), for every deadline.
THRESHOLDS = (0.05, 0.2, 0.5, 0.7, 0.8, 0.9, 0.99, 0.999, 0.9999, 0.99999)
QUICK_THRESHOLDS = (0.2, 0.5, 0.7, 0.9, 0.99)
#: Deadlines D of Figs 4-7 (None: fixed perception, no deadline).
DEADLINES = (None, 5, 10)


@dataclass(frozen=True)
class DeadlineRuns:
    """Runs with a deadline composed from independent attempts (arrays over K thresholds).

    Attributes
    ----------
    thresholds : (K,) ndarray
    decide_chance : (K, I) ndarray
        Chance that an attempt on each rod (identity class) reaches the threshold within D taps.
    shape_error_mm, position_error_mm : (K,) ndarray
        Mean errors over all runs (rods drawn uniformly); NaN where some rod never decides.
    decided_shape_error_mm, decided_position_error_mm : (K,) ndarray
        The same over the runs that decide (the rods with ``decide_chance > 0``).
    reaction_taps : (K,) ndarray
        Mean taps to a decision, null attempts included; inf where some rod never decides.
    null_fraction : (K,) ndarray
        Null decisions / attempts (paper 001 Fig. 6); 1 where some rod never decides.
    forced_fraction : (K,) ndarray
        Fraction of runs that never decide (their rod's ``decide_chance`` is 0).
    attempts : int
        Attempts measured per rod.
    """

    thresholds: np.ndarray
    decide_chance: np.ndarray
    shape_error_mm: np.ndarray
    position_error_mm: np.ndarray
    decided_shape_error_mm: np.ndarray
    decided_position_error_mm: np.ndarray
    reaction_taps: np.ndarray
    null_fraction: np.ndarray
    forced_fraction: np.ndarray
    attempts: int


def deadline_runs(env, deadline: int, *, thresholds, attempts: int, seed) -> DeadlineRuns:
    """Paper 001's runs with a 'boredom' deadline, composed from each rod's attempts (no cap on the taps).

    Parameters
    ----------
    env : perception.VirtualEnvironment
    deadline : int
        Taps per attempt, D.
    thresholds : sequence of float
        Joint-class decision thresholds (eq. 3).
    attempts : int
        Attempts measured per rod (each from a uniformly drawn position class).
    seed : int or sequence of int
        Seed of the attempts.

    Returns
    -------
    DeadlineRuns
    """
    thresholds = np.asarray(thresholds, dtype=np.float64)
    n_id, n_loc = env.model.n_identities, env.model.n_locations
    rng = np.random.default_rng(seed)
    chance, shape, position, taps = (np.zeros((len(thresholds), n_id)) for _ in range(4))
    for rod in range(n_id):
        result = monte_carlo(env, StationaryPolicy(), thresholds=thresholds, runs=attempts, seed=rng,
                             max_taps=deadline, decision_rule="joint", shift_mode="uniform",
                             start_location=rng.integers(0, n_loc, attempts), true_identity=np.full(attempts, rod))
        chance[:, rod] = 1.0 - result.forced
        shape[:, rod] = result.decided_identity_error
        position[:, rod] = result.decided_location_error
        with np.errstate(invalid="ignore", divide="ignore"):   # taps of the deciding attempt
            taps[:, rod] = (result.mean_taps - result.forced * deadline) / chance[:, rod]
    decides = chance > 0
    with np.errstate(invalid="ignore", divide="ignore"):
        nulls = np.where(decides, (1.0 - chance) / chance, np.inf).mean(axis=1)        # (K,) null attempts per run
        reaction = np.where(decides, deadline * (1.0 - chance) / chance + taps, np.inf).mean(axis=1)
        decided_shape = np.where(decides, shape, 0).sum(axis=1) / decides.sum(axis=1)
        decided_position = np.where(decides, position, 0).sum(axis=1) / decides.sum(axis=1)
    every = decides.all(axis=1)
    with np.errstate(invalid="ignore"):
        null_fraction = np.where(np.isfinite(nulls), nulls / (nulls + 1.0), 1.0)
    return DeadlineRuns(
        thresholds=thresholds, decide_chance=chance,
        shape_error_mm=np.where(every, decided_shape, np.nan), position_error_mm=np.where(every, decided_position, np.nan),
        decided_shape_error_mm=decided_shape, decided_position_error_mm=decided_position, reaction_taps=reaction,
        null_fraction=null_fraction,
        forced_fraction=1.0 - decides.mean(axis=1), attempts=int(attempts))


def _deadline_run(deadline, *, env, thresholds, runs: int, seed: int):
    """The runs with one deadline (None: fixed position), a piece of `run` (module level: it travels to a worker).

    Returns the rows and, with a deadline, its `DeadlineRuns`; without, the samples of Figs 7A and 8
    (`tactip.reproduce.figure_samples.p001_samples`).
    """
    from tactip.reproduce.figure_samples import p001_samples

    if deadline is None:
        result = monte_carlo(env, StationaryPolicy(), thresholds=thresholds, runs=runs, seed=seed + 1, max_taps=None,
                             decision_rule="joint", shift_mode="uniform")
        return [{"deadline": None, "threshold": float(t), "shape_error_mm": float(result.decided_identity_error[k]),
                 "position_error_mm": float(result.decided_location_error[k]),
                 "reaction_taps": float(result.mean_taps[k]), "null_fraction": 0.0,
                 "forced_fraction": float(result.forced[k])} for k, t in enumerate(result.thresholds)], \
            p001_samples(result, env.model)
    runs_d = deadline_runs(env, deadline, thresholds=thresholds, attempts=runs, seed=(seed, 1, deadline))
    return [{"deadline": deadline, "threshold": float(t), "shape_error_mm": float(runs_d.shape_error_mm[k]),
             "position_error_mm": float(runs_d.position_error_mm[k]), "reaction_taps": float(runs_d.reaction_taps[k]),
             "null_fraction": float(runs_d.null_fraction[k]), "forced_fraction": float(runs_d.forced_fraction[k])}
            for k, t in enumerate(runs_d.thresholds)], runs_d


def run(*, quick: bool = False, seed: int = 0, progress=None, map_fn=None) -> Report:
    """The experiment of paper 001; rows per deadline and threshold (see the module docstring)."""
    from tactip.reproduce.stimuli import make_stimulus

    env = environment(make_stimulus("rods"), seed=seed, taps_per_identity=320, n_locations=16)
    thresholds = QUICK_THRESHOLDS if quick else THRESHOLDS
    runs = 400 if quick else 2500
    attempts = 2000 if quick else 10000
    pieces = map_pieces(functools.partial(_deadline_run, env=env, thresholds=thresholds,
                                          runs=runs, seed=seed), list(DEADLINES), map_fn=map_fn, progress=progress)
    rows = [row for piece, _ in pieces for row in piece]
    for row in rows:    # strict JSON: an infinite reaction time is None, as NaN is
        if not np.isfinite(row["reaction_taps"]):
            row["reaction_taps"] = float("nan")
    fixed = [r for r in rows if r["deadline"] is None]
    short = pieces[1][1]
    top = len(thresholds) - 1
    comparisons = [
        Comparison(f"Fig. 4 fixed, theta {thresholds[top]:g}: shape error", fixed[top]["shape_error_mm"], 2.2, "mm"),
        Comparison(f"Fig. 4 fixed, theta {thresholds[top]:g}: position error", fixed[top]["position_error_mm"], 0.6,
                   "mm"),
        Comparison(f"Fig. 4 deadline 5, theta {thresholds[top]:g}: shape error", short.shape_error_mm[top], 1.4, "mm"),
        Comparison(f"Fig. 4 deadline 5, theta {thresholds[top]:g}: position error", short.position_error_mm[top],
                   0.1, "mm"),
        Comparison(f"Fig. 4 deadline 5, theta {thresholds[top]:g}: runs that never decide",
                   short.forced_fraction[top], None, "fraction"),
        Comparison("  the same, over the runs that decide: shape error", short.decided_shape_error_mm[top], None, "mm"),
        Comparison("  the same, over the runs that decide: position error", short.decided_position_error_mm[top],
                   None, "mm"),
    ]
    # Fig. 5: errors at matched mean reaction time (the fixed curve interpolated at deadline 5's times)
    fixed_taps = [r["reaction_taps"] for r in fixed]
    for k in range(len(thresholds)):
        taps = short.reaction_taps[k]
        if short.null_fraction[k] > 0.1 and np.isfinite(taps) and fixed_taps[0] <= taps <= fixed_taps[-1]:
            for name, error, key in (("shape", short.shape_error_mm, "shape_error_mm"),
                                     ("position", short.position_error_mm, "position_error_mm")):
                matched = np.interp(taps, fixed_taps, [r[key] for r in fixed])
                comparisons.append(Comparison(f"Fig. 5 at {taps:.1f} taps: {name} error D=5 / fixed",
                                              error[k] / matched, None, "ratio"))
    comparisons += [Comparison(f"Fig. 6 null fraction, D={d}, theta {thresholds[top]:g}",
                               pieces[i][1].null_fraction[top], None) for i, d in ((1, 5), (2, 10))]
    notes = [f"{runs} fixed runs per threshold, {attempts} attempts per rod and deadline; simulated sensor seed {seed}; "
             "joint stop rule (eq. 3); no cap on the taps.",
             "deadline runs are composed from independent attempts (a null decision restarts from the flat prior at a "
             "uniform position); a rod none of whose attempts decides never decides: forced_fraction counts its runs "
             "and the means over all runs (errors, reaction taps) are then undefined (null in JSON).",
             "tuned: rod session differences against Fig. 4 black (fixed position); deadline rows are predictions.",
             "the simulated rods give ~0.15 nats of evidence per tap (fixed perception: ~44 taps to theta 0.99, paper: "
             "minimum errors within 5-10 taps), so a 5-tap attempt rarely reaches theta >= 0.9 and for most rods never "
             "reaches 0.99: the world, not the deadline, is what fails the paper's comparison at its highest thresholds."]
    return Report("001", "embodied hyperacuity: rod shape x position, deadline and random relocation", rows,
                  comparisons, notes, samples=pieces[0][1])
