"""``gcu-async send URL COMMAND [ARGS…]``: run one command, print its feedback as JSON.

Parsed in two stages: the ``send`` parser takes the URL, the command's name and the options
given before the name; the command's own parser (:func:`command_parser`, which also gives
its ``--help``) takes its arguments and the options given after the name.

Exit status: 0 success, 1 failure / timeout / no link, 2 usage error, 130 interrupted.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import sys
import textwrap
import time
import warnings
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any, NoReturn

from gcu_async._checks import did_you_mean
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
from gcu_async.cli._logging import VERBOSE_HELP, configure_logging
from gcu_async.cli._parser import CliParser
from gcu_async.cli.send_commands import (
    COMMANDS,
    AircraftFix,
    CliCommand,
    parse_aircraft,
    parse_cameras,
)
from gcu_async.client.client import GcuClient
from gcu_async.client.connect import connect
from gcu_async.errors import CommandFailed, FieldRangeError, GcuError, LinkLost
from gcu_async.protocol.feedback import Feedback

PROG = "gcu-async send"
NEEDS_MARK = "[--aircraft]"
"""Marks the commands that need ``--aircraft`` in ``send --help``."""
DEFAULT_TIMEOUT = 5.0
"""Seconds: how long the link and a command's feedback may take when ``--timeout`` is not
given (a method with a ``timeout`` parameter, e.g. ``calibrate``, keeps its own default)."""


def _shared_options(parser: argparse.ArgumentParser, *, cameras: bool = True) -> None:
    """The options taken both before and after the command's name (``cameras=False``: the
    command takes no cameras, ``--cameras`` is accepted but hidden and refused later)."""
    parser.add_argument(
        "--timeout", type=float, default=None, metavar="SECONDS",
        help=f"seconds to wait for the link and for the command's feedback, for every command, "
        f"at most {SECONDS_MAX:g} (default {DEFAULT_TIMEOUT:g}; calibrate: 15, its method's "
        "default)",
    )
    parser.add_argument(
        "--aircraft", type=parse_aircraft, default=None, metavar="LAT,LON,ALT[,YAW]",
        help="send the aircraft's state while the command runs: standing still and level at "
        "latitude, longitude (degrees), altitude (metres MSL), heading YAW (degrees, default "
        "0 = north); INS valid goes out while it is given. Required by the commands marked "
        f"{NEEDS_MARK!r} below",
    )
    parser.add_argument("--rate", type=float, default=50.0, metavar="HZ",
                        help="heartbeat rate in Hz (default 50)")
    parser.add_argument(
        "--hold", type=float, default=None, metavar="SECONDS",
        help="after a mode command, keep sending its control values this long (default 3 s "
        "for enter-euler-control/enter-angle-control/enter-fpv, stopping early once the camera "
        "is there; 0 otherwise)",
    )
    parser.add_argument(
        "--cameras", type=parse_cameras, default=None, metavar="LIST",
        help="the cameras a camera command addresses: camera numbers 1-8 or names (visible = "
        "1, thermal = 2), comma-separated, e.g. 1,2 (default: the method's, camera 1 or 2)"
        if cameras else argparse.SUPPRESS,
    )
    parser.add_argument("--capture", type=Path, metavar="FILE",
                        help="write the packets exchanged to FILE (pcapng; open it in Wireshark "
                        "with the dissector: gcu-async wireshark --install)")  # fmt: skip


def _command_list() -> str:
    """The commands for ``gcu-async send --help``."""
    lines = ["commands (gcu-async send URL COMMAND --help: its arguments, units, ranges;",
             f"{NEEDS_MARK}: needs --aircraft, the GCU runs it only with valid INS data):"]
    width = max(map(len, COMMANDS))
    for name, spec in COMMANDS.items():
        args = [f"[{p.name}]" if p.optional else p.name for p in spec.params]
        mark = [NEEDS_MARK] if spec.needs_ins else []
        lines.append(f"  {name:<{width}} {' '.join([*args, f'-> {spec.method}()', *mark])}")
        lines.append(f"  {'':<{width}} {spec.summary}")
    return "\n".join(lines)


def register(sub: Any) -> None:
    p = sub.add_parser(
        "send",
        help="send one command to a GCU and print its feedback as JSON",
        description=textwrap.fill(
            "Connect, run one command, print its feedback (with the camera's attitude and "
            "mode) as one JSON object. Exit 0 on success, 1 on failure or timeout, 2 on a "
            "usage error, 130 when interrupted.", 78),
        epilog=_command_list(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("url", metavar="URL",
                   help="udp://HOST[:PORT], tcp://HOST[:PORT] or serial:///dev/…")
    p.add_argument("name", metavar="COMMAND", help="one of the commands below")
    rest = p.add_argument("args", nargs=argparse.REMAINDER, metavar="ARG ...",
                          help="the command's arguments, then options")
    rest.required = False  # argparse takes a REMAINDER for required; a command may take none
    _shared_options(p)
    p.set_defaults(run=run)  # fmt: skip


class CommandParser(CliParser):
    """The parser of one ``send`` command: a usage error is one line on stderr, status 2."""

    def __init__(self, command: str, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.command = command

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USAGE, f"{PROG}: {self.command}: {message}\n")


@cache
def command_parser(name: str) -> CommandParser:
    """The parser of command ``name``: its arguments (converted, in ``arg_<name>``), the
    shared options, ``-v`` and ``--help`` (the command's own help)."""
    spec = COMMANDS[name]
    parser = CommandParser(
        name, prog=f"{PROG} URL {name}", description=spec.description(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )  # fmt: skip
    for param in spec.params:
        parser.add_argument(f"arg_{param.name}", metavar=param.name, type=param.convert,
                            nargs="?" if param.optional else None, help=param.help)  # fmt: skip
    for param in spec.params:  # an optional argument by name too: --pitch -45 alone
        if param.optional:
            parser.add_argument(f"--{param.name}", dest=f"opt_{param.name}",
                                type=param.convert, metavar=param.name.upper(),
                                help=f"{param.name} by name")  # fmt: skip
    _shared_options(parser, cameras=spec.takes_cameras)
    parser.add_argument("-v", "--verbose", action="count", help=VERBOSE_HELP)
    return parser


@dataclass(frozen=True)
class Invocation:
    """A checked ``send`` command line: what to call and how long to wait."""

    url: str
    name: str
    spec: CliCommand
    values: list[Any]
    named: dict[str, Any]
    """Optional arguments given by name (``--pitch -45``)."""
    extra: dict[str, Any]
    """Keyword arguments from the options: ``cameras``, ``timeout`` (if the method has it)."""
    timeout: float
    """Seconds the link and the command's feedback may take."""
    rate: float
    hold: float
    capture: PacketCapture | None = None
    """Where the client records its packets (``--capture``)."""
    aircraft: AircraftFix | None = None
    """The aircraft state sent while the command runs (``--aircraft``)."""


def resolve(args: argparse.Namespace) -> Invocation:
    """Parse the command's part of the command line into ``args`` and check it all, values
    against the method's ranges included; opens nothing. Raises ``ValueError`` with a
    one-line reason; the command's parser exits with status 2 (one line) for a bad
    argument, 0 after printing its ``--help``."""
    spec = COMMANDS.get(args.name)
    if spec is None:
        raise ValueError(_unknown(args.name))
    command_parser(args.name).parse_args(args.args, namespace=args)
    given = [getattr(args, f"arg_{p.name}") for p in spec.params]
    values = [v for v in given if v is not None]
    named = {p.name: v for p in spec.params if p.optional
             and (v := getattr(args, f"opt_{p.name}", None)) is not None}  # fmt: skip
    group = [name for name in spec.together
             if getattr(args, f"arg_{name}") is not None or name in named]  # fmt: skip
    if group and len(group) != len(spec.together):
        raise ValueError(f"{args.name}: give all of {' '.join(spec.together)}, or none")
    if args.timeout is not None:
        check_seconds("--timeout", args.timeout)
    extra: dict[str, Any] = {}
    if args.cameras is not None:
        if not spec.takes_cameras:
            raise ValueError(f"--cameras: {args.name} addresses no camera ({spec.method}() has "
                             "no cameras parameter)")  # fmt: skip
        extra["cameras"] = args.cameras
    if args.timeout is not None and spec.takes_timeout:
        extra["timeout"] = args.timeout
    spec.check(values, named, **extra)  # the method's own checks, before anything is opened
    if spec.needs_ins and args.aircraft is None:
        raise ValueError(f"{args.name}: the GCU runs it only with valid INS data: give the "
                         "aircraft's state with --aircraft LAT,LON,ALT[,YAW]")  # fmt: skip
    with warnings.catch_warnings():  # the advice outside 30-50 Hz comes once, when it runs
        warnings.simplefilter("ignore")
        try:  # the URL, its options and --rate, checked by the client itself; opens nothing
            unopened = connect(args.url, rate_hz=args.rate)
        except FieldRangeError as exc:
            if exc.field != "rate_hz":
                raise
            raise ValueError(f"--rate: {str(exc).removeprefix('rate_hz: ')}") from None
    if args.aircraft is not None:
        try:
            unopened.update_aircraft(**args.aircraft.state())
        except (TypeError, ValueError) as exc:
            raise ValueError(f"--aircraft: {exc}") from None
    hold = args.hold if args.hold is not None else (3.0 if spec.holds else 0.0)
    check_seconds("--hold", hold, zero=True)
    try:
        capture = as_capture(args.capture)
    except (TypeError, CaptureUnavailable) as exc:
        raise ValueError(f"--capture: {exc}") from None
    timeout = args.timeout if args.timeout is not None else DEFAULT_TIMEOUT
    return Invocation(args.url, args.name, spec, values, named, extra, timeout, args.rate, hold,
                      capture, args.aircraft)


def _unknown(name: str) -> str:
    """The message for an unknown command, one short line: up to three close names
    (``zoom_to`` → ``zoom-to``) and where the whole list is."""
    spelt = name.replace("_", "-").lower()
    hint = did_you_mean(spelt, [spelt] if spelt in COMMANDS else COMMANDS, n=3)
    hint += " " if hint else ""
    return f"unknown command {name!r}; {hint}{PROG} --help lists all {len(COMMANDS)}"


async def _feed_aircraft(gcu: GcuClient, fix: AircraftFix) -> None:
    """Claim the aircraft state again well within ``aircraft_timeout``, until cancelled."""
    while True:
        gcu.update_aircraft(**fix.state())
        await asyncio.sleep(gcu.aircraft_timeout / 4)


async def _send(inv: Invocation) -> tuple[Any, dict[str, Any]]:
    client = connect(inv.url, command_timeout=inv.timeout, connect_timeout=inv.timeout,
                     rate_hz=inv.rate, capture=inv.capture)  # fmt: skip
    feeding = None
    if inv.aircraft is not None:
        feeding = asyncio.create_task(_feed_aircraft(client, inv.aircraft))
        await asyncio.sleep(0)  # the first packet already carries it
    try:
        return await _run_command(client, inv)
    finally:
        if feeding is not None:
            feeding.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await feeding


async def _run_command(client: GcuClient, inv: Invocation) -> tuple[Any, dict[str, Any]]:
    async with client as gcu:
        feedback = await inv.spec.call(gcu, inv.values, inv.named, **inv.extra)
        # Control values only act while packets carry them: hold them for a while (angle
        # modes stop early once the camera's attitude matches the target).
        deadline = time.monotonic() + inv.hold
        while time.monotonic() < deadline:
            if inv.spec.angle_target and _arrived(gcu, inv.spec.build(inv.values, inv.named)[1]):
                break
            await asyncio.sleep(0.05)
        status = gcu.status  # the command's feedback came with a reply: never None here
        assert status is not None
        return feedback, {"attitude_deg": status.attitude._asdict(),
                          "mode": status.mode.name}  # fmt: skip


def _arrived(gcu: GcuClient, targets: dict[str, Any]) -> bool:
    """The camera is within 0.5° of the pitch and yaw given (those left out: any)."""
    if gcu.status is None:
        return False
    att = gcu.status.attitude
    pitch, yaw = targets.get("pitch"), targets.get("yaw")
    return (pitch is None or abs(att.pitch - float(pitch)) < 0.5) and (
        yaw is None or abs((att.yaw - float(yaw) + 180) % 360 - 180) < 0.5)


def run(args: argparse.Namespace) -> int:
    verbose = args.verbose
    try:
        inv = resolve(args)
    except ValueError as exc:
        print(f"{PROG}: {exc}", file=sys.stderr)
        return EXIT_USAGE
    if args.verbose != verbose:  # -v after the command's name
        configure_logging(args.verbose)
    try:
        feedback, state = asyncio.run(interruptible(_send(inv)))
    except (Interrupted, KeyboardInterrupt):  # KeyboardInterrupt: no loop signal handlers
        return _print({"ok": False, "error": "interrupted"}, EXIT_INTERRUPTED)
    except ValueError as exc:  # a value out of range for the method
        print(f"{PROG}: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except CommandFailed as exc:
        cause = exc.likely_cause
        out = {"ok": False, "error": str(exc), "opcode": exc.opcode, "status_raw": exc.status,
               "failed_cameras": int(exc.failed_cameras),
               "likely_cause": None if cause is None else cause.name,
               "cause_detail": exc.cause_detail}  # fmt: skip
        return _print(out, EXIT_FAILED)
    except (TimeoutError, LinkLost, GcuError, OSError) as exc:
        return _print({"ok": False, "error": str(exc) or type(exc).__name__}, EXIT_FAILED)
    if feedback is None:
        return _print({"ok": True, "skipped": True}, EXIT_OK)
    assert isinstance(feedback, Feedback)
    return _print({"ok": True, **feedback.as_dict(), **state}, EXIT_OK)


def _print(result: dict[str, Any], status: int) -> int:
    """Print the result's JSON line; return ``status``, the command's, even when the reader
    of stdout has gone (``| head -c 0``): quietly then."""
    try:
        print(json.dumps(result), flush=True)
    except BrokenPipeError:
        silence_stdout()
    return status
