"""Reproduce a paper's experiment on the simulated sensor and print its figures beside the paper's.

PAPER is 000 (tactile hyperacuity: Table II on the simulated fingertip), 001 (rod shape and
position with a 'boredom' deadline), 003 (texture under depth uncertainty, passive / weakly /
strongly active) or 004 (edge angle and position, contour following, adaptive prior). Paper 002
(the inspection station) is reproduced by bench/bench_station.py. Each simulated world was tuned
against the paper's first figure only; the other figures are predictions. --quick runs the same
experiment with fewer runs and conditions (seconds to a minute); the full run takes minutes.

Examples:
  tactip reproduce 001 --json results/001.json
  tactip reproduce 004 --quick --json > out/004.json
"""

from __future__ import annotations

import argparse

from tactip.cli._types import add_json_argument, seed

HELP = "run a paper's experiment (000, 001, 003, 004) on the simulator, figures beside the paper's"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the parser of ``tactip reproduce``."""
    parser.add_argument("paper", choices=("000", "001", "002", "003", "004"), metavar="PAPER",
                        help="paper number: 000, 001, 003 or 004 (002: bench/bench_station.py)")
    add_json_argument(parser, "the rows of the paper's figures")
    parser.add_argument("--quick", action="store_true", help="fewer runs and conditions (for a quick look and tests)")
    parser.add_argument("--seed", type=seed, default=0, help="seed of the simulated sensor and runs, >= 0 (default 0)")


def run(args: argparse.Namespace) -> int:
    """Run the reproduction, print the report, write the JSON rows."""
    import functools

    from _shared.progress import progress_bar
    from tactip._output import write_json
    from tactip.errors import TactipError
    from tactip.reproduce import reproduce

    if args.paper == "002":
        raise TactipError("paper 002 runs on the simulated inspection station: python bench/bench_station.py "
                          "(choose 000, 001, 003 or 004 here)")
    progress = functools.partial(progress_bar, desc=f"paper {args.paper}", unit="condition", disable=args.quiet,
                                 leave=False)
    report = reproduce(args.paper, quick=args.quick, seed=args.seed, progress=progress)
    print(report.text())
    if args.json is not None:
        write_json(args.json, report.json_rows())
        if str(args.json) != "-":
            print(f"wrote {len(report.rows)} rows to {args.json}")
    return 0
