"""What ``tactip validate`` prints and writes about the label: its unit, whether it wraps, and the baselines.

The label is what a model decides: the identity (a gap width, a slide direction, a shape), or the
location of a model with a single identity. Every JSON row of the policy comparison carries
``mean_label_error`` in the label's unit (wrapped for a circular label; for a named label the
fraction of decisions wrong, so that every kind of label has one error to compare) and
``label_error_unit``. With ``--baselines`` the rows gain one row per baseline (``model:
"baseline-knn"`` ...; ``policy`` and ``threshold`` null, ``mean_taps`` 1) and one verdict row per
model (``check: "baselines"``, ``policy`` and ``threshold`` null too, so that a filter on them finds only
Monte Carlo rows) saying whether it earns its keep: ``one_tap_error``, ``best_baseline``,
``best_baseline_error``, ``one_tap_ratio``, ``worse_than_baseline``, and at ``held_threshold`` 0.9 with
``held_policy``: ``threshold_error``, ``threshold_mean_taps``, ``threshold_ratio``, ``well_below_baseline``.
"""

from __future__ import annotations

#: Decision threshold whose decisions are held against the best baseline's 1-tap error.
KEEP_THRESHOLD = 0.9


def label_error_unit(model) -> str:
    """Unit of ``mean_label_error``: the label's unit, or ``"fraction wrong"`` for a named label."""
    if model.n_identities > 1:
        return "fraction wrong" if model.identity_names else model.identity_unit
    return model.location_unit


def describe_label(model) -> str:
    """One line: what the label is, its unit and whether its errors wrap."""
    if model.n_identities <= 1:
        return f"label: the location, {model.location_unit} (the model has one identity)"
    if model.identity_names:
        return (f"label: {model.n_identities} named classes; error = fraction of decisions wrong "
                f"(1 - accuracy)")
    if model.identity_period is not None:
        return (f"label: {model.identity_unit}, circular: errors wrap at {model.identity_period:g} "
                f"{model.identity_unit} (the shorter way round)")
    return f"label: {model.identity_unit}, errors do not wrap"


def with_label_error(model, rows: list[dict]) -> list[dict]:
    """The Monte Carlo rows with ``mean_label_error`` and ``label_error_unit`` added."""
    key = "mean_identity_error" if model.n_identities > 1 else "mean_location_error"
    unit = label_error_unit(model)
    return [{**row, "mean_label_error": row[key], "label_error_unit": unit} for row in rows]


def print_rows(model, rows) -> None:
    """The speed-accuracy table; no location error for a one-location model (it is always 0)."""
    locations = model.n_locations > 1 and model.n_identities > 1
    unit = label_error_unit(model)
    error = "wrong" if model.identity_names and model.n_identities > 1 else f"error {unit}"
    print(f"{'policy':<11} {'threshold':>9} {'taps':>6} {error:>10} {'accuracy':>8}"
          + (f" {'loc error':>9}" if locations else ""))
    for row in rows:
        print(f"{row['policy']:<11} {row['threshold']:>9.4g} {row['mean_taps']:>6.2f} "
              f"{row['mean_label_error']:>10.3f} {row['accuracy']:>8.3f}"
              + (f" {row['mean_location_error']:>9.3f}" if locations else ""))


