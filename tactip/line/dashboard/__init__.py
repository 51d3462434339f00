"""The station's live dashboard (`tactip serve`): a read-only web page over the results database.

It shows, live while `tactip inspect` runs (on this host or any station writing to the same
PostgreSQL database), one tile per station with its last verdict, alarms (a stop, an aborted
inspection, a station offline by its heartbeat), each tap as it is stored, the belief over widths,
per-gap trend charts on a time axis against the tolerance band and control limits, and the process
capability (Cp/Cpk) per gap and station; with the station stopped it shows the history. It reads
only: the store is opened read-only and every route is a GET. `tactip.line.dashboard.guard` keeps
strangers out (Host header, connection cap, header timeout, token length).

Examples
--------
>>> from tactip.line.dashboard import make_app, DashboardServer
>>> from tactip.line.results import open_results
>>> app = make_app(lambda: open_results("results.sqlite", read_only=True))  # doctest: +SKIP
>>> with DashboardServer(app, port=0) as server:                            # doctest: +SKIP
...     print(server.url)
"""

from tactip.line.dashboard.app import TokenRequired, make_app
from tactip.line.dashboard.feed import LiveFeed
from tactip.line.dashboard.server import DashboardError, DashboardServer, check_bind
from tactip.line.dashboard.summary import dashboard_state, gap_trends, station_status

__all__ = ["make_app", "TokenRequired", "LiveFeed", "DashboardServer", "DashboardError", "check_bind",
           "dashboard_state", "gap_trends", "station_status"]
