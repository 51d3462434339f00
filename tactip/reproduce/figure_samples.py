"""Samples that only figures draw: distributions, per-class maps and traced contours.

The paper runners keep, beside their JSON rows, what some figures need from the same runs
(`Report.samples`, never written to the JSON):

- 001 Fig. 7A (`p001_samples`): the reaction-time distribution of fixed perception (no deadline) at
  two thresholds (the paper: 0.9 and 0.999), one value per Monte Carlo run;
- 001 Fig. 8: shape error, position error and reaction time per test class (rod x position) at
  threshold 0.9, fixed perception;
- 003 Fig. 7 (`texture_error_counts`): how often each texture error (0, 1, 2 ... classes) was made,
  per move threshold, summed over the simulator seeds (the paper's bar charts of error frequencies);
- 003 Fig. 6A (`p003_fig6a`): passive texture error per (depth, texture) class, each seed's map.

and, for ``--figure-runs`` (JSON rows, `tactip.reproduce.figure_runs`), 004 Fig. 6's traced contours
(`traced_contour_samples`): the edge points the first runs perceive, passive and active perception at
the paper's thresholds 0.2 and 0.9, with the adaptive prior beside them.
"""

from __future__ import annotations

import numpy as np

__all__ = ["FIG7A_THRESHOLDS", "FIG8_THRESHOLD", "FIG6_CONDITIONS", "p001_samples", "texture_error_counts",
           "p003_fig6a", "traced_contour_samples"]

#: Paper 001 Fig. 7A: the thresholds of its reaction-time histograms (grey 0.9, white 0.999).
FIG7A_THRESHOLDS = (0.9, 0.999)
#: Paper 001 Fig. 8: the threshold of its per-class maps.
FIG8_THRESHOLD = 0.9
#: Paper 004 Fig. 6: (method, threshold) of its panels A-D (passive and active at 0.2 and 0.9), and adaptive.
FIG6_CONDITIONS = (("passive", 0.2), ("passive", 0.9), ("active", 0.2), ("active", 0.9),
                   ("adaptive", 0.2), ("adaptive", 0.9))


def _nearest(thresholds, wanted: float) -> int:
    """Index of the threshold nearest to ``wanted`` on a logit scale (0.999 -> 0.99 when 0.999 was not run)."""
    t = np.clip(np.asarray(thresholds, dtype=np.float64), 1e-12, 1 - 1e-12)
    w = np.clip(wanted, 1e-12, 1 - 1e-12)
    return int(np.argmin(np.abs(np.log(t / (1 - t)) - np.log(w / (1 - w)))))


def p001_samples(result, model) -> dict:
    """001 Figs 7A and 8 from the Monte Carlo of fixed perception (no deadline).

    Parameters
    ----------
    result : perception.MonteCarloResult
        Fixed perception over the reproduction's thresholds (``taps_runs`` kept).
    model : perception.HistogramModel
        The rods' model: identities are rod diameters (mm), locations positions (mm).

    Returns
    -------
    dict
        ``fig7a``: ``{thresholds: [t1, t2], taps: [(runs,) int array, ...]}`` at the run thresholds
        nearest to `FIG7A_THRESHOLDS`; ``fig8``: ``{threshold, shapes_mm (I,), positions_mm (L,),
        shape_error_mm, position_error_mm, reaction_taps}``, each map (L, I) over the test classes.
    """
    picks = sorted({_nearest(result.thresholds, t) for t in FIG7A_THRESHOLDS})
    k = _nearest(result.thresholds, FIG8_THRESHOLD)
    return {"fig7a": {"thresholds": [float(result.thresholds[i]) for i in picks],
                      "taps": [np.asarray(result.taps_runs[i]) for i in picks]},
            "fig8": {"threshold": float(result.thresholds[k]), "shapes_mm": np.asarray(model.identities, float),
                     "positions_mm": np.asarray(model.location_centres, float),
                     "shape_error_mm": result.identity_error_map[k], "position_error_mm": result.location_error_map[k],
                     "reaction_taps": result.taps_map[k]}}


def texture_error_counts(result, n_textures: int) -> np.ndarray:
    """How many runs made each texture error 0 .. ``n_textures - 1`` classes (003 Fig. 7's bars).

    Parameters
    ----------
    result : perception.MonteCarloResult
        One threshold (the stop rule's), ``identity_error_runs`` kept.
    n_textures : int

    Returns
    -------
    (n_textures,) int ndarray
    """
    errors = np.rint(np.asarray(result.identity_error_runs[0], float)).astype(np.intp)
    return np.bincount(errors, minlength=n_textures)[:n_textures]


def p003_fig6a(result, model) -> dict:
    """003 Fig. 6A: passive texture error per (depth, texture) class, one seed.

    Returns
    -------
    dict
        ``{depths_mm (L,), textures (I,), texture_error_classes (L, I)}`` (NaN: no run started there).
    """
    return {"depths_mm": np.asarray(model.location_centres, float), "textures": np.asarray(model.identities, float),
            "texture_error_classes": np.asarray(result.identity_error_map[0], float)}


def traced_contour_samples(env, *, conditions=FIG6_CONDITIONS, traces: int, runs: int, decisions: int, max_taps: int,
                           seed: int, radius_mm: float = 30.0) -> list[dict]:
    """004 Fig. 6: the contours traced by the first ``traces`` runs of each (method, threshold).

    Parameters
    ----------
    env : perception.VirtualEnvironment
        The edge world of `tactip.reproduce.p004`.
    conditions : sequence of (str, float)
        Methods of `tactip.reproduce.p004.METHODS` and belief thresholds.
    traces, runs, decisions, max_taps, seed : int
        As `tactip.reproduce.contour.follow_contour` (the same seed as the reproduction's runs).
    radius_mm : float
        The plate's radius, mm.

    Returns
    -------
    list of dict
        ``{method, threshold, run, decision, x_mm, y_mm, closed_contour}``: one row per traced point
        (``closed_contour``: the fraction of all ``runs`` that closed it, the same in every row of a condition).
    """
    from tactip.reproduce.contour import follow_contour
    from tactip.reproduce.p004 import METHODS

    rows = []
    for method, threshold in conditions:
        result = follow_contour(env, threshold=threshold, seed=seed + 1, runs=runs, decisions=decisions,
                                max_taps=max_taps, radius_mm=radius_mm, traces=traces, **METHODS[method])
        for run, trace in enumerate(result.traced_mm):
            rows += [{"method": method, "threshold": float(threshold), "run": run, "decision": d,
                      "x_mm": float(x), "y_mm": float(y), "closed_contour": result.closed_contour}
                     for d, (x, y) in enumerate(trace)]
    return rows
