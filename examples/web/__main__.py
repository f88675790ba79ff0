"""``python -m examples.web``: serve the web example with uvicorn (from the repository root).

``--sim`` starts the built-in GCU simulator in the same process (UDP on 127.0.0.1) and
connects to it; otherwise the app connects to ``--gcu`` (default ``$GCU_URL`` or
``udp://127.0.0.1:2337``). The app starts whether or not the GCU answers and connects
when it does: ``--sim-delay 10`` powers the simulated GCU 10 s after the app, to see the
page wait. ``--aircraft-heading DEG`` (with ``--sim`` only) feeds a parked aircraft facing
DEG, so that "Ahead" points somewhere other than north.

``--token`` (or ``$GCU_WEB_TOKEN``; ``--token auto`` makes one) makes ``/api/`` and ``/ws/``
need ``Authorization: Bearer <token>``; the page is opened as ``/#token=<token>`` (printed
at start). ``--allowed-host NAME`` allows one more name in ``Host`` (loopback addresses,
``localhost`` and a non-wildcard ``--host`` are allowed already).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import os
import secrets
import socket
from collections.abc import AsyncIterator
from typing import Any

import uvicorn

from gcu_async.sim import GcuSimulator

from .aircraft import check_heading, feed_parked_aircraft
from .app import (
    DEFAULT_GCU_URL,
    DEFAULT_TELEMETRY_HZ,
    HOSTS_ENV,
    TOKEN_ENV,
    allowed_hosts_from,
    create_app,
)
from .guard import LOOPBACK_HOSTS, check_token, normalize_host

WILDCARD_HOSTS = frozenset({"0.0.0.0", "::", ""})
"""Bind addresses that are no host name a browser would send in ``Host``."""


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog="python -m examples.web",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument(
        "--gcu",
        default=os.environ.get("GCU_URL", DEFAULT_GCU_URL),
        help="GCU URL (udp://, tcp://, serial://); default %(default)s",
    )
    parser.add_argument(
        "--local-port",
        type=int,
        default=None,
        help="UDP port the client binds (default 2338; 0 = any)",
    )
    parser.add_argument(
        "--sim", action="store_true", help="start the built-in simulator and connect to it"
    )
    parser.add_argument("--pod", default="D-90Pro(TA)", help="simulated pod model (--sim)")
    parser.add_argument(
        "--sim-delay",
        type=float,
        default=0.0,
        metavar="SECONDS",
        help="start the simulator this long after the app (--sim)",
    )
    parser.add_argument(
        "--aircraft-heading",
        type=float,
        default=None,
        metavar="DEG",
        help="feed a parked aircraft facing DEG, [0, 360) (--sim only)",
    )
    parser.add_argument("--host", default="127.0.0.1", help="HTTP address (default loopback)")
    parser.add_argument("--port", type=int, default=8000, help="HTTP port (default 8000)")
    parser.add_argument(
        "--telemetry-hz",
        type=float,
        default=DEFAULT_TELEMETRY_HZ,
        help="WebSocket telemetry rate bound, (0, 50] (default 20)",
    )
    parser.add_argument(
        "--token",
        default=os.environ.get(TOKEN_ENV) or None,
        help=f"bearer token /api/ and /ws/ need (default ${TOKEN_ENV}; 'auto': a random one; "
        "16-256 characters A-Z a-z 0-9 . _ ~ -)",
    )
    parser.add_argument(
        "--allowed-host",
        action="append",
        default=[],
        metavar="NAME",
        help=f"also accept requests for this host name (repeatable; also ${HOSTS_ENV}, "
        "comma-separated)",
    )
    args = parser.parse_args(argv)
    if args.token == "auto":
        args.token = secrets.token_urlsafe(24)
    try:
        check_token(args.token)
    except ValueError as exc:
        parser.error(f"--token: {exc}")
    extra = [*os.environ.get(HOSTS_ENV, "").split(","), *args.allowed_host]
    if normalize_host(args.host) not in WILDCARD_HOSTS:
        extra.append(args.host)
    args.allowed_hosts = allowed_hosts_from(extra)
    if not args.sim and (args.sim_delay or args.aircraft_heading is not None):
        parser.error("--sim-delay and --aircraft-heading need --sim (a real GCU gets the "
                     "aircraft state from the real aircraft)")  # fmt: skip
    if not 0.0 <= args.sim_delay < 3600.0:
        parser.error(f"--sim-delay: {args.sim_delay!r} is outside the allowed range [0, 3600) s")
    if args.aircraft_heading is not None:
        try:
            check_heading(args.aircraft_heading)
        except ValueError as exc:
            parser.error(f"--aircraft-heading: {exc}")
    return args  # fmt: skip


def _free_udp_port() -> int:
    """A UDP port on 127.0.0.1 nobody uses right now (for a simulator started later)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        port: int = sock.getsockname()[1]
        return port


