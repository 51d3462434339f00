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

Example:
  tactip replay samples/synthetic_tap.mp4 --out out/replay.h5 --annotate out/annotated.mp4 --sensor tactip-331
  tactip replay taps.mp4 --out out/replay.h5 --calibration data/calibration.h5 --model data/model.h5
"""

from __future__ import annotations

import argparse
import math

from _shared.ranges import MAX_SAMPLES
from tactip.cli._scale import add_scale_arguments, pin_count
from tactip.cli._types import (float_in_range, int_in_range, non_negative_float, non_negative_int,
                               output_file)

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
    parser.add_argument("video", metavar="VIDEO", help="video file (or folder of frames) to replay")
    parser.add_argument("--out", type=output_file, required=True, metavar="RESULT.h5", help="HDF5 file to write")
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
    """Replay the video (`tactip.replay.video.replay_video`) and print what was found."""
    from pins import DetectionParams
    from tactip.replay.video import replay_video

    if args.decision_threshold is not None and args.model is None:
        from tactip.errors import TactipError

        raise TactipError("--decision-threshold sets the model's decisions: it needs --model (and --calibration)")
    params = DetectionParams(dark_pins=True) if args.dark_pins and not args.calibration else None
    result = replay_video(args.video, args.out, annotate_path=args.annotate, expected_pins=args.expected_pins,
                          params=params, n_samples=args.samples,
                          n_pins=args.pins, min_separation_mm=args.min_separation_mm,
                          sensor=args.sensor, pins_on_pad=args.pins_on_pad,
                          pad_diameter_mm=args.pad_diameter_mm, mm_per_px=args.mm_per_px,
                          rest_frame=args.rest_frame, calibration=args.calibration, model=args.model,
                          decision_threshold=args.decision_threshold, progress=not args.quiet)
    if not args.quiet:
        print(result.summary())
    return 0
