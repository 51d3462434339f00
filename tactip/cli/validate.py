"""Validate a perception model by Monte Carlo on an independent test dataset.

Each run picks a true class and a random starting location, then taps: every tap is drawn from
the test taps of the current (location, identity) class, the beliefs update, the policy moves
the sensor, until the identity belief crosses the decision threshold (papers 000 and 002).
For each threshold the table gives the mean decision taps, the mean label error, the fraction of
exactly right labels and the mean absolute location error. The label is what the model decides: the
identity, or the location of a model with one identity. Its error is in the label's unit, circular
for a label with a period (315 and 0 deg are 45 deg apart); for a named label (classes such as
shapes) it is the fraction of decisions wrong, 1 - accuracy. JSON rows carry it as
mean_label_error (beside mean_identity_error and mean_location_error), with label_error_unit.

Policies: active (move to the --fixation location), stationary (never move), random (move
uniformly over the range). Without --policy all three run on the same starting classes. A model
with one location (trained on a dataset from labelled recordings, tactip dataset build) never moves:
every policy is the same, so one runs, called stationary, and no location error or fixation is shown.

--sweep-fixation runs the active policy at every fixation location, picks the one with the
lowest error within --tap-budget mean taps, and writes it with its threshold into the model's
recommended settings (used by the station). --sweep-lateral gives the error when the test taps'
lateral placement is within [-SIGMA, SIGMA] mm, relative to the smallest SIGMA (paper 002 Fig. 11).
With --target-accuracy P, --sweep-fixation instead picks the fixation and threshold whose decisions
are within --tolerance of the true identity in a fraction P of runs in the fewest mean taps; a
calibrated model then gets a tap tempering g1..g5 fitted at the best fixation (the t-th tap's log
likelihood times g_t, beyond the 5th times g5), so that its beliefs after each of taps 1 to 5 mean what
they say (the taps of one run repeat each other's evidence); the factors are printed and written.
With --scheduler tcp://HOST:PORT a sweep's fixations (or sigmas) run on that Dask cluster, one per
worker at a time: the same seed gives the same figures as a run here.

Calibration: for the active policy, the expected calibration error (ECE) of the identity belief
after 1, 3 and 5 taps (a belief of 0.9 should be right 90 % of the time: ECE 0), and with --plot a
reliability diagram (OUT_reliability.png). --compare adds other models (e.g. trained with other
--model kinds) on the same runs: same seed, same true classes and starting locations.

Does the model earn its keep? --baselines --train TRAIN.h5 fits scikit-learn's simple learners on the
model's training taps (the model file does not hold them: give the dataset the model was trained on)
and scores them on the test taps: k-nearest neighbours (k chosen by cross-validation on the training
taps), logistic regression over the label classes, and ridge regression of a numeric label (of the
cos and sin of a circular one) snapped to the nearest class, so that each decides a class as the model
does. Features: every tap flattened (samples x dims), NaN (a pin unseen
during the tap) imputed with the training mean, standardised. Each decides from 1 tap, on every test
tap; beside them the model's own exact 1-tap decision and its decisions at threshold 0.9 (the active
policy, or the one policy run). The report says WORSE THAN BASELINE when the model's 1-tap error is
more than 5 % above the best baseline's, and NOT WELL BELOW BASELINE when its error at threshold 0.9
is above 0.75x the best baseline's 1-tap error.

Examples:
  tactip validate models/gaps.h5 data/test.h5 --plot out/curves.png --json out/curves.json
  tactip validate models/gaps.h5 data/test.h5 --policy active --fixation 4.75 --thresholds 0.9 0.99
  tactip validate models/gaps.h5 data/test.h5 --sweep-fixation --plot out/fixation.png
  tactip validate models/gaps.h5 data/test_jitter.h5 --sweep-lateral 0.25 0.5 1 2 --plot out/lateral.png
  tactip validate models/gaussian.h5 data/test.h5 --compare models/histogram.h5 --policy active --plot out/models.png
  tactip validate models/gaussian.h5 data/test.h5 --sweep-fixation --target-accuracy 0.95 --tolerance 0.25
  tactip validate models/gaps.h5 data/test.h5 --sweep-fixation --runs 20000 --scheduler tcp://10.0.0.5:8786
  tactip validate shapes/model.h5 shapes/test.h5 --baselines --train shapes/train.h5 --json out/shapes.json
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import pathlib

from _shared.ranges import MAX_TAPS
from perception.choices import POLICIES, SHIFT_MODES
from tactip.cli._validate_report import KEEP_THRESHOLD, with_label_error
from tactip.cli._types import (add_json_argument, finite_float, float_in_range, fraction, fractions, image_file, int_in_range,
                               non_negative_float, seed)

#: Most Monte Carlo runs per policy (and most taps per run, `_shared.ranges.MAX_TAPS`): beyond them a validation takes hours.
MAX_RUNS = 10_000_000

HELP = "Monte Carlo validation of a model on a test dataset (speed-accuracy, fixation sweep)"


#: Mean taps within which --sweep-fixation and --sweep-lateral take the best error, unless --tap-budget says.
DEFAULT_TAP_BUDGET = 12


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the parser of ``tactip validate``."""
    parser.add_argument("model", metavar="MODEL.h5", help="model from tactip train (tactip-model/1)")
    parser.add_argument("test", metavar="TEST.h5", help="independent test taps (tactip-dataset/1)")
    parser.add_argument("--policy", choices=POLICIES,
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
    parser.add_argument("--shift", choices=SHIFT_MODES, default=None,
                        help="belief shift at the range boundary after a move (default: the model's front-end "
                             "convention, uniform for taxel (paper 000), edge for tactip (paper 002))")
    sweep = parser.add_mutually_exclusive_group()
    sweep.add_argument("--sweep-fixation", action="store_true",
                       help="try every fixation location, write the best into the model's recommended settings")
    sweep.add_argument("--sweep-lateral", nargs="+", type=non_negative_float, metavar="SIGMA",
                       help="robustness to lateral placement noise (paper 002 Fig. 11): errors with test taps "
                            "whose lateral offset is within [-SIGMA, SIGMA] mm, e.g. 0 0.25 0.5 1 2 (the test set "
                            "must be collected with [protocol] lateral_jitter_mm)")
    parser.add_argument("--tap-budget", type=float_in_range(1, MAX_TAPS), default=None, metavar="TAPS",
                        help="mean taps within which --sweep-fixation takes the best error, 1..--max-taps "
                             f"(default {DEFAULT_TAP_BUDGET}, or --max-taps if fewer)")
    parser.add_argument("--target-accuracy", type=fraction, metavar="P",
                        help="with --sweep-fixation: pick the fixation and threshold reaching this fraction of "
                             "decisions within --tolerance in the fewest mean taps (e.g. 0.95)")
    parser.add_argument("--tolerance", type=non_negative_float, default=0.0, metavar="MM",
                        help="with --target-accuracy: largest |decided - true| identity that counts as right, "
                             "identity units (default 0: the exact class)")
    parser.add_argument("--compare", nargs="+", metavar="MODEL.h5", default=[],
                        help="other models validated on the same runs (speed-accuracy and calibration side by side)")
    parser.add_argument("--baselines", action="store_true",
                        help="also fit k-nearest neighbours, logistic and ridge regression (scikit-learn) on the "
                             "training taps (--train) and say whether the model beats them at 1 tap and at "
                             f"threshold {KEEP_THRESHOLD:g}")
    parser.add_argument("--train", metavar="TRAIN.h5",
                        help="with --baselines: the dataset the model was trained on (the model file does not hold "
                             "its taps); the baselines are fitted on it, never on the test taps")
    add_json_argument(parser, "one entry per policy and threshold (with --baselines, also one per baseline and "
                              "a verdict per model)")
    parser.add_argument("--plot", type=image_file, metavar="OUT.png",
                        help="plot error against mean taps (or against fixation); .png, .pdf, .svg ...")
    parser.add_argument("--seed", type=seed, default=0, help="random seed, >= 0 (default 0)")
    parser.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                        help="run --sweep-fixation's fixations or --sweep-lateral's sigmas on this Dask cluster "
                             "(dask scheduler; dask worker tcp://HOST:PORT on each machine); the same results as here")


