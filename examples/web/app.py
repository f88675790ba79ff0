"""A Starlette web backend for one gimbal: JSON commands, WebSocket telemetry, one page.

``create_app(gcu_url, **client_options)`` builds the ASGI app. Its lifespan opens ONE
:class:`~gcu_async.GcuClient` (``gcu_async.connect``) and closes it on shutdown; every
request shares it. Routes:

- ``GET /`` — the page (``static/index.html``), ``/static/*`` its script and style.
- ``GET /api/status`` — mode, attitude, relative angles, rates, zoom, flags, link health.
- ``GET /api/commands`` — the commands below with their parameters.
- ``POST /api/commands/{name}`` — run a command; JSON object body of parameters. Errors:
  404 unknown command, 400 body not JSON, 422 bad parameter (``ValueError`` /
  ``FieldRangeError``), 409 GCU answered failure (``CommandFailed``) or pod lacks the command
  (``UnsupportedCommandError``), 504 no feedback in time (``CommandTimeout``), 503 link down
  (``LinkLost``).
- ``WS /ws/telemetry`` — JSON telemetry at most ``telemetry_hz`` times a second (newest
  sample wins: a slow browser never backs up the client), and a ``{"type": "link"}``
  message every 0.5 s while no replies arrive.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import math
import os
from collections.abc import AsyncGenerator, AsyncIterator
from pathlib import Path
from typing import Any, cast

from starlette.applications import Starlette
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
    GcuError,
    LinkLost,
    TelemetrySample,
    UnsupportedCommandError,
    connect,
)
from gcu_async.protocol import opcode_name

from .commands import COMMANDS, parse_params
from .snapshot import client_state, link_json, state_json

log = logging.getLogger("gcu_async.examples.web")

DEFAULT_GCU_URL = "udp://127.0.0.1:2337"
"""Where the app looks for a GCU unless ``GCU_URL`` says otherwise (loopback only)."""
DEFAULT_TELEMETRY_HZ = 20.0
MAX_TELEMETRY_HZ = 50.0
LINK_REPORT_SECONDS = 0.5
"""While no replies arrive, the WebSocket reports the link health this often."""
STATIC_DIR = Path(__file__).resolve().parent / "static"


def create_app(
    gcu_url: str, *, telemetry_hz: float = DEFAULT_TELEMETRY_HZ, **client_options: Any
) -> Starlette:
    """The ASGI app for the GCU at ``gcu_url``.

    ``client_options`` go to :func:`gcu_async.connect` (``local_port``, ``command_timeout``,
    ``silence_timeout``, ``check_support`` …). ``telemetry_hz`` bounds the WebSocket rate,
    (0, 50]. The client is opened when the app starts (startup fails with ``LinkLost`` if
    the GCU does not answer within ``connect_timeout``) and closed when it stops.
    """
    if not 0 < telemetry_hz <= MAX_TELEMETRY_HZ:
        raise ValueError(f"telemetry_hz: {telemetry_hz!r} is outside the allowed range (0, 50] Hz")

    @contextlib.asynccontextmanager
    async def lifespan(app: Starlette) -> AsyncIterator[None]:
        async with connect(gcu_url, **client_options) as gcu:
            log.info("connected to %s (%s)", gcu_url, gcu.pod_model)
            app.state.gcu = gcu
            try:
                yield
            finally:
                log.info("closing the client of %s", gcu_url)

    async def telemetry(websocket: WebSocket) -> None:
        await stream_telemetry(websocket, _client(websocket), 1.0 / telemetry_hz)

    routes = [
        Route("/", index, methods=["GET"]),
        Route("/api/status", status, methods=["GET"]),
        Route("/api/commands", list_commands, methods=["GET"]),
        Route("/api/commands/{name}", run_command, methods=["POST"]),
        WebSocketRoute("/ws/telemetry", telemetry),
        Mount("/static", StaticFiles(directory=STATIC_DIR), name="static"),
    ]
    app = Starlette(routes=routes, lifespan=lifespan)
    app.state.gcu_url = gcu_url
    return app


def app_from_env() -> Starlette:
    """The app configured from the environment, for ``uvicorn --factory``: ``GCU_URL``
    (default ``udp://127.0.0.1:2337``), ``GCU_LOCAL_PORT`` (UDP port the client binds,
    default 2338; 0 = any), ``GCU_TELEMETRY_HZ`` (default 20)."""
    options: dict[str, Any] = {}
    if "GCU_LOCAL_PORT" in os.environ:
        options["local_port"] = int(os.environ["GCU_LOCAL_PORT"])
    hz = float(os.environ.get("GCU_TELEMETRY_HZ", DEFAULT_TELEMETRY_HZ))
    return create_app(os.environ.get("GCU_URL", DEFAULT_GCU_URL), telemetry_hz=hz, **options)


def _client(conn: Request | WebSocket) -> GcuClient:
    gcu: GcuClient = conn.app.state.gcu
    return gcu


def _error(code: int, exc: BaseException | str, **extra: Any) -> JSONResponse:
    kind = "error" if isinstance(exc, str) else type(exc).__name__
    if isinstance(exc, CommandError):  # did it execute? "not sent", "unknown" or "failed"
        extra["outcome"] = exc.outcome.value
    return JSONResponse({"error": str(exc), "kind": kind, **extra}, status_code=code)


def _number(x: float) -> float | None:
    """JSON has no infinity: an unbounded side of a range is null."""
    return x if math.isfinite(x) else None


# -- HTTP ---------------------------------------------------------------------------------
async def index(request: Request) -> Response:
    return FileResponse(STATIC_DIR / "index.html", headers={"Cache-Control": "no-cache"})


async def status(request: Request) -> Response:
    """The latest state; 200 even while the link is down (``link.up`` is then false)."""
    try:
        return JSONResponse(client_state(_client(request)))
    except GcuError as exc:  # no reply yet: cannot happen once the lifespan has started
        return _error(503, exc)


async def list_commands(request: Request) -> Response:
    return JSONResponse({"commands": [spec.describe() for spec in COMMANDS.values()]})


async def run_command(request: Request) -> Response:
    """Run one command and answer its feedback, or an error mapped to an HTTP status."""
    name = request.path_params["name"]
    spec = COMMANDS.get(name)
    if spec is None:
        return _error(404, f"unknown command {name!r}", commands=sorted(COMMANDS))
    raw = await request.body()
    try:
        body = json.loads(raw) if raw.strip() else None
    except ValueError as exc:
        return _error(400, f"the body is not valid JSON: {exc}")
    try:
        values = parse_params(spec, body)
        feedback = await spec.run(_client(request), values)
    except CommandFailed as exc:
        return _error(
            409,
            exc,
            opcode=exc.opcode,
            command=opcode_name(exc.opcode),
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
async def stream_telemetry(websocket: WebSocket, gcu: GcuClient, period: float) -> None:
    """Send telemetry until the browser leaves or the client closes (then code 1001)."""
    await websocket.accept()
    sender = asyncio.create_task(_send_telemetry(websocket, gcu, period))
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
        with contextlib.suppress(Exception):  # the client closed: tell the browser
            await websocket.close(code=1001, reason="GCU client closed")


async def _until_disconnect(websocket: WebSocket) -> None:
    """Read (and ignore) what the browser sends until it disconnects."""
    while (await websocket.receive())["type"] != "websocket.disconnect":
        pass


async def _send_telemetry(websocket: WebSocket, gcu: GcuClient, period: float) -> None:
    loop = asyncio.get_running_loop()
    # maxsize=1: the newest sample wins, a slow browser never queues up behind the client
    stream = cast(AsyncGenerator[TelemetrySample, None], gcu.telemetry(maxsize=1))
    pending: asyncio.Future[Any] | None = None
    seq = 0
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
                await websocket.send_text(json.dumps({"type": "link", "link": link_json(gcu.link)}))
                continue
            try:
                sample = pending.result()
            except StopAsyncIteration:
                return
            finally:
                pending = None
            seq += 1
            message = state_json(sample.status, sample.info, gcu.link, sample.feedback)
            message.update(type="telemetry", seq=seq)
            await websocket.send_text(json.dumps(message))
            next_slot = loop.time() + period
    finally:
        if pending is not None:
            pending.cancel()
            with contextlib.suppress(asyncio.CancelledError, StopAsyncIteration):
                await pending
        await stream.aclose()
