"""List and export stored inspection results.

The station writes every inspection (and every tap, with its beliefs) to its results database as it
happens: an SQLite file, or a PostgreSQL database shared by a line of stations. Name the database
with --config (the station's [station] results) or --db (a file, or a postgresql:// URL); --station
keeps one station's rows. --json [FILE|-] writes JSON (list and export), to standard output with no
value or '-', else to FILE (like export's --out).

Examples:
  tactip results list --config samples/station_sim.toml
  tactip results list --db ~/.local/share/tactip/sim/results.sqlite --limit 20
  tactip results export --config samples/station_sim.toml --csv --out results.csv
  tactip results export --db results.sqlite --json
  tactip results list --config samples/station_sim.toml --json > out/results.json
  tactip results plot --config samples/station_sim.toml --out widths.png --last 20
  tactip results list --db postgresql://tactip@db.plant/line3 --station cell-2
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from tactip.cli._types import add_json_argument, image_file, int_at_least, json_target, output_file

HELP = "list or export stored inspection results (SQLite or PostgreSQL)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the parser for `tactip results`."""
    sub = parser.add_subparsers(dest="action", metavar="ACTION")
    sub.required = True
    for name, text in (("list", "print the inspections as a table"),
                       ("export", "write the inspections as CSV or JSON"),
                       ("plot", "plot estimated against nominal widths with the tolerance bands")):
        p = sub.add_parser(name, help=text, description=text)
        where = p.add_mutually_exclusive_group(required=True)
        where.add_argument("--config", type=Path, help="station TOML file (its [station] results database)")
        where.add_argument("--db", type=_location, metavar="FILE|URL",
                           help="results database: an SQLite file or a postgresql:// URL")
        p.add_argument("--station", default=None, metavar="NAME", help="only this station's inspections")
        if name == "list":
            p.add_argument("--limit", type=int_at_least(1), default=None, metavar="N",
                           help="show only the newest N inspections (N >= 1)")
            add_json_argument(p, "the inspections (instead of the table)")
        elif name == "plot":
            p.add_argument("--out", type=image_file, required=True, help="image file (.png, .pdf, .svg)")
            p.add_argument("--last", type=int_at_least(1), default=None, metavar="N",
                           help="only the newest N inspections (N >= 1)")
        else:
            fmt = p.add_mutually_exclusive_group(required=True)
            fmt.add_argument("--csv", action="store_true", help="comma-separated values with a header")
            fmt.add_argument("--json", type=json_target, nargs="?", const=json_target("-"), default=None,
                             metavar="FILE|-", help="a JSON list of objects, to standard output (no value or -) "
                                                    "or to FILE")
            p.add_argument("--out", type=output_file, default=None, help="output file (default: standard output)")


def run(args: argparse.Namespace) -> int:
    """Run `tactip results list|export`."""
    from tactip.line.results import is_database_url, open_results

    path = args.db
    if args.config is not None:
        from tactip.station.config import load_station_config

        path = load_station_config(args.config).results
    from tactip.errors import TactipError

    if args.action == "export" and args.json is not None and str(args.json) != "-" and args.out is not None:
        raise TactipError("give the JSON file once: --json FILE or --json --out FILE")
    if args.action == "export" and args.json is not None and str(args.json) != "-":
        args.out = args.json
    out = getattr(args, "out", None) or (args.json if args.action == "list" else None)
    if out is not None and str(out) != "-":
        from tactip._output import refuse_overwriting_inputs

        # The database and its WAL companions are inputs: an output over one of them would destroy it.
        files = [] if is_database_url(path) else [path, Path(f"{path}-wal"), Path(f"{path}-shm")]
        refuse_overwriting_inputs([out], [*files, args.config])
    inputs = [] if is_database_url(path) else [path]
    with open_results(path, read_only=True) as store:
        if args.action == "list":
            rows = store.inspections(limit=args.limit, station=args.station)
            if args.json is None:
                print(format_table(rows))
            else:
                from tactip._output import write_json

                write_json(args.json, json.loads(store.export_json(rows)), inputs=inputs)
            return 0
        if args.action == "plot":
            from tactip.line.results import plot_inspections

            plot_inspections(store.inspections(limit=args.last, station=args.station), args.out, inputs=inputs)
            print(f"wrote {args.out}")
            return 0
        rows = store.inspections(station=args.station)
        text = store.export_csv(rows) if args.csv else store.export_json(rows) + "\n"
    if args.out is None and args.json is not None:                      # JSON to standard output
        from tactip._output import write_json

        write_json("-", json.loads(text))
    elif args.out is None:
        sys.stdout.write(text)
    else:
        from tactip._output import write_text_atomic

        write_text_atomic(args.out, text, inputs=inputs)
        print(f"wrote {args.out}", file=sys.stderr)
    return 0


def _location(text: str) -> Path | str:
    """--db: a postgresql:// URL as given, else a file path."""
    from tactip.line.results import is_database_url

    return text if is_database_url(text) else Path(text)


def format_table(rows) -> str:
    """Inspections as a fixed-width text table (mm, belief 0-1)."""
    head = (f"{'id':>4}  {'station':<10} {'gap':<12} {'nominal':>7} {'estimate':>8} {'belief':>6} {'taps':>4}  "
            f"{'result':<9} {'policy':<10} started")
    lines = [head, "-" * len(head)]
    for r in rows:
        if r.status == "aborted":
            result = "ABORTED"
        elif r.status == "running":
            result = "running"
        else:
            result = {True: "pass", False: "FAIL", None: "undecided"}[r.passed]
        est = "" if r.estimated_width is None else f"{r.estimated_width:.2f}"
        belief = "" if r.belief is None else f"{r.belief:.3f}"
        lines.append(f"{r.id:>4}  {r.station or '':<10} {r.gap:<12} {r.nominal_width:>7.2f} {est:>8} {belief:>6} {r.taps:>4}  "
                     f"{result:<9} {r.policy:<10} {r.started_at[:19].replace('T', ' ')}")
    if len(lines) == 2:
        lines.append("(no inspections)")
    return "\n".join(lines)
