"""Inspect gaps by active Bayesian perception and store every result.

For each [[gaps]] entry: move over the gap, tap, update the (depth, width) beliefs, move in depth
as the policy asks, until the width belief crosses the decision threshold or max_taps is reached
(then the result is 'undecided'); judge the width against nominal +- tolerance. Every tap and
verdict goes to the results database (SQLite, or PostgreSQL for a line) as it happens ('tactip results list').
An arm fault stops the arm, records the inspection as aborted with the reason, and exits 1.

--sim runs the packaged simulated station (synthetic TacTip on a simulated arm over a plate of
20 gaps, 0.25-5 mm) with no hardware; on first use it calibrates, collects the training taps,
trains and picks the fixation depth (a few minutes), keeping everything in --data-dir (default
$TACTIP_SIM_DIR, else ~/.local/share/tactip/sim, whatever the current folder; the first line says where).

For a script: --json [FILE|-] writes the verdicts as JSON (to standard output with no value or '-',
every other line then going to standard error), and --fail-on sets the exit status:

  0  every inspection finished, and none is a verdict --fail-on names
  1  an error (bad input, an arm fault: the inspection is stored as aborted)
  2  a bad command line
  3  --fail-on fail: some gap FAILED; --fail-on undecided: some gap FAILED or stayed UNDECIDED
  130  stopped by Ctrl-C

Examples:
  tactip inspect --sim
  tactip inspect --sim --policy stationary --seed 3
  tactip inspect --sim --gap g01 --gap g02 --json --fail-on undecided > verdicts.json
  tactip inspect --config station.toml --gap door-left
"""

from __future__ import annotations

import argparse
import shlex
from pathlib import Path

from perception.choices import POLICIES
from tactip.cli._types import add_json_argument, finite_float, seed

#: Exit status when a verdict named by --fail-on is met (1 is an error, 2 a bad command line).
EXIT_VERDICT = 3

HELP = "inspect the configured gaps (or --sim: the simulated station, no hardware)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the parser for `tactip inspect`."""
    where = parser.add_mutually_exclusive_group(required=True)
    where.add_argument("--config", type=Path, help="station TOML file")
    where.add_argument("--sim", action="store_true", help="the packaged simulated station")
    parser.add_argument("--data-dir", type=Path, default=None,
                        help="with --sim: where the model, datasets and results live (default $TACTIP_SIM_DIR, else ~/.local/share/tactip/sim, whatever the "
                             "current folder)")
    parser.add_argument("--policy", choices=POLICIES, default=None,
                        help="override [perception] policy")
    parser.add_argument("--seed", type=seed, default=None, help="seed of the random start depths (>= 0)")
    parser.add_argument("--gap", action="append", default=None, metavar="NAME",
                        help="inspect only this gap (repeatable)")
    parser.add_argument("--start-depth", type=finite_float, default=None, metavar="MM",
                        help="start every inspection at this depth instead of a random one")
    add_json_argument(parser, "the verdicts (gap, nominal and estimated width in mm, belief, taps, verdict, "
                              "result id)")
    parser.epilog = (f"exit status: 0 done (whatever the verdicts, without --fail-on); 1 an error; 2 a bad command "
                     f"line; {EXIT_VERDICT} a verdict --fail-on names; 130 stopped by Ctrl-C")
    parser.add_argument("--fail-on", choices=("fail", "undecided"), default=None,
                        help=f"exit {EXIT_VERDICT} when a gap FAILED (fail), or FAILED or stayed UNDECIDED "
                             f"(undecided); default: exit 0 whatever the verdicts")


