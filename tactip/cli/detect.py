"""Detect the pins in one TacTip image and print them.

Finds the sensor disc, then the pin tips inside it (Gaussian blur, adaptive threshold,
connected components, intensity-weighted centroids). With --expected-pins the detection is first
tuned to find that many pins. With --json the output is exactly
{"count": n, "pins": [[x, y], ...]} in px (x to the right, y down).

Example:
  tactip detect samples/synthetic_frame.png --expected-pins 331 --json
"""

from __future__ import annotations

import argparse

from tactip.cli._types import positive_int
import json

HELP = "detect the pins in one image (optionally auto-tuned to an expected count)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``tactip detect``."""
    parser.add_argument("image", metavar="IMAGE", help="image file (png, jpg, bmp, tif)")
    parser.add_argument("--expected-pins", type=positive_int, metavar="N",
                        help="tune detection to N pins first (127, 331, 532 ...)")
    parser.add_argument("--dark-pins", action="store_true", help="dark markers on a light membrane")
    parser.add_argument("--json", action="store_true", help='print {"count": n, "pins": [[x, y], ...]}')


def run(args: argparse.Namespace) -> int:
    """Read the image, tune if asked, detect and print."""
    from pins import DetectionParams, detect_pins, find_sensor_disc, median_spacing_px, tune_detection
    from tactip.errors import SourceError
    from tactip.sources import ImageFolderSource

    with ImageFolderSource(args.image, grey=True) as source:
        if len(source) != 1:
            raise SourceError(f"{args.image!r} is a folder of {len(source)} images; give one image file")
        image = source.read().image
    params = DetectionParams(dark_pins=args.dark_pins)
    disc = find_sensor_disc(image, dark_pins=params.dark_pins)
    if args.expected_pins:
        params = tune_detection(image, args.expected_pins, start=params, disc=disc)
    pins = detect_pins(image, params=params, disc=disc)
    if args.json:
        print(json.dumps({"count": len(pins), "pins": [[round(x, 3), round(y, 3)] for x, y in pins.tolist()]}))
        return 0
    print(f"{len(pins)} pins in {args.image} (disc centre ({disc.cx:.1f}, {disc.cy:.1f}) px, "
          f"radius {disc.radius_px:.1f} px)")
    if len(pins):
        spacing = median_spacing_px(pins)
        low, high = pins.min(axis=0), pins.max(axis=0)
        print(f"x {low[0]:.1f}..{high[0]:.1f} px, y {low[1]:.1f}..{high[1]:.1f} px, median spacing {spacing:.1f} px")
    print(f"parameters{' (tuned)' if args.expected_pins else ''}: blur {params.blur_sigma_px:g} px, "
          f"block {params.block_size_px} px, offset {params.offset:g}, "
          f"area {params.min_area_px}-{params.max_area_px} px")
    return 0