def run(args: argparse.Namespace) -> int:
    """Run the Monte Carlo validation and report it."""
    from _shared.progress import progress_bar as tqdm

    from perception import DEFAULT_THRESHOLDS, VirtualEnvironment, load_dataset, load_model

    from tactip.cli._types import check_memory
    from tactip.errors import TactipError

    if args.tap_budget is None:  # the default follows a smaller --max-taps rather than refusing it
        args.tap_budget = float(min(DEFAULT_TAP_BUDGET, args.max_taps))
    elif args.tap_budget > args.max_taps:
        raise TactipError(f"--tap-budget {args.tap_budget:g} is out of range: mean taps must lie in 1..--max-taps "
                          f"({args.max_taps})")
    if args.deadline is not None and args.deadline > args.max_taps:
        raise TactipError(f"--deadline {args.deadline} is out of range: it must lie in 1..--max-taps ({args.max_taps})")
    from tactip._output import refuse_overwriting_inputs, write_json

    if args.target_accuracy is not None and not args.sweep_fixation:
        raise TactipError("--target-accuracy needs --sweep-fixation")
    if args.target_accuracy == 0:
        raise TactipError("--target-accuracy must be in (0, 1], got 0")
    if args.compare and (args.sweep_fixation or args.sweep_lateral):
        raise TactipError("--compare works with the policy comparison only (not with --sweep-fixation or "
                          "--sweep-lateral)")
    if args.scheduler is not None and not (args.sweep_fixation or args.sweep_lateral):
        raise TactipError("--scheduler runs a sweep on a Dask cluster: it needs --sweep-fixation or --sweep-lateral")
    _check_baseline_options(args)
    # An output written over the model or the taps would destroy what it was computed from.
    refuse_overwriting_inputs([args.json, args.plot, _reliability_path(args.plot)],
                              [args.model, args.test, *args.compare, *([args.train] if args.train else [])])
    model = load_model(args.model)
    _check_one_location(model, args)
    _check_fixation(model, args.fixation)
    test = load_dataset(args.test)
    train = load_dataset(args.train) if args.baselines else None
    thresholds = sorted({t for group in args.thresholds for t in group}) if args.thresholds else DEFAULT_THRESHOLDS
    if args.baselines:   # the decisions held against the baselines
        thresholds = sorted({*thresholds, KEEP_THRESHOLD})
    if args.sweep_fixation:
        thresholds = _deciding_thresholds(model, thresholds)
    # Peak memory of the runs stepping together: beliefs and their temporaries, then one result per threshold.
    check_memory(args.runs * (6 * 8 * model.n_classes + 64 * len(thresholds)),
                 what=f"{args.runs} Monte Carlo runs of {model.n_classes} classes", hint="use fewer --runs")
    environment = VirtualEnvironment(model, test)
    options = dict(thresholds=thresholds, runs=args.runs, max_taps=args.max_taps, deadline=args.deadline,
                   move_threshold=args.move_threshold, shift_mode=args.shift or model.shift_mode, seed=args.seed)
    print(model.summary())
    print(f"test: {len(test)} taps; {args.runs} runs per curve")
    with contextlib.ExitStack() as stack:
        if args.scheduler is not None:  # the sweep's pieces on the cluster, with its own progress bar
            from tactip.cluster import cluster_map, open_client

            what = "fixation" if args.sweep_fixation else "sigma"
            client = stack.enter_context(open_client(args.scheduler))
            options["map_fn"] = cluster_map(client, progress=functools.partial(
                tqdm, desc=f"{what}s on {args.scheduler}", unit=what, disable=args.quiet))
        rows = _validate(args, model, test, train, environment, options, tqdm)
    if args.json:
        inputs = [args.model, args.test, *args.compare, *([args.train] if args.train else [])]
        write_json(args.json, rows, inputs=inputs)
        if str(args.json) != "-":
            print(f"wrote {args.json}")
    if args.plot:
        print(f"wrote {args.plot}")
    return 0


