"""Capacity benchmark: the most 50 Hz UDP sessions one process holds, next to plain asyncio.

Run from the repository root::

    .venv/bin/python benchmarks/bench_capacity.py            # default: 10-15 minutes
    .venv/bin/python benchmarks/bench_capacity.py --quick    # under a minute
    .venv/bin/python benchmarks/bench_capacity.py --profile client:gcu:100   # where time goes

Two parts (``--parts``), each a search for the most sessions one process holds, for the
library and for a bare asyncio loop doing the same exchange, their probes interleaved:

``client``
    One process (the *tested* side) runs N idle 50 Hz sessions: ``gcu_async.connect(
    "udp://…", local_port=0)`` clients, or ``BareLoop`` s of the client benchmark (the same
    heartbeat bytes on the same 20 ms deadline scheme, ``add_reader`` + ``recv_into`` of the
    replies). The GCU side is a *responder* process that answers every datagram with one
    canned, valid GCU reply (the simulator model's reply to the heartbeat) and counts each
    session's packets by source address.
``sim``
    One process runs N gimbals: one ``GcuSimulator`` with its own UDP endpoint per gimbal
    (what a user running a fleet in one process writes; one endpoint shared by N hosts would
    be one gimbal), or N bare asyncio endpoints (``add_reader`` + ``recvfrom_into``, the
    canned reply sent back). The hosts are a *load generator* process: one socket, every
    gimbal sent the heartbeat on its own 50 Hz schedule (phases spread evenly), replies
    counted per gimbal.

The counting processes (responder, load generator) are benchmarks/_counter.py. A session
holds when the counting process (never the tested one) saw at least ``MIN_RATE`` (48) of its
packets per second in a fixed window after a warm-up. The two sides are pinned to different
CPUs (``--no-pin`` to leave it to the OS); every probe starts both afresh. A probe whose
counting process dropped datagrams, neared a full core or fell behind its send schedule is
void and repeated (``--retries``). The search doubles from ``--start`` until a probe fails,
then bisects down to ``--resolution``; later runs start from the previous run's edge and
step by 25 %. Exit status 1 if the exchange was wrong (a packet other than the heartbeat, a
reply that is not a GCU packet, a child process that exited unasked) or a probe stayed void
after its retries; targets only print. docs/benchmarks.md, "Capacity", explains the method
and the figures.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import cProfile
import gc
import json
import math
import os
import pstats
import resource
import socket
import statistics
import sys
import tempfile
import time
from collections import deque
from collections.abc import Awaitable, Callable, Sequence
from dataclasses import asdict, dataclass, field
from typing import IO, Any

from _counter import LOOPBACK, emit, pin, run_delay
from _machine import load_average, machine_lines
from bench_client import PERIOD, BareLoop, ClientLoop, FloorLoop

from gcu_async.protocol import GCU_HEADER, HostPacket, NullCommand
from gcu_async.protocol.aircraft import AircraftState
from gcu_async.session import SessionConfig
from gcu_async.session.pacing import MARGIN, WINDOW
from gcu_async.sim import GcuSimulator, SimulatorModel
from gcu_async.transport._datagram import MAX_PER_EVENT
from gcu_async.transport.base import CLOCK_RESOLUTION

MIN_RATE = 48.0
"""Packets per second a session must reach at the counting process to hold."""
TARGET_RATIO = 0.9
"""gcu_async capacity / bare loop capacity, for the client and for the simulator."""
SCRIPT = os.path.abspath(__file__)
COUNTER = os.path.join(os.path.dirname(SCRIPT), "_counter.py")
WAIT = 5.0
"""Upper bound of a single wait for a child process (a line, a mark, an exit)."""
COUNTER_LIMIT = 0.9
"""CPU share of the counting process from which a probe is void (it may be the limit)."""
KINDS = {"client": ("gcu", "bare"), "sim": ("sim", "bare")}
"""The library's series and its bare-loop reference, per part (ratio = first / second)."""
ENDPOINT = "endpoint"
"""Optional series (``--endpoint``): the bare loop on asyncio's stock datagram transport."""
FLOORS = {"client": "session-stub", "sim": "model-stub"}
"""Optional series (``--floor``), diagnostics: the client with its session cut down to the
heartbeat schedule (the client benchmark's ``FloorLoop``: driver and UDP transport alone);
the simulator whose model answers with the canned reply (endpoint and exchange alone)."""
IDLE_BOUND = "idle-bound"
"""Diagnostic series (``--floor``, client part): the bare loop plus the least an idle session
must do (:class:`IdleBound`): an upper bound for an idle fast path."""
NAMES = {"gcu": "gcu_async client", IDLE_BOUND: "bare + an idle session's least work",
         "sim": "GcuSimulator", "bare": "bare asyncio loop",
         ENDPOINT: "bare, create_datagram_endpoint", "session-stub": "client, session stubbed",
         "model-stub": "GcuSimulator, model stubbed"}  # fmt: skip


def heartbeat() -> bytes:
    """The idle client's heartbeat: a null command with the default aircraft data."""
    return HostPacket(AircraftState().main_frame(), None, NullCommand()).encode()


def raise_fd_limit() -> tuple[int, int]:
    """Raise this process's open-file limit to its hard limit (one socket per session);
    returns (soft, hard) after."""
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if hard == resource.RLIM_INFINITY or soft < hard:
        target = hard if hard != resource.RLIM_INFINITY else max(soft, 1 << 16)
        with contextlib.suppress(ValueError, OSError):
            resource.setrlimit(resource.RLIMIT_NOFILE, (target, hard))
    return resource.getrlimit(resource.RLIMIT_NOFILE)