async def _late_simulator(args: argparse.Namespace, port: int) -> None:
    """The simulator, powered on ``--sim-delay`` seconds from now, until cancelled."""
    await asyncio.sleep(args.sim_delay)
    async with GcuSimulator(pod=args.pod).serve_udp("127.0.0.1", port) as server:
        print(f"simulated {args.pod} powered on at {server.url}", flush=True)
        await asyncio.Event().wait()  # until cancelled with the app


@contextlib.asynccontextmanager
async def gcu_endpoint(args: argparse.Namespace) -> AsyncIterator[tuple[str, dict[str, Any]]]:
    """The URL and client options to use: the simulator's (``--sim``) or ``--gcu``."""
    options: dict[str, Any] = {}
    if args.local_port is not None:
        options["local_port"] = args.local_port
    if not args.sim:
        yield args.gcu, options
        return
    options.setdefault("local_port", 0)
    if args.sim_delay:
        port = _free_udp_port()
        print(f"the simulated {args.pod} powers on in {args.sim_delay:g} s", flush=True)
        task = asyncio.create_task(_late_simulator(args, port))
        try:
            yield f"udp://127.0.0.1:{port}", options
        finally:
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task
        return
    async with GcuSimulator(pod=args.pod).serve_udp("127.0.0.1", 0) as server:
        print(f"simulated {args.pod} at {server.url}", flush=True)
        yield server.url, options


class _Server(uvicorn.Server):
    """uvicorn's server, announcing the console's URL once it listens (the real port,
    also with ``--port 0``)."""

    def __init__(self, config: uvicorn.Config, args: argparse.Namespace) -> None:
        super().__init__(config)
        self.args = args

    async def startup(self, sockets: list[socket.socket] | None = None) -> None:
        await super().startup(sockets)
        if self.started and self.servers and self.servers[0].sockets:
            _announce(self.args, self.servers[0].sockets[0].getsockname()[1])


def _announce(args: argparse.Namespace, port: int) -> None:
    """Say where the page is (with its token) and warn about an open, token-less console."""
    host = normalize_host(args.host)
    shown = "127.0.0.1" if host in WILDCARD_HOSTS else args.host
    if ":" in shown:
        shown = f"[{normalize_host(shown)}]"
    fragment = f"#token={args.token}" if args.token else ""
    print(f"console: http://{shown}:{port}/{fragment}", flush=True)
    if host not in LOOPBACK_HOSTS and args.token is None:
        print(f"warning: listening on {args.host} without a token: anyone who reaches the "
              "port can move the gimbal (use --token)", flush=True)  # fmt: skip


async def main(args: argparse.Namespace) -> None:
    async with gcu_endpoint(args) as (url, options):
        app = create_app(url, telemetry_hz=args.telemetry_hz, token=args.token,
                         allowed_hosts=args.allowed_hosts, **options)  # fmt: skip
        feed = None
        if args.aircraft_heading is not None:
            feed = asyncio.create_task(feed_parked_aircraft(app.state.gcu, args.aircraft_heading))
        config = uvicorn.Config(app, host=args.host, port=args.port, log_level="info")
        try:
            await _Server(config, args).serve()
        finally:
            if feed is not None:
                feed.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await feed


if __name__ == "__main__":
    asyncio.run(main(parse_args()))
