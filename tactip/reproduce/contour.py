"""Contour following around a circular plate (paper 004 Sec. III): the circle world and its runs.

The plate is a disc of radius ``radius_mm`` centred at the origin; the sensor, at P (mm, world
frame, never rotated), perceives the edge at angle phi = atan2(P) (the outward normal; 72 classes
of 5 deg) and the position x = |P| - radius (mm past the edge, 18 classes of 1 mm over -9..9).
Every tap is drawn from the test taps of the class nearest to the true (x, phi) (the virtual
environment of the edge stimulus). One decision (the angle marginal crossing the threshold, eq.
4) is followed by a step of ``step_mm`` along the perceived tangent (counter-clockwise), so that
on a perfect run the true angle turns by ``turn_classes`` angle classes per decision. Active
perception moves the sensor to the target position (eqs. 5-6) after each undecided tap, along the
normal of the last decided angle (the robot is placed facing the edge for the first decision);
passive perception does not move between decisions. The adaptive prior (eq. 12) starts each
decision from alpha x the predicted distribution + (1 - alpha) x flat, Delta learned by predicted
information gain (`perception.ShiftLearner`) or fixed. The predicted distribution is eq. 7 as
printed, the last decision's joint posterior with its angle classes shifted by Delta
(``prior="joint"``: `perception.bayes.adaptive_prior`, as the live `perception.Perceiver` does); a
variant, ``prior="angle_only"``, keeps only the angle marginal and spreads it flat over the positions
(the paper says its forward model predicts angles only; the report names it as a variant).

A run closes the contour when its true angle has gone once round (360 deg) within ``decisions``
decisions, every decision was taken on the edge (|x| <= ``lost_mm``, 6 mm: beyond it the pad no
longer reaches the edge) and every traced point, the edge point the decision perceives (sensor
place minus the decided position along the decided normal; Fig. 6), lies within ``trace_mm``
(2 mm) of the circle.

Diagnostics (`bench/bench_004_mechanism.py`; never in the paper's runs): ``step="arc"`` removes the
radial drift of the straight tangent step (on a circle of radius R a step s along the tangent ends
sqrt(R^2 + s^2) - R further out: 0.45 mm for 5.2 mm on 30 mm), keeping the same angular progress, so
the sensor's distance to the edge changes only by the active moves; ``learn_delta=True`` learns
Delta by predicted information gain from runs that do not use it (e.g. active runs).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from perception import ShiftLearner, VirtualEnvironment, bayes

__all__ = ["ContourResult", "follow_contour"]


@dataclass(frozen=True)
class ContourResult:
    """Means over runs and decisions (after the first ``warmup`` decisions) of one method.

    Attributes
    ----------
    angle_error_deg, position_error_mm, taps_per_decision : float
    closed_contour : float
        Fraction of runs that went once round without losing the edge.
    delta_error_classes : float
        Mean |Delta - turn_classes| at the last decision, angle classes (NaN without a learned Delta).
    delta_error_by_decision : (D,) ndarray
        The same at every decision (Fig. 8).
    traced_mm : (N, D, 2) ndarray
        The traced contour of the first N runs (``traces``): the edge point (x, y) each decision
        perceives, mm (Fig. 6); (0, D, 2) unless asked for.
    delta_right : float
        Fraction of the decisions after the first that started with the learned Delta equal to
        ``turn_classes`` (NaN without a learned Delta).
    edge_lost : float
        Fraction of runs where some decision was taken off the edge (|x| > ``lost_mm``).
    trace_lost : float
        Fraction of runs where some traced point lies further than ``trace_mm`` from the circle.
    trace_error_mm : float
        Mean distance of the traced points from the circle, mm.
    """

    angle_error_deg: float
    position_error_mm: float
    taps_per_decision: float
    closed_contour: float
    delta_error_classes: float
    delta_error_by_decision: np.ndarray
    traced_mm: np.ndarray | None = None
    delta_right: float = float("nan")
    edge_lost: float = float("nan")
    trace_lost: float = float("nan")
    trace_error_mm: float = float("nan")


def follow_contour(env: VirtualEnvironment, *, threshold: float, active: bool, adaptive: bool = False,
                   prior_shift: int | None = None, runs: int = 200, decisions: int = 80, seed: int = 0,
                   radius_mm: float = 30.0, target_mm: float = 0.0, alpha: float = 0.5, max_taps: int = 50,
                   lost_mm: float = 6.0, warmup: int = 0, turn_classes: int = 2,
                   trace_mm: float = 2.0, prior: str = "joint", step: str = "tangent",
                   learn_delta: bool | None = None, traces: int = 0) -> ContourResult:
    """Follow the circle with passive, active or adaptive perception (see the module docstring).

    Parameters
    ----------
    env : VirtualEnvironment
        Edge stimulus: locations -9..9 mm (18 classes), identities 0..355 deg (72 classes).
    threshold : float
        Decision threshold on the angle marginal.
    active : bool
        Move to ``target_mm`` along the perceived normal after each undecided tap.
    adaptive : bool
        Start decisions from the adaptive prior; ``prior_shift`` fixes Delta (default: learned).
    trace_mm : float
        Largest distance of a traced edge point from the circle for a closed contour, mm.
    prior : {"joint", "angle_only"}
        The adaptive prior's predicted distribution: eq. 7 on the joint posterior (faithful), or the
        angle marginal spread flat over positions (a variant).
    step : {"tangent", "arc"}
        The step between decisions: straight along the perceived tangent (the paper), or a
        diagnostic with the same angular progress and no radial drift (the module docstring).
    learn_delta : bool, optional
        Learn Delta by predicted information gain; default: when the adaptive prior's Delta is not fixed.
    traces : int
        Keep the traced contour of the first ``traces`` runs (``ContourResult.traced_mm``, Fig. 6).
    runs, decisions, seed, radius_mm, target_mm, alpha, max_taps, lost_mm, warmup, turn_classes
        Runs side by side, decisions per run, randomness, plate radius (mm), target position (mm),
        weight of the prediction, taps at which a decision is forced, edge-lost distance (mm),
        decisions left out of the means (default none: the paper leaves none out), angle classes turned per
        decision on a perfect run (the step is radius x that angle).

    Returns
    -------
    ContourResult
    """
    if prior not in ("joint", "angle_only"):
        raise ValueError(f"prior must be 'joint' or 'angle_only', got {prior!r}")
    if step not in ("tangent", "arc"):
        raise ValueError(f"step must be 'tangent' or 'arc', got {step!r}")
    learn = adaptive and prior_shift is None if learn_delta is None else bool(learn_delta)
    model = env.model
    n_loc, n_id = model.n_locations, model.n_identities
    width, angle_step = model.class_width, 360.0 / n_id
    rng = np.random.default_rng(seed)
    step_mm = radius_mm * np.radians(angle_step * turn_classes)
    start = rng.uniform(0, 2 * np.pi, runs)
    p = (radius_mm + rng.uniform(-2.0, 2.0, runs))[:, None] * np.stack([np.cos(start), np.sin(start)], axis=1)
    table = env.log_likelihood.reshape(-1, n_loc, n_id)
    flat = np.broadcast_to(bayes.flat_prior(n_loc, n_id), (runs, n_loc, n_id))
    learner = ShiftLearner(n_id, alpha=alpha, circular=True, runs=runs)
    heading = np.degrees(start)         # normal the active moves follow: the last decided angle, deg
    turned = np.zeros(runs)
    edge_lost = np.zeros(runs, bool)
    trace_lost = np.zeros(runs, bool)
    trace_error, delta_right = [], []
    last = last_evidence = None
    errors = {"angle": [], "position": [], "taps": []}
    delta_error = np.full(decisions, np.nan)
    traces = min(int(traces), runs)
    traced_mm = np.zeros((traces, decisions, 2))
    edges = model.location_edges

    def truth(p):
        x = np.hypot(p[:, 0], p[:, 1]) - radius_mm
        phi = np.degrees(np.arctan2(p[:, 1], p[:, 0])) % 360.0
        location = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, n_loc - 1)
        return x, phi, location, np.rint(phi / angle_step).astype(np.intp) % n_id

    for d in range(decisions):
        delta = learner.delta if prior_shift is None else np.full(runs, int(prior_shift))
        if learn and last is not None:
            delta_error[d] = np.abs(learner.delta - turn_classes).mean()
            delta_right.append((learner.delta == turn_classes).mean())
        if adaptive and last is not None:
            predicted = last                                # eq. 7: the joint posterior, angles shifted by Delta
            if prior == "angle_only":                       # variant: the angle marginal, flat over positions
                predicted = np.broadcast_to(np.log(np.exp(last).sum(axis=1, keepdims=True) / n_loc), last.shape)
            log_belief = bayes.adaptive_prior(predicted, alpha=alpha, shift_classes=delta, circular=True)
        else:
            log_belief = flat.copy()
        # The decision's belief and the evidence alone (flat prior), side by side: one update and one shift
        # of both per tap, of the runs still deciding (a decided run's beliefs are never read again).
        beliefs = np.stack([log_belief, flat])  # (2, runs, L, I)
        done = np.zeros(runs, bool)
        decided = np.zeros((runs, 2), np.intp)
        posterior, final_evidence = log_belief.copy(), flat.copy()
        x_true = np.zeros(runs)
        p_decided = p.copy()
        phi_true = np.zeros(runs)
        taps = np.zeros(runs)
        for tap in range(1, max_taps + 1):
            x, phi, location, angle = truth(p)
            likelihood = table[env.draw(location * n_id + angle, rng)]    # every run's draw: the same stream
            deciding = np.flatnonzero(~done)
            # g_t: none for the papers' histogram
            updated = bayes.tap_update(likelihood[deciding], beliefs[:, deciding], tap, model.tap_tempering)
            belief, map_location, map_angle = bayes.decide(updated[0])
            now = (belief > threshold) | (tap == max_taps)
            new = deciding[now]
            decided[new] = np.stack([map_location, map_angle], axis=1)[now]
            posterior[new], final_evidence[new] = updated[0, now], updated[1, now]
            x_true[new], phi_true[new], taps[new], p_decided[new] = x[new], phi[new], tap, p[new]
            done[new] = True
            if done.all():
                break
            if active:
                # move along the perceived normal to the target: x <- x + (x_target - x_MAP)   (eq. 6)
                centres = model.location_centres[map_location]
                offset = np.where(now, 0, np.rint((target_mm - centres) / width).astype(np.intp))
                offset = np.clip(map_location + offset, 0, n_loc - 1) - map_location
                normal = np.radians(heading[deciding])
                p[deciding] += (offset * width)[:, None] * np.stack([np.cos(normal), np.sin(normal)], axis=1)
                updated = bayes.shift(updated, np.broadcast_to(offset, (2, len(offset))), mode="uniform")
            beliefs[:, deciding] = updated
        # the traced contour: the edge point each decision perceives, P - x_decided n(angle_decided)
        normal = np.radians(decided[:, 1] * angle_step)
        traced = p_decided - model.location_centres[decided[:, 0]][:, None] * np.stack([np.cos(normal),
                                                                                         np.sin(normal)], axis=1)
        traced_mm[:, d] = traced[:traces]
        off_circle = np.abs(np.hypot(traced[:, 0], traced[:, 1]) - radius_mm)
        edge_lost |= np.abs(x_true) > lost_mm
        trace_lost |= off_circle > trace_mm
        trace_error.append(off_circle.mean())
        angle_error = np.abs((decided[:, 1] * angle_step - phi_true + 180.0) % 360.0 - 180.0)
        if d >= warmup:
            errors["angle"].append(angle_error.mean())
            errors["position"].append(np.abs(model.location_centres[decided[:, 0]] - x_true).mean())
            errors["taps"].append(taps.mean())
        if learn and last_evidence is not None:
            learner.observe(np.exp(last_evidence).sum(axis=1), np.exp(final_evidence).sum(axis=1))
        last, last_evidence = posterior, final_evidence
        # step along the perceived tangent (counter-clockwise)
        heading = decided[:, 1] * angle_step
        tangent = np.radians(heading + 90.0)
        before = np.arctan2(p[:, 1], p[:, 0])
        stepped = p + step_mm * np.stack([np.cos(tangent), np.sin(tangent)], axis=1)
        if step == "arc":                   # diagnostic: the same progress, the distance to the centre kept
            stepped *= (np.hypot(p[:, 0], p[:, 1]) / np.hypot(stepped[:, 0], stepped[:, 1]))[:, None]
        p = stepped
        turned += (np.arctan2(p[:, 1], p[:, 0]) - before + np.pi) % (2 * np.pi) - np.pi
    closed = (turned >= 2 * np.pi - 1e-9) & ~edge_lost & ~trace_lost
    final = np.abs(learner.delta - turn_classes).mean() if learn else np.nan
    return ContourResult(float(np.mean(errors["angle"])), float(np.mean(errors["position"])),
                         float(np.mean(errors["taps"])), float(closed.mean()), float(final), delta_error,
                         traced_mm, delta_right=float(np.mean(delta_right)) if delta_right else np.nan,
                         edge_lost=float(edge_lost.mean()), trace_lost=float(trace_lost.mean()),
                         trace_error_mm=float(np.mean(trace_error)))
