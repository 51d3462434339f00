"""Keeping strangers out of the dashboard: the Host header, a connection cap, timeouts, the token's length.

- **Host** (`HostGuard`): a page on another site can make a browser resolve its own name to 127.0.0.1
  (DNS rebinding) and read a loopback dashboard as "its" server; the browser then sends that site's name
  as ``Host``. Only the bound address (loopback: also ``localhost``; a wildcard address: any IP address
  and this machine's names) and the names given with ``--allow-host`` are answered; anything else gets
  421 Misdirected Request.
- **Connections** (`guarded_protocol`): uvicorn's HTTP protocol with a cap on open connections, kept
  below the open-file limit, and a timeout for a request's head. Past the cap, the connection that has
  waited longest without sending a request (half-open, or idle between requests) is closed to make room,
  so a flood of half-open connections cannot starve a real client nor run the process out of files.
- **Token** (`check_token`, `new_token`): at least `MIN_TOKEN_CHARS` characters.
"""

from __future__ import annotations

import ipaddress
import resource
import secrets
import socket

__all__ = ["HostGuard", "allowed_hosts", "guarded_protocol", "check_token", "new_token", "connection_cap",
           "MIN_TOKEN_CHARS", "HEADER_TIMEOUT_S", "MAX_CONNECTIONS", "ACCEPT_BATCH"]

#: The shortest token accepted, characters (a generated one has 32).
MIN_TOKEN_CHARS = 16
#: Time a connection may take to send a request's head (request line and headers), s.
HEADER_TIMEOUT_S = 5.0
#: Most connections open at once (lowered to fit the open-file limit, `connection_cap`).
MAX_CONNECTIONS = 200
#: Connections accepted per turn of the event loop (uvicorn's ``backlog``; the kernel's queue stays longer).
ACCEPT_BATCH = 16
# Files kept free for the results database, the feed, logs and Python itself.
_FD_RESERVE = 64


def new_token() -> str:
    """A fresh random token (32 URL-safe characters)."""
    return secrets.token_urlsafe(24)


def check_token(token: str | None) -> None:
    """Refuse a token shorter than `MIN_TOKEN_CHARS` (None: no token, allowed on loopback).

    Raises
    ------
    ValueError
        ``the token must be at least 16 characters, got N: ...``.
    """
    if token is not None and len(token) < MIN_TOKEN_CHARS:
        raise ValueError(f"the token must be at least {MIN_TOKEN_CHARS} characters, got {len(token)}: give "
                         f"--token without a value to have one generated")


def connection_cap(max_connections: int = MAX_CONNECTIONS) -> int:
    """``max_connections``, lowered so that the cap plus the connections accepted before it applies fit the
    process's open-file limit (``ulimit -n``)."""
    soft, _ = resource.getrlimit(resource.RLIMIT_NOFILE)
    if soft == resource.RLIM_INFINITY:
        return int(max_connections)
    return max(4, min(int(max_connections), soft - _FD_RESERVE - 4 * ACCEPT_BATCH))


def allowed_hosts(bind_host: str, names=()) -> frozenset[str] | None:
    """The host names a dashboard bound to ``bind_host`` answers to (lower case, no port).

    ``None`` in the result's place means "any IP address": a wildcard bind (``0.0.0.0``, ``::``); the
    machine's own names and ``names`` are in the set then. Loopback adds ``localhost``, ``127.0.0.1``, ``::1``.
    """
    hosts = {n.lower().strip("[]") for n in names if n}
    host = bind_host.lower().strip("[]")
    try:
        address = ipaddress.ip_address(host)
    except ValueError:
        address = None
    if host == "localhost" or (address is not None and address.is_loopback):
        hosts |= {"localhost", "127.0.0.1", "::1", host}
    elif address is not None and address.is_unspecified:
        hosts |= {"localhost", socket.gethostname().lower(), socket.getfqdn().lower(), "*ip*"}
    else:
        hosts.add(host)
    return frozenset(hosts)


