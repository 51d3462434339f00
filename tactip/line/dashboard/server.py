"""Running the dashboard: uvicorn on a socket of its own, bound to loopback unless a token guards it."""

from __future__ import annotations

import ipaddress
import socket
import signal
import threading

from tactip.errors import TactipError
from tactip.line.dashboard.guard import (ACCEPT_BATCH, HEADER_TIMEOUT_S, MAX_CONNECTIONS, HostGuard, allowed_hosts,
                                         check_token, connection_cap, guarded_protocol)

__all__ = ["DashboardServer", "check_bind", "DashboardError", "KEEP_ALIVE_S"]

#: An idle keep-alive connection is closed after this long, s.
KEEP_ALIVE_S = 5
#: The largest request head accepted, bytes.
MAX_HEAD_BYTES = 16 * 1024
#: The kernel's queue of connections not yet accepted.
LISTEN_BACKLOG = 1024


class DashboardError(TactipError):
    """The dashboard cannot start (address in use, a public address without a token)."""


def check_bind(host: str, token: str | None) -> None:
    """Refuse to serve on an address other than loopback without a token, or with a short token.

    Raises
    ------
    DashboardError
        ``--host X is not loopback: give --token ...``; a token shorter than 16 characters.
    """
    try:
        check_token(token)
    except ValueError as exc:
        raise DashboardError(str(exc)) from None
    if token:
        return
    if host == "localhost":
        return
    try:
        loopback = ipaddress.ip_address(host).is_loopback
    except ValueError:
        loopback = False
    if not loopback:
        raise DashboardError(f"--host {host} is reachable from other machines: give --token TOKEN (or set "
                             f"TACTIP_SERVE_TOKEN) to require it on every request, or serve on 127.0.0.1")


class DashboardServer:
    """The dashboard app served by uvicorn in a background thread (``with`` starts and stops it).

    Every request must name the bound address (or one of ``allow_hosts``) in its ``Host`` header
    (`tactip.line.dashboard.guard.HostGuard`); connections are capped and must send their request head
    within ``header_timeout_s`` (`tactip.line.dashboard.guard.guarded_protocol`), idle keep-alive ones
    are closed after `KEEP_ALIVE_S`.

    Parameters
    ----------
    app : ASGI app
        From `tactip.line.dashboard.make_app`.
    host : str
        Address to bind (default loopback).
    port : int
        TCP port; 0 picks a free one (see `url`).
    allow_hosts : sequence of str
        More host names the page may be opened by (a DNS name of this machine, a proxy's name).
    max_connections : int
        Most connections open at once; lowered to fit the open-file limit (`guard.connection_cap`).
    header_timeout_s : float
        Time a connection may take to send a request's head, s.
    """

    def __init__(self, app, *, host: str = "127.0.0.1", port: int = 8050, allow_hosts=(),
                 max_connections: int = MAX_CONNECTIONS, header_timeout_s: float = HEADER_TIMEOUT_S):
        import uvicorn

        family = socket.AF_INET6 if ":" in host else socket.AF_INET
        self._socket = socket.socket(family, socket.SOCK_STREAM)
        self._socket.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            self._socket.bind((host, int(port)))
            self._socket.listen(LISTEN_BACKLOG)  # connections wait from now on, until the server takes them
        except OSError as exc:
            self._socket.close()
            raise DashboardError(f"cannot serve on {host}:{port} ({exc.strerror or exc}): is another "
                                 f"dashboard running there? choose another --port") from None
        self.host, self.port = host, self._socket.getsockname()[1]
        feed = getattr(getattr(app, "state", None), "feed", None)
        self.hosts = allowed_hosts(host, allow_hosts)
        self.max_connections = connection_cap(max_connections)
        protocol = guarded_protocol(max_connections=self.max_connections, header_timeout_s=header_timeout_s)
        config = uvicorn.Config(HostGuard(app, self.hosts), log_level="warning", lifespan="on",
                                timeout_graceful_shutdown=2, access_log=False, http=protocol, backlog=ACCEPT_BATCH,
                                timeout_keep_alive=KEEP_ALIVE_S, h11_max_incomplete_event_size=MAX_HEAD_BYTES)
        listen_socket = self._socket

        class Server(uvicorn.Server):
            stopped_by: int | None = None

            async def startup(self, sockets=None):
                await super().startup(sockets=sockets)
                # asyncio listens with uvicorn's backlog, which is also how many it accepts per turn (kept
                # small so that the cap applies before the open files run out); the kernel's queue stays long.
                listen_socket.listen(LISTEN_BACKLOG)

            def handle_exit(self, sig, frame):  # Ctrl-C, SIGTERM: end the event streams, then stop
                self.stopped_by = self.stopped_by or sig
                if feed is not None:
                    feed.stop()
                super().handle_exit(sig, frame)

        self._server, self._feed = Server(config), feed
        self._thread: threading.Thread | None = None

    @property
    def url(self) -> str:
        """The page's address, ``http://host:port/``."""
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}/"

    def serve_forever(self) -> None:
        """Serve in this thread until Ctrl-C / SIGTERM, then raise `KeyboardInterrupt` / `Terminated`.

        uvicorn raises the signal again once it has stopped; that does nothing where the signal was
        ignored when the process started (SIGINT in a job a script put in the background), so the
        stop is raised here too.
        """
        from tactip._signals import Terminated

        self._server.run(sockets=[self._socket])
        self._socket.close()
        if self._server.stopped_by == signal.SIGINT:
            raise KeyboardInterrupt
        if self._server.stopped_by is not None:
            raise Terminated(self._server.stopped_by)

    def start(self) -> "DashboardServer":
        """Serve in a background thread; returns once the server accepts requests."""
        self._server.config.install_signal_handlers = False  # not the main thread
        self._thread = threading.Thread(target=self._server.run, kwargs=dict(sockets=[self._socket]),
                                        name="tactip-dashboard", daemon=True)
        self._thread.start()
        while not self._server.started:
            if not self._thread.is_alive():
                raise DashboardError(f"the dashboard on {self.url} failed to start")
            self._thread.join(0.02)
        return self

    def stop(self) -> None:
        """Stop serving and wait for the thread."""
        if self._feed is not None:
            self._feed.stop()  # ends the event streams, which would hold the shutdown
        self._server.should_exit = True
        if self._thread is not None:
            self._thread.join(10)
        self._socket.close()

    def __enter__(self) -> "DashboardServer":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()
