"""Reproduce a paper's experiment on the simulated sensor and print its figures beside the paper's.

PAPER is 000 (tactile hyperacuity: Table II on the simulated fingertip), 001 (rod shape and
position with a 'boredom' deadline), 002 (the inspection station: gap width by active, random and
stationary perception, Fig. 9), 003 (texture under depth uncertainty, passive / weakly / strongly
active) or 004 (edge angle and position, contour following, adaptive prior). Each simulated world was
tuned against one figure of its paper (the report says which: a fit, not a prediction); the other
figures are predictions. --quick runs the same
experiment with fewer runs and conditions (seconds to a minute); the full run takes minutes.
With --scheduler tcp://HOST:PORT the conditions (003: the simulator seeds; 001: the deadlines; 004:
the methods and thresholds; 000: the class counts) run on that Dask cluster: the same figures, seed
for seed, as a run here.

Examples:
  tactip reproduce 001 --json results/001.json
  tactip reproduce 004 --quick --json > out/004.json
  tactip reproduce 003 --scheduler tcp://10.0.0.5:8786
"""

from __future__ import annotations

import argparse

from tactip.cli._types import add_json_argument, seed

HELP = "run a paper's experiment (000-004) on the simulator, figures beside the paper's"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the parser of ``tactip reproduce``."""
    parser.add_argument("paper", choices=("000", "001", "002", "003", "004"), metavar="PAPER",
                        help="paper number: 000, 001, 002, 003 or 004")
    add_json_argument(parser, "the rows of the paper's figures")
    parser.add_argument("--quick", action="store_true", help="fewer runs and conditions (for a quick look and tests)")
    parser.add_argument("--seed", type=seed, default=0, help="seed of the simulated sensor and runs, >= 0 (default 0)")
    parser.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                        help="run the conditions on this Dask cluster (dask scheduler; dask worker on each machine)")


def run(args: argparse.Namespace) -> int:
    """Run the reproduction, print the report, write the JSON rows."""
    import contextlib
    import functools

    from _shared.progress import progress_bar
    from tactip._output import write_json
    from tactip.reproduce import reproduce

    progress = functools.partial(progress_bar, desc=f"paper {args.paper}", unit="condition", disable=args.quiet,
                                 leave=False)
    with contextlib.ExitStack() as stack:
        map_fn = None
        if args.scheduler is not None:
            from tactip.cluster import cluster_map, open_client

            map_fn = cluster_map(stack.enter_context(open_client(args.scheduler)), progress=progress)
        report = reproduce(args.paper, quick=args.quick, seed=args.seed, progress=progress, map_fn=map_fn)
    print(report.text())
    if args.json is not None:
        write_json(args.json, report.json_rows())
        if str(args.json) != "-":
            print(f"wrote {len(report.rows)} rows to {args.json}")
    return 0
