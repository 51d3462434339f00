"""Set up the arm of a station: check that it is ready, then try one slow tap.

Only the [arm] table of the configuration file is read (see samples/arm_sim.toml and
samples/arm_ur.toml). Poses are in the work frame: z up, origin on the part's surface
reference, mm and degrees; a positive tap depth goes down into the part.

  tactip arm status --config station.toml
      Connect, print the TCP pose in the work frame and the robot and safety state.
      Exit status 0 only when the arm is ready to move. --json [FILE|-]: the same as JSON.

  tactip arm tap --config station.toml --depth 1.5 --at 30 0
      One slow tap at (30, 0) mm of the work frame, down to 1.5 mm below the surface
      reference. Depths or points outside the configured limits are refused before
      anything moves.

Example:
  tactip arm status --config samples/arm_sim.toml
"""

from __future__ import annotations

import argparse

from tactip.cli._types import add_json_argument, finite_float, positive_float

HELP = "check the arm of a station (status) and try one slow tap (tap)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the parser of ``tactip arm`` with its ``status`` and ``tap`` subcommands."""
    sub = parser.add_subparsers(dest="arm_command", metavar="ARM_COMMAND")
    sub.required = True
    status = sub.add_parser("status", help="print the TCP pose and robot/safety state; exit 0 only when ready",
                            description="Connect to the arm, print the TCP pose in the work frame and the robot "
                                        "and safety state. Exit status 0 only when the arm is ready to move.")
    status.add_argument("--config", required=True, metavar="TOML", help="station configuration with an [arm] table")
    add_json_argument(status, "the backend, pose, modes and readiness")
    tap = sub.add_parser("tap", help="one slow tap at a point of the work frame",
                         description="One slow tap to check a new set-up. The depth and the point are checked "
                                     "against the [arm] limits before anything moves.")
    tap.add_argument("--config", required=True, metavar="TOML", help="station configuration with an [arm] table")
    tap.add_argument("--depth", required=True, type=finite_float, metavar="MM",
                     help="depth of the tap below the surface reference z = 0, mm (positive = into the part)")
    tap.add_argument("--at", nargs=2, type=finite_float, default=(0.0, 0.0), metavar=("X", "Y"),
                     help="tap point in the work frame, mm (default: the origin)")
    tap.add_argument("--speed", type=positive_float, default=5.0, metavar="MM_S",
                     help="stroke speed, mm/s (default 5; capped by max_tap_speed)")


def run(args: argparse.Namespace) -> int:
    """Run ``tactip arm status`` or ``tactip arm tap``."""
    from arm import arm_status, check_tap, load_arm_config

    config = load_arm_config(args.config)
    if args.arm_command == "status":
        report = arm_status(config)
        if args.json is not None:
            from tactip._output import write_json

            write_json(args.json, report.to_dict(), inputs=[args.config])
        if str(args.json) != "-":
            print(report.format())
        return 0 if report.ready else 1
    x, y = args.at
    event = check_tap(config, depth_mm=args.depth, x_mm=x, y_mm=y, speed_mm_s=args.speed,
                      on_contact=lambda e: print(f"contact  t={e.time_s:.3f} s  z={e.pose.z:.3f} mm", flush=True))
    print(f"release  t={event.time_s:.3f} s  z={event.pose.z:.3f} mm")
    if event.contact is not None and not event.contact.in_contact:
        print(f"simulated contact: none, the pad stopped {-event.contact.indentation_mm:.3f} mm above the surface")
    elif event.contact is not None:
        c = event.contact
        gap = f"gap {c.gap_name} width {c.gap_width_mm:g} mm offset {c.gap_offset_mm:.3f} mm" if c.gap_name else "no gap"
        print(f"simulated contact: indentation {c.indentation_mm:.3f} mm, {gap}")
    print(f"tapped at ({x:g}, {y:g}) mm of the work frame, depth {args.depth:g} mm")
    return 0