# --- the tested side: N sessions in one process -------------------------------------------
class BareGimbal:
    """A bare asyncio gimbal: its own UDP socket, ``add_reader`` + one ``recvfrom_into`` of a
    reused buffer per readiness event, the canned ``reply`` sent back to the sender; or
    (``reader="endpoint"``) asyncio's ``create_datagram_endpoint``."""

    def __init__(self, reply: bytes, reader: str) -> None:
        self.reply = reply
        self.reader = reader
        self.answered = 0
        self.port = 0
        self._sock: socket.socket | None = None
        self._transport: asyncio.DatagramTransport | None = None
        self._buffer = bytearray(2048)

    async def open(self) -> None:
        loop = asyncio.get_running_loop()
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
        sock.bind((LOOPBACK, 0))
        sock.setblocking(False)
        self.port = sock.getsockname()[1]
        reply = self.reply
        if self.reader == ENDPOINT:
            owner = self

            class Answer(asyncio.DatagramProtocol):
                def datagram_received(self, data: bytes, addr: Any) -> None:
                    assert owner._transport is not None
                    owner._transport.sendto(reply, addr)
                    owner.answered += 1

            self._transport, _ = await loop.create_datagram_endpoint(Answer, sock=sock)
        else:
            self._sock = sock
            loop.add_reader(sock.fileno(), self._read)

    def _read(self) -> None:
        assert self._sock is not None
        try:
            _, addr = self._sock.recvfrom_into(self._buffer)
            self._sock.sendto(self.reply, addr)
        except (BlockingIOError, InterruptedError):
            return
        self.answered += 1

    async def close(self) -> None:
        if self._transport is not None:
            self._transport.close()
        if self._sock is not None:
            asyncio.get_running_loop().remove_reader(self._sock.fileno())
            self._sock.close()
        await asyncio.sleep(0)


class SimGimbal:
    """One ``GcuSimulator`` with its own UDP endpoint; with ``canned``, its model answers
    every packet with those bytes (a diagnostic: the endpoint and exchange alone)."""

    def __init__(self, canned: bytes | None = None) -> None:
        self.sim = GcuSimulator()
        if canned is not None:  # an instance attribute shadows the method the exchange calls
            self.sim.model.handle_bytes = lambda packet: canned  # type: ignore[method-assign]
        self.server = self.sim.serve_udp(LOOPBACK, 0)
        self.port = 0

    async def open(self) -> None:
        await self.server.open()
        self.port = self.server.address[1]

    @property
    def answered(self) -> int:
        return self.sim.stats.replies_sent

    async def close(self) -> None:
        await self.server.close()


@dataclass
class Fleet:
    """N sessions of one kind open in this process."""

    sessions: list[Any]
    counts: Callable[[], list[Any]]
    """Each session's own count: (sent, replies) of a client, replies sent by a gimbal."""
    failed: int = 0
    error: str | None = None
    ports: list[int] = field(default_factory=list)
    """Gimbals: where each listens."""

    async def close(self) -> None:
        with contextlib.suppress(asyncio.TimeoutError):
            await asyncio.wait_for(asyncio.gather(*(s.close() for s in self.sessions),
                                                  return_exceptions=True), 3 * WAIT)  # fmt: skip


class IdleBound(BareLoop):
    """Diagnostic, not a client: the bare loop plus the least an idle gcu_async session must
    do per heartbeat and reply to keep every observable the same (an upper bound for an idle
    fast path that bypasses the driver, the transport and the session). Per heartbeat: the
    reply-arrival bound of the session contract's A4 (the socket read first when the reader
    may have left datagrams), the clock, the silence check, the rate window, the slot, the
    run and the counters. Per reply: ``recvfrom_into`` (the source is checked), the reader's
    stamp, the compare with the last reply, the link-health stamps and the run's
    identification; a socket read until empty unless a timer found it empty. Inlined, in
    one class: no layers."""

    def __init__(self, url: str, packet: bytes, reply: bytes) -> None:
        super().__init__(url, packet, "recv_into")
        self.reply = reply
        self.view = memoryview(self._buffer)
        self.unread_since: float | None = None
        self.quiet = False
        self.arrived_after = -math.inf
        self.silent_at = math.inf
        config = SessionConfig()
        self.silence, self.reply_window = config.silence_timeout, config.reply_window
        self.limit = math.floor(config.rate_hz) + 1
        self.window: deque[float] = deque(maxlen=self.limit)
        self.run_last_sent, self.run_stale_after = -math.inf, math.inf
        self.run_packets = self.identified = self.unmatched = self.other = 0
        self.last_reply = -math.inf
        self.recent: deque[float] = deque(maxlen=1024)
        self.remote = (self.dest[0], self.dest[1])

    def _tick(self) -> None:
        due = self._deadline
        since = self.unread_since
        if since is None or since <= due - CLOCK_RESOLUTION:
            self.unread_since, self.quiet = None, True
            self.arrived_after = due - CLOCK_RESOLUTION
        elif self._drain(time.monotonic(), MAX_PER_EVENT):
            self.arrived_after = time.monotonic()
        now = time.monotonic()
        if now >= self.silent_at:
            self.other += 1
        window = self.window
        if len(window) == self.limit and window[0] + (WINDOW + MARGIN) > now:
            self.other += 1
        window.append(now)
        self.run_last_sent = now
        self.run_packets += 1
        super()._tick()

    def _read(self) -> None:
        limit = 1 if self.quiet else MAX_PER_EVENT
        self.quiet = False
        self._drain(time.monotonic(), limit)

    def _drain(self, start: float, limit: int) -> bool:
        self.unread_since = start
        sock = self._sock
        assert sock is not None
        recv, view, reply = sock.recvfrom_into, self.view, self.reply
        for _ in range(limit):
            try:
                n, addr = recv(view)
            except (BlockingIOError, InterruptedError):
                self.unread_since = None
                return True
            if addr != self.remote or view[:n] != reply:
                self.other += 1
                continue
            now = time.monotonic()
            self.received += 1
            self.last_reply = now
            self.recent.append(now)
            self.silent_at = math.nextafter(now + self.silence, math.inf)
            earliest = self.arrived_after
            if earliest > now:
                earliest = now
            if (earliest >= self.run_stale_after
                    or self.run_last_sent <= earliest - self.reply_window):  # fmt: skip
                self.unmatched += 1
            else:
                self.identified += 1
        return False

    def counts(self) -> tuple[int, int]:
        """Packets sent and replies identified (a reply that was not is not counted)."""
        return self.sent, self.identified


