"""``gcu-async monitor URL``: live telemetry — mode, angles, zoom, flags, link health; with
``--report FILE``, the GCU conformance report of the replies (docs/conformance.md)."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import dataclasses
import json
import sys
import time
from pathlib import Path
from typing import Any

from gcu_async.capture import CaptureUnavailable, PacketCapture, as_capture
from gcu_async.cli._exit import (
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_USAGE,
    SECONDS_MAX,
    Interrupted,
    check_seconds,
    interruptible,
)
from gcu_async.cli._report import GCU_REPORT_HELP, add_report_option, write_report
from gcu_async.cli.liveview import relative_attitude
from gcu_async.client.client import GcuClient
from gcu_async.client.connect import connect
from gcu_async.client.telemetry import TelemetrySample
from gcu_async.conformance import GcuConformance
from gcu_async.errors import GcuError, LinkLost


def register(sub: Any) -> None:
    p = sub.add_parser(
        "monitor",
        help="show live telemetry of a GCU until Ctrl-C",
        description="Connects, keeps the heartbeat going, and prints one status line per "
        "interval: mode, camera attitude, zoom, flags and link health; during an outage a "
        "line saying how long no reply came. Ctrl-C or SIGTERM ends it (exit status 130).",
    )
    p.add_argument("url", help="udp://HOST[:PORT], tcp://HOST[:PORT] or serial:///dev/…")
    p.add_argument("--interval", type=float, default=0.5, metavar="SECONDS",
                   help=f"seconds between lines, at most {SECONDS_MAX:g} (default 0.5)")
    p.add_argument("--count", type=int, default=0,
                   help="stop after this many lines (default 0: never)")
    p.add_argument("--timeout", type=float, default=3.0, metavar="SECONDS",
                   help=f"seconds to wait for the GCU's first reply, at most {SECONDS_MAX:g} "
                   "(default 3)")
    p.add_argument("--json", action="store_true",
                   help="one JSON object per line (the frames as `decode` shows them; default: "
                   "text lines)")
    p.add_argument("--capture", type=Path, metavar="FILE",
                   help="write the packets exchanged to FILE (pcapng; open it in Wireshark "
                   "with the dissector: gcu-async wireshark --install; default: none)")
    add_report_option(p, f"{GCU_REPORT_HELP} when it ends (Ctrl-C, --count): every reply "
                      "of the live link")  # fmt: skip
    p.set_defaults(run=run)


def _names(flags: Any) -> list[str]:
    return [f.name.lower() for f in type(flags) if f in flags and f.name]


def format_line(gcu: GcuClient, sample: TelemetrySample) -> str:
    """One human-readable status line: the camera's absolute attitude ("att") and its
    attitude relative to the aircraft ("vs aircraft"), degrees."""
    st = sample.status
    att = st.attitude
    rel = relative_attitude(st)
    parts = [
        f"{st.mode.name:<15}",
        f"att r{att.roll:+7.2f} p{att.pitch:+7.2f} y{att.yaw:6.2f}",
        f"vs aircraft r{rel.roll:+7.2f} p{rel.pitch:+7.2f} y{rel.yaw:+7.2f}",
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


def json_line(gcu: GcuClient, sample: TelemetrySample | None) -> str:
    """One JSON object: the sample's frames as ``gcu-async decode`` shows them (``null``
    during an outage) and the link's health."""
    obj: dict[str, Any] = {"time": time.time(), "link": dataclasses.asdict(gcu.link)}
    if sample is not None:
        obj["status"] = sample.status.as_dict()
        obj["info"] = None if sample.info is None else sample.info.as_dict()
    else:
        obj["status"] = obj["info"] = None
    return json.dumps(obj)


def down_line(gcu: GcuClient) -> str:
    """The line printed for an interval without any reply."""
    link = gcu.link
    age = "no reply yet" if link.last_reply_age is None else (
        f"no reply for {link.last_reply_age:.1f} s")  # fmt: skip
    line = (f"link {'up' if link.up else 'DOWN'}: {age} | lost {link.lost_count} "
            f"restored {link.restored_count}")  # fmt: skip
    error = getattr(gcu.transport, "last_error", None)  # UDP: the OS's last report (ICMP, ...)
    return line if error is None else f"{line} | last error: {error}"


async def _monitor(url: str, interval: float, count: int, timeout: float, as_json: bool,
                   capture: PacketCapture | None = None,
                   report: Path | None = None) -> int:  # fmt: skip
    opened: list[GcuClient] = []
    try:
        return await _watch(url, interval, count, timeout, as_json, capture, report is not None,
                            opened)  # fmt: skip
    finally:  # an interrupt too: the report of what came (empty if the GCU never answered)
        if report is not None:
            gcu = opened[0] if opened else None
            found = gcu.conformance_report() if gcu is not None else GcuConformance().report()
            try:
                write_report(report, found.text() + "\n")
            except OSError as exc:
                print(f"gcu-async monitor: cannot write the report: {exc}", file=sys.stderr)


async def _watch(url: str, interval: float, count: int, timeout: float, as_json: bool,
                 capture: PacketCapture | None, conformance: bool,
                 opened: list[GcuClient]) -> int:  # fmt: skip
    async with connect(url, connect_timeout=timeout, capture=capture,
                       conformance=conformance) as gcu:  # fmt: skip
        opened.append(gcu)
        latest: list[TelemetrySample] = []
        fresh = asyncio.Event()

        def on_sample(sample: TelemetrySample) -> None:
            latest[:] = [sample]
            fresh.set()

        unsubscribe = gcu.on_telemetry(on_sample)
        loop = asyncio.get_running_loop()
        lines = 0
        try:
            while not count or lines < count:
                started = loop.time()
                with contextlib.suppress(asyncio.TimeoutError):
                    await asyncio.wait_for(fresh.wait(), interval)
                if fresh.is_set():
                    fresh.clear()
                    sample = latest[0]
                    print(json_line(gcu, sample) if as_json else format_line(gcu, sample),
                          flush=True)  # fmt: skip
                    await asyncio.sleep(max(0.0, started + interval - loop.time()))
                else:  # an outage: say so every interval
                    print(json_line(gcu, None) if as_json else down_line(gcu), flush=True)
                lines += 1
        finally:
            unsubscribe()
    return EXIT_OK


def run(args: argparse.Namespace) -> int:
    try:
        check_seconds("--interval", args.interval)
        check_seconds("--timeout", args.timeout)
        if args.count < 0:
            raise ValueError(f"--count: {args.count!r} must be >= 0")
        connect(args.url)
        capture = as_capture(args.capture)
    except (ValueError, CaptureUnavailable) as exc:
        print(f"gcu-async monitor: {exc}", file=sys.stderr)
        return EXIT_USAGE
    try:
        return asyncio.run(interruptible(_monitor(
            args.url, args.interval, args.count, args.timeout, args.json, capture,
            args.report)))  # fmt: skip
    except (Interrupted, KeyboardInterrupt):  # KeyboardInterrupt: no loop signal handlers
        return EXIT_INTERRUPTED
    except (LinkLost, GcuError, OSError) as exc:
        print(f"gcu-async monitor: {exc}", file=sys.stderr)
        return EXIT_FAILED
    finally:
        with contextlib.suppress(Exception):
            sys.stdout.flush()
