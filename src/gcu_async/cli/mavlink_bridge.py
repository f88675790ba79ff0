"""``gcu-async mavlink-bridge GCU_URL --mavlink CONNECTION …``: the XF gimbal and camera as
MAVLink components (docs/mavlink-bridge.md). Runs until Ctrl-C or SIGTERM, then exits 0:
stopping the bridge is how it is meant to end, not a failure (unlike the other sub-commands'
130)."""

from __future__ import annotations

import argparse
import asyncio
import sys
from typing import Any
from urllib.parse import urlsplit

from gcu_async.cli._exit import (
    EXIT_FAILED,
    EXIT_OK,
    EXIT_USAGE,
    Interrupted,
    interruptible,
    missing_extra,
)
from gcu_async.cli._parser import in_option_terms

OPTIONS = {"system_id": "--system-id", "video_url": "--video-url", "max_zoom": "--max-zoom"}
"""The bridge's parameters the options give (their errors are told in the options' terms)."""


def register(sub: Any) -> None:
    p = sub.add_parser(
        "mavlink-bridge",
        help="make the gimbal and camera standard MAVLink components (needs [mavlink])",
        description="Connects to the GCU and to one or more MAVLink peers (an autopilot, a "
        "ground station, a router) and appears there as a Gimbal Protocol v2 gimbal manager "
        "(MAV_COMP_ID_GIMBAL) and a Camera Protocol v2 camera (MAV_COMP_ID_CAMERA) of the "
        "vehicle; the autopilot's attitude, velocity, position and time feed the GCU. Logs "
        "link changes to stderr; Ctrl-C or SIGTERM ends it with exit status 0.",
    )
    p.add_argument("gcu_url", metavar="GCU_URL",
                   help="udp://HOST[:PORT], tcp://HOST[:PORT] or serial:///dev/…")
    p.add_argument("--mavlink", action="append", required=True, metavar="CONNECTION",
                   help="a MAVLink connection: udpout:HOST:PORT, udpin:HOST:PORT, tcp:HOST:PORT, "
                   "tcpin:HOST:PORT or DEVICE[,BAUD] such as /dev/ttyACM0,115200; IPv6 in "
                   "brackets, udpin:[::1]:14550 (repeat for several links)")
    p.add_argument("--system-id", type=int, default=1, metavar="N",
                   help="the vehicle's MAVLink system id (the autopilot's; default 1)")
    p.add_argument("--video-url", metavar="URL",
                   help="the video stream announced in VIDEO_STREAM_INFORMATION (default: "
                   "rtsp://GCU_HOST:554/ for a network GCU, none for a serial one)")
    p.add_argument("--max-zoom", type=float, metavar="RATIO",
                   help="camera 1's maximum zoom ratio, for the zoom level reported in "
                   "CAMERA_SETTINGS (the GCU does not report it; default: unknown)")  # fmt: skip
    p.set_defaults(run=run)


def default_video_url(gcu_url: str) -> str | None:
    """``rtsp://HOST:554/`` for a network GCU URL (RTSP's default port and path on the GCU's
    address), ``None`` for a serial one."""
    parts = urlsplit(gcu_url)
    if parts.scheme in ("udp", "tcp") and parts.hostname:
        host = f"[{parts.hostname}]" if ":" in parts.hostname else parts.hostname
        return f"rtsp://{host}:554/"
    return None


def run(args: argparse.Namespace) -> int:
    try:
        from gcu_async.bridge import CameraConfig, MavlinkBridge
        from gcu_async.bridge.endpoint import parse_endpoint
        from gcu_async.client.connect import connect
    except ImportError as exc:
        return missing_extra("gcu-async mavlink-bridge", "mavlink", exc)
    try:
        for connection in args.mavlink:  # every one checked before anything opens
            parse_endpoint(connection)
        video = args.video_url if args.video_url is not None else default_video_url(args.gcu_url)
        camera = CameraConfig(video_url=video, max_zoom=args.max_zoom)
        client = connect(args.gcu_url, check_support=True)
        bridge = MavlinkBridge(client, args.mavlink, system_id=args.system_id, camera=camera)
    except ValueError as exc:
        print(f"gcu-async mavlink-bridge: {in_option_terms(exc, OPTIONS)}", file=sys.stderr)
        return EXIT_USAGE
    try:
        asyncio.run(interruptible(_serve(bridge, args)))
    except (Interrupted, KeyboardInterrupt):
        print("gcu-async mavlink-bridge: stopped", file=sys.stderr)
        return EXIT_OK
    except OSError as exc:  # a MAVLink connection that cannot open (no such device, port taken)
        print(f"gcu-async mavlink-bridge: {exc}", file=sys.stderr)
        return EXIT_FAILED
    return EXIT_OK  # pragma: no cover - _serve only ends by cancellation


async def _serve(bridge: Any, args: argparse.Namespace) -> None:
    async with bridge:
        print(f"gcu-async mavlink-bridge: {args.gcu_url} as system {args.system_id} "
              f"(gimbal component 154, camera 100) on {', '.join(args.mavlink)}",
              file=sys.stderr, flush=True)  # fmt: skip
        await asyncio.Event().wait()  # until cancelled (Ctrl-C, SIGTERM)