async def open_clients(kind: str, n: int, url: str, ramp: float) -> Fleet:
    """Open ``n`` client sessions against ``url``, session i at ``i * ramp / n`` s (their 50 Hz
    phases spread over the period)."""
    packet = heartbeat()
    reply = SimulatorModel().handle_bytes(packet) or b""
    loop = asyncio.get_running_loop()
    start = loop.time()

    def make() -> ClientLoop | BareLoop:
        if kind == "gcu":
            return ClientLoop(url)
        if kind == FLOORS["client"]:
            return FloorLoop(url, packet)
        if kind == IDLE_BOUND:
            return IdleBound(url, packet, reply)
        return BareLoop(url, packet, "recv_into" if kind == "bare" else ENDPOINT)

    async def open_one(i: int) -> ClientLoop | BareLoop:
        await asyncio.sleep(max(0.0, start + i * ramp / n - loop.time()))
        session = make()
        await session.open()
        return session

    results = await asyncio.gather(*(open_one(i) for i in range(n)), return_exceptions=True)
    sessions = [r for r in results if not isinstance(r, BaseException)]
    errors = [r for r in results if isinstance(r, BaseException)]
    return Fleet(sessions, lambda: [s.counts() for s in sessions], len(errors),
                 repr(errors[0]) if errors else None)  # fmt: skip


async def open_gimbals(kind: str, n: int) -> Fleet:
    """Open ``n`` gimbals of ``kind``, one after the other."""
    reply = SimulatorModel().handle_bytes(heartbeat())
    assert reply is not None
    opened: list[SimGimbal | BareGimbal] = []
    error = None
    for _ in range(n):
        end: SimGimbal | BareGimbal
        if kind in ("sim", FLOORS["sim"]):
            end = SimGimbal(reply if kind == FLOORS["sim"] else None)
        else:
            end = BareGimbal(reply, kind)
        try:
            await end.open()
        except OSError as exc:
            error = repr(exc)
            break
        opened.append(end)
    return Fleet(opened, lambda: [e.answered for e in opened], n - len(opened), error,
                 [e.port for e in opened])  # fmt: skip


async def hold(fleet: Fleet) -> int:
    """Answer ``mark`` lines with this process's clock, CPU time and the sessions' own
    counts until stdin closes (the controller's end, or its death), then close them."""
    gc.collect()
    loop = asyncio.get_running_loop()
    reader = asyncio.StreamReader()
    await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(reader), sys.stdin)
    while line := await reader.readline():
        if line.strip() == b"mark":
            emit({"t": time.monotonic(), "cpu": time.process_time(), "waited": run_delay(),
                  "counts": fleet.counts()})  # fmt: skip
    await fleet.close()
    return 0


async def clients(kind: str, n: int, url: str, ramp: float) -> int:
    """``--role clients``: :func:`open_clients`, say how many opened, :func:`hold`."""
    raise_fd_limit()
    fleet = await open_clients(kind, n, url, ramp)
    emit({"ready": len(fleet.sessions), "failed": fleet.failed, "error": fleet.error})
    return await hold(fleet)


async def gimbals(kind: str, n: int) -> int:
    """``--role gimbals``: :func:`open_gimbals`, print their ports, :func:`hold`."""
    raise_fd_limit()
    fleet = await open_gimbals(kind, n)
    emit({"ports": fleet.ports, "failed": fleet.failed, "error": fleet.error})
    return await hold(fleet)


# --- the controller -----------------------------------------------------------------------
class ProbeError(Exception):
    """A child process did not answer in time (``broken`` False: the probe fails, as an
    overloaded process may) or exited (``broken`` True: the benchmark is wrong)."""

    def __init__(self, message: str, *, broken: bool = False) -> None:
        super().__init__(message)
        self.broken = broken


