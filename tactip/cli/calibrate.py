"""Calibrate the station's TacTip: rest frames off contact, detection tuned to the expected pin
count, reference pins and the feature-pin subset, written to the calibration file.

The arm lifts the pad clear of the part (above the first gap) while the rest frames are taken.
The file goes to [sensor] calibration, or DATA_DIR/calibration.h5; collect and inspect read it.
The scale (mm/px) is derived as `tactip detect` and `tactip replay` derive it: the pin pitch of
[sensor] pins on a pad of [sensor] pad_diameter_mm over the central pin pitch in px (the summary says
so). Feature pins that cannot be [sensor] min_separation_mm apart are taken as far apart as the pad
allows, as replay takes them, and the summary gives the separation reached.
Refuses with a clear message when the frame shows no sensor or the pin count is far from [sensor] pins.
An existing calibration is replaced only with --overwrite.

--sensor NAME names the sensor instead of [sensor] preset (its pin count and pitch; e.g. gelsight-mini
for a flat gel whose markers fill the frame).

Without a station (recordings only): --frames REST takes the rest frames from a video (its first
--rest-frames frames), a folder of frames or an image, with the pad off contact, and writes --out; the
sensor is described as 'tactip replay' and 'tactip dataset build' describe it (--sensor, or --pins-on-pad
and --pad-diameter-mm; --expected-pins, --pins, --min-separation-mm, --dark-pins), so the scale and the
pins are theirs, and 'tactip replay --calibration' and 'tactip dataset build --calibration' use the file.

Examples:
  tactip calibrate --config samples/station_sim.toml
  tactip calibrate --config station.toml --rest-frames 30
  tactip calibrate --config gel_station.toml --sensor gelsight-mini
  tactip calibrate --frames slide_000.avi --sensor radial-led-120 --out data/calibration.h5
  tactip calibrate --frames rest/ --pins-on-pad 120 --pad-diameter-mm 30 --out data/calibration.h5
"""

from __future__ import annotations

import argparse
from pathlib import Path

from tactip.cli._types import creatable_file, float_in_range, int_in_range

#: Most rest frames calibrate averages: a few seconds of a camera is plenty.
MAX_REST_FRAMES = 1000