def _validate(args, model, test, train, environment, options, tqdm) -> list[dict]:
    """The sweep asked for (`_sweep_fixation`, the lateral sweep), else the policy comparison; the JSON rows."""
    if args.sweep_fixation:
        return _sweep_fixation(args, model, test, options, tqdm)
    if not args.sweep_lateral:
        return _compare(args, model, environment, options, test, tqdm, train)
    from perception import lateral_sweep, make_policy

    name = args.policy or "active"
    policy = make_policy(name, fixation_class=model.fixation_class(args.fixation))
    progress = functools.partial(tqdm, desc="sigmas", unit="sigma", disable=args.quiet)
    sweep = lateral_sweep(environment, policy, sigmas=args.sweep_lateral, tap_budget=args.tap_budget,
                          progress=progress, **options)
    print(f"{name} policy; best error within {args.tap_budget:g} mean taps")
    print(f"{'sigma':>8} {'error':>8} {'ratio':>6}")
    for sigma, error, ratio in zip(sweep.sigmas, sweep.errors, sweep.ratio):
        print(f"{sigma:>8.3g} {error:>8.3f} {ratio:>6.2f}")
    rows = with_label_error(model, [{**row, "sigma": float(s)} for s, r in zip(sweep.sigmas, sweep.results)
                                    for row in r.rows()])
    if args.plot:
        from perception.plots import plot_lateral_sweep

        plot_lateral_sweep(sweep, args.plot)
    return rows


