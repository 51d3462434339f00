"""Collect the training and test taps by the station's protocol (paper 002 III-A.2).

For each gap of the configuration, taps over the depth range at the step ([protocol] depth_min,
depth_max, depth_step; repeats; optional lateral jitter), twice: DIR/train.h5 and DIR/test.h5,
two independent collections in the tactip-dataset/1 format. Each tap is appended as it is taken,
so a crash or Ctrl-C loses at most the tap in progress; rerun the same command to resume.
Needs a calibration ('tactip calibrate'). Then: tactip train DIR/train.h5 --out MODEL.h5 and
tactip validate MODEL.h5 DIR/test.h5 --sweep-fixation.

Examples:
  tactip collect --config samples/station_sim.toml --out station_data/sim/datasets
"""

from __future__ import annotations

import argparse
from pathlib import Path

from tactip.cli._types import output_folder, worker_count

HELP = "collect training and test taps over every gap and depth (resumable)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the parser for `tactip collect`."""
    parser.add_argument("--config", type=Path, required=True, help="station TOML file")
    parser.add_argument("--out", type=output_folder, required=True, metavar="DIR", help="folder for train.h5 and test.h5")
    parser.add_argument("--workers", type=worker_count, default=None,
                        help="processes rendering taps on the simulated station, 1..4 x CPU count "
                             "(default: CPU count, at most 4)")


def run(args: argparse.Namespace) -> int:
    """Run `tactip collect`."""
    from tactip.station.config import load_station_config
    from tactip.station.procedures import collect_station

    paths = collect_station(load_station_config(args.config), args.out, progress=not args.quiet,
                            workers=args.workers)
    for name, path in paths.items():
        print(f"{name}: {path}")
    return 0
