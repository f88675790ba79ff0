"""Client benchmark: what the command session costs and waits, side by side with plain asyncio.

Run from the repository root::

    .venv/bin/python benchmarks/bench_client.py            # default: about 4.5 minutes
    .venv/bin/python benchmarks/bench_client.py --quick    # under 40 s

Every GCU is a ``GcuSimulator`` in a child process (this script with ``--serve``), one
simulator per connection, on loopback (127.0.0.1, ephemeral ports). Parts (``--parts``):

``cpu``
    CPU time of this process while one idle 50 Hz ``GcuClient`` runs over UDP, and while bare
    asyncio loops send the client's own heartbeat bytes to the same simulator on the same
    deadline scheme and only read the replies, and while a client runs with its session
    stubbed to that schedule (the driver and transport's floor, a diagnostic); windows
    taken in turns, in rounds.
``isolated``
    Commands on an otherwise idle link, each client at most one command a second (the
    rate bound's spare packet is then free again): over TCP (``reorder_guard`` 0) next to
    a raw asyncio exchange of the client's own packet bytes with an identical simulator,
    and over UDP submitted just after the edge guard has passed or at a random heartbeat
    phase, next to a raw UDP exchange; all five taking turns, in random order, every round.
``b2b``
    1,000 (``--commands``) back-to-back commands per client, mixed opcodes and one opcode
    repeated, over UDP and over TCP (four clients, concurrently): latency with each wait
    broken out, host packets per command, and the most host packets in any 1-second window.

Every host packet a client sends is time-stamped twice: the session's send time (the ``now``
of the poll that produced it, read through the client's ``clock``) and the time it reached
the transport (a wrapper around ``transport.send``). The script exits with status 1 if any
client had more than ``floor(rate_hz) + 1`` packets within one second by either stamp, or if
a simulator executed a different number of commands than the client completed (each command
must run exactly once); targets only print.
docs/benchmarks.md explains each series and its figures.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import gc
import json
import math
import os
import random
import socket
import statistics
import sys
import time
from collections import Counter
from collections.abc import Awaitable, Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from _machine import load_average, machine_lines

from gcu_async import connect
from gcu_async.client import GcuClient
from gcu_async.protocol import (
    Command,
    Focus,
    HostPacket,
    NullCommand,
    Opcode,
    Osd,
    TakePhoto,
    ZoomStop,
    command_code,
)
from gcu_async.protocol.aircraft import AircraftState
from gcu_async.session.pacing import MARGIN
from gcu_async.sim import GcuSimulator

RATE_HZ = 50.0
PERIOD = 1.0 / RATE_HZ
LIMIT = math.floor(RATE_HZ) + 1
"""Most host packets allowed within any 1-second window (the session's rate bound)."""
WINDOW = 1.0
LOOPBACK = "127.0.0.1"
SCRIPT = os.path.abspath(__file__)
OPCODE_AT = 69
"""Byte of the command opcode in a host packet and of the feedback opcode in a GCU packet."""
WAIT = 5.0
"""Upper bound of every single wait (a reply, a child's line, a close)."""
SPACING = 1.02
"""Seconds between two isolated commands of one client: one early packet per 1 s window."""
GATE_TOLERANCE = 0.002
"""A first packet this close after a gate (edge guard, rate window) counts as held by it."""

TARGET_CPU_RATIO = 1.2
TARGET_TCP_RATIO = 2.0
MIXED = (TakePhoto(), Focus(), ZoomStop(), Osd(True))
"""Commands of the mixed series (each answered with success by the simulator at once)."""
SAME = TakePhoto()
ISOLATED = (TakePhoto(), Focus())


def percentile(values: Sequence[float], q: float) -> float:
    """Nearest-rank percentile (``q`` in [0, 100]) of ``values``."""
    s = sorted(values)
    if not s:
        return math.nan
    return s[min(len(s), max(1, math.ceil(q / 100.0 * len(s)))) - 1]


def ms(values: Sequence[float]) -> str:
    """``p50 / p99`` of seconds, in ms."""
    return f"{percentile(values, 50) * 1e3:7.3f} / {percentile(values, 99) * 1e3:7.3f}"


# --- the GCUs: simulators in a child process ---------------------------------------------
async def serve(kinds: Sequence[str]) -> int:
    """``--serve udp,tcp,...``: one simulator per endpoint; prints their URLs as one JSON
    line, serves until stdin closes, then prints each simulator's executions."""
    loop = asyncio.get_running_loop()
    sims = [GcuSimulator() for _ in kinds]
    servers = [sim.serve_udp(LOOPBACK, 0) if kind == "udp" else sim.serve_tcp(LOOPBACK, 0)
               for sim, kind in zip(sims, kinds, strict=True)]  # fmt: skip
    for server in servers:
        await server.open()
    print(json.dumps({"urls": [server.url for server in servers]}), flush=True)
    stdin = asyncio.StreamReader()
    await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(stdin), sys.stdin)
    await stdin.read()  # until the parent closes it (or dies)
    for server in servers:
        await server.close()
    stats = [{"executions": dict(sim.model.executions), "answered": sim.model.stats.answered}
             for sim in sims]  # fmt: skip
    with contextlib.suppress(BrokenPipeError):  # the parent is gone
        print(json.dumps({"stats": stats}), flush=True)
    return 0