def _reliability_path(plot):
    """Where the reliability diagram goes: beside --plot, ``NAME_reliability.SUFFIX``."""
    if plot is None:
        return None
    plot = pathlib.Path(plot)
    return plot.with_name(f"{plot.stem}_reliability{plot.suffix}")


def _compare(args, model, environment, options, test, tqdm, train=None) -> list[dict]:
    """Speed-accuracy of each policy and the calibration of the active policy, for each model; returns JSON rows."""
    from perception import (CALIBRATION_TAPS, VirtualEnvironment, compare_policies, load_model, make_policy,
                            trace_beliefs)

    from tactip.cli._validate_report import describe_label, print_rows, report_baselines

    unit = model.location_unit
    models = {args.model: model}
    environments = {args.model: environment}
    for path in args.compare:
        other = load_model(path)
        _check_same_classes(model, other, path)
        models[path] = other
        environments[path] = VirtualEnvironment(other, test)
    names = {path: _model_name(path, m, models) for path, m in models.items()}
    one_location = model.n_locations == 1
    if one_location:   # nowhere to move: every policy is the stationary one
        policy_names = ["stationary"]
        asked = f" (--policy {args.policy})" if args.policy and args.policy != "stationary" else ""
        print(f"one location class: the sensor never moves, so every policy is the same; shown as stationary{asked}")
    else:
        policy_names = [args.policy] if args.policy else sorted(POLICIES)
    fixation_class = model.fixation_class(args.fixation)
    if "active" in policy_names:
        print(f"active fixation: {model.location_centres[fixation_class]:g} {unit}")
    print(describe_label(model))
    rows, curves, traces, results = [], {}, {}, {}
    for path, m in models.items():
        policies = [make_policy(name, fixation_class=fixation_class) for name in policy_names]
        progress = functools.partial(tqdm, desc="policies", unit="policy", disable=args.quiet)
        results[path] = compare_policies(environments[path], policies, progress=progress, **options)
        if len(models) > 1:
            print(f"model {names[path]}: {m.summary()}")
        model_rows = with_label_error(m, [{**row, "model": names[path]} for result in results[path].values()
                                          for row in result.rows()])
        print_rows(m, model_rows)
        rows += model_rows
        for policy, result in results[path].items():
            curves[f"{names[path]} {policy}" if len(models) > 1 else policy] = result
        traces[names[path]] = trace_beliefs(environments[path], make_policy("active", fixation_class=fixation_class),
                                            runs=options["runs"], max_taps=options["max_taps"], seed=options["seed"],
                                            move_threshold=options["move_threshold"], shift_mode=options["shift_mode"])
    taps = [t for t in CALIBRATION_TAPS if t <= args.max_taps]
    what = "identity" if model.n_identities > 1 else "location"
    policy = "" if one_location else ", active policy"
    print(f"calibration of the {what} belief{policy} ({options['runs']} runs): expected calibration error "
          f"(0 = a belief of p is right a fraction p of the time)")
    print(f"{'model':<24} " + " ".join(f"{f'{t} tap' + ('s' if t > 1 else ''):>8}" for t in taps))
    for name, trace in traces.items():
        print(f"{name:<24} " + " ".join(f"{trace.calibration_error(t):>8.3f}" for t in taps))
    for row in rows:
        trace = traces[row["model"]]
        row.update({f"ece_{t}_taps": trace.calibration_error(t) for t in taps})
    if train is not None:
        held = "active" if "active" in policy_names else policy_names[0]
        rows += report_baselines(args, model, train, test, models, names, environments, results, held)
    if args.plot:
        from perception.plots import plot_reliability, plot_speed_accuracy

        plot_speed_accuracy(curves, args.plot, units=model.identity_unit if model.n_identities > 1 else unit)
        plot_reliability(traces, _reliability_path(args.plot), taps=taps)
        print(f"wrote {_reliability_path(args.plot)}")
    return rows


