"""Serve the station's live dashboard: a read-only web page over its results database.

The page shows, live while 'tactip inspect' runs (here, or on any station writing to the same
PostgreSQL database), each tap as it is stored (depth, width estimate, belief), the belief over
widths, each verdict; the last verdicts; per-gap trend charts of the estimate against nominal with
the tolerance band, and Cp/Cpk per gap over a chosen window. With the station stopped it shows the
history. It never writes. It binds to 127.0.0.1 unless told otherwise; any other address needs
--token (or TACTIP_SERVE_TOKEN; 16 characters or more, --token alone generates one), and then every
request must carry it (open /?token=TOKEN). Requests naming another host than the bound address are
refused (421: DNS rebinding); add names with --allow-host. Connections are capped below the open-file
limit, and one that sends no request within 5 s is closed.

Examples:
  tactip serve --sim
  tactip serve --config station.toml --port 8050
  tactip serve --db postgresql://tactip@db.plant/line3
  tactip serve --config station.toml --host 0.0.0.0 --token --allow-host station3.plant.local
  TACTIP_SERVE_TOKEN=a-long-shared-secret tactip serve --config station.toml --host 0.0.0.0
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from tactip.cli._types import float_in_range, int_in_range
from tactip.line import HEARTBEAT_S, OFFLINE_AFTER_S

HELP = "serve the live dashboard of the results (browser page; read-only)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the parser for `tactip serve`."""
    where = parser.add_mutually_exclusive_group(required=True)
    where.add_argument("--config", type=Path, help="station TOML file (its [station] results database)")
    where.add_argument("--sim", action="store_true", help="the simulated station's results (in --data-dir)")
    where.add_argument("--db", metavar="FILE|URL", help="results database: an SQLite file or a postgresql:// URL")
    parser.add_argument("--data-dir", type=Path, default=None,
                        help="with --sim: the simulated station's folder (default $TACTIP_SIM_DIR, else ~/.local/share/tactip/sim, whatever the "
                             "current folder)")
    parser.add_argument("--host", default="127.0.0.1",
                        help="address to listen on (default 127.0.0.1; any other needs --token)")
    parser.add_argument("--port", type=int_in_range(0, 65535), default=8050,
                        help="TCP port (0-65535, default 8050; 0 picks a free one)")
    parser.add_argument("--token", nargs="?", const="", default=None,
                        help="require this token (16 characters or more) on every request; --token alone "
                             "generates one and prints the page's address with it (default: $TACTIP_SERVE_TOKEN)")
    parser.add_argument("--allow-host", action="append", default=[], metavar="NAME",
                        help="also answer requests that name this host (a DNS name of this machine, a proxy); "
                             "by default only the bound address (and localhost on loopback): any other Host "
                             "header is refused (421), which keeps DNS-rebinding web pages out. Repeatable")
    parser.add_argument("--offline-after", type=float_in_range(1.0, 3600.0), default=OFFLINE_AFTER_S, metavar="S",
                        help=f"show a working station offline (red, in the alarms) when it has not sent its "
                             f"heartbeat for S seconds (1-3600, default {OFFLINE_AFTER_S:g}; stations beat every "
                             f"{HEARTBEAT_S:g} s while they inspect)")


def run(args: argparse.Namespace) -> int:
    """Run `tactip serve` until Ctrl-C."""
    from tactip.line.dashboard import DashboardServer, check_bind, make_app
    from tactip.line.dashboard.guard import new_token
    from tactip.line.results import describe_location, is_database_url, open_results

    if args.data_dir is not None and not args.sim:
        from tactip.errors import TactipError

        raise TactipError("--data-dir goes with --sim (a station TOML or --db names its own results)")
    generated = args.token == ""
    token = new_token() if generated else (args.token or os.environ.get("TACTIP_SERVE_TOKEN") or None)
    check_bind(args.host, token)
    info = None
    if args.db is not None:
        location = args.db if is_database_url(args.db) else Path(args.db)
    else:
        from tactip.station.config import load_station_config, simulated_station_config


        config = simulated_station_config(args.data_dir) if args.sim else load_station_config(args.config)
        location, info = config.results, station_info(config)
    name = describe_location(location)
    app = make_app(lambda: open_results(location, read_only=True), token=token, station_info=info,
                   results_name=name, offline_after_s=args.offline_after)
    server = DashboardServer(app, host=args.host, port=args.port, allow_hosts=args.allow_host)
    shown = f"?token={token}" if generated else "?token=..." if token else ""
    print(f"dashboard of {name} on {server.url}{shown}  (Ctrl-C stops)", flush=True)
    if generated:
        print(f"token: {token}  (generated; give it with --token or TACTIP_SERVE_TOKEN to keep it)", flush=True)
    server.serve_forever()
    return 0


def station_info(config) -> dict:
    """What the configuration says of the station, for the page: arm, camera, model."""
    arm = config.arm.backend + (f" {config.arm.host}" if getattr(config.arm, "host", None) else "")
    model = config.perception.model
    return {"station": config.name, "arm": arm, "camera": f"{config.sensor.source}, {config.sensor.frame_rate:g} frames/s",
            "model": f"{model}{'' if model is not None and Path(model).exists() else ' (not trained yet)'}"}
