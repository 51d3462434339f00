"""Paper 003 on the simulated fingertip: texture under depth uncertainty, passive and active (Figs 5-7).

Ten abrasive papers (`tactip.reproduce.stimuli.Textures`), 150 taps per texture over 0-3 mm of depth
in each of two sessions, 15 depth classes of 0.2 mm x 10 texture classes. Stop when the 'what'
(texture) marginal crosses 0.5 (eq. 7); move when the 'where' (depth) marginal crosses the move
threshold (eq. 8) towards the target depth 2.1 mm (the 11th class, eq. 9), beliefs shifted with
the uniform fill (eq. 10). Move thresholds: passive (never moves; the paper's ">1", written 1.5 in
the rows), weakly active 0.999, strongly active 0.05. Runs start at random depth and texture.

Tuned: the texture world (`Textures` docstring) against Figs 5-6 (passive perception at one depth
and over depth). Prediction: Fig. 7, active perception.

Weakly active perception is barely better than passive here (1-3 %, quick seeds 0-2), by the paper's
own mechanism: it moves only once the depth marginal passes 0.999, and with 15 depth classes of
0.2 mm that rarely happens before the texture marginal passes 0.5 (2000 runs, seeds 0-2: 1.8-3.2 % of
the weakly active runs move before deciding, against 89-90 % of the strongly active ones). The paper
gives no number for weakly active perception (Fig. 7B), only that it lies between the two.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from _shared import map_pieces
from perception import FixationPolicy, StationaryPolicy, VirtualEnvironment, fit_model, monte_carlo

from tactip.reproduce.report import Comparison, Report, collections

__all__ = ["MOVE_THRESHOLDS", "run"]

#: Move thresholds of Fig. 7; PASSIVE stands for the paper's ">1" (never moves).
PASSIVE = 1.5
MOVE_THRESHOLDS = (PASSIVE, 0.999, 0.05)
DECISION_THRESHOLD = 0.5
TARGET_CLASS = 10   # 2.0-2.2 mm
SEEDS = (0, 1, 2)


def _single_depth(train, test, offset_mm: float, runs: int, seed: int):
    """Fig. 5: a model of the 2.0-2.2 mm class only, tested on taps ``offset_mm`` deeper."""
    lo = 2.0
    train = train.subset((train.location >= lo) & (train.location < lo + 0.2))
    shifted = test.subset((test.location >= lo + offset_mm - 1e-9) & (test.location < lo + offset_mm + 0.2 - 1e-9))
    shifted = dataclasses.replace(shifted, location=np.clip(shifted.location - offset_mm, lo, lo + 0.2 - 1e-6))
    env = VirtualEnvironment(fit_model(train, n_locations=1), shifted)
    return monte_carlo(env, StationaryPolicy(), thresholds=[DECISION_THRESHOLD], runs=runs, seed=seed, max_taps=200)


def _seed_run(s: int, *, stimulus, runs: int, first: int) -> tuple[list, list, dict]:
    """Rows (and, for the first seed, comparisons) of one simulator seed: a piece of `run` that travels to a worker.

    The third element holds the seed's samples for Figs 6A and 7 (`tactip.reproduce.figure_samples`).
    """
    from tactip.reproduce.figure_samples import p003_fig6a, texture_error_counts

    rows, comparisons, samples = [], [], {"fig7_hist": {}}
    train, test = collections(stimulus, seed=s, taps_per_identity=150)
    env = VirtualEnvironment(fit_model(train, n_locations=15), test)
    options = dict(thresholds=[DECISION_THRESHOLD], runs=runs, seed=s + 1, max_taps=200, shift_mode="uniform")
    for move in MOVE_THRESHOLDS:
        result = (monte_carlo(env, StationaryPolicy(), **options) if move > 1 else
                  monte_carlo(env, FixationPolicy(TARGET_CLASS), move_threshold=move, **options))
        rows.append({"seed": s, "move_threshold": move, "texture_error_classes": float(result.mean_identity_error[0]),
                     "mean_taps": float(result.mean_taps[0]), "forced_fraction": float(result.forced[0])})
        samples["fig7_hist"][move] = texture_error_counts(result, env.model.n_identities)
        if move > 1:
            samples["fig6a"] = p003_fig6a(result, env.model)
        if move > 1 and s == first:
            depth_error = np.nanmean(result.identity_error_map[0], axis=1)      # (15,) over textures
            comparisons += [Comparison("Fig. 6B passive, depths 0-1 mm: texture error", depth_error[:5].mean(),
                                       3.0, "classes"),
                            Comparison("Fig. 6B passive, depths 1.5-3 mm: texture error",
                                       depth_error[7:].mean(), 0.5, "classes")]
    if s == first:
        for offset, paper in ((0.0, 0.4), (0.2, 1.0)):
            single = _single_depth(train, test, offset, runs, s + 1)
            comparisons.append(Comparison(f"Fig. 5 one depth class, test offset {offset:g} mm: texture error",
                                          single.mean_identity_error[0], paper, "classes"))
    return rows, comparisons, samples


def run(*, quick: bool = False, seed: int = 0, progress=None, map_fn=None) -> Report:
    """The experiment of paper 003; rows per simulator seed and move threshold."""
    from tactip.reproduce.stimuli import make_stimulus

    stimulus = make_stimulus("textures")
    runs = 600 if quick else 2000
    seeds = (seed,) if quick else tuple(seed + s for s in SEEDS)
    rows, comparisons = [], []
    pieces = map_pieces(functools.partial(_seed_run, stimulus=stimulus, runs=runs, first=seeds[0]), list(seeds),
                        map_fn=map_fn, progress=progress)
    for seed_rows, seed_comparisons, _ in pieces:
        rows += seed_rows
        comparisons += seed_comparisons
    # Fig. 7 as the paper draws it: error frequencies, summed over the seeds; Fig. 6A: each seed's map
    samples = {"fig7_hist": {move: sum(p[2]["fig7_hist"][move] for p in pieces) for move in MOVE_THRESHOLDS},
               "fig6a": [dict(p[2]["fig6a"], seed=s) for s, p in zip(seeds, pieces)]}
    for move, paper, name in ((PASSIVE, 1.4, "passive"), (0.999, None, "weakly active"), (0.05, 0.4, "strongly active")):
        errors = [r["texture_error_classes"] for r in rows if r["move_threshold"] == move]
        comparisons.append(Comparison(f"Fig. 7 {name}: texture error (mean of {len(errors)} seeds)",
                                      float(np.mean(errors)), paper, "classes"))
    notes = [f"{runs} runs per condition; simulator seeds {', '.join(map(str, seeds))}; stop at 'what' > 0.5.",
             "tuned: the texture world against Figs 5-6 (passive); Fig. 7 (active) is a prediction.",
             f"move_threshold {PASSIVE} stands for the paper's '>1' (never moves)."]
    return Report("003", "active touch: texture under depth uncertainty", rows, comparisons, notes, samples=samples)
