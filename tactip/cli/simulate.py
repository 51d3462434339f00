"""Simulate sensor data collections for training and validating perception models.

  tactip simulate taxel --sensor fingertip|skin --out DIR [--seed S]
      A capacitive iCub taxel sensor on a Cartesian robot taps an object at evenly spaced
      locations over its range, as in paper 000: the 12-taxel fingertip taps an 8 mm rod over
      30 mm (3000 taps), the 48-taxel skin taps an 8 mm sphere over 50 mm (5000 taps). Each tap
      is 50 samples (1 s at 50 Hz) of 8-bit readings, high-pass filtered and normalised. The
      whole collection is done twice with independent noise: DIR/train.h5 and DIR/test.h5
      (tactip-dataset/1, front end "taxel", location in mm, one identity). With --csv the raw
      readings of the test collection are also written to DIR/test_stream.csv.

  tactip simulate taxel --stimulus rods|textures|edge --out DIR [--seed S]
      The fingertip taps the stimulus of paper 001 (rods of 4-12 mm across a 16 mm sweep, 320
      taps per rod), 003 (ten abrasive papers over 0-3 mm of depth, 150 taps per texture) or
      004 (an edge at 72 angles over 18 mm, 90 taps per angle) in two sessions (train, test)
      that differ as the papers' collections did (tactip.reproduce.stimuli documents the physics).
      The identity is the rod diameter (mm), the texture class (0 = p60 .. 9 = p800) or the
      edge angle (deg). --locations sets the taps per identity.

Example:
  tactip simulate taxel --sensor fingertip --out data/fingertip --seed 1
  tactip train data/fingertip/train.h5 --out data/fingertip/model.h5 --locations 300
  tactip validate data/fingertip/model.h5 data/fingertip/test.h5 --fixation 15 --shift uniform --thresholds 0.005 0.01 0.05
(With 300 classes a single tap leaves a flat belief, so the thresholds that decide in about
2 taps are small; paper 000 Table II compares policies at a mean of 2 taps.)
"""

from __future__ import annotations

import argparse

from _shared.ranges import MAX_TAXEL_TAPS
from tactip.cli._types import int_in_range, output_folder, seed

#: Most taps per collection (the taxel collection's own limit).
MAX_TAPS = MAX_TAXEL_TAPS

HELP = "simulate training and test datasets (taxel: iCub fingertip or skin, paper 000)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the parser of ``tactip simulate`` with its ``taxel`` subcommand."""
    from tactip.taxel.sensors import TAXEL_SENSORS

    sub = parser.add_subparsers(dest="simulate_command", metavar="KIND")
    sub.required = True
    taxel = sub.add_parser(
        "taxel", help="capacitive taxel sensor tapping along its location range (train.h5 + test.h5)",
        description="Simulate the two data collections of paper 000 with a capacitive iCub taxel sensor "
                    "(fingertip: 12 taxels, rod, 30 mm; skin: 48 taxels, sphere, 50 mm) and write "
                    "DIR/train.h5 and DIR/test.h5.\n\nExample:\n  tactip simulate taxel --sensor fingertip "
                    "--out data/fingertip --seed 1",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    taxel.add_argument("--sensor", choices=TAXEL_SENSORS, default="fingertip",
                       help="which sensor (default fingertip)")
    taxel.add_argument("--out", type=output_folder, required=True, metavar="DIR", help="folder for train.h5 and test.h5 (created)")
    taxel.add_argument("--seed", type=seed, default=0, metavar="S",
                       help="seed of the simulated sensor and its noise, >= 0 (default 0)")
    taxel.add_argument("--locations", type=int_in_range(2, MAX_TAPS), default=None, metavar="N",
                       help=f"evenly spaced tap locations per collection, 2..{MAX_TAPS} (default: the paper's "
                            f"0.01 mm steps, 3000 for the fingertip, 5000 for the skin)")
    taxel.add_argument("--taps-per-location", type=int_in_range(1, MAX_TAPS // 2), default=1, metavar="N",
                       help="taps at each location (default 1); locations x taps at most "
                            f"{MAX_TAPS} per collection")
    taxel.add_argument("--stimulus", choices=("rod", "rods", "textures", "edge"), default="rod",
                       help="rod: paper 000's 8 mm rod or sphere (default); rods: paper 001; textures: 003; edge: 004")
    taxel.add_argument("--csv", action="store_true", help="also write the raw test stream to DIR/test_stream.csv")
    taxel.add_argument("--overwrite", action="store_true", help="replace DIR/train.h5 and DIR/test.h5 if they exist")


def run(args: argparse.Namespace) -> int:
    """Run ``tactip simulate taxel``."""
    from perception import load_dataset
    from tactip.errors import TactipError
    from tactip.taxel import simulate_taxel_datasets, write_taxel_test_stream
    from tactip.taxel.collect import DEFAULT_TAPS

    from tactip._output import refuse_replacing_project_files

    refuse_replacing_project_files([args.out / "train.h5", args.out / "test.h5"], overwrite=args.overwrite)
    if args.stimulus != "rod":
        return _run_stimulus(args)
    locations = DEFAULT_TAPS[args.sensor] if args.locations is None else args.locations
    if locations * args.taps_per_location > MAX_TAPS:
        raise TactipError(f"--locations {locations} x --taps-per-location {args.taps_per_location} = "
                          f"{locations * args.taps_per_location} taps per collection; at most {MAX_TAPS}")

    paths = simulate_taxel_datasets(args.out, sensor=args.sensor, seed=args.seed, locations=args.locations,
                                    taps_per_location=args.taps_per_location, quiet=args.quiet)
    for path in (paths.train, paths.test):
        print(f"wrote {path}: {load_dataset(path).describe()}")
    if args.csv:
        csv = write_taxel_test_stream(paths.test.parent / "test_stream.csv", sensor=args.sensor, seed=args.seed,
                                      locations=args.locations, taps_per_location=args.taps_per_location)
        print(f"wrote {csv}: raw 8-bit readings of the test collection")
    return 0


#: Taps per identity of each paper's collection (001: 320 per rod; 003: 150 per texture; 004: 90 per angle).
STIMULUS_TAPS = {"rods": 320, "textures": 150, "edge": 90}


def _run_stimulus(args: argparse.Namespace) -> int:
    """``tactip simulate taxel --stimulus rods|textures|edge``: the two sessions of papers 001, 003, 004."""
    from perception import save_dataset
    from tactip.errors import TactipError
    from tactip.taxel.collect import simulate_stimulus_dataset
    from tactip.reproduce.stimuli import make_stimulus

    if args.sensor != "fingertip" or args.csv or args.taps_per_location != 1:
        raise TactipError(f"--stimulus {args.stimulus} is tapped by the fingertip, one tap per location: "
                          "drop --sensor skin, --csv and --taps-per-location")
    stimulus = make_stimulus(args.stimulus)
    taps = STIMULUS_TAPS[args.stimulus] if args.locations is None else args.locations
    if taps * len(stimulus.identities) > MAX_TAPS:
        raise TactipError(f"--locations {taps} x {len(stimulus.identities)} identities is more than {MAX_TAPS} taps")
    args.out.mkdir(parents=True, exist_ok=True)
    for name in ("train", "test"):
        dataset = simulate_stimulus_dataset(stimulus, seed=args.seed, collection=name, taps_per_identity=taps)
        path = args.out / f"{name}.h5"
        save_dataset(path, dataset)
        print(f"wrote {path}: {dataset.describe()}")
    return 0
