"""Find the pins in one TacTip image and print them.

Finds the sensor disc (or, for a flat gel whose markers fill the frame, such as a GelSight's, takes the
whole frame: see the README, "Flat-gel sensors"), then the pin field inside it: the blobs that form the pin lattice
(neighbours at the lattice pitch, size, contrast and sharpness like their neighbours'), without
being told the pin count. The other blobs are rejected and counted by reason: "outside field"
(beyond the lattice: glare on a rim ring), "off lattice" (specks, light patches of skin between
pins), "size" and "contrast" (unlike their neighbours). With --expected-pins the count only
confirms the result: the summary says how far off it is (a warning when more than 10 % off).

The scale (mm/px) is derived as ``tactip calibrate`` and ``tactip replay`` derive it (`pins.sensor_scale`):
the sensor's pin pitch in mm (--sensor, or --pins-on-pad / --expected-pins / the pins found on a pad of
--pad-diameter-mm, default 40) over the central pin pitch in px (`pins.central_spacing_px`: the pins near
the field's centre; the one pitch printed). The summary says how it was derived.

With --json [FILE|-] (standard output with no value or -) the output is {"count": n, "pins": [[x, y], ...], "pitch_px": p,
"rejected": [[x, y, "reason"], ...], "dark_pins": bool, "scale": {"mm_per_px", "pitch_px", "pitch_mm",
"source", "sensor"}, "warnings": [...]} in px (x to the right, y down; "scale" is null with fewer than two
pins), plus "expected_pins" and "count_error" (found minus expected) with --expected-pins.

A frame that may hide pins earns a warning (on standard error, and in the JSON's "warnings"): a pad
saturated off the pins (more than 0.5 % of the pin field at grey level 253-255, or a pin on membrane
too bright to stand out: glare or a veil there hides the tips; lower the exposure), or pins faint
against the camera noise (the faintest tenth's contrast x sqrt(pi) x tip radius / noise below 8, or
contrast below 10 grey levels: a frame too dark, tips too small, filmed far off or at a low
resolution, or a noisy camera; some pins may be missed or lost). `tactip replay` lists the
same warnings for its rest frame.

The polarity (bright pins on a dark membrane, or dark markers on a light one) is decided from the
image unless --dark-pins says so: the one whose pin lattice keeps more pins wins, and an image where
neither forms a lattice of 40 pins or more shows no sensor (an error saying why for each). `tactip
replay` decides the same way on its rest frame and refuses with the same message.

With --annotate OUT.png a picture is written: kept pins in green, rejected blobs as crosses
coloured by reason, the pin field's circle in yellow and a legend (images under 480 px enlarged
by a whole factor). It never overwrites IMAGE.

Examples:
  tactip detect samples/synthetic_frame.png
  tactip detect frame.png --expected-pins 331 --annotate out/frame_pins.png
  tactip detect frame.png --dark-pins --json
  tactip detect frame.png --sensor radial-120
  tactip detect gel_frame.png --sensor gelsight-mini
"""

from __future__ import annotations

import argparse
import sys

from tactip.cli._scale import MAX_PINS, add_scale_arguments
from tactip.cli._types import add_json_argument, int_in_range, output_file

HELP = "find the pin field in one image (pins kept, blobs rejected and why; optional count check)"

# Picture formats --annotate writes (OpenCV's encoders).
_PICTURE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")