class Child:
    """A child process of this script in one role, spoken to in JSON lines."""

    def __init__(self, proc: asyncio.subprocess.Process, role: str, stderr: IO[bytes]) -> None:
        self.proc = proc
        self.role = role
        self.stderr = stderr
        """Where its stderr goes (shown when it exits unasked)."""

    @classmethod
    async def start(cls, role: str, script: str, *options: object, cpu: int | None) -> Child:
        argv = [sys.executable, script, *map(str, options)]
        if cpu is not None:
            argv += ["--cpu", str(cpu)]
        stderr = tempfile.TemporaryFile()  # noqa: SIM115 (it lives as long as the child)
        proc = await asyncio.create_subprocess_exec(
            *argv, stdin=asyncio.subprocess.PIPE, stdout=asyncio.subprocess.PIPE,
            stderr=stderr, limit=1 << 24)  # fmt: skip
        return cls(proc, role, stderr)

    async def line(self, timeout: float) -> dict[str, Any]:
        assert self.proc.stdout is not None
        try:
            raw = await asyncio.wait_for(self.proc.stdout.readline(), timeout)
        except asyncio.TimeoutError:
            raise ProbeError(f"{self.role}: no answer within {timeout:g} s") from None
        if not raw:
            with contextlib.suppress(asyncio.TimeoutError):
                await asyncio.wait_for(self.proc.wait(), WAIT)
            self.stderr.seek(0)
            tail = self.stderr.read().decode(errors="replace").strip().splitlines()[-5:]
            raise ProbeError(
                f"{self.role}: exited (status {self.proc.returncode})"
                + "".join(f"\n    {line}" for line in tail),
                broken=True,
            )
        result: dict[str, Any] = json.loads(raw)
        return result

    async def send(self, text: str) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(text.encode() + b"\n")
        try:
            await asyncio.wait_for(self.proc.stdin.drain(), WAIT)
        except (asyncio.TimeoutError, ConnectionError) as exc:
            raise ProbeError(f"{self.role}: cannot write to it ({exc!r})") from None

    async def mark(self) -> dict[str, Any]:
        await self.send("mark")
        return await self.line(WAIT)

    async def stop(self) -> None:
        """Close its stdin (it closes its sessions and exits); kill it if it has not
        exited within ``4 * WAIT``."""
        proc = self.proc
        if proc.stdin is not None:
            proc.stdin.close()
        try:
            await asyncio.wait_for(proc.wait(), 4 * WAIT)
        except asyncio.TimeoutError:
            proc.kill()
            await asyncio.wait_for(proc.wait(), WAIT)
        finally:
            self.stderr.close()


@dataclass
class Probe:
    """One trial: ``sessions`` sessions of one kind, judged over one window."""

    part: str
    kind: str
    sessions: int
    run: int
    held: bool = False
    reason: str = ""
    min_rate: float = math.nan
    """Lowest per-session packet rate at the counting process, packets/s."""
    median_rate: float = math.nan
    below: int = 0
    """Sessions under MIN_RATE."""
    own_min_rate: float = math.nan
    """Lowest per-session rate by the tested process's own count (replies received by a
    client; replies sent by a gimbal), a diagnostic."""
    sent_min_rate: float = math.nan
    """Load generator only: lowest per-gimbal send rate."""
    tested_cpu: float = math.nan
    """CPU share of the tested process over the window (1.0 = one core)."""
    tested_waited: float = math.nan
    """Share of the window the tested process was runnable but waited for a CPU (other
    processes had it): near 0 on a quiet machine."""
    counter_cpu: float = math.nan
    counter_waited: float = math.nan
    counter_late: float = 0.0
    """Load generator only: its latest send behind schedule in the window, seconds."""
    counter_drops: int | None = None
    """Datagrams the kernel dropped at the counting process's socket in the window."""
    other: int = 0
    window: float = 0.0
    load: str = ""

    @property
    def counter_limited(self) -> bool:
        """The counting process dropped datagrams, was near a full core or (load generator)
        did not send every gimbal MIN_RATE packets/s: the window says nothing about the
        tested side."""
        return (bool(self.counter_drops) or self.counter_cpu >= COUNTER_LIMIT
                or self.sent_min_rate < MIN_RATE)  # fmt: skip

    def line(self) -> str:
        head = f"  run {self.run} {self.part:<6} {NAMES[self.kind]:<31} {self.sessions:5d}"
        if self.reason and math.isnan(self.min_rate):
            return f"{head} FAILS not judged: {self.reason} [load {self.load}]"
        verdict = "void " if self.counter_limited else "holds" if self.held else "FAILS"
        what = (f"min {self.min_rate:5.1f}/s median {self.median_rate:5.1f}/s ({self.below}"
                f" below); own count min {self.own_min_rate:5.1f}/s; CPU (waited) tested"
                f" {pct(self.tested_cpu)} ({pct(self.tested_waited)}), counter"
                f" {pct(self.counter_cpu)} ({pct(self.counter_waited)})")  # fmt: skip
        if self.part == "sim":
            what += (f"; hosts sent min {self.sent_min_rate:4.1f}/s, late up to"
                     f" {self.counter_late * 1e3:.0f} ms")  # fmt: skip
        if self.counter_drops:
            what += f"; {self.counter_drops} dropped at the counter"
        return f"{head} {verdict} {what} [load {self.load}]"


def pct(share: float) -> str:
    return "  ? %" if math.isnan(share) else f"{share * 100:3.0f} %"


def judge(probe: Probe, counted: Sequence[int], dt: float) -> None:
    """Rates of every session from the counting process's counts over ``dt`` seconds
    (sessions it never heard from count as 0)."""
    rates = sorted(c / dt for c in counted)
    rates = [0.0] * max(0, probe.sessions - len(rates)) + rates
    probe.min_rate = rates[0] if rates else math.nan
    probe.median_rate = statistics.median(rates) if rates else math.nan
    probe.below = sum(1 for r in rates if r < MIN_RATE)
    probe.held = bool(rates) and probe.below == 0 and not probe.reason


@dataclass
class Setup:
    args: argparse.Namespace
    tested_cpu: int | None
    counter_cpu: int | None
    packet: bytes
    reply: bytes
    failures: list[str] = field(default_factory=list)
    probes: list[Probe] = field(default_factory=list)
    void: list[Probe] = field(default_factory=list)
    """Probes whose counting process was the limit (retried)."""
    report: dict[str, Any] = field(default_factory=dict)
    """Everything measured, for ``--json``."""

    async def responder(self) -> Child:
        """The client part's GCU side (benchmarks/_counter.py)."""
        return await Child.start("responder", COUNTER, "--reply", self.reply.hex(), "--packet",
                                 self.packet.hex(), "--period", PERIOD,
                                 cpu=self.counter_cpu)  # fmt: skip

    async def hosts(self) -> Child:
        """The simulator part's load generator (benchmarks/_counter.py)."""
        return await Child.start("hosts", COUNTER, "--packet", self.packet.hex(), "--expect",
                                 GCU_HEADER.hex(), "--period", PERIOD,
                                 cpu=self.counter_cpu)  # fmt: skip