class Peer:
    """The child process of :func:`serve`."""

    def __init__(self, proc: asyncio.subprocess.Process, urls: list[str]) -> None:
        self.proc = proc
        self.urls = urls
        self._tick = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100

    @classmethod
    async def start(cls, kinds: Sequence[str]) -> Peer:
        proc = await asyncio.create_subprocess_exec(
            sys.executable, SCRIPT, "--serve", ",".join(kinds),
            stdin=asyncio.subprocess.PIPE, stdout=asyncio.subprocess.PIPE,
        )  # fmt: skip
        assert proc.stdout is not None
        try:
            line = await asyncio.wait_for(proc.stdout.readline(), 3 * WAIT)
            urls = json.loads(line)["urls"]
        except BaseException:
            proc.kill()
            await asyncio.wait_for(proc.wait(), WAIT)
            raise
        return cls(proc, urls)

    def cpu_seconds(self) -> float | None:
        """User + system CPU time of the child so far (Linux /proc), else None."""
        try:
            with open(f"/proc/{self.proc.pid}/stat", encoding="ascii") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            return None
        return (int(fields[11]) + int(fields[12])) / self._tick

    async def stop(self) -> list[dict[str, Any]]:
        """End the child; returns each simulator's executions (opcode -> count) and
        answered-packet count."""
        proc = self.proc
        assert proc.stdin is not None
        assert proc.stdout is not None
        proc.stdin.close()
        try:
            line = await asyncio.wait_for(proc.stdout.readline(), WAIT)
            await asyncio.wait_for(proc.wait(), WAIT)
        except asyncio.TimeoutError:
            proc.kill()
            await asyncio.wait_for(proc.wait(), WAIT)
            raise SystemExit("the simulator process did not stop") from None
        stats: list[dict[str, Any]] = json.loads(line)["stats"]
        for s in stats:
            s["executions"] = {int(k): v for k, v in s["executions"].items()}
        return stats


# --- what a client sent -------------------------------------------------------------------
class SendClock:
    """The client's clock (``time.monotonic``) that remembers the last time it returned:
    when the client hands a packet to its transport, that is the ``now`` of the session
    poll that produced it — the packet's send time as the session counts it."""

    def __init__(self) -> None:
        self.last = 0.0

    def __call__(self) -> float:
        self.last = now = time.monotonic()
        return now


class Recorder:
    """Wraps ``client.transport.send`` (an instance attribute shadows the method): for every
    host packet, the session's send time (:class:`SendClock`), the time it reached the
    transport (``time.monotonic()``) and its opcode; and the first packet's bytes per
    opcode."""

    def __init__(self, client: GcuClient, clock: SendClock, name: str) -> None:
        self.name = name
        self.times: list[float] = []
        self.handed: list[float] = []
        self.opcodes = bytearray()
        self.first: dict[int, bytes] = {}
        send, monotonic, times, handed, opcodes, first = (
            client.transport.send, time.monotonic, self.times, self.handed, self.opcodes,
            self.first)  # fmt: skip

        def recorded(data: bytes) -> None:
            handed.append(monotonic())
            times.append(clock.last)
            opcode = data[OPCODE_AT]
            opcodes.append(opcode)
            if opcode not in first:
                first[opcode] = bytes(data)
            send(data)

        client.transport.send = recorded  # type: ignore[method-assign]


def window_counts(times: Sequence[float]) -> tuple[int, float]:
    """(most packets within any window ``[t, t + 1 s)``, shortest time spanned by
    ``LIMIT + 1`` consecutive packets — at least 1 s when the bound held)."""
    most, j, tightest = 0, 0, math.inf
    for i, t in enumerate(times):
        while times[j] <= t - WINDOW:
            j += 1
        most = max(most, i - j + 1)
        if i >= LIMIT:
            tightest = min(tightest, t - times[i - LIMIT])
    return most, tightest


@dataclass
class Sample:
    """One command: submitted, first packet handed to the transport, feedback returned."""

    opcode: int
    repeat: bool
    """Same opcode as the client's previous command."""
    submit: float
    first: float
    done: float
    packets: int
    """Host packets sent from submit to done (any opcode)."""
    nulls_before: int
    """Null packets sent between submit and the first packet."""
    copies: int
    """Packets carrying the command, first to feedback (1: its first packet's reply ended it)."""
    cause: str

    @property
    def latency(self) -> float:
        return self.done - self.submit

    @property
    def wait(self) -> float:
        return self.first - self.submit

    @property
    def wire(self) -> float:
        return self.done - self.first


CAUSES = ("none", "edge guard", "rate bound", "null + proof", "slot", "other")


