"""Shared by the web example's tests (tests/examples/test_example_web*.py): run the app under
uvicorn on 127.0.0.1 (an ephemeral port) and talk to it. Imported only after the test module has
checked that starlette, uvicorn, httpx and websockets are there."""

from __future__ import annotations

import asyncio
import contextlib
import json
import socket
import sys
import time
from collections.abc import AsyncIterator, Awaitable, Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx
import uvicorn
from websockets.asyncio.client import ClientConnection

from gcu_async import GcuClient
from gcu_async.client import ClientState
from gcu_async.pytest_plugin import SimHandle

ROOT = Path(__file__).resolve().parents[3]
if str(ROOT) not in sys.path:  # the examples live beside src/, not inside the package
    sys.path.insert(0, str(ROOT))

from examples.web.app import create_app  # noqa: E402
from examples.web.snapshot import Attempts  # noqa: E402

CHROMIUM = "/usr/bin/chromium"
"""Debian's Chromium, driven by Playwright (never ``playwright install``)."""
CHROMIUM_ARGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
]  # fmt: skip
START_TIMEOUT = 5.0
CONNECT_TIMEOUT = 5.0
"""Bound on the wait for the app's client to open against a running simulator."""


@dataclass
class Web:
    """The running app and its simulator."""

    sim: Any
    """The :class:`SimHandle` the app talks to (``None`` when the test runs its own)."""
    base_url: str
    http: httpx.AsyncClient
    app: Any

    @property
    def gcu(self) -> GcuClient:
        gcu: GcuClient = self.app.state.gcu
        return gcu

    @property
    def attempts(self) -> Attempts:
        """The app's count of its client's failed open attempts."""
        attempts: Attempts = self.app.state.attempts
        return attempts

    async def wait_open(self, timeout: float = 5.0) -> None:
        """Return once the app's client is open (the GCU answered)."""
        await eventually(self._open, timeout, "the app's client open")

    async def _open(self) -> bool:
        return self.gcu.state is ClientState.OPEN

    @property
    def ws_url(self) -> str:
        return self.base_url.replace("http://", "ws://", 1) + "/ws/telemetry"

    async def command(self, name: str, params: Any = None) -> httpx.Response:
        """POST a command with a JSON body (Python's encoder: ``Infinity`` passes through;
        ``None``: an empty body, all defaults)."""
        body = b"" if params is None else json.dumps(params).encode()
        headers = {"content-type": "application/json"}
        return await self.http.post(f"/api/commands/{name}", content=body, headers=headers)

    async def status(self) -> dict[str, Any]:
        response = await self.http.get("/api/status")
        assert response.status_code == 200, response.text
        result: dict[str, Any] = response.json()
        return result


@contextlib.asynccontextmanager
async def serve(app: Any, host: str = "127.0.0.1") -> AsyncIterator[str]:
    """Run ``app`` under uvicorn on ``host`` (loopback), an ephemeral port; yield its base
    URL."""
    config = uvicorn.Config(app, host=host, port=0, log_level="warning", lifespan="on")
    server = uvicorn.Server(config)

    async def run() -> None:
        try:
            await server.serve()
        except SystemExit as exc:  # uvicorn exits when the app's startup fails
            raise RuntimeError(f"uvicorn did not start (exit status {exc.code})") from None

    task = asyncio.create_task(run())
    deadline = time.monotonic() + START_TIMEOUT
    while not server.started and not task.done() and time.monotonic() < deadline:
        await asyncio.sleep(0.01)
    if not server.started:
        server.should_exit = True
        await asyncio.wait_for(task, START_TIMEOUT)  # raises the startup failure, if any
        raise RuntimeError(f"uvicorn did not start within {START_TIMEOUT} s")
    port = server.servers[0].sockets[0].getsockname()[1]
    try:
        yield f"http://{host}:{port}"
    finally:
        server.should_exit = True
        await asyncio.wait_for(task, START_TIMEOUT)


@contextlib.asynccontextmanager
async def running_web(
    url: str, sim: SimHandle | None, *, wait_connected: bool = True, **options: Any
) -> AsyncIterator[Web]:
    """The app for ``url`` (UDP: ``local_port=0`` unless given) under uvicorn with an HTTP
    client; with ``wait_connected`` only once its client is open."""
    if url.startswith("udp://"):
        options = {"local_port": 0, **options}
    app = create_app(url, **options)
    async with serve(app) as base_url, httpx.AsyncClient(base_url=base_url, timeout=5.0) as http:
        web = Web(sim, base_url, http, app)
        if wait_connected:
            await web.wait_open(CONNECT_TIMEOUT)
        yield web


async def eventually(
    check: Callable[[], Awaitable[bool]], timeout: float = 4.0, what: str = "condition"
) -> None:
    deadline = time.monotonic() + timeout
    while not await check():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        await asyncio.sleep(0.02)


async def next_message(ws: ClientConnection, timeout: float = 2.0) -> dict[str, Any]:
    message: dict[str, Any] = json.loads(await asyncio.wait_for(ws.recv(), timeout))
    return message


def angle_near(a: float, b: float, tol: float = 0.5) -> bool:
    return abs((a - b + 180.0) % 360.0 - 180.0) < tol


def free_udp_port() -> int:
    """A UDP port on 127.0.0.1 that nothing is bound to right now."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        port: int = sock.getsockname()[1]
        return port


@contextlib.asynccontextmanager
async def aircraft_heading(gcu: GcuClient, heading: float) -> AsyncIterator[None]:
    """Feed ``gcu`` a level, still aircraft facing ``heading`` every 0.1 s (as a real feed
    keeps updating) while the block runs."""

    async def feed() -> None:
        while True:
            gcu.update_aircraft(attitude=(0.0, 0.0, heading), velocity=(0.0, 0.0, 0.0),
                                acceleration=(0.0, 0.0, 0.0))  # fmt: skip
            await asyncio.sleep(0.1)

    task = asyncio.create_task(feed())
    try:
        yield
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task


def page_button(html: str, label: str) -> tuple[str, dict[str, Any]]:
    """The command and parameters of the page's button labelled ``label``."""
    for chunk in html.split("<button ")[1:]:
        attributes, _, rest = chunk.partition(">")
        if rest.split("</button>")[0].strip() != label:
            continue
        command = attributes.split('data-command="')[1].split('"')[0]
        params: dict[str, Any] = {}
        if "data-params='" in attributes:
            params = json.loads(attributes.split("data-params='")[1].split("'")[0])
        return command, params
    raise AssertionError(f"no button labelled {label!r} on the page")
