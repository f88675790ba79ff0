"""``gcu-async sim``: run the GCU simulator on UDP, TCP, a pty or a serial device.

Prints one line saying where it listens, logs every executed command (info level, stderr),
stops cleanly with exit status 0 on Ctrl-C / SIGTERM. Bad options: one line on stderr,
exit status 2. Cannot bind / open: exit status 1.

Switches while running (POSIX signals): SIGUSR1 kills the current TCP connection now;
SIGUSR2 silences the GCU for ``--silence`` seconds (default 5); with ``--stall SECONDS``,
SIGHUP stalls it for that long (without the option SIGHUP keeps its default: terminate);
SIGQUIT (Ctrl-\\ in a terminal) prints the host conformance report to stderr (and rewrites
``--report`` / ``--report-json``).

At exit it logs a summary and prints the host conformance report (every way the host's
packets deviated from V2.0.6) to stderr (``-q``: neither), and writes it to ``--report``
(text) and ``--report-json`` (JSON: the report and the simulator's counters) when given.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import ipaddress
import json
import logging
import signal
import sys
from pathlib import Path
from typing import Any

from gcu_async.capture import CaptureUnavailable, as_capture
from gcu_async.cli._exit import EXIT_FAILED, EXIT_INTERRUPTED, EXIT_USAGE
from gcu_async.cli._parser import in_option_terms
from gcu_async.cli._report import HOST_REPORT_HELP, add_report_option, write_report
from gcu_async.protocol.enums import opcode_name
from gcu_async.protocol.links import HOST_UDP_PORT
from gcu_async.sim.faults import FaultConfig, FaultPlan
from gcu_async.sim.firmware import DEFAULT_FIRMWARE, FIRMWARES
from gcu_async.sim.listen import ListenSpec, parse_hostport, parse_listen_url
from gcu_async.sim.model import DEFAULT_POD, SimulatorModel
from gcu_async.sim.serialport import SerialServer
from gcu_async.sim.server import SimServer
from gcu_async.sim.simulator import GcuSimulator
from gcu_async.sim.tcp import TcpServer
from gcu_async.sim.udp import interface_broadcast
from gcu_async.transport._common import format_hostport

PROG = "gcu-async sim"
DEFAULT_LISTEN = "udp://127.0.0.1:2337"
DEFAULT_REORDER_HOLD = FaultConfig().reorder_hold
DIRECTIONS = ("both", "requests", "replies")
MODEL_OPTIONS = {"pod model": "--pod", "max_zoom": "--max-zoom", "firmware": "--firmware"}
"""The model's parameters the options give (their errors are told in the options' terms)."""
LOOPBACK_BROADCAST = "127.255.255.255"
"""The loopback network's broadcast address: Linux delivers a datagram sent there to every
socket bound to its port (the loopback interface itself has no broadcast address)."""
log = logging.getLogger("gcu_async.sim")

DESCRIPTION = """\
Run a simulated GCU and pod that answers host packets like the real one.
Listen URLs: udp://HOST[:PORT] (default port 2337), tcp://HOST[:PORT] (2332),
pty, serial:///dev/ttyX[?baudrate=N]. Fault options apply to requests and
replies (see --faults-on), each direction with its own seeded random generator.
"""
FAULTS_EPILOG = """\
fault model (per direction, each packet independently, seeded):
  a packet is lost with probability --loss; otherwise one bit of it is flipped with
  probability --corrupt, it is sent twice with probability --duplicate, and it is
  delivered d seconds late, d = u + h: u uniform in [0, --delay], h = --reorder-hold when
  it is reordered (probability --reorder), else 0. Both copies of a duplicate get the
  same d. So in each direction every packet that gets through is delivered between 0 and
  --delay + --reorder-hold seconds after it was sent (plus the event loop's own latency):
  the delay variation, and how far a packet can be overtaken, is bounded by
  --delay + --reorder-hold; a request and its reply together by twice that.
  --faults-on picks the directions; replies draw from --seed + 1.
"""


def register(sub: Any) -> None:
    p = sub.add_parser(
        "sim",
        help="run a simulated GCU (UDP, TCP, pty or serial device)",
        description=DESCRIPTION,
        epilog=FAULTS_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--listen", default=DEFAULT_LISTEN, metavar="URL",
                   help=f"where to listen (default {DEFAULT_LISTEN})")  # fmt: skip
    p.add_argument("--pod", default=DEFAULT_POD, metavar="NAME",
                   help=f"pod model, Appendix 7 name or code (default {DEFAULT_POD})")  # fmt: skip
    p.add_argument("--firmware", default=DEFAULT_FIRMWARE, choices=sorted(FIRMWARES),
                   metavar="NAME", help="how the replies are filled: "
                   + "; ".join(f"{f.name}: {f.summary}" for f in FIRMWARES.values())
                   + f" (default {DEFAULT_FIRMWARE}; --pod Z-1Pro --firmware z1pro-6.7 plays "
                   "the logged Z-1Pro)")  # fmt: skip
    p.add_argument("--reply-to", metavar="HOST:PORT",
                   help="UDP: send every reply here (e.g. the broadcast address, port 2338) "
                   "instead of to the sender; 'broadcast[:PORT]' (Linux): the broadcast "
                   "address of the listen address's interface (127.255.255.255 on "
                   "loopback), port 2338 unless given, as a real GCU does: every listener "
                   "on that port hears every reply (gcu-async monitor --passive)")  # fmt: skip
    p.add_argument("--reply-port", type=int, metavar="PORT",
                   help="UDP: reply to the sender's host at this port (e.g. 2338)")  # fmt: skip
    p.add_argument("--silence", type=float, default=5.0, metavar="SECONDS",
                   help="how long SIGUSR2 silences the GCU (default 5)")  # fmt: skip
    p.add_argument("--stall", type=float, default=None, metavar="SECONDS",
                   help="make SIGHUP stall the GCU for SECONDS: it stops reading its "
                   "socket/pty (the OS buffers what the host sends), then answers "
                   "everything buffered, in order")  # fmt: skip
    p.add_argument("--loss", type=float, default=0.0, metavar="P",
                   help="probability of losing a packet")  # fmt: skip
    p.add_argument("--corrupt", type=float, default=0.0, metavar="P",
                   help="probability of flipping a bit in a packet")  # fmt: skip
    p.add_argument("--duplicate", type=float, default=0.0, metavar="P",
                   help="probability of sending a packet twice")  # fmt: skip
    p.add_argument("--reorder", type=float, default=0.0, metavar="P",
                   help="probability of holding a packet back by --reorder-hold, so "
                   "later packets overtake it")  # fmt: skip
    p.add_argument("--reorder-hold", type=float, default=DEFAULT_REORDER_HOLD,
                   metavar="SECONDS", help="how long a reordered packet is held back "
                   f"(default {DEFAULT_REORDER_HOLD:g})")  # fmt: skip
    p.add_argument("--delay", type=float, default=0.0, metavar="SECONDS",
                   help="maximum extra delay per packet (uniform in [0, SECONDS])")  # fmt: skip
    p.add_argument("--faults-on", choices=DIRECTIONS, default="both",
                   help="directions the fault options apply to (default both)")  # fmt: skip
    p.add_argument("--seed", type=int, default=0, metavar="N",
                   help="seed for fault injection and the model's noise (default 0)")  # fmt: skip
    p.add_argument("--max-zoom", type=float, default=None, metavar="X",
                   help="maximum optical zoom of camera 1 (default: per pod model)")  # fmt: skip
    p.add_argument("--capture", type=Path, metavar="FILE",
                   help="write the packets the simulator receives and sends to FILE (pcapng; "
                   "open it in Wireshark with: gcu-async wireshark --install)")  # fmt: skip
    add_report_option(p, f"{HOST_REPORT_HELP} at exit and on SIGQUIT (the simulator plays "
                      "the GCU: it reports the host)")  # fmt: skip
    p.add_argument("--report-json", type=Path, metavar="FILE",
                   help="write the host conformance report and the simulator's counters "
                   "(JSON) to FILE at exit and on SIGQUIT")  # fmt: skip
    p.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        help="quiet: log nothing and print no report at exit (--report, --report-json and "
        "SIGQUIT still give it)",
    )
    p.set_defaults(run=run)


class _UsageError(ValueError):
    pass


def _build(args: argparse.Namespace) -> tuple[GcuSimulator, ListenSpec]:
    try:
        try:
            spec = parse_listen_url(args.listen)
        except ValueError as exc:
            raise ValueError(f"--listen: {exc}") from None
        if args.reply_to is not None or args.reply_port is not None:
            option = "--reply-to" if args.reply_to is not None else "--reply-port"
            if spec.kind != "udp":
                raise ValueError(f"{option}: only for a udp:// listen URL")
            if args.reply_to is not None and args.reply_port is not None:
                raise ValueError("--reply-to and --reply-port: give at most one")
            reply_to = None
            if args.reply_to is not None:
                reply_to = _reply_to(args.reply_to, spec.host)
            if args.reply_port is not None and not 1 <= args.reply_port <= 65535:
                raise ValueError(f"--reply-port: {args.reply_port} is outside 1-65535")
            spec = ListenSpec(spec.kind, spec.host, spec.port, reply_to=reply_to,
                              reply_port=args.reply_port)  # fmt: skip
        if not 0.0 <= args.silence < float("inf"):
            raise ValueError(f"--silence: {args.silence!r} is outside the allowed range [0, inf) s")
        for option in ("loss", "corrupt", "duplicate", "reorder"):
            value = getattr(args, option)
            if not 0.0 <= value <= 1.0:
                raise ValueError(f"--{option}: {value!r} is outside the allowed range [0, 1]")
        for option in ("delay", "reorder_hold"):
            value = getattr(args, option)
            if not 0.0 <= value < float("inf"):
                name = "--" + option.replace("_", "-")
                raise ValueError(f"{name}: {value!r} is outside the allowed range [0, inf) s")
        if args.stall is not None and not 0.0 < args.stall < float("inf"):
            raise ValueError(f"--stall: {args.stall!r} is outside the allowed range (0, inf) s")
        faults = FaultConfig(
            drop=args.loss,
            corrupt=args.corrupt,
            duplicate=args.duplicate,
            reorder=args.reorder,
            delay=args.delay,
            seed=args.seed,
            reorder_hold=args.reorder_hold,
        )
        plan = FaultPlan.both(faults)
        if args.faults_on == "requests":
            plan = FaultPlan(requests=plan.requests)
        elif args.faults_on == "replies":
            plan = FaultPlan(replies=plan.replies)
        try:
            model = SimulatorModel(args.pod, seed=args.seed, max_zoom=args.max_zoom,
                                   firmware=args.firmware)  # fmt: skip
        except ValueError as exc:
            raise ValueError(in_option_terms(exc, MODEL_OPTIONS)) from None
        capture = as_capture(args.capture)
    except (ValueError, CaptureUnavailable) as exc:
        raise _UsageError(str(exc)) from None
    return GcuSimulator(model, faults=plan, capture=capture), spec


def _reply_to(text: str, listen_host: str) -> tuple[str, int]:
    """``--reply-to``: ``HOST:PORT``, or ``broadcast[:PORT]`` resolved for the listen host."""
    name, _, port = text.partition(":")
    if name != "broadcast":
        return parse_hostport(text, what="--reply-to")
    if port and not (port.isdigit() and 1 <= int(port) <= 65535):
        raise ValueError(f"--reply-to {text!r}: port must be a number in 1-65535")
    try:
        host = interface_broadcast(listen_host)
    except ValueError as exc:
        if not _linux_loopback(listen_host):
            raise ValueError(f"--reply-to broadcast: {exc}") from None
        host = LOOPBACK_BROADCAST  # a GCU on this machine: every local listener hears it
    return host, int(port) if port else HOST_UDP_PORT


def _linux_loopback(host: str) -> bool:
    """``host`` is an IPv4 loopback address on Linux (where :data:`LOOPBACK_BROADCAST`
    reaches every socket on the port)."""
    try:
        ip = ipaddress.ip_address(host)
    except ValueError:
        return False
    return sys.platform.startswith("linux") and ip.version == 4 and ip.is_loopback


class Reports:
    """Where the conformance report goes: stderr, and the ``--report`` / ``--report-json``
    files (each rewritten whole, through a temporary file, so a reader never sees half)."""

    def __init__(self, sim: GcuSimulator, text: Path | None, json_path: Path | None, *,
                 quiet: bool = False) -> None:  # fmt: skip
        self.sim = sim
        self.text_path = text
        self.json_path = json_path
        self.quiet = quiet
        """At exit, write the files only (``-q``); SIGQUIT still prints the report."""

    def document(self) -> dict[str, Any]:
        model = self.sim.model
        s = model.stats
        return {
            "conformance": model.conformance.report().as_dict(),
            "simulator": {
                "pod": model.profile.name, "firmware": model.firmware.name,
                "answered": s.answered, "anomalous": s.anomalous, "tolerated": s.tolerated,
                "frame_anomalies": s.frame_anomalies,
                "anomalies_by_field": dict(s.anomalies_by_field),
                "repeated": s.repeated, "other_versions": s.other_versions,
                "crc_errors": s.crc_errors, "malformed": s.malformed,
                "bytes_discarded": s.bytes_discarded,
                "executions": {opcode_name(k): v for k, v in sorted(model.executions.items())},
            },
        }  # fmt: skip

    def emit(self, *, at_exit: bool = False) -> None:
        """Print the text report to stderr (not at exit when :attr:`quiet`) and rewrite the
        files."""
        text = self.sim.model.conformance.report().text()
        if not (at_exit and self.quiet):
            print(text, file=sys.stderr, flush=True)
        try:
            if self.text_path is not None:
                write_report(self.text_path, text + "\n")
            if self.json_path is not None:
                write_report(self.json_path, json.dumps(self.document(), indent=2) + "\n")
        except OSError as exc:
            print(f"{PROG}: cannot write the report: {exc}", file=sys.stderr)


def _install_switches(
    loop: asyncio.AbstractEventLoop,
    sim: GcuSimulator,
    server: SimServer,
    silence: float,
    stall: float | None,
    reports: Reports | None = None,
) -> None:
    """SIGUSR1: kill the TCP connection now; SIGUSR2: silence the GCU for ``silence`` s;
    SIGHUP (only when ``stall`` is given): stall it for ``stall`` s; SIGQUIT: the report."""

    def kill() -> None:
        if isinstance(server, TcpServer):
            if not server.kill_connection():
                log.info("SIGUSR1: no TCP connection to kill")
        else:
            log.info("SIGUSR1: kill only applies to a tcp:// listen URL")

    def mute() -> None:
        log.info("SIGUSR2: silent for %g s", silence)
        sim.silence(silence)

    def freeze() -> None:
        log.info("SIGHUP: stalled for %g s", stall)
        sim.stall(stall or 0.0)

    switches = [("SIGUSR1", kill), ("SIGUSR2", mute)]
    if stall is not None:
        switches.append(("SIGHUP", freeze))
    if reports is not None:
        switches.append(("SIGQUIT", reports.emit))
    for name, action in switches:
        sig = getattr(signal, name, None)
        if sig is not None:
            with contextlib.suppress(NotImplementedError, RuntimeError, ValueError):
                loop.add_signal_handler(sig, action)


async def _serve(
    sim: GcuSimulator,
    spec: ListenSpec,
    silence: float,
    stall: float | None,
    reports: Reports | None = None,
) -> int:
    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError, RuntimeError, ValueError):
            loop.add_signal_handler(sig, stop.set)
    server = sim.serve(spec)
    try:
        await server.open()
    except OSError as exc:
        capture = sim.capture
        if capture is not None and exc.filename is not None and Path(exc.filename) == capture.path:
            print(f"{PROG}: cannot write the capture file: {exc}", file=sys.stderr)
        else:
            print(f"{PROG}: cannot listen on {args_url(spec)}: {exc}", file=sys.stderr)
        return EXIT_FAILED
    _install_switches(loop, sim, server, silence, stall, reports)
    try:
        where = server.url
        if isinstance(server, SerialServer) and spec.kind == "pty":
            where += f" (pty: open {server.device_path})"
        if spec.reply_to is not None:
            where += f" (replies to {format_hostport(*spec.reply_to)})"
        model = sim.model
        firmware = "" if model.firmware.name == DEFAULT_FIRMWARE else (
            f" (firmware {model.firmware.name})")  # fmt: skip
        print(f"{PROG}: {model.profile.name}{firmware} listening on {where}", flush=True)
        await stop.wait()
    finally:
        await server.close()
    s = sim.model.stats
    fields = ", ".join(f"{k} {v}" for k, v in s.anomalies_by_field.items())
    log.info("stopped: %d packets answered (%d with command anomalies, %d of them executed "
             "anyway; %d with frame-field anomalies%s; %d of other versions), %d repeated, "
             "%d CRC errors, %d malformed, %d bytes discarded", s.answered, s.anomalous,
             s.tolerated, s.frame_anomalies, f": {fields}" if fields else "", s.other_versions,
             s.repeated, s.crc_errors, s.malformed, s.bytes_discarded)  # fmt: skip
    if reports is not None:
        reports.emit(at_exit=True)
    return EXIT_INTERRUPTED  # only a signal ends it


def args_url(spec: ListenSpec) -> str:
    if spec.kind in ("udp", "tcp"):
        return f"{spec.kind}://{spec.host}:{spec.port}"
    return spec.kind if spec.kind == "pty" else f"serial://{spec.path}"


def run(args: argparse.Namespace) -> int:
    try:
        sim, spec = _build(args)
    except _UsageError as exc:
        print(f"{PROG}: {exc}", file=sys.stderr)
        return EXIT_USAGE
    if not args.quiet:
        logging.basicConfig(
            level=logging.INFO,
            stream=sys.stderr,
            format="%(asctime)s %(name)s %(levelname)s %(message)s",
        )
    try:
        reports = Reports(sim, args.report, args.report_json, quiet=args.quiet)
        return asyncio.run(_serve(sim, spec, args.silence, args.stall, reports))
    except KeyboardInterrupt:  # platforms without loop signal handlers
        return EXIT_INTERRUPTED