def _host_name(value: bytes) -> str:
    text = value.decode("latin-1").strip().lower()
    if text.startswith("["):                       # [::1]:8050
        return text[1:text.find("]")] if "]" in text else text
    return text.rsplit(":", 1)[0] if text.count(":") == 1 else text


class HostGuard:
    """ASGI middleware: answer 421 to a request whose ``Host`` is not one of ``hosts`` (`allowed_hosts`), 400
    to one without a Host.

    Parameters
    ----------
    app : ASGI app
    hosts : frozenset of str
        From `allowed_hosts`; ``"*ip*"`` in it admits any IP address.
    """

    def __init__(self, app, hosts: frozenset[str]):
        self.app, self.hosts = app, frozenset(hosts)
        self.state = getattr(app, "state", None)

    def __repr__(self) -> str:
        return f"HostGuard(hosts={sorted(self.hosts)!r})"

    def allows(self, host_header: bytes | None) -> bool:
        """Whether a request with this ``Host`` value is answered."""
        if not host_header:
            return False
        name = _host_name(host_header)
        if name in self.hosts:
            return True
        if "*ip*" in self.hosts:
            try:
                ipaddress.ip_address(name)
                return True
            except ValueError:
                return False
        return False

    async def __call__(self, scope, receive, send):
        if scope["type"] == "http":
            host = next((v for k, v in scope.get("headers", []) if k == b"host"), None)
            if not self.allows(host):
                from starlette.responses import PlainTextResponse

                text = ("this dashboard answers to " + ", ".join(sorted(h for h in self.hosts if h != "*ip*"))
                        + (" and IP addresses" if "*ip*" in self.hosts else "")
                        + "; serve it with --allow-host NAME to open it by another name")
                response = PlainTextResponse(text, status_code=421 if host else 400)
                await response(scope, receive, send)
                return
        await self.app(scope, receive, send)


def guarded_protocol(*, max_connections: int, header_timeout_s: float = HEADER_TIMEOUT_S):
    """uvicorn's h11 protocol class with a connection cap and a timeout for the request head.

    Parameters
    ----------
    max_connections : int
        Most connections open at once (see `connection_cap`). A connection past it closes the one that has
        waited longest for a request (never one being answered, such as an event stream); when there is none,
        the new connection is closed.
    header_timeout_s : float
        A connection that has not sent a whole request head this long after it opened (or after its last
        answer) is closed, s.
    """
    from uvicorn.protocols.http.h11_impl import H11Protocol

    class GuardedH11Protocol(H11Protocol):
        _waiting_since: float | None = None
        _head_timer = None

        def connection_made(self, transport) -> None:
            super().connection_made(transport)
            self._await_request()
            if len(self.connections) > max_connections:
                idle = [c for c in self.connections if c is not self and getattr(c, "_waiting_since", None) is not None]
                victim = min(idle, key=lambda c: c._waiting_since, default=self)
                victim._drop()

        def _await_request(self) -> None:
            self._waiting_since = self.loop.time()
            if self._head_timer is not None:
                self._head_timer.cancel()
            self._head_timer = self.loop.call_later(header_timeout_s, self._head_too_slow)

        def _head_too_slow(self) -> None:
            self._head_timer = None
            if self._waiting_since is not None:
                self._drop()

        def _drop(self) -> None:
            self._waiting_since = None
            if self._head_timer is not None:
                self._head_timer.cancel()
                self._head_timer = None
            if not self.transport.is_closing():
                self.transport.close()

        def handle_events(self) -> None:
            super().handle_events()
            if self.cycle is not None and not self.cycle.response_complete and self._waiting_since is not None:
                self._waiting_since = None                  # a request head arrived: it is being answered
                if self._head_timer is not None:
                    self._head_timer.cancel()
                    self._head_timer = None

        def on_response_complete(self) -> None:
            if not self.transport.is_closing():
                self._await_request()                       # before super(): it may start a pipelined request
            super().on_response_complete()

        def connection_lost(self, exc) -> None:
            self._waiting_since = None
            if self._head_timer is not None:
                self._head_timer.cancel()
                self._head_timer = None
            super().connection_lost(exc)

    return GuardedH11Protocol