def classify(rec: Recorder, k: int, submit: float, opcode: int, nulls: int,
             guard: float) -> str:  # fmt: skip
    """Why the first packet (index ``k``) went at that time: the latest gate it matches."""
    t = rec.times[k]
    if t - submit < 0.5e-3:
        return "none"
    if nulls:
        return "null + proof"
    gate = rec.times[k - LIMIT] + WINDOW + MARGIN if k >= LIMIT else math.inf
    if submit < gate and -1e-4 <= t - gate < GATE_TOLERANCE:
        return "rate bound"
    if k >= 1 and guard > 0 and rec.opcodes[k - 1] != opcode:
        gate = rec.times[k - 1] + guard
        if submit < gate and -1e-4 <= t - gate < GATE_TOLERANCE:
            return "edge guard"
    if k >= 1 and abs(t - rec.times[k - 1] - PERIOD) < GATE_TOLERANCE:
        return "slot"
    return "other"


async def timed_command(gcu: GcuClient, rec: Recorder, command: Command,
                        repeat: bool) -> Sample:  # fmt: skip
    """Run ``command`` and take its :class:`Sample` from the recorder."""
    opcode = command_code(command)
    i0 = len(rec.times)
    submit = time.monotonic()
    feedback = await gcu.execute(command, timeout=WAIT)
    done = time.monotonic()
    if feedback.opcode != opcode:
        raise SystemExit(f"{rec.name}: feedback {feedback} for {command}")
    ops = rec.opcodes
    k = next((i for i in range(i0, len(ops)) if ops[i] == opcode), None)
    if k is None:
        raise SystemExit(f"{rec.name}: {command} completed without a packet carrying it")
    nulls = sum(1 for i in range(i0, k) if ops[i] == Opcode.NULL)
    copies = sum(1 for i in range(k, len(ops)) if ops[i] == opcode)
    cause = classify(rec, k, submit, opcode, nulls, gcu.reorder_guard)
    return Sample(opcode, repeat, submit, rec.times[k], done, len(ops) - i0, nulls, copies,
                  cause)


async def open_client(url: str, name: str) -> tuple[GcuClient, Recorder]:
    clock = SendClock()
    options: dict[str, Any] = {"local_port": 0} if url.startswith("udp") else {}
    gcu = connect(url, connect_timeout=WAIT, command_timeout=WAIT, clock=clock, **options)
    rec = Recorder(gcu, clock, name)
    await gcu.open()
    return gcu, rec


# --- raw asyncio peers of the client ------------------------------------------------------
class RawStream(asyncio.Protocol):
    """A raw asyncio TCP exchange: write a packet, collect the reply's bytes (length from
    bytes 2-3), resolve a future. No CRC check, no decoding."""

    def __init__(self) -> None:
        self._buffer = bytearray()
        self._waiter: asyncio.Future[bytes] | None = None
        self.transport: Any = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = transport

    def data_received(self, data: bytes) -> None:
        buf = self._buffer
        buf += data
        if len(buf) >= 4 and len(buf) >= buf[2] | buf[3] << 8:
            size = buf[2] | buf[3] << 8
            reply = bytes(buf[:size])
            del buf[:size]
            if self._waiter is not None and not self._waiter.done():
                self._waiter.set_result(reply)

    async def exchange(self, packet: bytes) -> float:
        loop = asyncio.get_running_loop()
        self._waiter = waiter = loop.create_future()
        timer = loop.call_later(WAIT, waiter.cancel)
        start = time.monotonic()
        self.transport.write(packet)
        reply = await waiter
        elapsed = time.monotonic() - start
        timer.cancel()
        if reply[OPCODE_AT] != packet[OPCODE_AT]:
            raise SystemExit("raw TCP exchange: the reply's feedback is not the packet's")
        return elapsed


class RawDatagram(asyncio.DatagramProtocol):
    """A raw asyncio UDP exchange with the simulator: sendto, await the reply datagram."""

    def __init__(self, dest: tuple[str, int]) -> None:
        self.dest = dest
        self._waiter: asyncio.Future[bytes] | None = None
        self.transport: Any = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = transport

    def datagram_received(self, data: bytes, addr: Any) -> None:
        if self._waiter is not None and not self._waiter.done():
            self._waiter.set_result(data)

    async def exchange(self, packet: bytes) -> float:
        loop = asyncio.get_running_loop()
        self._waiter = waiter = loop.create_future()
        timer = loop.call_later(WAIT, waiter.cancel)
        start = time.monotonic()
        self.transport.sendto(packet, self.dest)
        reply = await waiter
        elapsed = time.monotonic() - start
        timer.cancel()
        if reply[OPCODE_AT] != packet[OPCODE_AT]:
            raise SystemExit("raw UDP exchange: the reply's feedback is not the packet's")
        return elapsed


def hostport(url: str) -> tuple[str, int]:
    host, port = url.split("://", 1)[1].rsplit(":", 1)
    return host, int(port)


