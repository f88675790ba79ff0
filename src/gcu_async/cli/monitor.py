"""``gcu-async monitor URL``: live telemetry — mode, angles, zoom, flags, link health; with
``--report FILE``, the GCU conformance report of the replies (docs/conformance.md).

By default it is a client with a heartbeat of its own; ``--passive`` (UDP) hears the replies
to another host's packets and sends nothing (:mod:`gcu_async.cli.passive`). Both print the
same lines."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import dataclasses
import inspect
import json
import sys
import time
from collections.abc import AsyncIterator, Callable
from pathlib import Path
from typing import Any, Protocol

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
    silence_stdout,
)
from gcu_async.cli._report import GCU_REPORT_HELP, add_report_option, write_report
from gcu_async.cli.liveview import relative_attitude
from gcu_async.cli.passive import (
    PassiveLink,
    PassiveListener,
    passive_refusal,
    passive_transport,
)
from gcu_async.client.client import GcuClient
from gcu_async.client.connect import connect
from gcu_async.client.telemetry import TelemetrySample
from gcu_async.conformance import GcuConformance, GcuReport
from gcu_async.errors import GcuError, LinkLost
from gcu_async.session.health import RATE_WINDOW_S, LinkHealth
from gcu_async.transport.base import Transport
from gcu_async.transport.tap import with_capture

PROG = "gcu-async monitor"
DEFAULT_TIMEOUT = 3.0
HEARTBEAT_HZ: float = inspect.signature(GcuClient).parameters["rate_hz"].default
"""The client's heartbeat rate, which the active monitor sends at."""

DESCRIPTION = (
    "Prints one status line per interval: mode, camera attitude, zoom, flags and link "
    "health; during an outage a line saying how long no reply came. Ctrl-C or SIGTERM ends "
    f"it (exit status 130). By default it connects as a client and sends its own heartbeat "
    f"({HEARTBEAT_HZ:g} packets/s, no aircraft data, control values invalid). Beside an "
    "application on the same GCU that changes what the pod does: the GCU runs the monitor's "
    "packets between the application's, so rates and aircraft data the application sends "
    "act only part of the time (in the simulator a 20 °/s pointing-lock rate came out at "
    "4-16 °/s). To watch an application's session, use --passive (UDP): it sends nothing."
)
PASSIVE_HELP = (
    "listen only (udp://): show the replies the GCU broadcasts to another host's packets "
    "(your application's), sending nothing. It binds the broadcast address of the GCU's "
    "subnet on the reply port (2338, or the URL's local_port; local_host=ADDRESS to give it), "
    "shared with the application, so it never takes a reply meant for the application; a "
    "GCU or emulator that answers by unicast it cannot hear (gcu-async sim broadcasts with "
    "--reply-to broadcast). Not for tcp:// or serial://: those carry the replies to one "
    "reader only"
)


def register(sub: Any) -> None:
    p = sub.add_parser("monitor", help="show live telemetry of a GCU until Ctrl-C",
                       description=DESCRIPTION)  # fmt: skip
    p.add_argument("url", help="udp://HOST[:PORT], tcp://HOST[:PORT] or serial:///dev/…")
    p.add_argument("--passive", action="store_true", help=PASSIVE_HELP)
    p.add_argument("--interval", type=float, default=0.5, metavar="SECONDS",
                   help=f"seconds between lines, at most {SECONDS_MAX:g} (default 0.5)")
    p.add_argument("--count", type=int, default=0,
                   help="stop after this many lines (default 0: never)")
    p.add_argument("--timeout", type=float, default=None, metavar="SECONDS",
                   help=f"seconds to wait for the GCU's first reply, at most {SECONDS_MAX:g} "
                   f"(default {DEFAULT_TIMEOUT:g}; not with --passive, which waits for no "
                   "reply of its own)")
    p.add_argument("--json", action="store_true",
                   help="one JSON object per line (the frames as `decode` shows them; default: "
                   "text lines)")
    p.add_argument("--capture", type=Path, metavar="FILE",
                   help="write the packets exchanged (--passive: heard) to FILE (pcapng; open "
                   "it in Wireshark with the dissector: gcu-async wireshark --install; "
                   "default: none)")
    add_report_option(p, f"{GCU_REPORT_HELP} when it ends (Ctrl-C, --count): every reply "
                      "of the live link")  # fmt: skip
    p.set_defaults(run=run)


