"""``gcu-async demo`` options: the command line, checked into :class:`DemoOptions`."""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from gcu_async.capture import CaptureUnavailable, PacketCapture, as_capture
from gcu_async.client.connect import connect
from gcu_async.protocol.enums import PodModel
from gcu_async.protocol.pods import resolve_pod_model
from gcu_async.sim.listen import ListenSpec, parse_listen_url
from gcu_async.sim.model import DEFAULT_POD

PROG = "gcu-async demo"
DEFAULT_LISTEN = "udp://127.0.0.1:0"
QUICK_SPEED = 10.0
MAX_SPEED = 1000.0
CONNECT_TIMEOUT = 3.0


def add_parser(sub: Any) -> argparse.ArgumentParser:
    """The ``demo`` subcommand's parser, with its options."""
    p: argparse.ArgumentParser = sub.add_parser(
        "demo",
        help="run a scripted session against a built-in simulator (or a real GCU)",
        description="Start a simulated GCU in this process on loopback, connect over real "
        "UDP and run a short scripted session: pointing-follow, Euler slew, pointing-lock "
        "pan, centre, top-down, zoom to 10x and back, photo, recording, laser ranging, "
        "tracking. A live view shows mode, attitude, zoom, flags and link health; a summary "
        "(commands, latency, packets, errors) closes the run. No hardware, no network "
        "beyond loopback.",
        epilog="Exit status: 0 all steps passed, 1 a step failed or no connection, 2 bad "
        "options, 130 interrupted (Ctrl-C or SIGTERM stop cleanly and print the summary so "
        "far). Against a real GCU over UDP the client binds local port 2338 unless the URL "
        "says otherwise (udp://HOST:PORT?local_port=0 picks a free one).",
    )
    p.add_argument("--url", metavar="URL",
                   help="drive an existing GCU or simulator instead of starting one: "
                   "udp://HOST[:PORT][?local_port=N], tcp://HOST[:PORT], "
                   "serial:///dev/ttyX[?baudrate=N]")  # fmt: skip
    p.add_argument("--listen", metavar="URL",
                   help=f"where the in-process simulator listens (default {DEFAULT_LISTEN}): "
                   "udp://HOST[:PORT], tcp://HOST[:PORT] or pty; port 0 = a free port")  # fmt: skip
    p.add_argument(
        "--pod",
        metavar="NAME",
        help=f"simulated pod model, Appendix 7 name or code (default {DEFAULT_POD})",
    )
    p.add_argument("--speed", metavar="FACTOR",
                   help="divide the script's pauses by FACTOR (default 1); the gimbal and zoom "
                   "still move at their own pace")  # fmt: skip
    p.add_argument(
        "--quick",
        action="store_true",
        help=f"short pauses, same as --speed {QUICK_SPEED:g} (--speed wins)",
    )
    p.add_argument(
        "--no-live", action="store_true", help="no live status view, only the progress lines"
    )
    p.add_argument("--capture", type=Path, metavar="FILE",
                   help="write the packets the client exchanges to FILE (pcapng; open it in "
                   "Wireshark with the dissector: gcu-async wireshark --install)")  # fmt: skip
    return p


@dataclass(frozen=True)
class DemoOptions:
    url: str | None
    """``None``: start the simulator in-process."""
    listen: ListenSpec
    pod: PodModel
    speed: float
    live: str
    """``tty``, ``plain`` or ``off`` (see :class:`Console`)."""
    capture: PacketCapture | None = None
    """Where the client records its packets."""


def parse_options(args: argparse.Namespace, *, isatty: bool) -> DemoOptions:
    """Check the options; ``ValueError`` with a one-line reason for any problem."""
    if args.url is not None:
        for option, value in (("--listen", args.listen), ("--pod", args.pod)):
            if value is not None:
                raise ValueError(f"{option}: only for the in-process simulator, not with --url")
        try:
            connect(args.url)  # validates the URL and its options; opens nothing
        except ValueError as exc:
            raise ValueError(f"--url: {exc}") from None
    try:
        listen = parse_listen_url(args.listen if args.listen is not None else DEFAULT_LISTEN)
    except ValueError as exc:
        raise ValueError(f"--listen: {exc}") from None
    if listen.kind == "serial":
        raise ValueError(
            "--listen: a serial device would be shared by simulator and client; use pty, or "
            "run `gcu-async sim --listen serial://...` and `gcu-async demo --url serial://...`"
        )
    try:
        pod = resolve_pod_model(args.pod if args.pod is not None else DEFAULT_POD)
    except ValueError as exc:
        raise ValueError(f"--pod: {exc}") from None
    speed = QUICK_SPEED if args.quick else 1.0
    if args.speed is not None:
        try:
            speed = float(args.speed)
        except ValueError:
            raise ValueError(f"--speed: {args.speed!r} is not a number") from None
        if not 0 < speed <= MAX_SPEED:
            raise ValueError(f"--speed: {speed!r} is outside the allowed range (0, {MAX_SPEED:g}]")
    live = "off" if args.no_live else ("tty" if isatty else "plain")
    try:
        capture = as_capture(getattr(args, "capture", None))
    except (TypeError, CaptureUnavailable) as exc:
        raise ValueError(f"--capture: {exc}") from None
    return DemoOptions(args.url, listen, pod, speed, live, capture)

