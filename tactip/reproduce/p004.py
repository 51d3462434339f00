"""Paper 004 on the simulated fingertip: edge angle and position, contour following (Figs 6-8).

An edge at 72 angles (5 deg) x 18 positions (1 mm) (`tactip.reproduce.stimuli.Edge`), 90 taps per
angle over 18 mm in each of two sessions; the fingertip follows a circular plate
(`tactip.reproduce.contour`) with passive, active and adaptive perception (active + the adaptive
prior of eq. 12 with Delta learned by predicted information gain, eqs. 7-11), and, as a control,
the adaptive prior with Delta fixed at 0. Stop when the angle marginal crosses the threshold
(eq. 4); active moves to the target position 0 mm (the edge under the pad centre).

Tuned: the edge world's sharpness (``Edge`` docstring) against passive perception (the paper
gives no number: it cannot follow the contour) and the active single-decision angle error (~4
deg). Predictions: contour closing, the adaptive prior's gain, the learned Delta.
"""

from __future__ import annotations

import functools

from _shared import map_pieces

from tactip.reproduce.contour import follow_contour
from tactip.reproduce.report import Comparison, Report, environment

__all__ = ["THRESHOLDS", "METHODS", "run"]

THRESHOLDS = (0.05, 0.2, 0.5, 0.9)
QUICK_THRESHOLDS = (0.05, 0.5)
#: method -> follow_contour options
#: ``adaptive`` is eq. 7 as printed (the joint posterior shifted, as the live Perceiver does);
#: ``adaptive_angle_only`` is a variant (the angle marginal, flat over positions), reported beside it;
#: ``adaptive_shift0`` is a control (Delta fixed at 0).
METHODS = {"passive": dict(active=False), "active": dict(active=True),
           "adaptive": dict(active=True, adaptive=True),
           "adaptive_angle_only": dict(active=True, adaptive=True, prior="angle_only"),
           "adaptive_shift0": dict(active=True, adaptive=True, prior_shift=0)}


def _condition_run(condition, *, env, seed: int, options: dict):
    """Contour following by one (method, threshold), a piece of `run` (module level: it travels to a worker)."""
    method, threshold = condition
    return follow_contour(env, threshold=threshold, seed=seed + 1, **options, **METHODS[method])


def run(*, quick: bool = False, seed: int = 0, progress=None, map_fn=None) -> Report:
    """The experiment of paper 004; rows per method and threshold."""
    from tactip.reproduce.stimuli import make_stimulus

    env = environment(make_stimulus("edge"), seed=seed, taps_per_identity=90, n_locations=18)
    thresholds = QUICK_THRESHOLDS if quick else THRESHOLDS
    options = dict(runs=24, decisions=40, max_taps=25) if quick else dict(runs=100, decisions=45, max_taps=50)
    rows, results = [], {}
    conditions = [(m, t) for t in thresholds for m in METHODS]
    pieces = map_pieces(functools.partial(_condition_run, env=env, seed=seed, options=options), conditions,
                        map_fn=map_fn, progress=progress)
    for (method, threshold), r in zip(conditions, pieces):
        results[method, threshold] = r
        rows.append({"method": method, "threshold": threshold, "angle_error_deg": r.angle_error_deg,
                     "position_error_mm": r.position_error_mm, "taps_per_decision": r.taps_per_decision,
                     "closed_contour": r.closed_contour, "delta_error_classes": r.delta_error_classes})
    high = 0.5
    active, adaptive = results["active", high], results["adaptive", high]
    variant = results["adaptive_angle_only", high]
    comparisons = [
        Comparison(f"Fig. 7A active, theta {high:g}: angle error", active.angle_error_deg, 4.0, "deg"),
        Comparison(f"Fig. 7A adaptive, theta {high:g}: angle error", adaptive.angle_error_deg, 2.8, "deg"),
        Comparison(f"Fig. 7A adaptive, variant angle only, theta {high:g}: angle error", variant.angle_error_deg,
                   2.8, "deg"),
        Comparison(f"Fig. 7B adaptive, theta {high:g}: position error", adaptive.position_error_mm, 1.8, "mm"),
        Comparison(f"Fig. 7C taps per decision, adaptive / active, theta {high:g}",
                   adaptive.taps_per_decision / active.taps_per_decision, None, "ratio"),
        Comparison(f"Fig. 8 learned Delta, |error| after {options['decisions']} decisions",
                   adaptive.delta_error_classes, None, "classes"),
    ]
    comparisons += [Comparison(f"Fig. 6 closed contour, {m}, theta {t:g}", results[m, t].closed_contour, None)
                    for t in thresholds for m in ("passive", "active", "adaptive", "adaptive_angle_only")]
    comparisons += [Comparison(f"Fig. 6 adaptive, theta {high:g}: runs losing the edge", adaptive.edge_lost, None),
                    Comparison(f"Fig. 6 adaptive, theta {high:g}: runs tracing > 2 mm off", adaptive.trace_lost, None)]
    notes = [f"{options['runs']} runs x {options['decisions']} decisions per condition, a 30 mm circle, 10 deg "
             "turned per decision on a perfect run; simulated sensor seed {seed}.".replace("{seed}", str(seed)),
             "tuned: the edge world against passive and active single decisions; the contour, the adaptive prior "
             "and Delta are predictions.",
             "adaptive: eq. 7 as printed, the joint posterior shifted by Delta (as the live Perceiver); "
             "adaptive_angle_only: a variant, the angle marginal spread flat over positions (the paper says its "
             "forward model predicts angles only), reported beside it, never instead.",
             "every decision counts in the means (the paper leaves none out).",
             "why the claim (adaptive <= 0.9 x active at theta 0.5, contour closed) fails here, measured by "
             "bench/bench_004_mechanism.py (quick, seeds 0-9): the runs are faithful, and two causes remove it. "
             "(a) The straight step along the tangent of the 30 mm circle ends 0.45 mm further out at every "
             "decision; eq. 7 carries the last position belief, which cannot predict that, and with ~5 taps per "
             "decision the position lags until the traced points leave the 2 mm band (the edge itself is never "
             "lost). (b) The learned Delta, fed by those ~5 taps per decision, is the true 2 classes in about half "
             "of the decisions (about 85 % when learned alongside the active runs' ~12 taps). Without the drift "
             "(a diagnostic step along the arc) and with Delta fixed at 2, the joint prior holds the claim on "
             "every seed; removing either cause alone does not."]
    return Report("004", "adaptive perception: edge angle and position, contour following", rows, comparisons, notes)
