"""Record frames from a camera (or the synthetic TacTip) to a video file, to replay it later.

A live camera needs --seconds or --frames; an existing --out file is replaced only with --overwrite.
The recording can then be replayed:
tactip replay REC.mp4 --out REC.h5 --annotate REC_annotated.mp4.

Examples:
  tactip record 0 --seconds 10 --out taps.avi                 # camera 0, Motion-JPEG
  tactip record /dev/video2 --frames 400 --exposure 50 --out taps.mp4
  tactip record synthetic --out synthetic.mp4                 # scripted taps, no hardware
"""

from __future__ import annotations

import argparse

from tactip.cli._types import finite_float, float_in_range, output_file, positive_float, positive_int

HELP = "record a camera (or the synthetic TacTip) to a video file for replay"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the parser for `tactip record`."""
    parser.add_argument("source", metavar="SOURCE",
                        help="camera index (0) or /dev/videoN, 'synthetic', 'synthetic:PINS' or 'synthetic:PRESET' (tactip-331, rim-ring-331, brown-127, radial-120 ...), or a video")
    parser.add_argument("--out", type=output_file, required=True, metavar="FILE",
                        help="video to write: .mp4 or .avi (Motion-JPEG)")
    parser.add_argument("--seconds", type=positive_float, default=None, help="stop after this long")
    parser.add_argument("--frames", type=positive_int, default=None, help="stop after this many frames")
    parser.add_argument("--frame-rate", type=float_in_range(0.01, 1000, unit="frames/s"), default=None,
                        help="frames/s in the file header, 0.01..1000 (default: the source's)")
    parser.add_argument("--exposure", type=finite_float, default=None,
                        help="fixed camera exposure, where the driver allows")
    parser.add_argument("--overwrite", action="store_true",
                        help="replace an existing --out file (without it an earlier recording is never replaced)")


def run(args: argparse.Namespace) -> int:
    """Run `tactip record`."""
    from tactip.errors import TactipError
    from tactip.replay.record import record_video

    from tactip._output import refuse_overwriting_inputs

    refuse_overwriting_inputs([args.out], [args.source])  # the video recorded from is never replaced
    if args.out.exists() and not args.overwrite:
        # A recording cannot be made again: replacing one takes an explicit --overwrite.
        raise TactipError(f"--out {str(args.out)!r} exists (an earlier recording?): give another name, or "
                          f"--overwrite to replace it")
    options = {} if args.exposure is None else {"exposure": args.exposure}
    result = record_video(args.source, args.out, seconds=args.seconds, frames=args.frames,
                          frame_rate=args.frame_rate, progress=not args.quiet, **options)
    print(result.summary())
    return 0
