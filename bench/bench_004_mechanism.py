"""Why paper 004's claim fails in the simulated world: the faithful runs beside diagnostics that remove one cause each.

Issue 25's bar for 004: at threshold 0.5, the adaptive prior's angle error <= 0.9 x active's, with the
contour closed. The faithful runs are `tactip reproduce 004 --quick --seed S`'s (eq. 7 on the joint
posterior, Delta learned; the same `follow_contour` calls, so their margins are the claim's). Beside
them, each on the same simulated sensor and the same Monte Carlo seed:

- ``adaptive beta=2``: Delta fixed at the true turn (2 classes per decision): is the learned Delta the cause?
- ``arc``: the step between decisions keeps the distance to the plate centre (no radial drift): a
  straight step of s along the tangent of a circle of radius R ends sqrt(R^2 + s^2) - R further out,
  which the joint prior (the last decision's position belief, carried over) cannot predict;
- ``learn alongside active``: Delta learned by predicted information gain from active runs' evidence
  (no adaptive prior): how often the learner is right when each decision has more taps.
- ``angle_only``: the variant that predicts only the angle (reported beside, never instead).

Diagnostics change the world or the mechanism on purpose: they say why, they are not the claim.
Prints per-seed figures and, over the seeds, each margin's mean with its 95 % interval (Student t).

    python bench/bench_004_mechanism.py [--seeds 0 1 2 3 4 5 6 7 8 9] [--threshold 0.5]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

#: name -> follow_contour options (on top of the quick run's), in the order printed
CONDITIONS = {
    "active": dict(active=True),
    "adaptive": dict(active=True, adaptive=True),
    "adaptive beta=2": dict(active=True, adaptive=True, prior_shift=2),
    "active arc": dict(active=True, step="arc"),
    "adaptive arc": dict(active=True, adaptive=True, step="arc"),
    "adaptive beta=2 arc": dict(active=True, adaptive=True, prior_shift=2, step="arc"),
    "learn alongside active": dict(active=True, learn_delta=True),
    "angle_only": dict(active=True, adaptive=True, prior="angle_only"),
    "angle_only beta=2": dict(active=True, adaptive=True, prior="angle_only", prior_shift=2),
}
#: (label, adaptive condition, active condition) margins 0.9 x active - adaptive, deg (contour closed in half the runs)
MARGINS = (("faithful (the claim)", "adaptive", "active"), ("beta=2", "adaptive beta=2", "active"),
           ("arc, learned", "adaptive arc", "active arc"), ("arc, beta=2", "adaptive beta=2 arc", "active arc"),
           ("angle_only (variant)", "angle_only", "active"), ("angle_only beta=2", "angle_only beta=2", "active"))


def margin(adaptive, active) -> float:
    """The claim's margin (`tactip.reproduce.seeds`, paper 004): 0.9 x active - adaptive, deg; < 0 if open."""
    value = 0.9 * active.angle_error_deg - adaptive.angle_error_deg
    return value if adaptive.closed_contour >= 0.5 else -abs(value) - 1e-9


def interval(values) -> tuple[float, float, float]:
    """Mean and 95 % interval (Student t) of per-seed values."""
    from scipy import stats

    values = np.asarray(values, float)
    half = stats.t.ppf(0.975, len(values) - 1) * values.std(ddof=1) / np.sqrt(len(values)) if len(values) > 1 else 0
    return float(values.mean()), float(values.mean() - half), float(values.mean() + half)


def main() -> None:
    """Run the conditions over the seeds; print per-seed rows and the margins over seeds."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", nargs="+", type=int, default=list(range(10)))
    parser.add_argument("--threshold", type=float, default=0.5)
    args = parser.parse_args()

    from tactip.reproduce.contour import follow_contour
    from tactip.reproduce.report import environment
    from tactip.reproduce.stimuli import make_stimulus

    options = dict(runs=24, decisions=40, max_taps=25)            # `tactip reproduce 004 --quick`
    radius_mm, step_mm = 30.0, 30.0 * np.radians(10.0)
    print(f"straight tangent step {step_mm:.2f} mm on a {radius_mm:g} mm circle: "
          f"{np.hypot(radius_mm, step_mm) - radius_mm:.3f} mm outward per decision")
    print(f"threshold {args.threshold:g}, quick size ({options}); per condition: angle error deg, closed %, "
          "taps/decision, position error mm, runs losing the edge %, runs whose trace leaves 2 mm %, "
          "trace error mm, learned Delta right %")
    margins = {label: [] for label, _, _ in MARGINS}
    right = {"adaptive": [], "adaptive arc": [], "learn alongside active": []}
    for seed in args.seeds:
        started = time.monotonic()
        env = environment(make_stimulus("edge"), seed=seed, taps_per_identity=90, n_locations=18)
        results = {name: follow_contour(env, threshold=args.threshold, seed=seed + 1, **options, **extra)
                   for name, extra in CONDITIONS.items()}
        print(f"seed {seed} ({time.monotonic() - started:.0f} s)")
        for name, r in results.items():
            print(f"  {name:<24} {r.angle_error_deg:5.2f} deg  closed {100 * r.closed_contour:5.1f} %  "
                  f"{r.taps_per_decision:5.2f} taps  {r.position_error_mm:4.2f} mm  edge lost "
                  f"{100 * r.edge_lost:5.1f} %  trace lost {100 * r.trace_lost:5.1f} %  trace {r.trace_error_mm:4.2f} mm"
                  + ("" if np.isnan(r.delta_right) else f"  Delta right {100 * r.delta_right:5.1f} %"))
        for label, adaptive, active in MARGINS:
            margins[label].append(margin(results[adaptive], results[active]))
        for name in right:
            right[name].append(results[name].delta_right)
        print("  margins: " + ", ".join(f"{label} {values[-1]:+.2f}" for label, values in margins.items()), flush=True)
    print(f"over seeds {', '.join(map(str, args.seeds))}: margin 0.9 x active - adaptive, deg, mean [95 % interval], "
          "seeds held")
    for label, values in margins.items():
        mean, low, high = interval(values)
        print(f"  {label:<22} {mean:+.2f} [{low:+.2f}, {high:+.2f}]  held {sum(v > 0 for v in values)} of {len(values)}")
    for name, values in right.items():
        mean, low, high = interval(values)
        print(f"  learned Delta right, {name:<22} {100 * mean:5.1f} % [{100 * low:.1f}, {100 * high:.1f}]  "
              f"(seeds: {', '.join(f'{100 * v:.0f}' for v in values)})")


if __name__ == "__main__":
    main()
