"""Replay a recorded TacTip video: track every pin, find the taps, write HDF5.

The rest frame (off contact) is the first frame unless --rest-frame says otherwise; pins are
detected there, tracked through the video, and their displacements from it are integrated. Taps
are found from the displacements, 40 pins at least 4 mm apart are selected (on a pad without room
for them: 40 pins as far apart as it allows, or all its pins, with a warning), and each tap becomes
a 40-sample x 80-dimension feature array (x then y displacements of the selected pins).

The scale (mm/px) is the sensor's pin pitch over the pitch measured on the rest frame: name the
sensor (--sensor tactip-331; the list is in --help), or give its pin count and pad diameter
(--pins-on-pad, --pad-diameter-mm; default the pins detected on a 40 mm pad), or the scale itself
(--mm-per-px). The summary prints the scale and how it was derived.

Once the video has been tracked the HDF5 file is always written: positions and displacements
(frames x pins x 2, NaN where a pin was lost), lost and retired pin masks and counts per frame,
blank frames, time stamps, tap bounds, the selected pins, the tap features, the scale and the
parameters used, and any warnings (a rest frame that looks taken during a tap, feature pins closer
than asked, no taps). The summary lists lost and retired pins per frame and the blank frames.

With --calibration (the station's sensor calibration, from 'tactip calibrate') the calibrated
detection, pins, feature pins and scale are used instead, so the taps line up with the station's
model. With --model as well, a passive perceiver decides the gap width from the taps in order
(the recording cannot move the sensor); the HDF5 file gets a 'decisions' group, each tap's
estimate is printed, and the annotated video shows each tap's width estimate and belief.

An archive: several videos, folders of videos or quoted glob patterns with --out-dir OUT write
OUT/<stem>.h5 for each (the file a single replay writes), on Dask distributed: an embedded local
cluster (--workers N, default one per core) or a running cluster (--scheduler tcp://HOST:PORT, whose
workers see the same paths). A video that fails is named at the end, after the others are done, and
the command exits 1; a rerun skips the videos whose output is already in place (--overwrite replays
them). OUT/summary.json has one row per video. One video without --out-dir replays as above.
Where torch sees a GPU (tactip[accel]; --device auto, the default), each worker tracks --together
videos at once and measures their pins' windows in one batch on the GPU: the same files.

Example:
  tactip replay samples/synthetic_tap.mp4 --out out/replay.h5 --annotate out/annotated.mp4 --sensor tactip-331
  tactip replay taps.mp4 --out out/replay.h5 --calibration data/calibration.h5 --model data/model.h5
  tactip replay archive/ 'more/**/*.mp4' --out-dir out/archive --sensor tactip-331 --workers 2
  tactip replay archive/ --out-dir /shared/out --scheduler tcp://10.0.0.5:8786
"""

from __future__ import annotations

import argparse
import math

from _shared.ranges import MAX_SAMPLES
from tactip.cli._scale import add_scale_arguments, pin_count
from tactip.cli._types import (float_in_range, int_in_range, non_negative_float, non_negative_int,
                               output_file, output_folder)

HELP = "track the pins of a recorded video, find the taps and write positions and tap features to HDF5"