def report_baselines(args, model, train, test, models: dict, names: dict, environments: dict,
                     results: dict, policy: str) -> list[dict]:
    """Fit and print the baselines beside every model; returns their JSON rows and one verdict row per model.

    Parameters
    ----------
    args : argparse.Namespace
        ``train``, ``seed``.
    model : LikelihoodModel
        The first model (the baselines predict its label).
    train, test : Dataset
    models, names, environments : dict
        Path -> model, its shown name, its `VirtualEnvironment` on the test taps.
    results : dict
        Path -> policy -> `MonteCarloResult` of the policy comparison.
    policy : str
        The policy whose decisions at `KEEP_THRESHOLD` are held against the baselines.
    """
    from perception.baselines import THRESHOLD_RATIO, compare_baselines, keep_verdict, one_tap

    unit = label_error_unit(model)
    report = compare_baselines(model, train, test, seed=args.seed,
                               log_likelihood=environments[args.model].log_likelihood)
    print(f"baselines fitted on {args.train} ({len(train)} taps): features = the flattened taps ({test.samples} "
          f"samples x {test.dims} dims), NaN (unseen pins) imputed with the training mean, standardised; each decides "
          f"from 1 tap, on every one of the {len(test)} test taps, classes weighed equally")
    width = max(24, *(len(f"{n}, threshold {KEEP_THRESHOLD:g} ({policy})") for n in names.values()))
    print(f"{'model':<{width}} {'taps':>6} {f'error {unit}':>12} {'accuracy':>8}  settings")
    rows = []
    for baseline in report.baselines:
        settings = ", ".join(f"{k}={v:.3g}" if isinstance(v, float) else f"{k}={v}"
                             for k, v in baseline.settings.items())
        print(f"{'baseline-' + baseline.name:<{width}} {1:>6.2f} {baseline.error:>12.3f} {baseline.accuracy:>8.3f}  "
              f"{settings}")
        rows.append({"model": f"baseline-{baseline.name}", "policy": None, "threshold": None, "mean_taps": 1.0,
                     "accuracy": baseline.accuracy, "mean_label_error": baseline.error, "label_error_unit": unit,
                     "settings": baseline.settings, "train": str(args.train)})
    best = report.best
    verdicts = []
    for path, other in models.items():
        name = names[path]
        _, error, accuracy = (None, report.model_error, report.model_accuracy) if path == args.model else \
            one_tap(other, test, log_likelihood=environments[path].log_likelihood)
        result = results[path][policy]
        at = [k for k, t in enumerate(result.thresholds) if abs(t - KEEP_THRESHOLD) < 1e-12][0]
        label_errors = result.mean_identity_error if other.n_identities > 1 else result.mean_location_error
        held, taps = float(label_errors[at]), float(result.mean_taps[at])
        verdict = keep_verdict(error, best.error, held)
        print(f"{name + ', 1 tap':<{width}} {1:>6.2f} {error:>12.3f} {accuracy:>8.3f}  exact, from the flat prior")
        print(f"{f'{name}, threshold {KEEP_THRESHOLD:g} ({policy})':<{width}} {taps:>6.2f} {held:>12.3f} "
              f"{float(result.accuracy[at]):>8.3f}  {result.runs} Monte Carlo runs")
        verdicts.append(_verdict_lines(name, error, held, taps, best, verdict, unit, policy, THRESHOLD_RATIO))
        rows.append({"model": name, "check": "baselines", "policy": None, "threshold": None, "held_policy": policy,
                     "held_threshold": KEEP_THRESHOLD,
                     "one_tap_error": error, "one_tap_accuracy": accuracy, "best_baseline": f"baseline-{best.name}",
                     "best_baseline_error": best.error, "one_tap_ratio": verdict.one_tap_ratio,
                     "worse_than_baseline": verdict.worse_at_one_tap, "threshold_error": held,
                     "threshold_mean_taps": taps, "threshold_ratio": verdict.threshold_ratio,
                     "well_below_baseline": verdict.well_below_at_threshold, "label_error_unit": unit})
    for lines in verdicts:
        print("\n".join(lines))
    if any(row.get("worse_than_baseline") for row in rows):
        print("note: when training and test taps come from the same recordings (tactip dataset build --split "
              "alternate), a baseline may recognise the recording rather than the label; --split group keeps each "
              "recording on one side, the honest test of a new recording")
    return rows


def _verdict_lines(name, error, held, taps, best, verdict, unit, policy, ratio) -> list[str]:
    """Plain words: is the model worse than the best baseline at 1 tap, and well below it at the threshold?"""
    against = f"the best baseline's (baseline-{best.name}, {best.error:.3g} {unit})"
    at = f"at threshold {KEEP_THRESHOLD:g} ({policy}, {taps:.2f} taps)"
    if best.error == 0:   # nothing to be below: the model can only match an exact baseline
        lines = [f"{name}: exact at 1 tap, as is baseline-{best.name}" if error == 0 else
                 f"{name}: WORSE THAN BASELINE at 1 tap: error {error:.3g} {unit}, where baseline-{best.name} is exact"]
        lines.append(f"{name}: exact {at}" if held == 0 else
                     f"{name}: NOT WELL BELOW BASELINE {at}: error {held:.3g} {unit}, where baseline-{best.name} is "
                     f"exact at 1 tap")
        return lines
    lines = []
    if verdict.worse_at_one_tap:
        lines.append(f"{name}: WORSE THAN BASELINE at 1 tap: error {error:.3g} {unit} is "
                     f"{_times(verdict.one_tap_ratio)} {against}, more than 5 % above it")
    else:
        standing = "below it" if verdict.one_tap_ratio < 1 else "level with it" if verdict.one_tap_ratio == 1 else \
            "within 5 % of it"
        lines.append(f"{name}: at 1 tap, error {error:.3g} {unit} is {_times(verdict.one_tap_ratio)} {against}: "
                     f"{standing}")
    if verdict.well_below_at_threshold:
        lines.append(f"{name}: {at}, error {held:.3g} {unit} is {_times(verdict.threshold_ratio)} the best "
                     f"baseline's 1-tap error: well below it (bar {ratio:g}x)")
    else:
        lines.append(f"{name}: NOT WELL BELOW BASELINE {at}: error {held:.3g} {unit} is "
                     f"{_times(verdict.threshold_ratio)} the best baseline's 1-tap error (bar {ratio:g}x)")
    return lines


def _times(ratio: float) -> str:
    return "infinitely many times" if ratio == float("inf") else f"{ratio:.2f}x"