class Watched(Protocol):
    """What the monitor reads: a :class:`GcuClient` or a
    :class:`~gcu_async.cli.passive.PassiveListener`."""

    @property
    def link(self) -> LinkHealth: ...
    @property
    def transport(self) -> Transport: ...
    def on_telemetry(self, callback: Callable[[TelemetrySample], None]) -> Callable[[], None]:
        ...
    def conformance_report(self) -> GcuReport: ...


@dataclasses.dataclass(frozen=True)
class Options:
    """A checked ``monitor`` command line."""

    url: str
    interval: float
    count: int
    timeout: float
    as_json: bool
    passive: bool
    capture: PacketCapture | None = None
    report: Path | None = None


def _names(flags: Any) -> list[str]:
    return [f.name.lower() for f in type(flags) if f in flags and f.name]


def link_text(link: LinkHealth, warm: bool) -> str:
    """``link up 50/s crc_err 0 lost 0``; the rate is ``-`` while not ``warm`` (its window
    of :data:`~gcu_async.session.health.RATE_WINDOW_S` not yet filled with the link up)."""
    rate = f"{link.reply_rate:.0f}" if warm else "-"
    return (f"link {'up' if link.up else 'DOWN'} {rate}/s crc_err {link.crc_errors} "
            f"lost {link.lost_count}")  # fmt: skip


def format_line(link: LinkHealth, sample: TelemetrySample, *, warm: bool = True) -> str:
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
    parts.append(link_text(link, warm))
    return " | ".join(parts)


def json_line(link: LinkHealth, sample: TelemetrySample | None, *, warm: bool = True) -> str:
    """One JSON object: the sample's frames as ``gcu-async decode`` shows them (``null``
    during an outage) and the link's health (``reply_rate`` ``null`` while not ``warm``)."""
    health = dataclasses.asdict(link)
    if not warm:
        health["reply_rate"] = None
    obj: dict[str, Any] = {"time": time.time(), "link": health}
    if sample is not None:
        obj["status"] = sample.status.as_dict()
        obj["info"] = None if sample.info is None else sample.info.as_dict()
    else:
        obj["status"] = obj["info"] = None
    return json.dumps(obj)


PASSIVE_HINT = ("a GCU replies to the subnet's broadcast address; gcu-async sim does with "
                "--reply-to broadcast")  # fmt: skip
"""Why a passive monitor may hear nothing: a GCU (or simulator) answering by unicast."""


def down_line(link: LinkHealth, error: object = None, *, passive: bool = False) -> str:
    """The line printed for an interval without any reply (``error``: the transport's last
    one, e.g. an ICMP port unreachable)."""
    if link.last_reply_age is None:
        age = (f"no broadcast reply heard yet ({PASSIVE_HINT})" if passive
               else "no reply yet")  # fmt: skip
    else:
        age = f"no reply for {link.last_reply_age:.1f} s"
    line = (f"link {'up' if link.up else 'DOWN'}: {age} | lost {link.lost_count} "
            f"restored {link.restored_count}")  # fmt: skip
    return line if error is None else f"{line} | last error: {error}"


@contextlib.asynccontextmanager
async def _opened(opts: Options) -> AsyncIterator[Watched]:
    """The client (active) or the listener (``--passive``), open."""
    if not opts.passive:
        async with connect(opts.url, connect_timeout=opts.timeout, capture=opts.capture,
                           conformance=opts.report is not None) as gcu:  # fmt: skip
            yield gcu
        return
    transport = await passive_transport(opts.url)
    link = PassiveLink(conformance=GcuConformance() if opts.report is not None else None)
    async with PassiveListener(with_capture(transport, opts.capture), link) as listener:
        where = f"{transport.local_host}:{transport.local_port}"
        print(f"{PROG}: passive: hearing what {transport.url} broadcasts to {where}; "
              "sending nothing", file=sys.stderr, flush=True)  # fmt: skip
        yield listener


