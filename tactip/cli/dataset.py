"""Turn your own labelled recordings into tap datasets: a training set, a test set and their calibration.

  tactip dataset build LABELS.csv --out DIR
      LABELS.csv has a header with a 'path' column (a video, a folder of frames or an image, relative
      to the CSV) and label columns (--label COL picks one when there are several); optionally 'rest'
      (an image's rest image) and 'split' (train or test, for --split column).
      A video gives one tap per contact found (press or slide), each with its row's label; an image
      gives one tap: its pins' displacement from a rest image (--rest IMAGE or the 'rest' column).
      One calibration serves the whole set: the feature pins are chosen once, on the first rest frame,
      and found again in every recording, so taps of different recordings line up.
      Labels are numbers (--classes N bins them into N equal-width classes), names (each a class) or
      angles (--period 360: identities and errors wrap, and with --classes the bins wrap too,
      centred on 0, 360/N, ...). The label is the datasets' identity (what a model decides); the
      location is one constant.
      --split alternate (taps of each class alternate train/test), group (whole recordings on one side,
      balanced per class, --seed), or column (the CSV's split column).
      Writes DIR/calibration.h5, DIR/train.h5, DIR/test.h5 and DIR/summary.json (taps per class and
      split, feature pins seen, rows left out with their line numbers, warnings). A bad row (missing
      or unreadable file, empty label, a video without contact) is named and left out; nothing is
      written when nothing is left, and nothing half-written on an error or Ctrl-C. Existing outputs
      are kept unless --overwrite.
      Many recordings: --workers N replays them on an embedded Dask cluster of N worker processes, or
      --scheduler tcp://HOST:PORT on a running Dask cluster (as tactip replay --out-dir does); the
      datasets are the same as made one recording after another (the default).
      Many images: where torch sees a GPU (tactip[accel]; --device auto, the default) their pins are
      detected --together images at a time as tensors on the GPU (pins.accel_detect); the same datasets.

Examples:
  tactip dataset build slides/labels.csv --out data/slides --label direction_deg --period 360
  tactip dataset build presses/labels.csv --out data/depth --label depth_mm --classes 6 --split group
  tactip dataset build shapes.csv --out data/shapes --rest shapes/rest.png --sensor tactip-127
  tactip train data/slides/train.h5 --out data/slides/model.h5 --model gaussian
  tactip validate data/slides/model.h5 data/slides/test.h5
  tactip replay new.mp4 --out out/new.h5 --calibration data/slides/calibration.h5 --model data/slides/model.h5
"""

from __future__ import annotations

import argparse
import contextlib
import functools
from pathlib import Path

from tactip.cli._types import float_in_range, int_in_range, output_folder, seed