def run(args: argparse.Namespace) -> int:
    """Run `tactip inspect`; exit 0 when every inspection finished (3 when --fail-on meets its verdict)."""
    import time

    from tactip.station.config import load_station_config, simulated_station_config
    from tactip.station.inspection import inspect_station
    from tactip.errors import TactipError
    from tactip.station.procedures import model_is_prepared, prepare_model

    if args.data_dir is not None and not args.sim:
        raise TactipError("--data-dir goes with --sim; a station TOML names its own [station] data_dir")
    config = simulated_station_config(args.data_dir) if args.sim else load_station_config(args.config)
    if args.sim:
        print(f"simulated station in {config.data_dir}")
    known = [gap.name for gap in config.gaps]
    unknown = [name for name in args.gap or () if name not in known]
    if unknown:  # said before any preparation or inspection starts
        raise TactipError(f"no gap {', '.join(map(repr, unknown))} on station {config.name!r}; its gaps are "
                          f"{', '.join(known[:30])}{' ...' if len(known) > 30 else ''}")
    protocol = config.protocol
    if args.start_depth is not None and not protocol.depth_min - 1e-9 <= args.start_depth <= protocol.depth_max + 1e-9:
        # Refused before anything starts: no inspection row is opened for a depth the station cannot tap.
        raise TactipError(f"--start-depth {args.start_depth:g} mm is outside the protocol range "
                          f"{protocol.depth_min:g}..{protocol.depth_max:g} mm")
    if args.sim and not model_is_prepared(config.perception.model):
        if config.perception.model.exists():
            print(f"The model in {config.data_dir} has no recommended settings (an earlier preparation was "
                  f"interrupted): resuming the preparation.")
        else:
            print(f"No trained model in {config.data_dir} yet: training one on the simulated station first "
                  f"(calibrate, collect, train, choose the fixation depth; a few minutes, once).")
        started = time.monotonic()
        prepare_model(config, progress=not args.quiet)
        print(f"model ready in {time.monotonic() - started:.0f} s")
    started = time.monotonic()
    log = (lambda line: None if line.startswith("  ") else print(line)) if args.quiet else print
    outcomes = inspect_station(config, policy=args.policy, seed=args.seed, gaps=args.gap,
                               start_depth=args.start_depth, log=log)
    print(summary(outcomes, time.monotonic() - started))
    from tactip.line.results import describe_location

    where = describe_location(config.results)
    print(f"results: {where}  (tactip results list --db {shlex.quote(where)})")
    if args.json is not None:
        from tactip._output import write_json

        write_json(args.json, [verdict_row(o) for o in outcomes])
    return exit_status(outcomes, args.fail_on)


def verdict_row(outcome) -> dict:
    """One inspection as JSON-ready values (widths in mm, belief 0-1)."""
    gap = outcome.gap
    return {"gap": gap.name, "verdict": outcome.verdict, "nominal_width_mm": gap.nominal_width,
            "tolerance_mm": gap.tolerance, "estimated_width_mm": round(float(outcome.estimated_width), 6),
            "belief": round(float(outcome.belief), 6), "taps": int(outcome.taps), "decided": bool(outcome.decided),
            "duration_s": round(float(outcome.duration_s), 3), "result_id": int(outcome.inspection_id)}


def exit_status(outcomes, fail_on: str | None) -> int:
    """0, or `EXIT_VERDICT` when a verdict ``fail_on`` names is among ``outcomes`` (``"fail"``: FAIL;
    ``"undecided"``: FAIL or UNDECIDED)."""
    gating = {None: (), "fail": ("FAIL",), "undecided": ("FAIL", "UNDECIDED")}[fail_on]
    return EXIT_VERDICT if any(o.verdict in gating for o in outcomes) else 0


def summary(outcomes, elapsed_s: float) -> str:
    """One paragraph for a person: verdict counts, mean taps, mean width error where known."""
    import numpy as np

    verdicts = [o.verdict for o in outcomes]
    text = (f"{len(outcomes)} gap(s) in {elapsed_s:.0f} s: {verdicts.count('PASS')} pass, {verdicts.count('FAIL')} "
            f"fail, {verdicts.count('UNDECIDED')} undecided; mean {np.mean([o.taps for o in outcomes]):.1f} taps")
    errors = [abs(o.estimated_width - o.gap.true_width) for o in outcomes if o.gap.true_width is not None]
    if not errors:
        errors = [abs(o.estimated_width - o.gap.nominal_width) for o in outcomes]
        return text + f"; mean |estimate - nominal| {np.mean(errors):.2f} mm"
    return text + f"; mean width error {np.mean(errors):.2f} mm"