def _model_name(path, model, models) -> str:
    """The model's kind, or its file name when two models share a kind."""
    kinds = [m.KIND for m in models.values()]
    return model.KIND if kinds.count(model.KIND) == 1 else pathlib.Path(path).name


def _check_same_classes(model, other, path) -> None:
    """--compare models must share the class grid, so the runs are the same."""
    import numpy as np

    from tactip.errors import TactipError

    if other.n_locations != model.n_locations or not np.allclose(other.identities, model.identities) or \
            not np.allclose(other.location_edges, model.location_edges):
        raise TactipError(f"--compare {path}: its classes ({other.n_locations} locations x {other.n_identities} "
                          f"identities) differ from {model.n_locations} x {model.n_identities}; train it on the same "
                          f"collection with the same --locations")


def _sweep_fixation(args, model, test, options, tqdm) -> list[dict]:
    """--sweep-fixation: `calibration.recommend_fixation` writes the best fixation and threshold; its table."""
    from calibration import recommend_fixation

    progress = functools.partial(tqdm, desc="fixations", unit="fixation", disable=args.quiet)
    unit, identity_unit = model.location_unit, model.identity_unit
    sweep_options = {k: options[k] for k in ("move_threshold", "shift_mode", "map_fn") if k in options}
    if args.target_accuracy is None:
        sweep_options.update(thresholds=options["thresholds"], deadline=options["deadline"])
    model, sweep = recommend_fixation(args.model, args.test, runs=args.runs, tap_budget=args.tap_budget,
                                      seed=args.seed, progress=progress, log=lambda line: None,
                                      target_accuracy=args.target_accuracy, tolerance=args.tolerance,
                                      max_taps=args.max_taps, fall_back=False, report=_print_sweep(args, model),
                                      model=model, test=test, **sweep_options)
    fixation, threshold = model.recommended["fixation_location"], model.recommended["decision_threshold"]
    if args.target_accuracy is None:
        print(f"best fixation {fixation:g} {unit} (threshold {threshold:g}, error "
              f"{sweep.errors[sweep.best]:.3f} in {sweep.taps[sweep.best]:.1f} taps); written to {args.model}")
        if args.plot:
            from perception.plots import plot_fixation_sweep

            plot_fixation_sweep(sweep, args.plot, units=unit)
        return with_label_error(model, [{**row, "fixation": float(f)} for f, r in zip(sweep.fixations, sweep.results)
                                        for row in r.rows()])
    best = sweep.best
    tempering = "" if not sweep.tap_tempering else (
        f", tap tempering g1..g{len(sweep.tap_tempering)} " + ", ".join(f"{g:.3g}" for g in sweep.tap_tempering)
        + " for the beliefs after taps 1, 2, ...")
    print(f"best fixation {fixation:g} {unit} (threshold {threshold:g}: {sweep.accuracy[best]:.3f} within "
          f"{args.tolerance:g} {identity_unit} in {sweep.taps[best]:.1f} taps{tempering}); written to {args.model}")
    if args.plot:
        from perception.plots import plot_accuracy_sweep

        plot_accuracy_sweep(sweep, args.plot, units=unit)
    return [{"fixation": float(f), "threshold": float(t), "mean_taps": float(n), "accuracy_within_tolerance": float(a),
             "tap_tempering": list(sweep.tap_tempering) if i == sweep.best else [], "tolerance": args.tolerance,
             "target_accuracy": args.target_accuracy}
            for i, (f, t, n, a) in enumerate(zip(sweep.fixations, sweep.thresholds, sweep.taps, sweep.accuracy))]