async def window(setup: Setup, counter_side: Child, tested: Child,
                 probe: Probe) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any],
                                        dict[str, Any]]:  # fmt: skip
    """Warm-up, then marks at both ends of the window: (counter 0, counter 1, tested 0,
    tested 1)."""
    args = setup.args
    await asyncio.sleep(args.warmup)
    c0, t0 = await asyncio.gather(counter_side.mark(), tested.mark())
    await asyncio.sleep(args.window)
    c1, t1 = await asyncio.gather(counter_side.mark(), tested.mark())
    probe.window = c1["t"] - c0["t"]
    probe.tested_cpu = (t1["cpu"] - t0["cpu"]) / (t1["t"] - t0["t"])
    probe.counter_cpu = (c1["cpu"] - c0["cpu"]) / probe.window
    if t0["waited"] is not None and t1["waited"] is not None:
        probe.tested_waited = (t1["waited"] - t0["waited"]) / (t1["t"] - t0["t"])
    if c0["waited"] is not None and c1["waited"] is not None:
        probe.counter_waited = (c1["waited"] - c0["waited"]) / probe.window
    if c0["drops"] is not None and c1["drops"] is not None:
        probe.counter_drops = c1["drops"] - c0["drops"]
    probe.other = c1["other"]
    probe.counter_late = c1["late"]
    return c0, c1, t0, t1


async def probe_client(setup: Setup, kind: str, n: int, run: int) -> Probe:
    args = setup.args
    probe = Probe("client", kind, n, run, load=load_average())
    responder = await setup.responder()
    try:
        port = (await responder.line(3 * WAIT))["port"]
        ramp = max(args.min_ramp, n * args.ramp_per_session)
        tested = await Child.start("clients", SCRIPT, "--role", "clients", "--kind", kind,
                                   "--sessions", n, "--url", f"udp://{LOOPBACK}:{port}",
                                   "--ramp", ramp, cpu=setup.tested_cpu)  # fmt: skip
        try:
            ready = await tested.line(3 * WAIT + ramp + n * 0.01)
            if ready["failed"]:
                probe.reason = f"{ready['failed']} of {n} did not open ({ready['error']})"
                return probe
            c0, c1, t0, t1 = await window(setup, responder, tested, probe)
        finally:
            await tested.stop()
    finally:
        await responder.stop()
    before = c0["received"]
    counted = [v - before.get(k, 0) for k, v in c1["received"].items()]
    counted = [c for c in counted if c > 0]
    if len(counted) > n:
        probe.reason = f"the responder heard {len(counted)} sources for {n} sessions"
    judge(probe, counted, probe.window)
    dt = t1["t"] - t0["t"]
    own = [(b[1] - a[1]) / dt for a, b in zip(t0["counts"], t1["counts"], strict=True)]
    probe.own_min_rate = min(own, default=math.nan)
    if probe.other:
        setup.failures.append(f"client {kind} x{n}: {probe.other} packets other than the"
                              " heartbeat reached the responder")  # fmt: skip
    return probe


async def probe_sim(setup: Setup, kind: str, n: int, run: int) -> Probe:
    probe = Probe("sim", kind, n, run, load=load_average())
    tested = await Child.start("gimbals", SCRIPT, "--role", "gimbals", "--kind", kind,
                               "--sessions", n, cpu=setup.tested_cpu)  # fmt: skip
    try:
        ready = await tested.line(3 * WAIT + n * 0.02)
        if ready["failed"]:
            probe.reason = f"{ready['failed']} of {n} did not open ({ready['error']})"
            return probe
        ports: list[int] = ready["ports"]
        hosts = await setup.hosts()
        try:
            await hosts.line(3 * WAIT)
            await hosts.send(json.dumps({"ports": ports}))
            c0, c1, t0, t1 = await window(setup, hosts, tested, probe)
        finally:
            await hosts.stop()
    finally:
        await tested.stop()
    r0, r1 = c0["received"], c1["received"]
    counted = [r1.get(str(p), 0) - r0.get(str(p), 0) for p in ports]
    judge(probe, [c for c in counted if c > 0], probe.window)
    probe.sent_min_rate = min(
        ((b - a) / probe.window for a, b in zip(c0["sent"], c1["sent"], strict=True)),
        default=math.nan,
    )
    dt = t1["t"] - t0["t"]
    own = [(b - a) / dt for a, b in zip(t0["counts"], t1["counts"], strict=True)]
    probe.own_min_rate = min(own, default=math.nan)
    if probe.other:
        setup.failures.append(f"sim {kind} x{n}: {probe.other} replies that are not GCU"
                              " packets")  # fmt: skip
    return probe


class Bracket:
    """The search for one series' edge: ``lo`` the most sessions seen to hold, ``hi`` the
    fewest seen to fail. Grows by ``factor`` from ``start`` until a probe fails (or ``most``
    holds), then bisects until ``hi - lo <= resolution * lo`` (or 1)."""

    def __init__(self, start: int, most: int, factor: float, resolution: float) -> None:
        self.start = max(1, min(start, most))
        self.most = most
        self.factor = factor
        self.resolution = resolution
        self.lo = 0
        self.hi: int | None = None
        self.bounded = False
        """``hi`` is where the counting process, not the tested side, was the limit: ``lo``
        is then a lower bound of the edge."""
        self.probes: list[Probe] = []

    def next(self) -> int | None:
        lo, hi = self.lo, self.hi
        if hi is None:
            if lo >= self.most:
                return None
            return self.start if not lo else min(self.most, max(lo + 1, round(lo * self.factor)))
        if hi - lo <= max(1.0, self.resolution * lo):
            return None
        if not lo:  # nothing held yet: step down
            return max(1, math.floor(hi / self.factor))
        return (lo + hi) // 2

    def record(self, probe: Probe) -> None:
        self.probes.append(probe)
        if probe.held and not probe.counter_limited:
            self.lo = max(self.lo, probe.sessions)
        elif self.hi is None or probe.sessions <= self.hi:
            self.bounded = probe.counter_limited
            self.hi = probe.sessions


