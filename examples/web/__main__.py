"""``python -m examples.web``: serve the web example with uvicorn (from the repository root).

``--sim`` starts the built-in GCU simulator in the same process (UDP on 127.0.0.1, an
ephemeral port) and connects to it; otherwise the app connects to ``--gcu`` (default
``$GCU_URL`` or ``udp://127.0.0.1:2337``).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import os
from collections.abc import AsyncIterator
from typing import Any

import uvicorn

from gcu_async.sim import GcuSimulator

from .app import DEFAULT_GCU_URL, DEFAULT_TELEMETRY_HZ, create_app


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
    parser.add_argument("--host", default="127.0.0.1", help="HTTP address (default loopback)")
    parser.add_argument("--port", type=int, default=8000, help="HTTP port (default 8000)")
    parser.add_argument(
        "--telemetry-hz",
        type=float,
        default=DEFAULT_TELEMETRY_HZ,
        help="WebSocket telemetry rate bound, (0, 50] (default 20)",
    )
    return parser.parse_args(argv)  # fmt: skip


@contextlib.asynccontextmanager
async def gcu_endpoint(args: argparse.Namespace) -> AsyncIterator[tuple[str, dict[str, Any]]]:
    """The URL and client options to use: the simulator's (``--sim``) or ``--gcu``."""
    options: dict[str, Any] = {}
    if args.local_port is not None:
        options["local_port"] = args.local_port
    if not args.sim:
        yield args.gcu, options
        return
    async with GcuSimulator(pod=args.pod).serve_udp("127.0.0.1", 0) as server:
        options.setdefault("local_port", 0)
        print(f"simulated {args.pod} at {server.url}", flush=True)
        yield server.url, options


async def main(args: argparse.Namespace) -> None:
    async with gcu_endpoint(args) as (url, options):
        app = create_app(url, telemetry_hz=args.telemetry_hz, **options)
        config = uvicorn.Config(app, host=args.host, port=args.port, log_level="info")
        await uvicorn.Server(config).serve()


if __name__ == "__main__":
    asyncio.run(main(parse_args()))
