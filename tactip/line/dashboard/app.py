"""The dashboard's web app (Starlette): one page, its JSON state, and a server-sent event stream.

Routes (all GET; the app never writes):

``/``
    The page (``page.html``): live taps, the belief over widths, verdicts, trend charts, Cp/Cpk.
``/api/state?window=N&verdicts=M``
    `tactip.line.dashboard.summary.dashboard_state` as JSON (history: works with the station stopped).
``/api/events``
    Server-sent events from the `LiveFeed`: ``tap``, ``inspection`` and ``station`` (JSON rows), ``status``
    (the feed's: ``live`` or what keeps it from reading the store), a comment every `KEEPALIVE_S`; at most
    `MAX_STREAMS` at once.
``/healthz``
    ``ok`` and the feed's status.

With a token, every request must carry it: ``Authorization: Bearer TOKEN`` or ``?token=TOKEN``
(the page passes its own ``?token=`` on to its requests).
"""

from __future__ import annotations

import asyncio
import contextlib
import hmac
import json
from importlib import resources
from typing import Callable
from urllib.parse import parse_qs

from tactip.line.dashboard.feed import POLL_S, LiveFeed
from tactip.line.dashboard.guard import check_token
from tactip.line.dashboard.summary import OFFLINE_AFTER_S, dashboard_state

__all__ = ["make_app", "KEEPALIVE_S", "MAX_STREAMS"]

#: Time between keep-alive comments on an idle event stream, s.
KEEPALIVE_S = 15.0
#: Most event streams (live pages) at once; more are refused (503).
MAX_STREAMS = 32


def make_app(open_store: Callable, *, token: str | None = None, station_info: dict | None = None,
             results_name: str = "", poll_s: float = POLL_S, offline_after_s: float = OFFLINE_AFTER_S):
    """The Starlette app of the dashboard.

    Parameters
    ----------
    open_store : callable
        Returns a new read-only results store (`tactip.line.results.open_results` with ``read_only=True``);
        each request and the feed thread open their own.
    token : str, optional
        Required on every request when given; at least 16 characters (`guard.MIN_TOKEN_CHARS`).
    station_info : dict, optional
        Static facts about the station from its configuration (arm, camera frame rate, model).
    results_name : str
        The results location as it may be shown (no password).
    poll_s : float
        Time between two polls of the store by the live feed, s.
    offline_after_s : float
        A working station without a heartbeat for longer than this is shown offline, s.
    """
    from starlette.applications import Starlette
    from starlette.responses import HTMLResponse, JSONResponse, PlainTextResponse, Response, StreamingResponse
    from starlette.routing import Route

    check_token(token)
    feed = LiveFeed(open_store, poll_s=poll_s)
    streams = [0]  # open event streams
    page = resources.files("tactip.line.dashboard").joinpath("page.html").read_text(encoding="utf-8")

    def index(request):
        return HTMLResponse(page, headers={"Cache-Control": "no-store"})

    def state(request):  # sync: Starlette runs it in its thread pool
        window = _int_param(request, "window", 50, 2, 10_000)
        verdicts = _int_param(request, "verdicts", 20, 1, 1000)
        if isinstance(window, str) or isinstance(verdicts, str):
            return PlainTextResponse(window if isinstance(window, str) else verdicts, status_code=400)
        try:
            with open_store() as store:
                body = dashboard_state(store, verdicts=verdicts, window=window, station_info=station_info,
                                       offline_after_s=offline_after_s)
        except Exception as exc:  # no database yet, or the server is unreachable: the page says so
            body = dict(error=" ".join(str(exc).split()), stations=[], current=[], verdicts=[], gaps=[],
                        width_classes_mm=None, last_tap_id=0, station_info=station_info, window=window, alarms=[],
                        offline_after_s=offline_after_s)
        body.update(results=results_name, feed=feed.status)
        return JSONResponse(body, headers={"Cache-Control": "no-store"})

    async def events(request):
        if streams[0] >= MAX_STREAMS:
            return PlainTextResponse(f"too many live pages ({MAX_STREAMS}): close one", status_code=503)

        async def stream():  # subscribed only once it runs: a page gone before it starts leaves nothing behind
            queue = feed.subscribe()
            streams[0] += 1
            try:
                yield f"event: hello\ndata: {json.dumps({'feed': feed.status})}\n\n"
                while True:
                    try:
                        item = await asyncio.wait_for(queue.get(), KEEPALIVE_S)
                    except asyncio.TimeoutError:
                        yield ": keep-alive\n\n"
                        continue
                    if item is None:
                        return
                    name, data = item
                    yield f"event: {name}\ndata: {json.dumps(data)}\n\n"
            finally:
                feed.unsubscribe(queue)
                streams[0] -= 1

        return StreamingResponse(stream(), media_type="text/event-stream",
                                 headers={"Cache-Control": "no-store", "X-Accel-Buffering": "no"})

    def favicon(request):
        return Response(status_code=204)

    def health(request):
        return PlainTextResponse(f"ok\nfeed: {feed.status}\n")

    @contextlib.asynccontextmanager
    async def lifespan(app):
        feed.start()
        try:
            yield
        finally:
            feed.stop()

    app = Starlette(routes=[Route("/", index), Route("/api/state", state), Route("/api/events", events),
                            Route("/healthz", health), Route("/favicon.ico", favicon)], lifespan=lifespan)
    app.state.feed = feed
    return TokenRequired(app, token) if token else app


class TokenRequired:
    """ASGI middleware: refuse (401) any HTTP request without the token (header or ``?token=``)."""

    def __init__(self, app, token: str):
        self.app, self._token = app, token.encode()
        self.state = getattr(app, "state", None)

    async def __call__(self, scope, receive, send):
        if scope["type"] == "http" and not self._allowed(scope):
            from starlette.responses import PlainTextResponse

            response = PlainTextResponse("a token is required: open the page as /?token=TOKEN", status_code=401,
                                         headers={"WWW-Authenticate": "Bearer"})
            await response(scope, receive, send)
            return
        await self.app(scope, receive, send)

    def _allowed(self, scope) -> bool:
        given = parse_qs(scope.get("query_string", b"").decode("latin-1")).get("token", [""])[-1].encode()
        for name, value in scope.get("headers", []):
            if name == b"authorization" and value.lower().startswith(b"bearer "):
                given = value[7:].strip()
        return hmac.compare_digest(given, self._token)


def _int_param(request, name: str, default: int, low: int, high: int):
    text = request.query_params.get(name)
    if text is None:
        return default
    try:
        value = int(text)
    except ValueError:
        return f"{name} must be an integer in {low}..{high}, got {text!r}"
    if not low <= value <= high:
        return f"{name} must be an integer in {low}..{high}, got {value}"
    return value
