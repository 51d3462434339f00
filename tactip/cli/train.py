"""Train a perception model from a tap dataset.

The model is a histogram likelihood over joint (location, identity) classes: the taps'
locations (e.g. depth, mm) are split into --locations equal classes over their range, each
distinct identity (e.g. gap width, mm) is a class, and each sensor dimension is binned into
--bins equal intervals over its training range (papers 000 and 002). Use a dataset collected
separately from the one you validate with (tactip validate).

Example:
  tactip train data/train.h5 --out models/gaps.h5 --locations 11
"""

from __future__ import annotations

import argparse

from tactip.cli._types import int_at_least, int_in_range, output_file, positive_float

HELP = "train a perception model (histogram likelihood) from a tap dataset"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the parser of ``tactip train``."""
    parser.add_argument("dataset", metavar="DATASET.h5", help="training taps (tactip-dataset/1 HDF5)")
    parser.add_argument("--out", type=output_file, required=True, metavar="MODEL.h5", help="model file to write (tactip-model/1 HDF5)")
    parser.add_argument("--locations", type=int_in_range(1, 1000), default=11, metavar="N",
                        help="equal location classes over the training range, 1..1000 (default 11; "
                             "a dataset with one location gets one class)")
    parser.add_argument("--bins", type=int_in_range(2, 10_000), default=100, metavar="N",
                        help="value bins per sensor dimension, 2..10000 (default 100)")
    parser.add_argument("--epsilon", type=positive_float, default=None,
                        help="count added to every histogram bin (default 1e-3)")
    parser.add_argument("--min-taps", type=int_at_least(1), default=1, metavar="N",
                        help="fewest training taps a class may have (default 1)")


def run(args: argparse.Namespace) -> int:
    """Load the dataset, fit the model, write it and print a summary."""
    import math

    from perception import fit_model, load_dataset, save_model
    from tactip._output import refuse_overwriting_inputs
    from tactip.cli._types import check_memory
    from tactip.errors import TactipError

    if args.epsilon is not None and not math.isfinite(args.epsilon):
        raise TactipError(f"--epsilon must be a finite number > 0, got {args.epsilon}")
    refuse_overwriting_inputs([args.out], [args.dataset])
    dataset = load_dataset(args.dataset)
    print(dataset.describe())
    identities = len(set(dataset.identity.tolist()))  # the histograms: dims x bins x classes, float32, and a copy
    check_memory(8.0 * dataset.taps.shape[2] * args.bins * args.locations * identities,
                 what=f"histograms of {args.locations} x {identities} classes x {args.bins} bins",
                 hint="use fewer --locations or --bins")
    options = {} if args.epsilon is None else {"epsilon": args.epsilon}
    model = fit_model(dataset, n_locations=args.locations, bins=args.bins, min_taps_per_class=args.min_taps,
                      **options)
    save_model(args.out, model, inputs=[args.dataset])
    counts = model.taps_per_class
    print(model.summary())
    print(f"training taps per class: {counts.min()}..{counts.max()}; location class width "
          f"{model.class_width:g} {model.location_unit}")
    print(f"wrote {args.out}")
    return 0