async def _monitor(opts: Options) -> int:
    opened: list[Watched] = []
    try:
        return await _watch(opts, opened)
    finally:  # an interrupt too: the report of what came (empty if the GCU never answered)
        if opts.report is not None:
            found = opened[0].conformance_report() if opened else GcuConformance().report()
            try:
                write_report(opts.report, found.text() + "\n")
            except OSError as exc:
                print(f"{PROG}: cannot write the report: {exc}", file=sys.stderr)


async def _watch(opts: Options, opened: list[Watched]) -> int:
    async with _opened(opts) as watched:
        opened.append(watched)
        loop = asyncio.get_running_loop()
        latest: list[TelemetrySample] = []
        first: list[float] = []  # when the first sample came: the rate's window fills from it
        fresh = asyncio.Event()

        def on_sample(sample: TelemetrySample) -> None:
            latest[:] = [sample]
            if not first:
                first.append(loop.time())
            fresh.set()

        unsubscribe = watched.on_telemetry(on_sample)
        lines = 0
        try:
            while not opts.count or lines < opts.count:
                started = loop.time()
                with contextlib.suppress(asyncio.TimeoutError):
                    await asyncio.wait_for(fresh.wait(), opts.interval)
                link = watched.link
                warm = bool(first) and loop.time() - first[0] >= RATE_WINDOW_S
                if fresh.is_set():
                    fresh.clear()
                    sample = latest[0]
                    print(json_line(link, sample, warm=warm) if opts.as_json
                          else format_line(link, sample, warm=warm), flush=True)  # fmt: skip
                    await asyncio.sleep(max(0.0, started + opts.interval - loop.time()))
                else:  # an outage: say so every interval
                    error = getattr(watched.transport, "last_error", None)  # UDP: ICMP, ...
                    text = down_line(link, error, passive=opts.passive)
                    print(json_line(link, None, warm=warm) if opts.as_json else text, flush=True)
                lines += 1
        finally:
            unsubscribe()
    return EXIT_OK


def _options(args: argparse.Namespace) -> Options:
    """Check the command line; ``ValueError`` (a usage error) naming the option. Opens
    nothing."""
    check_seconds("--interval", args.interval)
    if args.timeout is not None:
        if args.passive:
            raise ValueError("--timeout: not with --passive: a passive monitor waits for no "
                             "reply of its own; it listens until Ctrl-C or --count")  # fmt: skip
        check_seconds("--timeout", args.timeout)
    if args.count < 0:
        raise ValueError(f"--count: {args.count!r} must be >= 0")
    if args.passive:
        why = passive_refusal(args.url)
        if why is not None:
            raise ValueError(f"--passive: {why}")
    else:
        connect(args.url)
    try:
        capture = as_capture(args.capture)
    except CaptureUnavailable as exc:
        raise ValueError(str(exc)) from None
    timeout = DEFAULT_TIMEOUT if args.timeout is None else args.timeout
    return Options(args.url, args.interval, args.count, timeout, args.json, args.passive,
                   capture, args.report)  # fmt: skip


def run(args: argparse.Namespace) -> int:
    try:
        opts = _options(args)
    except ValueError as exc:
        print(f"{PROG}: {exc}", file=sys.stderr)
        return EXIT_USAGE
    try:
        return asyncio.run(interruptible(_monitor(opts)))
    except (Interrupted, KeyboardInterrupt):  # KeyboardInterrupt: no loop signal handlers
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # the reader has all it wants (`monitor … | head`)
        silence_stdout()
        return EXIT_OK
    except (LinkLost, GcuError, OSError) as exc:
        print(f"{PROG}: {str(exc) or type(exc).__name__}", file=sys.stderr)
        return EXIT_FAILED
    finally:
        with contextlib.suppress(Exception):
            sys.stdout.flush()
