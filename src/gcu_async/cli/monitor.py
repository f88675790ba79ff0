"""``gcu-async monitor URL``: live telemetry — mode, angles, zoom, flags, link health."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import sys
import time
from pathlib import Path
from typing import Any

from gcu_async.capture import CaptureUnavailable, PacketCapture, as_capture
from gcu_async.client.client import GcuClient
from gcu_async.client.connect import connect
from gcu_async.client.telemetry import TelemetrySample
from gcu_async.errors import GcuError, LinkLost


def register(sub: Any) -> None:
    p = sub.add_parser(
        "monitor",
        help="show live telemetry of a GCU until Ctrl-C",
        description="Connects, keeps the heartbeat going, and prints one status line per "
        "interval: mode, camera attitude, zoom, flags and link health.",
    )
    p.add_argument("url", help="udp://HOST[:PORT], tcp://HOST[:PORT] or serial:///dev/…")
    p.add_argument("--interval", type=float, default=0.5, help="seconds between lines")
    p.add_argument("--count", type=int, default=0, help="stop after this many lines (0: never)")
    p.add_argument("--timeout", type=float, default=3.0, help="seconds to wait for the GCU")
    p.add_argument("--capture", type=Path, metavar="FILE",
                   help="write the packets exchanged to FILE (pcapng; open it in Wireshark "
                   "with the dissector: gcu-async wireshark --install)")  # fmt: skip
    p.set_defaults(run=run)


def _names(flags: Any) -> list[str]:
    return [f.name.lower() for f in type(flags) if f in flags and f.name]


def format_line(gcu: GcuClient, sample: TelemetrySample) -> str:
    """One human-readable status line."""
    st = sample.status
    att = st.attitude
    rel = st.relative_angles
    parts = [
        f"{st.mode.name:<15}",
        f"att r{att.roll:+7.2f} p{att.pitch:+7.2f} y{att.yaw:6.2f}",
        f"rel x{rel.x:+7.2f} y{rel.y:+7.2f} z{rel.z:+7.2f}",
    ]
    info = sample.info
    if info is not None:
        flags = _names(st.pod_status) + _names(info.camera_flags)
        dist = "-" if info.target_distance is None else f"{info.target_distance:.1f}m"
        parts.append(f"zoom {info.camera1_zoom:4.1f}x/{info.camera2_zoom:3.1f}x")
        parts.append(f"range {dist}")
        parts.append(f"flags [{','.join(flags)}]")
    link = gcu.link
    parts.append(
        f"link {'up' if link.up else 'DOWN'} {link.reply_rate:.0f}/s "
        f"crc_err {link.crc_errors} lost {link.lost_count}"
    )
    return " | ".join(parts)


async def _monitor(
    url: str, interval: float, count: int, timeout: float, capture: PacketCapture | None = None
) -> int:
    lines = 0
    async with connect(url, connect_timeout=timeout, capture=capture) as gcu:
        next_at = 0.0
        async for sample in gcu.telemetry():
            now = time.monotonic()
            if now < next_at:
                continue
            next_at = now + interval
            print(format_line(gcu, sample), flush=True)
            lines += 1
            if count and lines >= count:
                break
    return 0


def run(args: argparse.Namespace) -> int:
    try:
        if not args.interval > 0:
            raise ValueError(f"--interval: {args.interval!r} must be > 0")
        connect(args.url)
        capture = as_capture(args.capture)
    except (ValueError, CaptureUnavailable) as exc:
        print(f"gcu-async monitor: {exc}", file=sys.stderr)
        return 2
    try:
        return asyncio.run(_monitor(args.url, args.interval, args.count, args.timeout, capture))
    except KeyboardInterrupt:
        return 0
    except (LinkLost, GcuError, OSError) as exc:
        print(f"gcu-async monitor: {exc}", file=sys.stderr)
        return 1
    finally:
        with contextlib.suppress(Exception):
            sys.stdout.flush()
