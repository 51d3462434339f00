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

Examples:
  tactip calibrate --config samples/station_sim.toml
  tactip calibrate --config station.toml --rest-frames 30
  tactip calibrate --config gel_station.toml --sensor gelsight-mini
"""

from __future__ import annotations

import argparse
from pathlib import Path

from tactip.cli._types import creatable_file, int_in_range

#: Most rest frames calibrate averages: a few seconds of a camera is plenty.
MAX_REST_FRAMES = 1000

HELP = "calibrate the TacTip (detection, reference pins, feature pins) from rest frames"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the parser for `tactip calibrate`."""
    parser.add_argument("--config", type=Path, required=True, help="station TOML file")
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


def run(args: argparse.Namespace) -> int:
    """Run `tactip calibrate`."""
    from tactip._output import refuse_replacing_project_files
    from tactip.errors import TactipError
    from tactip.station.config import load_station_config
    from tactip.station.procedures import calibrate_station, calibration_path

    config = load_station_config(args.config)
    if args.sensor:
        try:
            config = with_sensor(config, args.sensor)
        except ValueError as exc:
            raise TactipError(f"--sensor: {exc}") from None
    refuse_replacing_project_files([args.out or calibration_path(config)], overwrite=args.overwrite)
    calibrate_station(config, rest_frames=args.rest_frames, out=args.out)
    return 0


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