PROBES: dict[str, Callable[[Setup, str, int, int], Awaitable[Probe]]] = {
    "client": probe_client, "sim": probe_sim}  # fmt: skip


@dataclass
class Edge:
    part: str
    kind: str
    run: int
    held: int
    failed: int | None
    bounded: bool
    """The search ended at the counting process's limit: ``held`` is a lower bound."""
    probes: int
    load: str

    def text(self) -> str:
        return f"{'>=' if self.bounded else ''}{self.held} ({self.failed or '-'})"


async def search(setup: Setup, part: str, kinds: Sequence[str], run: int,
                 previous: dict[str, int]) -> list[Edge]:  # fmt: skip
    """One run of ``part``: every series' edge, their probes interleaved (one probe of each
    series in turn), so that what else the machine does falls on all of them alike."""
    args = setup.args
    brackets = {}
    for kind in kinds:
        if kind in previous and previous[kind] > 0:
            brackets[kind] = Bracket(previous[kind], args.max, 1.25, args.resolution)
        else:
            brackets[kind] = Bracket(args.start, args.max, 2.0, args.resolution)
    pending = list(kinds)
    while pending:
        for kind in list(pending):
            bracket = brackets[kind]
            n = bracket.next()
            if n is None:
                pending.remove(kind)
                continue
            for attempt in range(1 + args.retries):
                try:
                    probe = await PROBES[part](setup, kind, n, run)
                except ProbeError as exc:
                    probe = Probe(part, kind, n, run, reason=str(exc), load=load_average())
                    if exc.broken:
                        setup.failures.append(f"{part} {kind} x{n}: {exc}")
                print(probe.line(), flush=True)
                if not probe.counter_limited:
                    break
                if attempt < args.retries:
                    setup.void.append(probe)
            bracket.record(probe)  # void after its retries: the counting side's limit
    setup.probes += [p for b in brackets.values() for p in b.probes]
    return [Edge(part, kind, run, b.lo, b.hi, b.bounded, len(b.probes), load_average())
            for kind, b in brackets.items()]  # fmt: skip


def spread(values: Sequence[float]) -> str:
    if not values:
        return "n/a"
    return (f"median {statistics.median(values):g}, {min(values):g}-{max(values):g}"
            f" ({len(values)} runs)")  # fmt: skip


def series(part: str, args: argparse.Namespace) -> tuple[str, ...]:
    """The series of ``part``: the library's, the bare loop, the optional ones asked for."""
    floors = (FLOORS[part], IDLE_BOUND) if part == "client" else (FLOORS[part],)
    extra = ((ENDPOINT,) if args.endpoint else ()) + (floors if args.floor else ())
    return (*KINDS[part], *extra)


def bound_ratio(num: Edge, den: Edge) -> tuple[float, str]:
    """``num.held / den.held`` and how far it is known: "" exact, "<=" (the reference is a
    lower bound), ">=" (the numerator is), "~" (both)."""
    if not den.held:
        return math.nan, ""
    sign = {(False, False): "", (False, True): "<=", (True, False): ">=", (True, True): "~"}
    return num.held / den.held, sign[num.bounded, den.bounded]


def summary(part: str, kinds: Sequence[str], edges: list[Edge]) -> tuple[bool, str]:
    """Print each run's edges and ratios, and the spread over the runs; returns whether the
    library's median ratio meets the target, and its line."""
    print(f"\n{part}: the most sessions holding >= {MIN_RATE:g} packets/s each (fails at;"
          " >=: the counting process's limit ended the search)")  # fmt: skip
    library, bare = kinds[0], kinds[1]
    ratios: dict[str, list[float]] = {k: [] for k in kinds if k != bare}
    signs: dict[str, set[str]] = {k: set() for k in kinds if k != bare}
    for run in sorted({e.run for e in edges}):
        by = {e.kind: e for e in edges if e.run == run}
        cells = [f"{NAMES[k]} {by[k].text()}" for k in kinds]
        shown = []
        for kind in ratios:
            ratio, sign = bound_ratio(by[kind], by[bare])
            if not math.isnan(ratio):
                ratios[kind].append(ratio)
                signs[kind].add(sign)
            shown.append(f"{sign}{ratio:.3f}x")
        print(f"  run {run}: {'; '.join(cells)}; ratio {', '.join(shown)}"
              f"  [load at the end {by[library].load}]")  # fmt: skip
    for kind in kinds:
        print(f"  {NAMES[kind]:<31} {spread([e.held for e in edges if e.kind == kind])}")
    text = ""
    for kind, values in ratios.items():
        sign = "".join(sorted(signs[kind]))
        line = (
            f"{NAMES[kind]} / {NAMES[bare]} capacity: "
            + (
                f"median {statistics.median(values):.3f}x, {min(values):.3f}-{max(values):.3f}x"
                if values
                else "n/a"
            )
            + (f" ({sign} in some runs: a counting process's limit)" if sign else "")
        )
        print(f"  {line}")
        if kind == library:
            text = line
    values = ratios[library]
    return bool(values) and statistics.median(values) >= TARGET_RATIO, text


