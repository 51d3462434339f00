"""Validate a perception model by Monte Carlo on an independent test dataset.

Each run picks a true class and a random starting location, then taps: every tap is drawn from
the test taps of the current (location, identity) class, the beliefs update, the policy moves
the sensor, until the identity belief crosses the decision threshold (papers 000 and 002).
For each threshold the table gives the mean decision taps, the mean absolute identity error,
the fraction of exactly right identities and the mean absolute location error.

Policies: active (move to the --fixation location), stationary (never move), random (move
uniformly over the range). Without --policy all three run on the same starting classes.

--sweep-fixation runs the active policy at every fixation location, picks the one with the
lowest error within --tap-budget mean taps, and writes it with its threshold into the model's
recommended settings (used by the station). --sweep-lateral gives the error when the test taps'
lateral placement is within [-SIGMA, SIGMA] mm, relative to the smallest SIGMA (paper 002 Fig. 11).

Examples:
  tactip validate models/gaps.h5 data/test.h5 --plot out/curves.png --json out/curves.json
  tactip validate models/gaps.h5 data/test.h5 --policy active --fixation 4.75 --thresholds 0.9 0.99
  tactip validate models/gaps.h5 data/test.h5 --sweep-fixation --plot out/fixation.png
  tactip validate models/gaps.h5 data/test_jitter.h5 --sweep-lateral 0.25 0.5 1 2 --plot out/lateral.png
"""

from __future__ import annotations

import argparse

from tactip.cli._types import (finite_float, float_in_range, fraction, fractions, image_file, int_in_range,
                               non_negative_float, output_file, seed)
import functools
import json
import pathlib

#: Most Monte Carlo runs per policy, and most taps per run: beyond them a validation takes hours.
MAX_RUNS = 10_000_000
MAX_TAPS = 1000