def _finite(parse):
    """An argparse type: ``parse``'s value, which must also be finite (inf and nan say nothing)."""
    def finite(text: str) -> float:
        value = parse(text)
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"must be a finite number, got {text}")
        return value
    return finite


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``tactip replay``."""
    parser.add_argument("videos", nargs="+", metavar="VIDEO", help="video file (or folder of frames) to replay; "
                        "with --out-dir: several, folders of videos or quoted glob patterns")
    parser.add_argument("--out", type=output_file, metavar="RESULT.h5", help="HDF5 file to write (one video)")
    batch = parser.add_argument_group("archives (several videos, on Dask distributed)")
    batch.add_argument("--out-dir", type=output_folder, metavar="OUT", help="write OUT/<stem>.h5 per video and "
                       "OUT/summary.json")
    batch.add_argument("--workers", type=int_in_range(1, 1024), metavar="N",
                       help="workers of the embedded local cluster (default: one per core)")
    batch.add_argument("--scheduler", metavar="tcp://HOST:PORT", help="run on the Dask cluster of this scheduler "
                       "instead (dask scheduler; dask worker tcp://HOST:PORT on each machine)")
    batch.add_argument("--overwrite", action="store_true", help="one video: replace a replay file at --out; a "
                       "batch: replay again videos whose output is in OUT (default: skip them)")
    batch.add_argument("--device", choices=("auto", "cpu", "cuda"), default="auto",
                       help="cuda: track --together videos at once per worker, their pin windows measured in one "
                       "torch batch on the GPU (tactip[accel]); cpu: each video on its own; auto (default): cuda "
                       "where torch sees a GPU, else cpu. The files are the same")
    batch.add_argument("--together", type=int_in_range(1, 256), default=8, metavar="N",
                       help="videos tracked together per GPU task (default 8)")
    parser.add_argument("--annotate", type=output_file, metavar="OUT.mp4", help="also write a video with pins, displacement "
                        "arrows (x3) and the tap state drawn on")
    add_sensor_arguments(parser)
    parser.add_argument("--calibration", metavar="CAL.h5", help="the station's sensor calibration: use its "
                        "detection, pins, feature pins and scale (instead of --expected-pins, --mm-per-px, ...)")
    parser.add_argument("--model", metavar="MODEL.h5", help="the station's model (needs --calibration): "
                        "decide the gap width from the taps")
    parser.add_argument("--decision-threshold", type=float_in_range(0, 1, low_open=True), metavar="P",
                        help="decision threshold on the width belief, (0, 1] (default: the model's recommended, "
                             "else 0.9)")


def add_sensor_arguments(parser: argparse.ArgumentParser) -> None:
    """--expected-pins, --samples, --pins, --min-separation-mm, the scale's flags, --rest-frame and --dark-pins.

    How a recording's pins are found, which become feature pins and how a tap is sampled: the flags
    ``tactip replay`` and ``tactip dataset build`` share.
    """
    parser.add_argument("--expected-pins", type=pin_count, metavar="N",
                        help="pins expected in view on the rest frame: confirms the pin field found there (the summary says "
                        "how far off it is) and is the default of --pins-on-pad")
    parser.add_argument("--samples", type=int_in_range(1, MAX_SAMPLES), default=40, metavar="N",
                        help="samples per tap feature array (default: 40)")
    parser.add_argument("--pins", type=int_in_range(1, 2000), default=40, metavar="N",
                        help="tactile pins to select (default: 40)")
    parser.add_argument("--min-separation-mm", type=_finite(non_negative_float), default=4.0, metavar="MM",
                        help="preferred distance between selected pins, mm; a pad without room for --pins pins "
                        "this far apart gets them as far apart as it allows (default: 4)")
    add_scale_arguments(parser)  # --sensor, --pins-on-pad, --pad-diameter-mm, --mm-per-px (as tactip detect)
    parser.add_argument("--rest-frame", type=non_negative_int, default=0, metavar="N",
                        help="index of the rest frame, off contact (default: 0, the first frame); one that looks "
                        "taken during a tap is reported")
    parser.add_argument("--dark-pins", action="store_true",
                        help="dark markers on a light membrane (default: the polarity is decided from the rest frame, "
                        "as tactip detect decides it)")


def run(args: argparse.Namespace) -> int:
    """Replay the video (`tactip.replay.video.replay_video`) and print what was found; or a batch."""
    from pins import DetectionParams
    from tactip.errors import TactipError

    if args.decision_threshold is not None and args.model is None:
        raise TactipError("--decision-threshold sets the model's decisions: it needs --model (and --calibration)")
    params = DetectionParams(dark_pins=True) if args.dark_pins and not args.calibration else None
    if args.out_dir is not None:
        return _run_batch(args, params)
    batch_only = [flag for flag, value in (("--workers", args.workers), ("--scheduler", args.scheduler),
                                           ("--device", None if args.device == "auto" else args.device),
                                           ("--together", None if args.together == 8 else args.together))
                  if value is not None]
    if batch_only:
        raise TactipError(f"{', '.join(batch_only)} {'goes' if len(batch_only) == 1 else 'go'} with --out-dir (a "
                          f"batch); one video with --out is replayed here, its output replaced")
    if len(args.videos) > 1:
        raise TactipError(f"{len(args.videos)} videos need --out-dir OUT (one HDF5 file each); --out names one "
                          f"video's file")
    if args.out is None:
        raise TactipError("give --out RESULT.h5 (one video) or --out-dir OUT (one file per video)")
    from tactip.replay.video import replay_video

    result = replay_video(args.videos[0], args.out, annotate_path=args.annotate, expected_pins=args.expected_pins,
                          params=params, n_samples=args.samples,
                          n_pins=args.pins, min_separation_mm=args.min_separation_mm,
                          sensor=args.sensor, pins_on_pad=args.pins_on_pad,
                          pad_diameter_mm=args.pad_diameter_mm, mm_per_px=args.mm_per_px,
                          rest_frame=args.rest_frame, calibration=args.calibration, model=args.model,
                          decision_threshold=args.decision_threshold, progress=not args.quiet)
    if not args.quiet:
        print(result.summary())
    return 0


def _run_batch(args: argparse.Namespace, params) -> int:
    """--out-dir: every video on Dask (`tactip.replay.batch.replay_batch`); failed videos named, exit 1."""
    import sys

    from tactip.cluster import open_client
    from tactip.errors import TactipError
    from tactip.replay.batch import expand_videos, replay_batch

    for flag, value in (("--out", args.out), ("--annotate", args.annotate)):
        if value is not None:
            raise TactipError(f"{flag} names one video's output; a batch (--out-dir) writes OUT/<stem>.h5 per "
                              f"video and no annotated videos")
    if args.scheduler is not None and args.workers is not None:
        raise TactipError("--workers sizes the embedded local cluster; a --scheduler's cluster has its own workers")
    if args.device == "cuda" and args.scheduler is None:  # the embedded cluster's GPU is this machine's
        from pins.accel import pick_device

        try:
            pick_device("cuda")
        except ImportError:
            raise TactipError("--device cuda needs torch: pip install 'tactip[accel]'") from None
        except ValueError as exc:
            raise TactipError(f"--device cuda: {exc}") from None
    videos = expand_videos(args.videos)
    with open_client(args.scheduler, workers=args.workers) as client:
        result = replay_batch(videos, args.out_dir, client=client, overwrite=args.overwrite, progress=not args.quiet,
                              device=args.device, together=args.together,
                              expected_pins=args.expected_pins, params=params, n_samples=args.samples,
                              n_pins=args.pins, min_separation_mm=args.min_separation_mm, sensor=args.sensor,
                              pins_on_pad=args.pins_on_pad, pad_diameter_mm=args.pad_diameter_mm,
                              mm_per_px=args.mm_per_px, rest_frame=args.rest_frame, calibration=args.calibration,
                              model=args.model, decision_threshold=args.decision_threshold)
    if not args.quiet:
        print(result.text())
    for row in result.failed:
        print(f"failed: {row['video']}: {row['error']}", file=sys.stderr)
    if result.failed:
        raise TactipError(f"{len(result.failed)} of {len(result.rows)} videos failed (named above); the others are "
                          f"in {result.out_dir}")
    return 0
