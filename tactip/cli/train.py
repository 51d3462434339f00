"""Train a perception model from a tap dataset.

The model gives the likelihood of a tap for every joint (location, identity) class: the taps'
locations (e.g. depth, mm) are split into --locations equal classes over their range, and each
distinct identity (e.g. gap width, mm) is a class (papers 000 and 002). --model picks the kind:

  histogram             the papers' model: each sensor dimension binned into --bins intervals,
                        mean log probability over samples and dimensions (reproduces the papers)
  calibrated-histogram  the same counts, tempered by a factor fitted by cross-validation over the
                        training taps so that a one-tap belief is calibrated
  gaussian              class-conditional Gaussians with a shared covariance on whitened principal
                        components of the tap (correlations between pins and samples), tempered
                        the same way; the station's default
  torch                 an ensemble of five small networks over the tap (every value, one pooled
                        scale -> 64 ReLU units -> the classes), each early-stopped on held-out
                        taps, the ensemble tempered the same way; trains on every core (large
                        taps; small networks on one); --epochs caps each network's training
                        (default 100); needs torch (pip install torch==2.13.0, the CPU build; or
                        tactip[learned])

The calibrated kinds need at least two taps per class, ideally repeated at the same locations
([protocol] repeats = 2). Use a dataset collected separately from the one you validate with
(tactip validate).

--choose-fixation also picks the fixation location, the decision threshold and (calibrated kinds)
the tap tempering g1..g5 for taps 1-5, as the station does on its first run, without looking at the test set:
the training taps are held out in 4 folds, each scored by a model fitted on the others, and the
settings are chosen on those out-of-fold scores; a model fitted on every training tap is written with them. Then 'tactip validate
MODEL TEST' gives figures the settings were not chosen on.

Examples:
  tactip train data/train.h5 --out models/gaps.h5 --locations 11
  tactip train data/train.h5 --out models/gaps.h5 --model gaussian
  tactip train data/train.h5 --out models/gaps.h5 --model torch
  tactip train data/train.h5 --out models/quick.h5 --model torch --epochs 30   # a quicker, rougher network
  tactip train data/train.h5 --out models/gaps.h5 --model gaussian --choose-fixation --target-accuracy 0.95 --tolerance 0.25
"""

from __future__ import annotations

import argparse

from _shared.ranges import MAX_BINS, MAX_LOCATIONS
from perception.choices import MODEL_KINDS
from tactip.cli._types import fraction, int_at_least, int_in_range, non_negative_float, output_file, positive_float