HELP = "calibrate the TacTip (detection, reference pins, feature pins) from rest frames"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the parser for `tactip calibrate`."""
    where = parser.add_mutually_exclusive_group(required=True)
    where.add_argument("--config", type=Path, help="station TOML file")
    where.add_argument("--frames", type=Path, metavar="REST",
                       help="without a station: a video (its first --rest-frames frames), a folder of frames or an "
                       "image of the pad off contact; needs --out")
    parser.add_argument("--rest-frames", type=int_in_range(1, MAX_REST_FRAMES), default=10, metavar="N",
                        help=f"frames off contact to average, 1..{MAX_REST_FRAMES} (default 10)")
    parser.add_argument("--out", type=creatable_file, default=None,
                        help="calibration file (default: [sensor] calibration or DATA_DIR/calibration.h5)")
    # The names are checked when the command runs (`pins.sensor_preset`): building this parser imports no
    # package, so a bad station file is reported at once (`tactip detect --help` lists the sensors).
    parser.add_argument("--sensor", metavar="NAME",
                        help="the sensor, instead of [sensor] preset: its pins (markers in view on a flat gel) are "
                        "the count expected and its pin (or marker) pitch gives the scale (e.g. gelsight-mini, "
                        "tactip-331; 'tactip detect --help' lists them)")
    from tactip.cli._scale import pin_count

    frames = parser.add_argument_group("with --frames (as 'tactip replay' and 'tactip dataset build' take them)")
    frames.add_argument("--pins-on-pad", type=pin_count, metavar="N",
                        help="pins on the whole pad, in view or not, for the pin pitch (default: the sensor's, "
                        "else the pins detected)")
    frames.add_argument("--pad-diameter-mm", type=float_in_range(0, 500, low_open=True, unit="mm"), metavar="MM",
                        help="diameter of the hemispherical pad, mm, for the pin pitch (default: the sensor's, "
                        "else 40)")
    frames.add_argument("--mm-per-px", type=float_in_range(0, 10, low_open=True, unit="mm/px"), metavar="MM",
                        help="image scale at the pad, mm per px, instead of the one from the pin pitch")
    frames.add_argument("--expected-pins", type=pin_count, metavar="N",
                        help="pins in view, to confirm the count found (default: those found)")
    frames.add_argument("--pins", type=int_in_range(1, 1000), default=40, metavar="N",
                        help="feature pins to choose (default 40)")
    frames.add_argument("--min-separation-mm", type=float_in_range(0, 100, unit="mm"), default=4.0, metavar="MM",
                        help="least separation of the feature pins, mm (default 4; as far apart as the pad allows)")
    frames.add_argument("--dark-pins", action="store_true", help="dark markers on a light membrane (default: "
                        "decided from the frames, as 'tactip detect' decides)")


def run(args: argparse.Namespace) -> int:
    """Run `tactip calibrate`."""
    from tactip._output import refuse_replacing_project_files
    from tactip.errors import TactipError
    from tactip.station.config import load_station_config
    from tactip.station.procedures import calibrate_station, calibration_path

    if args.frames is not None:
        return _run_frames(args)
    given = [flag for flag, value in (("--pins-on-pad", args.pins_on_pad), ("--pad-diameter-mm", args.pad_diameter_mm),
                                      ("--mm-per-px", args.mm_per_px), ("--expected-pins", args.expected_pins),
                                      ("--dark-pins", args.dark_pins or None))
             if value is not None]
    if given:
        raise TactipError(f"{', '.join(given)} go with --frames; a station's [sensor] describes its sensor")
    config = load_station_config(args.config)
    if args.sensor:
        try:
            config = with_sensor(config, args.sensor)
        except ValueError as exc:
            raise TactipError(f"--sensor: {exc}") from None
    refuse_replacing_project_files([args.out or calibration_path(config)], overwrite=args.overwrite)
    calibrate_station(config, rest_frames=args.rest_frames, out=args.out)
    return 0


def _run_frames(args: argparse.Namespace) -> int:
    """`tactip calibrate --frames`: rest frames of a recording -> the calibration file, no station."""
    from calibration import save_calibration
    from pins import sensor_preset

    from tactip._output import refuse_overwriting_inputs, refuse_replacing_project_files
    from tactip.dataset.build import make_calibration
    from tactip.errors import TactipError

    if args.out is None:
        raise TactipError("--frames needs --out (the calibration file to write)")
    if args.sensor:
        try:
            sensor_preset(args.sensor)
        except ValueError as exc:
            raise TactipError(f"--sensor: {exc}") from None
    refuse_overwriting_inputs([args.out], [args.frames])
    refuse_replacing_project_files([args.out], overwrite=args.overwrite)
    frames = read_rest_frames(args.frames, args.rest_frames)
    calibration = make_calibration(frames, expected_pins=args.expected_pins, n_pins=args.pins,
                                   min_separation_mm=args.min_separation_mm, sensor=args.sensor,
                                   pins_on_pad=args.pins_on_pad, pad_diameter_mm=args.pad_diameter_mm,
                                   mm_per_px=args.mm_per_px, dark_pins=True if args.dark_pins else None,
                                   source=str(args.frames))
    save_calibration(args.out, calibration)
    if not args.quiet:
        frames_text = f"{len(frames)} rest frame" + ("s" if len(frames) != 1 else "")
        print(f"calibrated on {frames_text} of {args.frames}: {calibration.describe()}")
        print(f"wrote {args.out}")
    return 0


def read_rest_frames(path: Path, count: int) -> list:
    """The first ``count`` frames (grey uint8) of a video, a folder of frames or an image."""
    from tactip import open_source
    from tactip.errors import TactipError

    if not path.exists():
        raise TactipError(f"--frames: {path} does not exist")
    frames = []
    with open_source(str(path), grey=True) as source:
        for frame in source:
            frames.append(frame.image)
            if len(frames) == count:
                break
    if not frames:
        raise TactipError(f"--frames: no frame could be read from {path}")
    return frames


def with_sensor(config, name: str):
    """The station configuration with ``[sensor]`` describing the named sensor (`pins.SENSOR_PRESETS`):
    its preset, its pin count (a flat gel's: the markers in view) and its pad diameter (a TacTip's)."""
    import dataclasses

    from pins import sensor_preset

    description = sensor_preset(name)
    changes = {"preset": name, "pins": description.pins}
    if not description.flat:
        changes["pad_diameter_mm"] = description.pad_diameter_mm
    return dataclasses.replace(config, sensor=dataclasses.replace(config.sensor, **changes))