async def controller(args: argparse.Namespace, setup: Setup) -> int:
    tested_cpu, counter_cpu = setup.tested_cpu, setup.counter_cpu
    pin(counter_cpu)  # the controller mostly sleeps; it stays off the tested CPU
    packet, reply = setup.packet, setup.reply
    soft, hard = raise_fd_limit()
    print(f"  files  : open-file limit raised to {soft} (hard {hard}) in every process")
    print("  pinned : " + (f"tested side on CPU {tested_cpu}, counting side and controller"
                           f" on CPU {counter_cpu}" if tested_cpu is not None
                           else "no (the OS schedules)"))  # fmt: skip
    print(
        f"  probes : warm-up {args.warmup:g} s, window {args.window:g} s; a session holds"
        f" at >= {MIN_RATE:g} packets/s; {args.runs} run(s); search from {args.start}"
        f" (x2, later runs from the previous edge x1.25) up to {args.max}, to"
        f" {args.resolution:.0%}; heartbeat {len(packet)} B, reply {len(reply)} B"
    )
    edges: list[Edge] = []
    previous: dict[str, dict[str, int]] = {part: {} for part in args.parts}
    for run in range(1, args.runs + 1):
        for part in args.parts:
            kinds = series(part, args)
            found = await search(setup, part, kinds, run, previous[part])
            edges += found
            previous[part] = {e.kind: e.held for e in found}
    print(f"\nCapacity (load average at the end: {load_average()})")
    targets = []
    for part in args.parts:
        kinds = series(part, args)
        met, text = summary(part, kinds, [e for e in edges if e.part == part])
        targets.append((part, met, text))
    print(f"\nTargets (capacity ratio >= {TARGET_RATIO:g}x the bare loop, median of the runs):")
    for part, met, text in targets:
        print(f"  {'met   ' if met else 'MISSED'} {part:<6} {text}")
    for failure in setup.failures:
        print(f"  FAILED {failure}")
    setup.report = {"edges": [asdict(e) for e in edges],
                    "probes": [asdict(p) for p in setup.probes],
                    "void": [asdict(p) for p in setup.void], "failures": setup.failures,
                    "machine": machine_lines()}  # fmt: skip
    return 1 if setup.failures else 0


# --- profile: where the tested side's time goes -----------------------------------------
def where(key: tuple[str, int, str]) -> str:
    """``file:line(function)`` of a pstats key, the file relative to the package or stdlib."""
    file, line, name = key
    if file == "~":
        return name
    for anchor in ("/site-packages/", "/src/", "/lib/python"):
        if anchor in file:
            file = file.split(anchor, 1)[1]
            break
    return f"{file}:{line}({name})"


async def measured(counter_side: Child, seconds: float,
                   profiler: cProfile.Profile | None) -> tuple[float, int]:  # fmt: skip
    """(CPU seconds of this process, packets the counting process counted) over ``seconds``,
    with ``profiler`` on if given."""
    c0 = await counter_side.mark()
    cpu0 = time.process_time()
    if profiler is not None:
        profiler.enable()
    await asyncio.sleep(seconds)
    if profiler is not None:
        profiler.disable()
    cpu = time.process_time() - cpu0
    c1 = await counter_side.mark()
    return cpu, sum(c1["received"].values()) - sum(c0["received"].values())