def _print_sweep(args, model):
    """The table of a fixation sweep, printed before anything is decided (`recommend_fixation`'s report)."""
    def report(sweep) -> None:
        if args.target_accuracy is None:
            print(f"{'fixation':>10} {'error':>8} {'taps':>6} {'threshold':>9}")
            for fixation, error, taps, threshold in zip(sweep.fixations, sweep.errors, sweep.taps, sweep.thresholds):
                print(f"{fixation:>10.3f} {error:>8.3f} {taps:>6.2f} {threshold:>9.4g}")
            return
        print(f"decisions within {args.tolerance:g} {model.identity_unit} in {100 * args.target_accuracy:g} % of runs:")
        print(f"{'fixation':>10} {'threshold':>9} {'taps':>6} {'accuracy':>8}")
        for k, (fixation, threshold, taps, accuracy) in enumerate(zip(sweep.fixations, sweep.thresholds, sweep.taps,
                                                                      sweep.accuracy)):
            shown = "-" if not threshold == threshold else f"{threshold:.4g}"
            tempered = ""
            if k == sweep.best and sweep.tap_tempering:
                tempered = "  (tap tempering " + ", ".join(f"{g:.3g}" for g in sweep.tap_tempering) + ")"
            print(f"{fixation:>10.3f} {shown:>9} {taps:>6.2f} {accuracy:>8.3f}{tempered}")

    return report


def _check_baseline_options(args) -> None:
    """--baselines needs --train (the model's training taps), a different file from the test taps."""
    from tactip.errors import TactipError

    if args.train and not args.baselines:
        raise TactipError("--train is only read by --baselines (the baselines are fitted on it)")
    if not args.baselines:
        return
    if args.sweep_fixation or args.sweep_lateral:
        raise TactipError("--baselines works with the policy comparison only (not with --sweep-fixation or "
                          "--sweep-lateral)")
    if not args.train:
        raise TactipError("--baselines needs --train TRAIN.h5, the dataset the model was trained on (the model file "
                          "does not hold its taps)")
    if pathlib.Path(args.train).resolve() == pathlib.Path(args.test).resolve():
        raise TactipError(f"--train {args.train} is the test dataset: the baselines must be fitted on the training "
                          f"taps and scored on other taps")


def _check_one_location(model, args) -> None:
    """A model with one location class has no fixation to give or sweep."""
    from tactip.errors import TactipError

    if model.n_locations > 1:
        return
    if args.sweep_fixation:
        raise TactipError("--sweep-fixation: nothing to sweep, the model has one location class (the sensor never "
                          "moves); validate without it and read the threshold off the table")
    if args.fixation is not None:
        raise TactipError(f"--fixation {args.fixation:g}: the model has one location class, so there is no fixation "
                          f"to choose; leave --fixation out")


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
