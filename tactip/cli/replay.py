"""Replay a recorded TacTip video: track every pin, find the taps, write HDF5.

The rest frame (off contact) is the first frame unless --rest-frame says otherwise; pins are
detected there, tracked through the video, and their displacements from it are integrated. Taps
are found from the displacements, 40 pins at least 4 mm apart are selected, and each tap becomes
a 40-sample x 80-dimension feature array (x then y displacements of the selected pins).

The HDF5 file holds positions and displacements (frames x pins x 2, NaN where a pin was lost),
time stamps, tap bounds, the selected pins, the tap features and the parameters used. It is
written only when the replay succeeds.

With --calibration (the station's sensor calibration, from 'tactip calibrate') the calibrated
detection, pins, feature pins and scale are used instead, so the taps line up with the station's
model. With --model as well, a passive perceiver decides the gap width from the taps in order
(the recording cannot move the sensor); the HDF5 file gets a 'decisions' group, each tap's
estimate is printed, and the annotated video shows each tap's width estimate and belief.

Example:
  tactip replay samples/synthetic_tap.mp4 --out out/replay.h5 --annotate out/annotated.mp4
  tactip replay taps.mp4 --out out/replay.h5 --calibration data/calibration.h5 --model data/model.h5
"""

from __future__ import annotations

import argparse

from tactip.cli._types import fraction, non_negative_float, non_negative_int, positive_float, positive_int

HELP = "track the pins of a recorded video, find the taps and write positions and tap features to HDF5"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``tactip replay``."""
    parser.add_argument("video", metavar="VIDEO", help="video file (or folder of frames) to replay")
    parser.add_argument("--out", required=True, metavar="RESULT.h5", help="HDF5 file to write")
    parser.add_argument("--annotate", metavar="OUT.mp4", help="also write a video with pins, displacement "
                        "arrows (x3) and the tap state drawn on")
    parser.add_argument("--expected-pins", type=positive_int, metavar="N",
                        help="auto-tune detection to N pins on the rest frame first")
    parser.add_argument("--samples", type=positive_int, default=40, metavar="N",
                        help="samples per tap feature array (default: 40)")
    parser.add_argument("--pins", type=positive_int, default=40, metavar="N",
                        help="tactile pins to select (default: 40)")
    parser.add_argument("--min-separation-mm", type=non_negative_float, default=4.0, metavar="MM",
                        help="minimum distance between selected pins, mm (default: 4)")
    parser.add_argument("--pad-diameter-mm", type=positive_float, default=40.0, metavar="MM",
                        help="pad diameter, mm; the scale is this over the detected disc diameter (default: 40)")
    parser.add_argument("--mm-per-px", type=positive_float, metavar="MM",
                        help="image scale at the pad, mm per px, instead of the one from the disc diameter")
    parser.add_argument("--rest-frame", type=non_negative_int, default=0, metavar="N",
                        help="index of the rest frame, off contact (default: 0, the first frame)")
    parser.add_argument("--dark-pins", action="store_true", help="dark markers on a light membrane")
    parser.add_argument("--calibration", metavar="CAL.h5", help="the station's sensor calibration: use its "
                        "detection, pins, feature pins and scale (instead of --expected-pins, --mm-per-px, ...)")
    parser.add_argument("--model", metavar="MODEL.h5", help="the station's model (needs --calibration): "
                        "decide the gap width from the taps")
    parser.add_argument("--decision-threshold", type=fraction, metavar="P",
                        help="decision threshold on the width belief (default: the model's recommended, else 0.9)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar and no summary")


def run(args: argparse.Namespace) -> int:
    """Replay the video (`tactip.replay.replay_video`) and print what was found."""
    from pins import DetectionParams
    from tactip.replay import replay_video

    params = None if args.calibration else DetectionParams(dark_pins=args.dark_pins)
    result = replay_video(args.video, args.out, annotate_path=args.annotate, expected_pins=args.expected_pins,
                          params=params, n_samples=args.samples,
                          n_pins=args.pins, min_separation_mm=args.min_separation_mm,
                          pad_diameter_mm=args.pad_diameter_mm, mm_per_px=args.mm_per_px,
                          rest_frame=args.rest_frame, calibration=args.calibration, model=args.model,
                          decision_threshold=args.decision_threshold, progress=not args.quiet)
    if not args.quiet:
        print(result.summary())
    return 0