HELP = "train a perception model (histogram, calibrated histogram, gaussian, torch) from a tap dataset"
#: --epochs: the torch model's own default (`perception.learned.fit_torch`'s ``max_epochs``) and the most allowed.
DEFAULT_EPOCHS, MAX_EPOCHS = 100, 10000


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the parser of ``tactip train``."""
    parser.add_argument("dataset", metavar="DATASET.h5", help="training taps (tactip-dataset/1 HDF5)")
    parser.add_argument("--out", type=output_file, required=True, metavar="MODEL.h5", help="model file to write (tactip-model/1 HDF5)")
    parser.add_argument("--model", choices=MODEL_KINDS, default="histogram",
                        help="kind of likelihood model (default histogram, the papers' model)")
    parser.add_argument("--locations", type=int_in_range(1, MAX_LOCATIONS), default=11, metavar="N",
                        help="equal location classes over the training range, 1..1000 (default 11; "
                             "a dataset with one location gets one class)")
    parser.add_argument("--bins", type=int_in_range(2, MAX_BINS), default=None, metavar="N",
                        help="value bins per sensor dimension, 2..10000, histogram kinds (default 100)")
    parser.add_argument("--epsilon", type=positive_float, default=None,
                        help="count added to every histogram bin, histogram kinds (default 1e-3)")
    parser.add_argument("--epochs", type=int_in_range(1, MAX_EPOCHS), default=None, metavar="N",
                        help=f"torch model: most epochs each network trains, 1..{MAX_EPOCHS} (early stopping on "
                             f"held-out taps may stop sooner; default {DEFAULT_EPOCHS}); fewer trains faster, "
                             f"and may fit worse")
    parser.add_argument("--min-taps", type=int_at_least(1), default=1, metavar="N",
                        help="fewest training taps a class may have (default 1)")
    parser.add_argument("--choose-fixation", action="store_true",
                        help="also choose the fixation, threshold and tempering on the training taps, each held "
                             "out in 4 folds and scored by a model fitted on the others (never the test set), "
                             "and write them into the model (which is fold 0's)")
    parser.add_argument("--target-accuracy", type=fraction, metavar="P",
                        help="with --choose-fixation: the threshold reaching this fraction of decisions within "
                             "--tolerance in the fewest taps (default: the lowest error within 12 taps)")
    parser.add_argument("--tolerance", type=non_negative_float, default=0.0, metavar="U",
                        help="with --target-accuracy: largest |decided - true| identity counted right, identity "
                             "units (default 0: the exact class)")


def run(args: argparse.Namespace) -> int:
    """Load the dataset, fit the model, write it and print a summary."""
    import math

    from perception import load_dataset, save_model, train_model
    from tactip._output import refuse_overwriting_inputs
    from tactip.cli._types import check_memory
    from tactip.errors import TactipError

    from perception.histogram import MAX_EPSILON

    if args.epsilon is not None and not (math.isfinite(args.epsilon) and args.epsilon <= MAX_EPSILON):
        raise TactipError(f"--epsilon must be a number in (0, {MAX_EPSILON:g}] (a count added to every bin; more "
                          f"drowns the taps' counts), got {args.epsilon:g}")
    if "histogram" not in args.model:
        given = [flag for flag, value in (("--bins", args.bins), ("--epsilon", args.epsilon)) if value is not None]
        if given:
            raise TactipError(f"{' and '.join(given)} set{'s' if len(given) == 1 else ''} the histograms of the "
                              f"histogram kinds; a {args.model} model has none (leave {' and '.join(given)} out)")
    args.bins = 100 if args.bins is None else args.bins
    if not args.choose_fixation and (args.target_accuracy is not None or args.tolerance):
        raise TactipError("--target-accuracy and --tolerance go with --choose-fixation")
    if args.target_accuracy == 0:
        raise TactipError("--target-accuracy must be in (0, 1], got 0")
    if args.epochs is not None and args.model != "torch":
        raise TactipError(f"--epochs sets how long the torch model's networks train; a {args.model} model has none "
                          f"(leave --epochs out)")
    refuse_overwriting_inputs([args.out], [args.dataset])
    dataset = load_dataset(args.dataset)
    print(dataset.describe())
    identities = len(set(dataset.identity.tolist()))  # the histograms: dims x bins x classes, float32, and a copy
    check_memory(8.0 * dataset.taps.shape[2] * args.bins * args.locations * identities,
                 what=f"histograms of {args.locations} x {identities} classes x {args.bins} bins",
                 hint="use fewer --locations or --bins")
    options = {} if args.epsilon is None else {"epsilon": args.epsilon}
    if args.epochs is not None:   # the torch model's own option (`perception.train_model`), as in its folds
        options["max_epochs"] = args.epochs
    if args.model == "torch":
        _require_torch()
        values = dataset.taps.shape[1] * dataset.taps.shape[2]   # the imputation Gaussian's covariance, and copies
        check_memory(8.0 * (3 * values ** 2 + 4 * len(dataset) * values),
                     what=f"the torch model's imputation Gaussian over {values} values per tap",
                     hint="use fewer feature pins or samples per tap")
    import warnings

    with warnings.catch_warnings(record=True) as caught:  # e.g. a pin never seen in some class: said in one line
        warnings.simplefilter("always", UserWarning)
        if args.choose_fixation:
            model = _choose_fixation(args, dataset, {**options, "min_taps_per_class": args.min_taps})
        else:
            model = train_model(dataset, kind=args.model, n_locations=args.locations, bins=args.bins,
                                min_taps_per_class=args.min_taps, **options)
    for warning in {str(w.message): w for w in caught}.values():
        print(f"warning: {warning.message}")
    save_model(args.out, model, inputs=[args.dataset])
    counts = model.taps_per_class
    print(model.summary())
    print(f"training taps per class: {counts.min()}..{counts.max()}; location class width "
          f"{model.class_width:g} {model.location_unit}")
    print(f"wrote {args.out}")
    return 0


def _choose_fixation(args, dataset, options):
    """--choose-fixation: a model fitted on most training taps, its settings chosen on the others."""
    import functools

    from _shared.progress import progress_bar
    from calibration import CalibrationError, fit_with_fixation
    from perception.errors import DatasetError, ModelError

    from tactip.errors import TactipError

    try:
        return fit_with_fixation(dataset, kind=args.model, n_locations=args.locations, bins=args.bins,
                                 target_accuracy=args.target_accuracy, tolerance=args.tolerance, fall_back=False,
                                 progress=None if args.quiet else functools.partial(progress_bar, leave=False,
                                                                                    desc="fixations"),
                                 **options)
    except (CalibrationError, DatasetError, ModelError) as exc:  # e.g. a class without taps in the split
        raise TactipError(f"--choose-fixation: {exc}") from None


def _require_torch() -> None:
    """Refuse --model torch, in one line, when torch is not installed."""
    from perception.learned import require_torch
    from tactip.errors import TactipError

    try:
        require_torch()
    except ImportError as exc:
        raise TactipError(f"--model torch: {exc}") from None
