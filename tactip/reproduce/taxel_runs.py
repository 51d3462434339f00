"""Paper 000 Figs 7, 8B, 10 and 11 on the simulated fingertip: the runs only these figures need.

The fingertip of `tactip.reproduce.p000` (3000 taps over 30 mm against an 8 mm rod, a training and
a test collection, `tactip.taxel.simulate_taxel_dataset`), histogram models at a few class counts,
Monte Carlo runs (`perception.monte_carlo`) from random locations, beliefs shifted with the uniform
fill of eq. 8, active perception fixating at 15 mm (the centre of the range, as the paper):

- Fig. 7 (`trajectory_rows`): example trajectories, passive and active, at theta 0.95 (30 classes):
  the location of each of the first runs at every tap up to its decision;
- Fig. 8B (`decision_time_rows`): histograms of decision times at several thresholds (passive, 30
  classes);
- Fig. 10 (`location_rows`): passive mean error and decision time against the sensor location, one
  curve per threshold (30 classes);
- Fig. 11 (`threshold_rows`): passive and active mean error and decision time against the threshold,
  per class count (C: error against decision time, from the same rows).

The paper's thresholds run from 0 to 0.999; runs are capped at `MAX_TAPS` taps (a run still
undecided is decided there and counted in ``forced``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["THRESHOLDS", "FIG8B_THRESHOLDS", "FIG11_CLASSES", "QUICK_FIG11_CLASSES", "MAX_TAPS", "fingertip_collections",
           "trajectory_rows", "decision_time_rows", "location_rows", "threshold_rows", "taxel_figure_rows"]

#: Belief thresholds of Figs 10 and 11 (the paper: 0-0.999).
THRESHOLDS = (0.0, 0.2, 0.4, 0.6, 0.8, 0.9, 0.95, 0.99, 0.999)
#: Thresholds of the decision-time histograms of Fig. 8B.
FIG8B_THRESHOLDS = (0.2, 0.6, 0.9, 0.99, 0.999)
#: Class counts of Fig. 11 (the paper shades 10-300).
FIG11_CLASSES = (10, 30, 100, 300)
QUICK_FIG11_CLASSES = (30, 300)
#: Class count of Figs 7, 8B and 10.
CLASSES = 30
#: Fig. 7: threshold and number of example trajectories per policy.
FIG7_THRESHOLD = 0.95
FIG7_RUNS = 100
#: Taps at which an undecided run is decided all the same.
MAX_TAPS = 50
FIXATION_MM = 15.0


def fingertip_collections(*, seed: int):
    """The training and test collections of paper 000's fingertip (as `tactip.reproduce.p000`)."""
    from tactip.reproduce.p000 import SENSORS
    from tactip.taxel import TaxelSimulator, simulate_taxel_dataset, sweep_locations

    simulator = TaxelSimulator("fingertip", seed=seed)
    where = sweep_locations(simulator.sensor, SENSORS["fingertip"]["taps"])
    return (simulate_taxel_dataset(simulator, where, seed=(seed, 2), collection="train"),
            simulate_taxel_dataset(simulator, where, seed=(seed, 3), collection="test"))


def _environment(train, test, classes: int):
    from perception import VirtualEnvironment, fit_model

    return VirtualEnvironment(fit_model(train, n_locations=int(classes)), test)


def _policies(env):
    from perception import FixationPolicy, StationaryPolicy

    return {"passive": StationaryPolicy(), "active": FixationPolicy(int(env.model.location_class(FIXATION_MM)))}


def _monte_carlo(env, policy, thresholds, runs: int, seed: int, max_taps: int = MAX_TAPS):
    from perception import monte_carlo

    return monte_carlo(env, policy, thresholds=thresholds, runs=runs, seed=seed, max_taps=max_taps, shift_mode="uniform")