# More than this relative difference from --expected-pins earns a warning.
_COUNT_WARNING = 0.1


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``tactip detect``."""
    parser.add_argument("image", metavar="IMAGE", help="image file (png, jpg, bmp, tif)")
    parser.add_argument("--expected-pins", type=int_in_range(1, MAX_PINS), metavar="N",
                        help=f"the sensor's pin count (127, 331, 532 ...; 1..{MAX_PINS}): confirms the pins found "
                             "and says how far off they are; does not change what is found")
    parser.add_argument("--dark-pins", action="store_true",
                        help="dark markers on a light membrane (default: the polarity is decided from the image)")
    add_json_argument(parser, '{"count": n, "pins": [[x, y], ...], "pitch_px": p, "rejected": [[x, y, "reason"], '
                              '...], "dark_pins": bool, "scale": {"mm_per_px": s, "source": "how", ...}, '
                              '"warnings": [...]} (px)')
    parser.add_argument("--annotate", type=output_file, metavar="OUT.png",
                        help="also write a picture: kept pins green, rejected blobs coloured by reason, legend")
    add_scale_arguments(parser)  # --sensor, --pins-on-pad, --pad-diameter-mm, --mm-per-px (as tactip replay)


def run(args: argparse.Namespace) -> int:
    """Read the image, find the pin field, print it (and draw it)."""
    from pins import draw_pin_field, find_pin_field
    from tactip._output import atomic_output, refuse_overwriting_inputs, write_json
    from tactip.errors import SourceError
    from tactip.sources import ImageFolderSource

    refuse_overwriting_inputs([args.annotate, args.json], [args.image])
    if args.annotate:
        if args.annotate.suffix.lower() not in _PICTURE_SUFFIXES:
            raise SourceError(f"cannot write the picture {str(args.annotate)!r}: use a .png, .jpg, .bmp or .tif name")
    with ImageFolderSource(args.image) as source:
        if len(source) != 1:
            raise SourceError(f"{args.image!r} is a folder of {len(source)} images; give one image file")
        image = source.read().image
    # The polarity is decided as replay decides it (pins.find_pin_field with dark_pins=None).
    field = find_pin_field(image, expected_pins=args.expected_pins, dark_pins=True if args.dark_pins else None)
    scale = _scale(args, field)
    reason = scale if isinstance(scale, str) else ""
    scale = None if reason else scale
    if args.annotate:
        import cv2

        picture = draw_pin_field(image, field)
        # Encoded in memory and written by Python: a full disk or a lost permission is an OSError named
        # as such (cv2.imwrite only returns False).
        encoded, data = cv2.imencode(args.annotate.suffix.lower(), picture)
        if not encoded:
            raise SourceError(f"cannot encode the picture {str(args.annotate)!r}")
        with atomic_output(args.annotate, inputs=[args.image]) as tmp:
            with open(tmp, "wb") as f:
                f.write(data.tobytes())
    if args.json is not None:
        data = {"count": field.count, "pins": [[round(x, 3), round(y, 3)] for x, y in field.centres.tolist()],
                "pitch_px": None if field.count < 2 else round(field.pitch_px, 3),
                "rejected": [[round(float(x), 3), round(float(y), 3), str(reason)]
                             for (x, y), reason in zip(field.rejected, field.rejected_reason)],
                "dark_pins": bool(field.params.dark_pins),
                "scale": None if scale is None else scale.to_dict(), "warnings": list(field.warnings)}
        if args.expected_pins:
            data.update(expected_pins=field.expected_pins, count_error=field.count_error)
        write_json(args.json, data, inputs=[args.image], indent=None)
    if str(args.json) != "-":
        _print_summary(args, field, scale, reason)
    for warning in field.warnings:  # a saturated pad, faint or small tips: what may have hidden pins
        print(f"tactip detect: warning: {warning}", file=sys.stderr)
    if args.expected_pins and abs(field.count_error) > _COUNT_WARNING * args.expected_pins:
        why = ("pins hidden or out of focus, something touching the pad, or a wrong count?" if field.count_error < 0
               else "is the count right?")
        print(f"tactip detect: warning: {field.count} pins found, {args.expected_pins} expected "
              f"({field.count_error:+d}, {field.count_error / args.expected_pins:+.0%}): {why}", file=sys.stderr)
    return 0


def _scale(args: argparse.Namespace, field):
    """The scale of the pins found (`pins.PadScale`), by the rule calibrate and replay use; else why not (str)."""
    from pins import PinsError, sensor_scale

    try:
        return sensor_scale(field.centres, sensor=args.sensor, pins_on_pad=args.pins_on_pad,
                            pad_diameter_mm=args.pad_diameter_mm, mm_per_px=args.mm_per_px,
                            expected_pins=args.expected_pins)
    except (PinsError, ValueError) as exc:  # too few pins to measure the pitch on, or a count below one ring
        return " ".join(str(exc).split())


def _print_summary(args: argparse.Namespace, field, scale, reason: str) -> None:
    disc, params = field.field_disc, field.params
    polarity = "dark markers on a light membrane" if params.dark_pins else "bright pins on a dark membrane"
    region = ("sensing region: the whole frame, no disc" if field.disc.whole_frame else
              f"pin field centre ({disc.cx:.1f}, {disc.cy:.1f}) px, radius {disc.radius_px:.1f} px")
    print(f"{field.count} pins in {args.image} ({polarity}; {region})")
    if field.count:
        low, high = field.centres.min(axis=0), field.centres.max(axis=0)
        print(f"x {low[0]:.1f}..{high[0]:.1f} px, y {low[1]:.1f}..{high[1]:.1f} px")
    if scale is not None:  # the pitch is printed here, in the scale's derivation
        print(f"scale {scale.describe()}")
    else:
        print(f"scale: none ({reason})")
    counts = field.rejected_counts()
    detail = ", ".join(f"{n} {reason}" for reason, n in counts.items() if n)
    print(f"rejected {len(field.rejected)} blobs" + (f": {detail}" if detail else ""))
    if args.expected_pins:
        error = field.count_error
        off = "exactly as expected" if error == 0 else f"{error:+d} ({error / args.expected_pins:+.1%})"
        print(f"expected {args.expected_pins} pins: {off}")
    print(f"parameters for later frames: blur {params.blur_sigma_px:g} px, block {params.block_size_px} px, "
          f"offset {params.offset:g}, area {params.min_area_px}-{params.max_area_px} px")