HELP = "turn labelled recordings (videos, frame folders, images + a labels CSV) into train and test datasets"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the parser of ``tactip dataset`` with its ``build`` subcommand (room for more)."""
    from tactip.cli.replay import add_sensor_arguments

    sub = parser.add_subparsers(dest="dataset_command", metavar="DATASET_COMMAND")
    sub.required = True
    build = sub.add_parser("build", help="labelled recordings -> DIR/train.h5, test.h5, calibration.h5, summary.json",
                           description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    build.add_argument("labels", type=Path, metavar="LABELS.csv",
                       help="CSV with a 'path' column (relative to the CSV) and label columns")
    build.add_argument("--out", type=output_folder, required=True, metavar="DIR", help="folder to write into")
    build.add_argument("--label", metavar="COL", help="the label column (default: the only one)")
    build.add_argument("--classes", type=int_in_range(1, 1000), metavar="N",
                       help="bin number labels into N equal-width classes (angles: centred on 0, period/N, ...)")
    build.add_argument("--period", type=float_in_range(0, 1e9, low_open=True), metavar="P",
                       help="the labels are angles of period P (e.g. 360 for deg): identities and errors wrap")
    build.add_argument("--unit", metavar="UNIT",
                       help="the label's unit (default: the column name's suffix, depth_mm: mm; deg with --period 360)")
    build.add_argument("--split", choices=("alternate", "group", "column"), default="alternate",
                       help="alternate: taps of each class alternate train/test (default); group: whole recordings "
                            "on one side, balanced per class; column: the CSV's 'split' column (train or test)")
    build.add_argument("--test-fraction", type=float_in_range(0, 1, low_open=True), default=0.5, metavar="F",
                       help="share of each class's taps in the test set, --split group (default 0.5)")
    build.add_argument("--seed", type=seed, default=0, help="seed of --split group's shuffle (default 0)")
    build.add_argument("--rest", type=Path, metavar="IMAGE",
                       help="rest image (off contact) of image rows without a 'rest' column")
    build.add_argument("--calibration", type=Path, metavar="CAL.h5",
                       help="use this sensor calibration (tactip calibrate, or an earlier build) instead of making one")
    build.add_argument("--image-samples", type=int_in_range(1, 1000), metavar="N",
                       help="rows of an image's tap (its displacement repeated; default 1, or --samples when the set "
                            "also holds videos)")
    add_sensor_arguments(build)  # --expected-pins, --samples, --pins, --min-separation-mm, scale, --rest-frame, --dark-pins
    build.add_argument("--workers", type=int_in_range(1, 1024), metavar="N",
                       help="track the recordings on an embedded Dask cluster of N workers (default: one by one here)")
    build.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                       help="track the recordings on this Dask cluster (its workers must see the same paths)")
    build.add_argument("--overwrite", action="store_true", help="replace existing outputs in DIR")
    build.add_argument("--device", choices=("auto", "cpu", "cuda"), default="auto",
                       help="cuda: detect the images' pins --together at a time as torch tensors on the GPU "
                            "(tactip[accel]); cpu: one image at a time; auto (default): cuda where torch sees a GPU, "
                            "else cpu. The datasets are the same")
    build.add_argument("--together", type=int_in_range(1, 1024), default=32, metavar="N",
                       help="images detected together on the GPU (default 32)")


def run(args: argparse.Namespace) -> int:
    """Run ``tactip dataset build`` (`tactip.dataset.build_dataset`) and print its summary."""
    from tactip.errors import TactipError

    if args.test_fraction >= 1.0:
        raise TactipError(f"--test-fraction must be below 1, got {args.test_fraction:g}")
    if args.calibration is not None:
        given = [flag for flag, value in (("--expected-pins", args.expected_pins), ("--sensor", args.sensor),
                                          ("--pins-on-pad", args.pins_on_pad), ("--pad-diameter-mm", args.pad_diameter_mm),
                                          ("--mm-per-px", args.mm_per_px), ("--dark-pins", args.dark_pins or None))
                 if value is not None]
        if given:
            raise TactipError(f"{', '.join(given)} cannot be combined with --calibration (it sets detection, pins "
                              f"and scale)")
    if args.workers is not None and args.scheduler is not None:
        raise TactipError("--workers sizes the embedded Dask cluster; a --scheduler's cluster has its own workers")
    if args.device == "cuda":  # the images are detected here, on this machine's GPU
        from pins.accel import pick_device

        try:
            pick_device("cuda")
        except ImportError:
            raise TactipError("--device cuda needs torch and kornia: pip install 'tactip[accel]'") from None
        except ValueError as exc:
            raise TactipError(f"--device cuda: {exc}") from None
    with contextlib.ExitStack() as stack:
        map_fn = None
        if args.workers is not None or args.scheduler is not None:
            from _shared.progress import progress_bar as tqdm

            from tactip.cluster import cluster_map, open_client

            client = stack.enter_context(open_client(args.scheduler, workers=args.workers))
            map_fn = cluster_map(client, progress=functools.partial(tqdm, desc="recordings", unit="recording",
                                                                    disable=args.quiet))
        result = _build(args, map_fn)
    if not args.quiet:
        print(result.text())
    return 0


def _build(args: argparse.Namespace, map_fn):
    """`tactip.dataset.build_dataset` with the command's options."""
    from tactip.dataset import build_dataset

    return build_dataset(args.labels, args.out, label=args.label, classes=args.classes, period=args.period,
                         unit=args.unit, split=args.split, test_fraction=args.test_fraction, seed=args.seed,
                         rest=args.rest, calibration=args.calibration, expected_pins=args.expected_pins,
                         n_pins=args.pins, min_separation_mm=args.min_separation_mm, sensor=args.sensor,
                         pins_on_pad=args.pins_on_pad, pad_diameter_mm=args.pad_diameter_mm,
                         mm_per_px=args.mm_per_px, dark_pins=True if args.dark_pins else None,
                         n_samples=args.samples, image_samples=args.image_samples, rest_frame=args.rest_frame,
                         overwrite=args.overwrite, progress=not args.quiet, map_fn=map_fn, device=args.device,
                         together=args.together)