def trajectory_rows(env, *, runs: int = FIG7_RUNS, threshold: float = FIG7_THRESHOLD, seed: int) -> list[dict]:
    """Fig. 7: ``{policy, run, tap, location_mm, decided}`` for every tap of the first ``runs`` runs.

    A run's location at tap t is the true location at the decision of the same runs capped at t
    taps: the runs draw the same random numbers tap by tap whatever the cap, so the capped runs are
    the uncapped ones cut at tap t (`perception.monte_carlo`). ``decided`` marks the decision tap.
    """
    rows = []
    for name, policy in _policies(env).items():
        full = _monte_carlo(env, policy, [threshold], runs, seed)
        taps = full.taps_runs[0]
        centres = env.model.location_centres
        for t in range(1, int(taps.max()) + 1):
            where = _monte_carlo(env, policy, [threshold], runs, seed, max_taps=t).final_location[0]
            rows += [{"policy": name, "run": r, "tap": t, "location_mm": float(centres[where[r]]),
                      "decided": bool(taps[r] == t)} for r in np.flatnonzero(taps >= t)]
    return rows


def decision_time_rows(env, *, thresholds=FIG8B_THRESHOLDS, runs: int, seed: int) -> list[dict]:
    """Fig. 8B: ``{threshold, taps, runs}``: how many passive runs decided after each number of taps."""
    result = _monte_carlo(env, _policies(env)["passive"], thresholds, runs, seed)
    rows = []
    for t, taps in zip(result.thresholds, result.taps_runs):
        counts = np.bincount(taps, minlength=MAX_TAPS + 1)
        rows += [{"threshold": float(t), "taps": n, "runs": int(counts[n])} for n in range(1, MAX_TAPS + 1)]
    return rows


def location_rows(env, *, thresholds=THRESHOLDS, runs: int, seed: int) -> list[dict]:
    """Fig. 10: ``{threshold, location_mm, error_mm, decision_taps}``: passive runs by their (fixed) location class."""
    result = _monte_carlo(env, _policies(env)["passive"], thresholds, runs, seed)
    centres = env.model.location_centres
    return [{"threshold": float(t), "location_mm": float(centres[l]), "error_mm": float(result.location_error_map[k, l, 0]),
             "decision_taps": float(result.taps_map[k, l, 0])}
            for k, t in enumerate(result.thresholds) for l in range(env.model.n_locations)]


def threshold_rows(train, test, *, class_counts, thresholds=THRESHOLDS, runs: int, seed: int,
                   progress=None) -> list[dict]:
    """Fig. 11: ``{policy, classes, threshold, error_mm, mean_taps, forced}`` over all starting locations."""
    rows = []
    for classes in (progress or (lambda x: x))(list(class_counts)):
        env = _environment(train, test, classes)
        for name, policy in _policies(env).items():
            result = _monte_carlo(env, policy, thresholds, runs, seed)
            rows += [{"policy": name, "classes": int(classes), "threshold": float(t),
                      "error_mm": float(result.mean_location_error[k]), "mean_taps": float(result.mean_taps[k]),
                      "forced": float(result.forced[k])} for k, t in enumerate(result.thresholds)]
    return rows


def taxel_figure_rows(*, quick: bool, seed: int, progress=None) -> dict:
    """The rows of 000 Figs 7, 8B, 10 and 11 (figure name -> rows), on the fingertip of ``seed``."""
    train, test = fingertip_collections(seed=seed)
    env = _environment(train, test, CLASSES)
    runs = 1000 if quick else 10000           # the paper: 10000 trials per threshold
    return {"fig7": trajectory_rows(env, seed=seed + 1),
            "fig8b": decision_time_rows(env, runs=runs, seed=seed + 1),
            "fig10": location_rows(env, runs=runs, seed=seed + 1),
            "fig11": threshold_rows(train, test, class_counts=QUICK_FIG11_CLASSES if quick else FIG11_CLASSES,
                                    runs=runs, seed=seed + 1, progress=progress)}