HELP = "Monte Carlo validation of a model on a test dataset (speed-accuracy, fixation sweep)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the parser of ``tactip validate``."""
    parser.add_argument("model", metavar="MODEL.h5", help="model from tactip train (tactip-model/1)")
    parser.add_argument("test", metavar="TEST.h5", help="independent test taps (tactip-dataset/1)")
    parser.add_argument("--policy", choices=("active", "stationary", "random"),
                        help="one policy (default: all three)")
    parser.add_argument("--fixation", type=finite_float, metavar="MM",
                        help="fixation location of the active policy, location units, inside the model's range "
                             "(default: the model's recommended one, else the centre of the range)")
    parser.add_argument("--thresholds", nargs="+", type=fractions, metavar="T",
                        help="decision thresholds, space or comma separated (default: 20 over 0-0.9999)")
    parser.add_argument("--runs", type=int_in_range(1, MAX_RUNS), default=5000, metavar="N",
                        help=f"Monte Carlo runs per policy, 1..{MAX_RUNS} (default 5000)")
    parser.add_argument("--max-taps", type=int_in_range(1, MAX_TAPS), default=20, metavar="N",
                        help=f"taps at which a decision is forced, 1..{MAX_TAPS} (default 20)")
    parser.add_argument("--deadline", type=int_in_range(1, MAX_TAPS), metavar="N",
                        help="null decision and random relocation after N taps without a decision")
    parser.add_argument("--move-threshold", type=fraction, default=0.0, metavar="P",
                        help="location belief needed before moving (0 always moves, 1 never; default 0)")
    parser.add_argument("--shift", choices=("edge", "uniform"), default=None,
                        help="belief shift at the range boundary after a move (default: the model's front-end "
                             "convention, uniform for taxel (paper 000), edge for tactip (paper 002))")
    sweep = parser.add_mutually_exclusive_group()
    sweep.add_argument("--sweep-fixation", action="store_true",
                       help="try every fixation location, write the best into the model's recommended settings")
    sweep.add_argument("--sweep-lateral", nargs="+", type=non_negative_float, metavar="SIGMA",
                       help="robustness to lateral placement noise (paper 002 Fig. 11): errors with test taps "
                            "whose lateral offset is within [-SIGMA, SIGMA] mm, e.g. 0 0.25 0.5 1 2 (the test set "
                            "must be collected with [protocol] lateral_jitter_mm)")
    parser.add_argument("--tap-budget", type=float_in_range(1, MAX_TAPS), default=12, metavar="TAPS",
                        help="mean taps within which --sweep-fixation takes the best error, 1..--max-taps "
                             "(default 12)")
    parser.add_argument("--json", type=output_file, metavar="OUT.json", help="write one entry per policy and threshold")
    parser.add_argument("--plot", type=image_file, metavar="OUT.png",
                        help="plot error against mean taps (or against fixation); .png, .pdf, .svg ...")
    parser.add_argument("--seed", type=seed, default=0, help="random seed, >= 0 (default 0)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def run(args: argparse.Namespace) -> int:
    """Run the Monte Carlo validation and report it."""
    from tqdm import tqdm

    from perception import (DEFAULT_THRESHOLDS, VirtualEnvironment, compare_policies, fixation_sweep, load_dataset,
                            load_model, make_policy, save_model)

    from tactip.cli._types import check_memory
    from tactip.errors import TactipError

    if args.tap_budget > args.max_taps:
        raise TactipError(f"--tap-budget {args.tap_budget:g} is out of range: mean taps must lie in 1..--max-taps "
                          f"({args.max_taps})")
    if args.deadline is not None and args.deadline > args.max_taps:
        raise TactipError(f"--deadline {args.deadline} is out of range: it must lie in 1..--max-taps ({args.max_taps})")
    from tactip._output import refuse_overwriting_inputs, write_text_atomic

    refuse_overwriting_inputs([args.json, args.plot], [args.model, args.test])  # issue 9: never over an input
    model = load_model(args.model)
    _check_fixation(model, args.fixation)
    test = load_dataset(args.test)
    thresholds = sorted({t for group in args.thresholds for t in group}) if args.thresholds else DEFAULT_THRESHOLDS
    if args.sweep_fixation:
        thresholds = _deciding_thresholds(model, thresholds)
    # Peak memory of the runs stepping together: beliefs and their temporaries, then one result per threshold.
    check_memory(args.runs * (6 * 8 * model.n_classes + 64 * len(thresholds)),
                 what=f"{args.runs} Monte Carlo runs of {model.n_classes} classes", hint="use fewer --runs")
    environment = VirtualEnvironment(model, test)
    options = dict(thresholds=thresholds, runs=args.runs, max_taps=args.max_taps, deadline=args.deadline,
                   move_threshold=args.move_threshold, shift_mode=args.shift or model.shift_mode, seed=args.seed)
    unit = model.location_unit
    print(model.summary())
    print(f"test: {len(test)} taps; {args.runs} runs per curve")
    if args.sweep_fixation:
        progress = functools.partial(tqdm, desc="fixations", unit="fixation", disable=args.quiet)
        sweep = fixation_sweep(environment, tap_budget=args.tap_budget, progress=progress, **options)
        if sweep.taps[sweep.best] > args.tap_budget:
            fewest = float(min(r.mean_taps.min() for r in sweep.results))
            raise TactipError(f"--tap-budget {args.tap_budget:g} is too tight: no fixation decides within "
                              f"{args.tap_budget:g} mean taps at any threshold (fewest: {fewest:.2f}); use "
                              f"--tap-budget in {fewest:.2f}..{args.max_taps}; nothing written")
        print(f"{'fixation':>10} {'error':>8} {'taps':>6} {'threshold':>9}")
        for fixation, error, taps, threshold in zip(sweep.fixations, sweep.errors, sweep.taps, sweep.thresholds):
            print(f"{fixation:>10.3f} {error:>8.3f} {taps:>6.2f} {threshold:>9.4g}")
        model = model.with_recommended(fixation_location=sweep.best_fixation, decision_threshold=sweep.best_threshold,
                                       policy="active")
        save_model(args.model, model)
        print(f"best fixation {sweep.best_fixation:g} {unit} (threshold {sweep.best_threshold:g}, error "
              f"{sweep.errors[sweep.best]:.3f} in {sweep.taps[sweep.best]:.1f} taps); written to {args.model}")
        rows = [{**row, "fixation": float(f)} for f, r in zip(sweep.fixations, sweep.results) for row in r.rows()]
        if args.plot:
            from perception.plots import plot_fixation_sweep

            plot_fixation_sweep(sweep, args.plot, units=unit)
    elif args.sweep_lateral:
        from perception import lateral_sweep

        name = args.policy or "active"
        policy = make_policy(name, fixation_class=model.fixation_class(args.fixation))
        progress = functools.partial(tqdm, desc="sigmas", unit="sigma", disable=args.quiet)
        sweep = lateral_sweep(environment, policy, sigmas=args.sweep_lateral, tap_budget=args.tap_budget,
                              progress=progress, **options)
        print(f"{name} policy; best error within {args.tap_budget:g} mean taps")
        print(f"{'sigma':>8} {'error':>8} {'ratio':>6}")
        for sigma, error, ratio in zip(sweep.sigmas, sweep.errors, sweep.ratio):
            print(f"{sigma:>8.3g} {error:>8.3f} {ratio:>6.2f}")
        rows = [{**row, "sigma": float(s)} for s, r in zip(sweep.sigmas, sweep.results) for row in r.rows()]
        if args.plot:
            from perception.plots import plot_lateral_sweep

            plot_lateral_sweep(sweep, args.plot)
    else:
        fixation_class = model.fixation_class(args.fixation)
        names = [args.policy] if args.policy else ["active", "random", "stationary"]
        if "active" in names:
            print(f"active fixation: {model.location_centres[fixation_class]:g} {unit}")
        policies = [make_policy(name, fixation_class=fixation_class) for name in names]
        progress = functools.partial(tqdm, desc="policies", unit="policy", disable=args.quiet)
        results = compare_policies(environment, policies, progress=progress, **options)
        rows = [row for result in results.values() for row in result.rows()]
        print(f"{'policy':<11} {'threshold':>9} {'taps':>6} {'id error':>8} {'accuracy':>8} {'loc error':>9}")
        for row in rows:
            print(f"{row['policy']:<11} {row['threshold']:>9.4g} {row['mean_taps']:>6.2f} "
                  f"{row['mean_identity_error']:>8.3f} {row['accuracy']:>8.3f} {row['mean_location_error']:>9.3f}")
        if args.plot:
            from perception.plots import plot_speed_accuracy

            plot_speed_accuracy(results, args.plot, units=model.identity_unit if model.n_identities > 1 else unit)
    if args.json:
        write_text_atomic(args.json, json.dumps(rows, indent=1) + "\n", inputs=[args.model, args.test])
        print(f"wrote {args.json}")
    if args.plot:
        print(f"wrote {args.plot}")
    return 0


def _check_fixation(model, fixation) -> None:
    """Refuse a --fixation outside the model's location range (its class edges)."""
    from tactip.errors import TactipError

    if fixation is None:
        return
    low, high = float(model.location_edges[0]), float(model.location_edges[-1])
    if not low <= fixation <= high:
        raise TactipError(f"--fixation {fixation:g} {model.location_unit} lies outside the model's location range "
                          f"{low:g}..{high:g} {model.location_unit}")


def _deciding_thresholds(model, thresholds) -> list[float]:
    """The thresholds a fixation sweep may recommend: those a belief must earn.

    The decision belief is a maximum over n classes (the identities, or the locations of a model with one
    identity), so it is at least 1/n after any tap: a threshold below that decides after the first tap
    whatever was sensed (in air, at the start of an inspection) and is no recommendation.
    """
    from tactip.errors import TactipError

    n = model.n_identities if model.n_identities > 1 else model.n_locations
    floor = 1.0 / n
    kept = [t for t in thresholds if t >= floor]
    if not kept:
        raise TactipError(f"--thresholds: every threshold is below 1/{n} = {floor:.3g}, which decides after the first "
                          f"tap whatever it senses; give thresholds in [{floor:.3g}, 1] for --sweep-fixation")
    return kept