# --- part cpu -----------------------------------------------------------------------------
class BareLoop:
    """A careful hand-written 50 Hz host: its own unconnected UDP socket (like the client's:
    the GCU answers to the broadcast address, so a host cannot connect its socket), one
    pre-encoded packet sent on absolute deadlines (``loop.call_at``, ``deadline += period``,
    restarting the phase only when a whole period late), replies read and counted, nothing
    decoded. ``reader``: ``endpoint`` = asyncio's own datagram transport
    (``create_datagram_endpoint``), ``recv_into`` = ``loop.add_reader`` + one
    ``sock.recv_into`` of a reused buffer per readiness event."""

    def __init__(self, url: str, packet: bytes, reader: str) -> None:
        self.dest = hostport(url)
        self.packet = packet
        self.reader = reader
        self.sent = self.received = 0
        self._sock: socket.socket | None = None
        self._transport: asyncio.DatagramTransport | None = None
        self._timer: asyncio.TimerHandle | None = None
        self._buffer = bytearray(65536)
        self._send: Callable[[], None] = lambda: None

    async def open(self) -> None:
        loop = asyncio.get_running_loop()
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
        sock.bind(("0.0.0.0", 0))
        sock.setblocking(False)
        packet, dest = self.packet, self.dest
        if self.reader == "endpoint":
            owner = self

            class Counter(asyncio.DatagramProtocol):
                def datagram_received(self, data: bytes, addr: Any) -> None:
                    owner.received += 1

            transport, _ = await loop.create_datagram_endpoint(Counter, sock=sock)
            self._transport = transport
            sendto: Callable[..., Any] = transport.sendto
        else:
            self._sock = sock
            loop.add_reader(sock.fileno(), self._read)
            sendto = sock.sendto
        self._send = lambda: sendto(packet, dest)
        self._deadline = loop.time()
        self._loop = loop
        self._tick()

    def _tick(self) -> None:
        self._send()
        self.sent += 1
        self._deadline += PERIOD
        now = self._loop.time()
        if self._deadline <= now - PERIOD:  # a whole period late: restart the phase
            self._deadline = now
        self._timer = self._loop.call_at(self._deadline, self._tick)

    def _read(self) -> None:
        assert self._sock is not None
        try:
            self._sock.recv_into(self._buffer)
        except (BlockingIOError, InterruptedError):
            return
        self.received += 1

    def counts(self) -> tuple[int, int]:
        return self.sent, self.received

    async def close(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
        if self._transport is not None:
            self._transport.close()
        if self._sock is not None:
            self._loop.remove_reader(self._sock.fileno())
            self._sock.close()
        await asyncio.sleep(0)


class ClientLoop:
    """One idle ``GcuClient`` (heartbeat only) in the shape of :class:`BareLoop`."""

    def __init__(self, url: str) -> None:
        self.client = connect(url, local_port=0, connect_timeout=WAIT)

    async def open(self) -> None:
        await self.client.open()

    def counts(self) -> tuple[int, int]:
        link = self.client.link
        return link.packets_sent, link.packets_received

    async def close(self) -> None:
        await self.client.close()


class FloorLoop(ClientLoop):
    """Diagnostic, not a client: a ``GcuClient`` whose session is cut down to the heartbeat
    schedule (``poll`` returns the same heartbeat bytes on the same 50 Hz slots,
    ``next_wakeup`` the next slot, ``receive`` only counts). What is left is the driver and
    the UDP transport: the floor below which no work in the session can bring the client."""

    def __init__(self, url: str, packet: bytes) -> None:
        super().__init__(url)
        self.packet = packet
        self.sent = self.received = 0

    async def open(self) -> None:
        await self.client.open()
        session = self.client.session
        next_slot = time.monotonic() + PERIOD

        def poll(now: float) -> bytes | None:
            nonlocal next_slot
            if now < next_slot:
                return None
            next_slot += PERIOD
            if next_slot <= now - PERIOD:  # a whole period late: restart the phase
                next_slot = now
            self.sent += 1
            return self.packet

        def receive(data: bytes, now: float, **_: Any) -> None:
            self.received += 1

        # instance attributes shadow the methods the driver calls
        session.poll = poll  # type: ignore[method-assign]
        session.next_wakeup = lambda now: next_slot  # type: ignore[method-assign]
        session.receive = receive  # type: ignore[method-assign]

    def counts(self) -> tuple[int, int]:
        return self.sent, self.received


@dataclass
class CpuWindow:
    cpu: float
    """Seconds of CPU time of this process."""
    wall: float
    sent: int
    received: int
    peer_cpu: float | None

    @property
    def pct(self) -> float:
        return self.cpu / self.wall * 100.0


def pooled_share(windows: list[CpuWindow]) -> float:
    """CPU seconds per wall second over all ``windows`` together."""
    return sum(w.cpu for w in windows) / sum(w.wall for w in windows)


async def cpu_window(session: ClientLoop | BareLoop, peer: Peer, warmup: float,
                     seconds: float) -> CpuWindow:  # fmt: skip
    await session.open()
    try:
        await asyncio.sleep(warmup)
        gc.collect()
        await asyncio.sleep(3 * PERIOD)
        (s0, r0), p0 = session.counts(), peer.cpu_seconds()
        c0, w0 = time.process_time(), time.monotonic()
        await asyncio.sleep(seconds)
        c1, w1 = time.process_time(), time.monotonic()
        (s1, r1), p1 = session.counts(), peer.cpu_seconds()
    finally:
        await session.close()
    peer_cpu = None if p0 is None or p1 is None else p1 - p0
    return CpuWindow(c1 - c0, w1 - w0, s1 - s0, r1 - r0, peer_cpu)


async def idle(kind: str, url: str, seconds: float) -> int:
    """``--idle``: one idle session for ``seconds``; its packet counts on stderr."""
    heartbeat = HostPacket(AircraftState().main_frame(), None, NullCommand()).encode()
    session = {"client": lambda: ClientLoop(url), "floor": lambda: FloorLoop(url, heartbeat),
               "bare": lambda: BareLoop(url, heartbeat, "recv_into")}[kind]()  # fmt: skip
    await session.open()
    try:
        await asyncio.sleep(seconds)
        sent, received = session.counts()
    finally:
        await session.close()
    print(f"{kind}: {sent} sent, {received} replies in {seconds:g} s", file=sys.stderr)
    return 0


CPU_SERIES = ("GcuClient", "bare: add_reader + recv_into", "bare: create_datagram_endpoint",
              "GcuClient, session stubbed")  # fmt: skip
"""The client, the baseline of the target, asyncio's stock datagram transport (which
allocates a 256 KiB buffer per datagram: mmap/mremap/munmap on glibc) for context, and the
driver + transport floor (:class:`FloorLoop`)."""


async def part_cpu(args: argparse.Namespace, report: Report) -> None:
    peer = await Peer.start(["udp"])
    url = peer.urls[0]
    try:
        gcu, rec = await open_client(url, "heartbeat capture")
        await asyncio.sleep(0.2)
        await gcu.close()
        heartbeat = rec.first[Opcode.NULL]
        expected = HostPacket(AircraftState().main_frame(), None, NullCommand()).encode()
        if heartbeat != expected or heartbeat[OPCODE_AT] != Opcode.NULL:
            raise SystemExit("setup check failed: unexpected heartbeat bytes")
        makers: dict[str, Callable[[], ClientLoop | BareLoop]] = {
            CPU_SERIES[0]: lambda: ClientLoop(url),
            CPU_SERIES[1]: lambda: BareLoop(url, heartbeat, "recv_into"),
            CPU_SERIES[2]: lambda: BareLoop(url, heartbeat, "endpoint"),
            CPU_SERIES[3]: lambda: FloorLoop(url, heartbeat),
        }
        windows: dict[str, list[CpuWindow]] = {name: [] for name in makers}
        rng = random.Random(2006)
        for _ in range(args.cpu_rounds):
            for name in rng.sample(list(makers), len(makers)):
                windows[name].append(await cpu_window(makers[name](), peer, args.warmup,
                                                      args.cpu_seconds))  # fmt: skip
    finally:
        await peer.stop()
    report.cpu = windows
    print(f"\ncpu: one idle 50 Hz session over UDP against a simulator in another process;"
          f" {args.cpu_rounds} rounds of {len(windows)} windows of {args.cpu_seconds:g} s"
          f" (after {args.warmup:g} s warm-up), in random order each round;"
          f" heartbeat {len(heartbeat)} B")  # fmt: skip
    client = windows[CPU_SERIES[0]]
    for name, ws in windows.items():
        cpu, wall = sum(w.cpu for w in ws), sum(w.wall for w in ws)
        sent, received = sum(w.sent for w in ws), sum(w.received for w in ws)
        peer_cpu = [w.peer_cpu for w in ws if w.peer_cpu is not None]
        ratios = [c.cpu / c.wall / (w.cpu / w.wall) for c, w in zip(client, ws, strict=True)]
        sim = f"; simulator {sum(peer_cpu) / wall * 100:.2f} %" if peer_cpu else ""
        print(f"  {name:<30} CPU {cpu / wall * 100:6.3f} % of a core"
              f" ({cpu / max(1, sent) * 1e6:5.1f} us per packet + reply);"
              f" {sent} sent, {received} replies in {wall:.1f} s{sim}")  # fmt: skip
        print(f"  {'':<30} per-window % {' '.join(f'{w.pct:.3f}' for w in ws)}")
        if name != CPU_SERIES[0]:
            pooled = pooled_share(client) / pooled_share(ws)
            print(f"  {'':<30} GcuClient / this: {pooled:.3f}x pooled; per round"
                  f" {min(ratios):.3f}-{max(ratios):.3f}x,"
                  f" median {statistics.median(ratios):.3f}x")  # fmt: skip
            if name == CPU_SERIES[3]:
                floor = pooled_share(ws) / pooled_share(windows[CPU_SERIES[1]])
                print(f"  {'':<30} this / {CPU_SERIES[1]}: {floor:.3f}x pooled (the"
                      " driver and transport alone)")  # fmt: skip
            if name == CPU_SERIES[1]:
                report.target(f"CPU of one idle session <= {TARGET_CPU_RATIO:g}x bare asyncio"
                              " loop", pooled <= TARGET_CPU_RATIO,
                              f"{pooled:.3f}x (per-round median"
                              f" {statistics.median(ratios):.3f}x)")  # fmt: skip


# --- part isolated ------------------------------------------------------------------------
@dataclass
class Isolated:
    tcp: list[Sample] = field(default_factory=list)
    tcp_raw: list[float] = field(default_factory=list)
    udp_aligned: list[Sample] = field(default_factory=list)
    udp_random: list[Sample] = field(default_factory=list)
    udp_raw: list[float] = field(default_factory=list)


async def part_isolated(args: argparse.Namespace, report: Report) -> None:
    peer = await Peer.start(["tcp", "tcp", "udp", "udp", "udp"])
    tcp_url, raw_tcp_url, aligned_url, random_url, raw_udp_url = peer.urls
    loop = asyncio.get_running_loop()
    res = Isolated()
    clients: list[tuple[GcuClient, Recorder]] = []
    raw_udp_t: asyncio.BaseTransport | None = None
    raw_tcp_t: asyncio.BaseTransport | None = None
    counts: dict[str, Counter[int]] = {}
    try:
        for url, name in ((tcp_url, "tcp"), (aligned_url, "udp, after the guard"),
                          (random_url, "udp, random phase")):  # fmt: skip
            clients.append(await open_client(url, name))
            counts[name] = Counter()
        (tcp, tcp_rec), (aligned, aligned_rec), (rnd, rnd_rec) = clients
        raw_tcp_t, raw_tcp = await loop.create_connection(RawStream, *hostport(raw_tcp_url))
        raw_udp_t, raw_udp = await loop.create_datagram_endpoint(
            lambda: RawDatagram(hostport(raw_udp_url)), local_addr=("0.0.0.0", 0))
        for i in range(6):  # warm-up; the packets the raw exchanges send come from here
            for gcu, rec in clients:
                await gcu.execute(ISOLATED[i % 2])
                counts[rec.name][command_code(ISOLATED[i % 2])] += 1
        tcp_packets = {command_code(c): tcp_rec.first[command_code(c)] for c in ISOLATED}
        udp_packets = {command_code(c): aligned_rec.first[command_code(c)] for c in ISOLATED}
        for packet in (*tcp_packets.values(), *udp_packets.values()):
            await raw_tcp.exchange(packet)
            await raw_udp.exchange(packet)
        last = dict.fromkeys(("tcp", "aligned", "random"), time.monotonic())
        rng = random.Random(2006)
        guard = aligned.reorder_guard

        async def spaced(key: str) -> None:
            await asyncio.sleep(max(0.0, last[key] + SPACING - time.monotonic()))
            await asyncio.sleep(rng.uniform(0.0, PERIOD))  # a random heartbeat phase

        async def command(key: str, gcu: GcuClient, rec: Recorder, out: list[Sample],
                          cmd: Command) -> None:  # fmt: skip
            out.append(await timed_command(gcu, rec, cmd, False))
            counts[rec.name][command_code(cmd)] += 1
            last[key] = time.monotonic()

        gc.collect()
        for r in range(args.rounds):
            cmd = ISOLATED[r % 2]
            op = command_code(cmd)
            for what in rng.sample(range(5), 5):
                if what == 0:
                    await spaced("tcp")
                    await command("tcp", tcp, tcp_rec, res.tcp, cmd)
                elif what == 1:
                    await asyncio.sleep(rng.uniform(0.0, PERIOD))
                    res.tcp_raw.append(await raw_tcp.exchange(tcp_packets[op]))
                elif what == 2:
                    await spaced("aligned")
                    for _ in range(100):  # until the guard has passed since its last packet
                        gap = aligned_rec.times[-1] + guard - time.monotonic()
                        if gap <= 0:
                            break
                        await asyncio.sleep(gap)
                    await command("aligned", aligned, aligned_rec, res.udp_aligned, cmd)
                elif what == 3:
                    await spaced("random")
                    await command("random", rnd, rnd_rec, res.udp_random, cmd)
                else:
                    await asyncio.sleep(rng.uniform(0.0, PERIOD))
                    res.udp_raw.append(await raw_udp.exchange(udp_packets[op]))
    finally:
        for gcu, _ in clients:
            await gcu.close()
        for t in (raw_tcp_t, raw_udp_t):
            if t is not None:
                t.close()
        await asyncio.sleep(0)
        stats = await peer.stop()
    for (_, rec), s in zip(clients, (stats[0], stats[2], stats[3]), strict=True):
        report.check_executions(rec.name, counts[rec.name], s["executions"])
        report.check_rate(rec)
    report.isolated = res
    print(f"\nisolated: {args.rounds} rounds; per round, in random order: a TCP command, a raw"
          f" TCP exchange, a UDP command after the guard, a UDP command at a random phase,"
          f" a raw UDP exchange; each client >= {SPACING:g} s between commands; take_photo /"
          f" focus alternating by round")  # fmt: skip
    print("  series                                 latency p50 / p99 ms    wait before"
          " the first packet p50 / p99   first packet -> feedback p50 / p99")
    for name, samples in (("TCP GcuClient (guard 0)", res.tcp),
                          ("UDP GcuClient, after the guard", res.udp_aligned),
                          ("UDP GcuClient, random phase", res.udp_random)):  # fmt: skip
        print_samples(name, samples)
    print(f"  {'TCP raw asyncio exchange':<38} {ms(res.tcp_raw)}")
    print(f"  {'UDP raw asyncio exchange':<38} {ms(res.udp_raw)}")
    ratio = percentile([s.latency for s in res.tcp], 50) / percentile(res.tcp_raw, 50)
    ratio99 = percentile([s.latency for s in res.tcp], 99) / percentile(res.tcp_raw, 99)
    print(f"  TCP: GcuClient p50 / raw p50 = {ratio:.3f}x (p99 / p99 = {ratio99:.3f}x)")
    udp = percentile([s.wire for s in res.udp_aligned], 50) / percentile(res.udp_raw, 50)
    print(f"  UDP after the guard: first packet -> feedback p50 / raw p50 = {udp:.3f}x")
    report.target(f"TCP command p50 <= {TARGET_TCP_RATIO:g}x raw asyncio exchange p50",
                  ratio <= TARGET_TCP_RATIO, f"{ratio:.3f}x")  # fmt: skip


def print_samples(name: str, samples: Sequence[Sample]) -> None:
    print(f"  {name:<38} {ms([s.latency for s in samples])}    {ms([s.wait for s in samples])}"
          f"                     {ms([s.wire for s in samples])}   ({len(samples)})")
    parts = []
    for cause in CAUSES:
        waits = [s.wait for s in samples if s.cause == cause]
        if waits:
            parts.append(f"{cause} {len(waits)} (wait p50 {percentile(waits, 50) * 1e3:.2f}"
                         f" ms)")  # fmt: skip
    print(f"  {'':<38} first packet held by: {'; '.join(parts)}")
    again = [s.wire for s in samples if s.copies > 1]
    if again:
        print(f"  {'':<38} sent more than once (the first reply did not end it): {len(again)},"
              f" first packet -> feedback p50 {percentile(again, 50) * 1e3:.2f} ms")


# --- part b2b -----------------------------------------------------------------------------
B2B = (("UDP, mixed", "udp", "mixed"), ("UDP, same opcode", "udp", "same"),
       ("TCP, mixed", "tcp", "mixed"), ("TCP, same opcode", "tcp", "same"))  # fmt: skip


@dataclass
class Series:
    name: str
    samples: list[Sample]
    packets: int
    seconds: float
    most: int
    tightest: float


async def run_series(gcu: GcuClient, rec: Recorder, commands: Sequence[Command],
                     counts: Counter[int]) -> Series:  # fmt: skip
    samples: list[Sample] = []
    i0, t0 = len(rec.times), time.monotonic()
    previous: int | None = None
    for cmd in commands:
        op = command_code(cmd)
        samples.append(await timed_command(gcu, rec, cmd, op == previous))
        counts[op] += 1
        previous = op
    t1 = time.monotonic()
    most, tightest = window_counts(rec.times[i0:])
    return Series(rec.name, samples, len(rec.times) - i0, t1 - t0, most, tightest)


async def part_b2b(args: argparse.Namespace, report: Report) -> None:
    peer = await Peer.start([kind for _, kind, _ in B2B])
    clients: list[tuple[GcuClient, Recorder]] = []
    counts = [Counter[int]() for _ in B2B]
    rng = random.Random(2006)
    try:
        for url, (name, _, _) in zip(peer.urls, B2B, strict=True):
            clients.append(await open_client(url, name))
        await asyncio.sleep(0.5)
        gc.collect()
        jobs = []
        for (gcu, rec), (_, _, kind), c in zip(clients, B2B, counts, strict=True):
            cmds = ([rng.choice(MIXED) for _ in range(args.commands)] if kind == "mixed"
                    else [SAME] * args.commands)  # fmt: skip
            jobs.append(run_series(gcu, rec, cmds, c))
        series: list[Series] = await asyncio.gather(*jobs)
    finally:
        for gcu, _ in clients:
            await gcu.close()
        stats = await peer.stop()
    for (_, rec), c, st in zip(clients, counts, stats, strict=True):
        report.check_executions(rec.name, c, st["executions"])
        report.check_rate(rec)
    report.b2b = series
    print(f"\nb2b: {args.commands} back-to-back commands per client, four clients at once;"
          f" mixed = each drawn at random from {', '.join(type(c).__name__ for c in MIXED)};"
          f" same opcode = {type(SAME).__name__} every time")  # fmt: skip
    print("  series                                 latency p50 / p99 ms    wait before"
          " the first packet p50 / p99   first packet -> feedback p50 / p99")
    for s in series:
        groups = [(s.name, s.samples)]
        if "mixed" in s.name:
            groups += [(f"  {s.name}, new opcode", [x for x in s.samples if not x.repeat]),
                       (f"  {s.name}, repeated opcode", [x for x in s.samples if x.repeat])]
        for name, samples in groups:
            print_samples(name, samples)
        per = s.packets / len(s.samples)
        print(f"  {'':<38} {s.packets} host packets = {per:.3f} per command,"
              f" {len(s.samples) / s.seconds:.1f} commands/s; most packets in any 1 s:"
              f" {s.most} (limit {LIMIT}); shortest span of {LIMIT + 1} packets"
              f" {s.tightest:.6f} s")  # fmt: skip


# --- report -------------------------------------------------------------------------------
@dataclass
class Report:
    targets: list[tuple[str, bool, str]] = field(default_factory=list)
    failures: list[str] = field(default_factory=list)
    rates: list[tuple[str, int, int, float, int, float]] = field(default_factory=list)
    cpu: dict[str, list[CpuWindow]] = field(default_factory=dict)
    isolated: Isolated | None = None
    b2b: list[Series] = field(default_factory=list)

    def target(self, name: str, ok: bool, value: str) -> None:
        self.targets.append((name, ok, value))

    def check_rate(self, rec: Recorder) -> None:
        most, tightest = window_counts(rec.times)
        handed, _ = window_counts(rec.handed)
        lag = max((h - t for h, t in zip(rec.handed, rec.times, strict=True)), default=0.0)
        self.rates.append((rec.name, len(rec.times), most, tightest, handed, lag))
        if most > LIMIT:
            self.failures.append(f"{rec.name}: {most} host packets within 1 s at the session's"
                                 f" send times (limit {LIMIT})")  # fmt: skip
        if handed > LIMIT:
            self.failures.append(f"{rec.name}: {handed} host packets within 1 s at the times"
                                 f" they reached the transport (limit {LIMIT})")  # fmt: skip

    def check_executions(self, name: str, done: Counter[int], executed: dict[int, int]) -> None:
        if dict(done) != {k: v for k, v in executed.items() if v}:
            self.failures.append(f"{name}: the simulator executed {executed}, the client"
                                 f" completed {dict(done)}")  # fmt: skip


async def run(args: argparse.Namespace) -> int:
    report = Report()
    print(f"  loop   : {type(asyncio.get_running_loop()).__name__}; loopback only")
    parts: dict[str, Callable[[argparse.Namespace, Report], Awaitable[None]]] = {
        "cpu": part_cpu, "isolated": part_isolated, "b2b": part_b2b}  # fmt: skip
    for name in args.parts:
        await parts[name](args, report)
    print(f"\nrate bound: most host packets in any 1 s window per client, at the session's"
          f" send times (limit {LIMIT}; each client's whole life); [at the times they reached"
          f" the transport; the longest delay from send time to transport]")  # fmt: skip
    for name, sent, most, tightest, handed, lag in report.rates:
        print(f"  {name:<34} {sent:6d} sent, most in 1 s {most:3d}; shortest span of"
              f" {LIMIT + 1} packets {tightest:.6f} s [{handed} in 1 s; {lag * 1e6:.0f} us]")
    print(f"\nTargets (load average at the end: {load_average()}):")
    for name, ok, value in report.targets:
        print(f"  {'met   ' if ok else 'MISSED'} {name:<66} {value}")
    for failure in report.failures:
        print(f"  FAILED {failure}")
    return 1 if report.failures else 0


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="short run (under 40 s)")
    ap.add_argument("--parts", default="cpu,isolated,b2b",
                    help="comma-separated parts: cpu, isolated, b2b [all]")
    ap.add_argument("--cpu-rounds", type=int, help="rounds of CPU windows [16; quick 4]")
    ap.add_argument("--cpu-seconds", type=float, help="length of a CPU window [1.5; quick 0.8]")
    ap.add_argument("--warmup", type=float, help="seconds before a CPU window [0.3]")
    ap.add_argument("--rounds", type=int, help="rounds of isolated commands [120; quick 10]")
    ap.add_argument("--commands", type=int,
                    help="back-to-back commands per client [1000; quick 100]")
    ap.add_argument("--serve", help=argparse.SUPPRESS)
    ap.add_argument("--idle", choices=["client", "floor", "bare"],
                    help="run one idle session (the client, the client with its session"
                         " stubbed, or the add_reader + recv_into loop) against --url for"
                         " --seconds, then print its packet counts:"
                         " for an instruction count (valgrind --tool=callgrind), the"
                         " difference of two lengths")  # fmt: skip
    ap.add_argument("--url", help="with --idle: the simulator's UDP URL")
    ap.add_argument("--seconds", type=float, default=2.0, help="with --idle [2]")
    args = ap.parse_args(argv)
    if args.serve:
        return asyncio.run(serve(args.serve.split(",")))
    if args.idle:
        if not args.url or not args.url.startswith("udp://") or args.seconds <= 0:
            ap.error("--idle needs --url udp://HOST:PORT and positive --seconds")
        return asyncio.run(idle(args.idle, args.url, args.seconds))
    quick = args.quick
    defaults = {"cpu_rounds": (16, 4), "cpu_seconds": (1.5, 0.8), "warmup": (0.3, 0.3),
                "rounds": (120, 10), "commands": (1000, 100)}  # fmt: skip
    for key, (full, short) in defaults.items():
        if getattr(args, key) is None:
            setattr(args, key, short if quick else full)
    args.parts = [p.strip() for p in args.parts.split(",") if p.strip()]
    if (set(args.parts) - {"cpu", "isolated", "b2b"} or args.cpu_rounds < 1
            or args.cpu_seconds <= 0 or args.warmup < 0 or args.rounds < 2
            or args.commands < 2):  # fmt: skip
        ap.error("parts: cpu, isolated, b2b; positive counts and durations")
    print("gcu_async client benchmark" + (" (--quick)" if quick else ""))
    for line in machine_lines():
        print(f"  {line}")
    return asyncio.run(run(args))


if __name__ == "__main__":
    sys.exit(main())
