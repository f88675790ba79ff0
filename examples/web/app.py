"""A Starlette web backend for one gimbal: JSON commands, WebSocket telemetry, one page.

``create_app(gcu_url, **client_options)`` builds the ASGI app. It creates ONE
:class:`~gcu_async.GcuClient` (``gcu_async.connect(url, wait=False)``; a bad URL or option
raises at once) that every request shares. The app starts whether or not the GCU answers:
its lifespan opens the client, which returns at once and brings the link up in the
background (a GCU powered after the app), keeps it up through outages of any length, and
closes it on shutdown. Routes:

- ``GET /`` — the page (``static/index.html``), ``/static/*`` its script and style.
- ``GET /api/status`` — mode, attitude, relative angles, rates, zoom, flags, link health and
  ``connection`` (:meth:`~examples.web.snapshot.Attempts.json`); 503 ``NotConnected``
  (with ``connection``) while the client is not open (no reply yet, or it failed).
- ``GET /api/commands`` — the commands below with their parameters.
- ``POST /api/commands/{name}`` — run a command; JSON object body of parameters
  (``Content-Type: application/json``, at most ``max_body`` bytes). Errors:
  404 unknown command, 415 not declared JSON, 413 too large, 400 body not JSON (or nested
  too deep, or with duplicate keys), 422 bad parameter (``ValueError`` /
  ``FieldRangeError``), 409 GCU answered failure (``CommandFailed``) or pod lacks the command
  (``UnsupportedCommandError``), 504 no feedback in time (``CommandTimeout``), 503 link down
  (``LinkLost``) or client not open (``NotConnected``).
- ``WS /ws/telemetry`` — JSON telemetry at most ``telemetry_hz`` times a second (newest
  sample wins: a slow browser never backs up the client), and a ``{"type": "link"}``
  message every 0.5 s while no replies arrive (link down, or still waiting for the GCU).

Every request and WebSocket passes :class:`~examples.web.guard.Guard` first: ``Host`` in
``allowed_hosts``, same-origin ``Origin`` on POST and WebSocket, and the bearer ``token``
on ``/api/`` and ``/ws/`` when one is set (README, "Security").
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import math
import os
from collections.abc import AsyncIterator, Iterable
from pathlib import Path
from typing import Any

from starlette.applications import Starlette
from starlette.middleware import Middleware
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, Response
from starlette.routing import Mount, Route, WebSocketRoute
from starlette.staticfiles import StaticFiles
from starlette.websockets import WebSocket, WebSocketDisconnect

from gcu_async import (
    CommandError,
    CommandFailed,
    CommandTimeout,
    FieldRangeError,
    GcuClient,
    LinkLost,
    UnsupportedCommandError,
    connect,
)
from gcu_async.client import ClientState
from gcu_async.protocol import opcode_name

from .body import DEFAULT_MAX_BODY, BodyError, read_json
from .commands import COMMANDS, parse_params
from .guard import LOOPBACK_HOSTS, WS_PROTOCOL, Guard, Policy
from .snapshot import Attempts, client_state, link_json, state_json

log = logging.getLogger("gcu_async.examples.web")

DEFAULT_GCU_URL = "udp://127.0.0.1:2337"
"""Where the app looks for a GCU unless ``GCU_URL`` says otherwise (loopback only)."""
DEFAULT_TELEMETRY_HZ = 20.0
MAX_TELEMETRY_HZ = 50.0
LINK_REPORT_SECONDS = 0.5
"""While no replies arrive, the WebSocket reports the link health this often."""
STATIC_DIR = Path(__file__).resolve().parent / "static"


def create_app(
    gcu_url: str,
    *,
    telemetry_hz: float = DEFAULT_TELEMETRY_HZ,
    token: str | None = None,
    allowed_hosts: Iterable[str] | None = None,
    max_body: int = DEFAULT_MAX_BODY,
    **client_options: Any,
) -> Starlette:
    """The ASGI app for the GCU at ``gcu_url``.

    ``client_options`` go to :func:`gcu_async.connect` (``local_port``, ``command_timeout``,
    ``connect_timeout``, ``silence_timeout``, ``check_support``, ``restore`` …); a bad URL or
    option raises here. ``telemetry_hz`` bounds the WebSocket rate, (0, 50]. The app starts
    at once; the client opens in the background (``wait=False``: each attempt waits
    ``connect_timeout`` for a reply, the library's backoff between them) and closes when the
    app stops. ``app.state.gcu`` is the client, ``app.state.attempts`` its failed attempts
    (:class:`~examples.web.snapshot.Attempts`).

    ``token`` (16–256 URL-safe characters, ``None``: none) is the bearer token ``/api/`` and
    ``/ws/`` need; ``allowed_hosts`` the host names ``Host`` may carry (default loopback
    and ``localhost``); ``max_body`` the largest command body in bytes, [2, 1 MiB].
    """
    if not 0 < telemetry_hz <= MAX_TELEMETRY_HZ:
        raise ValueError(f"telemetry_hz: {telemetry_hz!r} is outside the allowed range (0, 50] Hz")
    if isinstance(max_body, bool) or not isinstance(max_body, int) or not 2 <= max_body <= 2**20:
        raise ValueError(f"max_body: {max_body!r} is outside the allowed range [2, 1048576] bytes")
    policy = Policy.make(allowed_hosts, token)
    gcu = connect(gcu_url, wait=False, **client_options)
    attempts = Attempts(gcu)

    @contextlib.asynccontextmanager
    async def lifespan(app: Starlette) -> AsyncIterator[None]:
        async with gcu:  # returns at once: the link comes up in the background
            log.info("serving the GCU at %s (connecting in the background)", gcu_url)
            try:
                yield
            finally:
                log.info("closing the client of %s", gcu_url)

    async def telemetry(websocket: WebSocket) -> None:
        await stream_telemetry(websocket, attempts, 1.0 / telemetry_hz)

    routes = [
        Route("/", index, methods=["GET"]),
        Route("/api/status", status, methods=["GET"]),
        Route("/api/commands", list_commands, methods=["GET"]),
        Route("/api/commands/{name}", run_command, methods=["POST"]),
        WebSocketRoute("/ws/telemetry", telemetry),
        Mount("/static", StaticFiles(directory=STATIC_DIR), name="static"),
    ]
    app = Starlette(routes=routes, lifespan=lifespan,
                    middleware=[Middleware(Guard, policy=policy)])  # fmt: skip
    app.state.gcu_url = gcu_url
    app.state.policy = policy
    app.state.max_body = max_body
    app.state.gcu = gcu
    app.state.attempts = attempts
    return app


def app_from_env() -> Starlette:
    """The app configured from the environment, for ``uvicorn --factory``: ``GCU_URL``
    (default ``udp://127.0.0.1:2337``), ``GCU_LOCAL_PORT`` (UDP port the client binds,
    default 2338; 0 = any), ``GCU_TELEMETRY_HZ`` (default 20), ``GCU_WEB_TOKEN`` (the
    bearer token; unset or empty: none), ``GCU_WEB_ALLOWED_HOSTS`` (comma-separated host
    names allowed besides loopback and ``localhost``)."""
    options: dict[str, Any] = {}
    if "GCU_LOCAL_PORT" in os.environ:
        options["local_port"] = int(os.environ["GCU_LOCAL_PORT"])
    hz = float(os.environ.get("GCU_TELEMETRY_HZ", DEFAULT_TELEMETRY_HZ))
    return create_app(os.environ.get("GCU_URL", DEFAULT_GCU_URL), telemetry_hz=hz,
                      token=os.environ.get(TOKEN_ENV) or None,
                      allowed_hosts=allowed_hosts_from(os.environ.get(HOSTS_ENV, "")),
                      **options)  # fmt: skip


TOKEN_ENV = "GCU_WEB_TOKEN"
"""The environment variable holding the bearer token (``--token`` overrides it)."""
HOSTS_ENV = "GCU_WEB_ALLOWED_HOSTS"
"""The environment variable listing extra allowed host names, comma-separated."""


def allowed_hosts_from(extra: Iterable[str] | str) -> frozenset[str]:
    """Loopback and ``localhost`` plus ``extra`` (names, or one comma-separated string)."""
    names = extra.split(",") if isinstance(extra, str) else list(extra)
    return LOOPBACK_HOSTS | {name.strip() for name in names if name.strip()}


def _attempts(conn: Request | WebSocket) -> Attempts:
    attempts: Attempts = conn.app.state.attempts
    return attempts


def _error(code: int, exc: BaseException | str, kind: str | None = None,
           **extra: Any) -> JSONResponse:  # fmt: skip
    if kind is None:
        kind = "error" if isinstance(exc, str) else type(exc).__name__
    if isinstance(exc, CommandError):  # did it execute? "not sent", "unknown" or "failed"
        extra["outcome"] = exc.outcome.value
    return JSONResponse({"error": str(exc), "kind": kind, **extra}, status_code=code)


def _not_connected(attempts: Attempts, **extra: Any) -> JSONResponse:
    """503 while the client is not open: what it waits for, or why it failed."""
    return _error(503, attempts.describe(), "NotConnected", connection=attempts.json(),
                  **extra)  # fmt: skip


def _number(x: float) -> float | None:
    """JSON has no infinity: an unbounded side of a range is null."""
    return x if math.isfinite(x) else None


# -- HTTP ---------------------------------------------------------------------------------
async def index(request: Request) -> Response:
    return FileResponse(STATIC_DIR / "index.html", headers={"Cache-Control": "no-cache"})


async def status(request: Request) -> Response:
    """The latest state; 200 even while the link is down (``link.up`` is then false), 503
    ``NotConnected`` while the client is not open (still waiting for the GCU, or failed)."""
    attempts = _attempts(request)
    state = client_state(attempts.gcu)
    if attempts.gcu.state is not ClientState.OPEN or state is None:
        return _not_connected(attempts)
    return JSONResponse({**state, "connection": attempts.json()})


async def list_commands(request: Request) -> Response:
    return JSONResponse({"commands": [spec.describe() for spec in COMMANDS.values()]})


async def run_command(request: Request) -> Response:
    """Run one command and answer its feedback, or an error mapped to an HTTP status."""
    name = request.path_params["name"]
    spec = COMMANDS.get(name)
    if spec is None:
        return _error(404, f"unknown command {name!r}", commands=sorted(COMMANDS))
    try:
        body = await read_json(request, request.app.state.max_body)
    except BodyError as exc:
        response = _error(exc.status, exc, exc.kind)
        if exc.status == 413:  # the rest of the body is unread: end the connection, not drain it
            response.headers["connection"] = "close"
        return response
    attempts = _attempts(request)
    try:
        values = parse_params(spec, body)
        if attempts.gcu.state is not ClientState.OPEN:
            return _not_connected(attempts, outcome="not sent")
        feedback = await spec.run(attempts.gcu, values)
    except CommandFailed as exc:
        return _error(
            409,
            exc,
            opcode=exc.opcode,
            command=None if exc.opcode is None else opcode_name(exc.opcode),
            status=exc.status,
            failed_cameras=int(exc.failed_cameras),
        )
    except UnsupportedCommandError as exc:
        return _error(409, exc, command=exc.command, pod_model=exc.pod_model)
    except CommandTimeout as exc:
        return _error(504, exc)
    except LinkLost as exc:
        return _error(503, exc)
    except FieldRangeError as exc:
        return _error(422, exc, field=exc.field, low=_number(exc.low), high=_number(exc.high),
                      unit=exc.unit)  # fmt: skip
    except ValueError as exc:
        return _error(422, exc)
    return JSONResponse(
        {"command": name, "feedback": None if feedback is None else feedback.as_dict()}
    )


# -- WebSocket ----------------------------------------------------------------------------
async def stream_telemetry(websocket: WebSocket, attempts: Attempts, period: float) -> None:
    """Send telemetry until the browser leaves or the app stops (then code 1001). A client
    offering the :data:`~examples.web.guard.WS_PROTOCOL` subprotocol (the page does, beside
    its token) gets it."""
    offered = websocket.scope.get("subprotocols", [])
    await websocket.accept(subprotocol=WS_PROTOCOL if WS_PROTOCOL in offered else None)
    sender = asyncio.create_task(_send_telemetry(websocket, attempts, period))
    receiver = asyncio.create_task(_until_disconnect(websocket))
    try:
        done, _ = await asyncio.wait({sender, receiver}, return_when=asyncio.FIRST_COMPLETED)
    finally:
        for task in (sender, receiver):
            task.cancel()
        results = await asyncio.gather(sender, receiver, return_exceptions=True)
    for result in results:
        if isinstance(result, (WebSocketDisconnect, OSError)):
            log.debug("telemetry socket closed: %r", result)
        elif isinstance(result, Exception):
            log.warning("telemetry socket failed: %r", result)
    if sender in done and sender.exception() is None and receiver not in done:
        with contextlib.suppress(Exception):  # the app stops: tell the browser
            await websocket.close(code=1001, reason="GCU client closed")


async def _until_disconnect(websocket: WebSocket) -> None:
    """Read (and ignore) what the browser sends until it disconnects."""
    while (await websocket.receive())["type"] != "websocket.disconnect":
        pass


def _link_message(attempts: Attempts) -> str:
    return json.dumps({"type": "link", "link": link_json(attempts.gcu.link),
                       "connection": attempts.json()})  # fmt: skip


async def _send_telemetry(websocket: WebSocket, attempts: Attempts, period: float) -> None:
    """The client's telemetry, and a link message every 0.5 s while none arrives (before
    the GCU first answers, during an outage, after the client failed). Returns when the
    client closes (the app stops). ``seq`` counts telemetry messages on this socket."""
    gcu = attempts.gcu
    seq = 0
    while True:
        if gcu.state in (ClientState.OPENING, ClientState.OPEN):
            seq = await _send_client_telemetry(websocket, attempts, period, seq)
        elif gcu.state is ClientState.FAILED:  # it stays so until the app stops
            await websocket.send_text(_link_message(attempts))
            await asyncio.sleep(LINK_REPORT_SECONDS)
        else:  # closing or closed: the app stops
            return


async def _send_client_telemetry(
    websocket: WebSocket, attempts: Attempts, period: float, seq: int
) -> int:
    """Telemetry of the client until it closes or fails; returns the last ``seq`` sent."""
    gcu: GcuClient = attempts.gcu
    loop = asyncio.get_running_loop()
    # maxsize=1: the newest sample wins, a slow browser never queues up behind the client
    stream = gcu.telemetry(maxsize=1)
    pending: asyncio.Future[Any] | None = None
    next_slot = loop.time()
    try:
        while True:
            delay = next_slot - loop.time()
            if delay > 0:
                await asyncio.sleep(delay)
            if pending is None:
                pending = asyncio.ensure_future(anext(stream))
            done, _ = await asyncio.wait({pending}, timeout=LINK_REPORT_SECONDS)
            if not done:  # no reply for a while: report the link, keep waiting
                await websocket.send_text(_link_message(attempts))
                continue
            try:
                sample = pending.result()
            except StopAsyncIteration:
                return seq
            finally:
                pending = None
            seq += 1
            message = state_json(sample.status, sample.info, gcu.link, sample.feedback,
                                 aircraft=gcu.aircraft)  # fmt: skip
            message.update(type="telemetry", seq=seq, connection=attempts.json())
            await websocket.send_text(json.dumps(message))
            next_slot = loop.time() + period
    finally:
        if pending is not None:
            pending.cancel()
            with contextlib.suppress(asyncio.CancelledError, StopAsyncIteration):
                await pending
        await stream.aclose()