async def profile(setup: Setup, part: str, kind: str, n: int) -> int:
    """``--profile PART:KIND:N``: the tested side in this process (on the tested CPU), the
    counting side a child as in a probe; a window without and one with ``cProfile``; prints
    CPU per packet and the functions with the most own time, per packet."""
    args = setup.args
    pin(setup.tested_cpu)
    counter_side: Child | None = None
    fleet: Fleet | None = None
    try:
        if part == "client":
            counter_side = await setup.responder()
            port = (await counter_side.line(3 * WAIT))["port"]
            ramp = max(args.min_ramp, n * args.ramp_per_session)
            fleet = await open_clients(kind, n, f"udp://{LOOPBACK}:{port}", ramp)
        else:
            fleet = await open_gimbals(kind, n)
            counter_side = await setup.hosts()
            await counter_side.line(3 * WAIT)
            await counter_side.send(json.dumps({"ports": fleet.ports}))
        if fleet.failed:
            raise SystemExit(f"{fleet.failed} of {n} did not open: {fleet.error}")
        await asyncio.sleep(args.warmup)
        gc.collect()
        cpu, packets = await measured(counter_side, args.window, None)
        profiler = cProfile.Profile()
        cpu_p, packets_p = await measured(counter_side, args.window, profiler)
    finally:
        if fleet is not None:
            await fleet.close()
        if counter_side is not None:
            await counter_side.stop()
    what = "packet + reply" if part == "client" else "host packet answered"
    print(f"\nprofile: {part}, {NAMES[kind]} x{n}, windows of {args.window:g} s"
          f" [load {load_average()}]")  # fmt: skip
    print(f"  without the profiler: {cpu / max(1, packets) * 1e6:.1f} us of CPU per {what}"
          f" ({packets / args.window / n:.1f} per session per second, CPU"
          f" {cpu / args.window * 100:.0f} %)")  # fmt: skip
    stats = pstats.Stats(profiler).stats  # type: ignore[attr-defined]
    # cProfile times on the wall clock: the loop's wait in epoll is not work
    waits = [k for k in stats if k[0] == "~" and k[2].startswith("<method 'poll' of")]
    for key in waits:
        del stats[key]
    per = 1e6 / max(1, packets_p)
    calls = sum(nc for _, nc, _, _, _ in stats.values())
    print(f"  with cProfile: {cpu_p * per:.1f} us of CPU per {what};"
          f" {calls / max(1, packets_p):.1f}"
          f" function calls per {what} ({packets_p / args.window / n:.1f} per session per"
          f" second)")  # fmt: skip
    print(f"  {'own us':>8} {'calls':>7} {'incl us':>8}  function (per {what}; top"
          f" {args.top} by own time)")  # fmt: skip
    ranked = sorted(stats.items(), key=lambda item: item[1][2], reverse=True)
    for key, (_, nc, tt, ct, _) in ranked[: args.top]:
        print(f"  {tt * per:8.2f} {nc / max(1, packets_p):7.2f} {ct * per:8.2f}  {where(key)}")
    files: dict[str, float] = {}
    for key, (_, _, tt, _, _) in stats.items():
        file = where(key).split(":", 1)[0] if key[0] != "~" else "(built-in)"
        files[file] = files.get(file, 0.0) + tt
    print(f"  own time by file (us per {what}):")
    for file, tt in sorted(files.items(), key=lambda item: item[1], reverse=True)[: args.top]:
        print(f"  {tt * per:8.2f}  {file}")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smoke run (under a minute)")
    ap.add_argument("--parts", default="client,sim", help="comma-separated: client, sim [both]")
    ap.add_argument("--runs", type=int, help="searches per series [3; quick 1]")
    ap.add_argument("--warmup", type=float, help="seconds before the window [2; quick 0.5]")
    ap.add_argument("--window", type=float, help="seconds judged [5; quick 1]")
    ap.add_argument("--start", type=int, help="first probe's sessions [200; quick 25]")
    ap.add_argument("--max", type=int, help="most sessions probed [6400; quick 100]")
    ap.add_argument(
        "--resolution",
        type=float,
        help="stop when the edge is known to this fraction [0.1; quick 1]",
    )
    ap.add_argument(
        "--min-ramp",
        type=float,
        default=0.5,
        help="clients: least seconds over which they open [0.5]",
    )
    ap.add_argument(
        "--ramp-per-session",
        type=float,
        default=0.001,
        help="clients: seconds of opening per session [0.001]",
    )
    ap.add_argument(
        "--endpoint",
        action="store_true",
        help="also asyncio's stock datagram transport (create_datagram_endpoint)",
    )
    ap.add_argument("--floor", action="store_true",
                    help="also the client with its session stubbed, the bare loop plus an idle"
                         " session's least work, and the simulator with its model stubbed"
                         " (diagnostics: the layers below; the best an idle fast path can"
                         " do)")  # fmt: skip
    ap.add_argument(
        "--no-pin",
        dest="pin",
        action="store_false",
        help="do not pin the two sides to different CPUs",
    )
    ap.add_argument(
        "--retries",
        type=int,
        default=2,
        help="probes repeated when the counting process was the limit [2]",
    )
    ap.add_argument("--profile", metavar="PART:KIND:N",
                    help="instead of the search: profile N sessions of one series in this"
                         " process, e.g. client:gcu:100 or sim:sim:50")  # fmt: skip
    ap.add_argument("--top", type=int, default=30, help="with --profile: lines shown [30]")
    ap.add_argument("--json", help="also write every probe and edge to this file")
    # the child processes' roles
    ap.add_argument("--role", choices=["clients", "gimbals"], help=argparse.SUPPRESS)
    ap.add_argument("--kind", help=argparse.SUPPRESS)
    ap.add_argument("--sessions", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--url", help=argparse.SUPPRESS)
    ap.add_argument("--ramp", type=float, help=argparse.SUPPRESS)
    ap.add_argument("--cpu", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.role:
        pin(args.cpu)
        if args.role == "clients":
            return asyncio.run(clients(args.kind, args.sessions, args.url, args.ramp))
        return asyncio.run(gimbals(args.kind, args.sessions))
    quick = args.quick
    defaults = {"runs": (3, 1), "warmup": (2.0, 0.5), "window": (5.0, 1.0), "start": (200, 25),
                "max": (6400, 100), "resolution": (0.1, 1.0)}  # fmt: skip
    for key, (full, short) in defaults.items():
        if getattr(args, key) is None:
            setattr(args, key, short if quick else full)
    args.parts = [p.strip() for p in args.parts.split(",") if p.strip()]
    if (set(args.parts) - set(KINDS) or not args.parts or args.runs < 1 or args.warmup < 0
            or args.window <= 0 or args.start < 1 or args.max < args.start
            or args.resolution <= 0):  # fmt: skip
        ap.error("parts: client, sim; positive counts and durations; --max >= --start")
    print(
        "gcu_async capacity benchmark"
        + (f" (--quick: a smoke test, at most {args.max} sessions; no figures)" if quick else "")
    )
    for line in machine_lines():
        print(f"  {line}")
    packet = heartbeat()
    reply = SimulatorModel().handle_bytes(packet)
    assert reply is not None
    cpus = sorted(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else []
    tested_cpu, counter_cpu = (cpus[0], cpus[1]) if args.pin and len(cpus) >= 2 else (None, None)
    setup = Setup(args, tested_cpu, counter_cpu, packet, reply)
    if args.profile:
        try:
            part, kind, count = args.profile.split(":")
            n = int(count)
        except ValueError:
            ap.error("--profile: PART:KIND:N, e.g. client:gcu:100")
        kinds = (*KINDS.get(part, ()), ENDPOINT, FLOORS.get(part, ""))
        kinds += (IDLE_BOUND,) if part == "client" else ()
        if part not in KINDS or kind not in kinds or n < 1:
            ap.error(f"--profile: PART client or sim, KIND one of {kinds}, N >= 1")
        return asyncio.run(profile(setup, part, kind, n))
    status = asyncio.run(controller(args, setup))
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(setup.report, f, indent=1)
    return status


if __name__ == "__main__":
    sys.exit(main())
