"""Client benchmark: command latency, heartbeat timing, CPU per session, concurrent sessions.

Run from the repository root::

    .venv/bin/python benchmarks/bench_client.py            # default: about 5 min
    .venv/bin/python benchmarks/bench_client.py --quick    # under 30 s

Everything runs over loopback UDP (127.0.0.1, ephemeral ports); ``--parts`` picks parts.

1. Command latency: ``await gcu.take_photo()`` / ``await gcu.focus()`` against a
   ``GcuSimulator`` served over UDP in this process, each right after a raw asyncio UDP echo
   round trip (a ``DatagramProtocol`` echo server and client in the same loop, same 73-byte
   payload), the series taking turns in rounds. Series: isolated commands (the link idle
   for the client's reorder guard + 2 ms first), the same against a minimal GCU (a UDP peer
   answering with pre-encoded GCU packets: the client's path without the simulator's
   model), and back to back: take_photo / focus alternately, and take_photo after
   take_photo (a null command must be acknowledged in between, NOTES §3).
2. Heartbeat timing and 3. CPU: one 50 Hz session against ``gcu-async sim`` in another
   process. The send time of every packet is taken when the client hands it to the
   transport (a wrapper around ``transport.send``); the CPU time of this process
   (``time.process_time``) over the same window is everything this process did. First the
   same with plain asyncio (a pre-encoded packet on the same deadline loop): the floor.
4. Concurrent sessions: N clients in this process against one ``gcu-async sim`` UDP endpoint
   in another process (it answers each sender at its own address), N ramped up until no
   window of a step keeps every session's jitter p99 within the limit; then the same
   against the minimal GCU in another process, which costs next to nothing per packet, so
   the client's own cost decides. Each ramp ends with plain asyncio sessions at the
   failing N, for reference.

Jitter of a session = |interval between consecutive heartbeat sends − 20 ms|.
Rate error of one session = (sends − 1) / (last send − first send) against 50 Hz, in %; of N
sessions: all their sends in the window / (N × window) against 50 Hz (skipped late ticks
show as a deficit).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import gc
import itertools
import math
import os
import platform
import random
import resource
import signal
import statistics
import sys
import time
from collections.abc import Awaitable, Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from _machine import cpu_model

from gcu_async import connect
from gcu_async.client import GcuClient
from gcu_async.protocol import (
    Feedback,
    HostPacket,
    NullCommand,
    Opcode,
    TakePhoto,
    decode_gcu_packet,
)
from gcu_async.protocol.aircraft import AircraftState
from gcu_async.protocol.enums import SubFrameRequest
from gcu_async.sim import GcuSimulator

RATE_HZ = 50.0
PERIOD = 1.0 / RATE_HZ
LOOPBACK = "127.0.0.1"
SCRIPT = os.path.abspath(__file__)
OPCODE_OFFSET = 69
"""Byte of the command opcode in a host packet (spec: host → GCU packet layout)."""
WAIT = 5.0
"""Upper bound of every single wait (a reply, a subprocess line, a close)."""

TARGET_LATENCY_RATIO = 2.0
TARGET_RATE_ERROR_PCT = 0.5
TARGET_JITTER_P99_MS = 2.0
TARGET_CPU_PCT = 1.0
SESSIONS_JITTER_P99_MS = 5.0
TARGET_SESSIONS = 200
PHASES = {"random": "at random times within one period", "together": "all at once"}


# --- machine ------------------------------------------------------------------------------
def load_average() -> str:
    try:
        return " ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:
        return "?"


# --- statistics ---------------------------------------------------------------------------
def percentile(sorted_values: Sequence[float], q: float) -> float:
    """Nearest-rank percentile (``q`` in [0, 100]) of an ascending sequence."""
    if not sorted_values:
        return math.nan
    rank = max(1, math.ceil(q / 100.0 * len(sorted_values)))
    return sorted_values[min(rank, len(sorted_values)) - 1]


@dataclass
class Timing:
    """Heartbeat timing of one session over a window."""

    sends: int
    rate_hz: float
    jitter_ms: list[float]  # ascending

    @property
    def rate_error_pct(self) -> float:
        return (self.rate_hz - RATE_HZ) / RATE_HZ * 100.0

    def p(self, q: float) -> float:
        return percentile(self.jitter_ms, q)

    @property
    def max_ms(self) -> float:
        return self.jitter_ms[-1] if self.jitter_ms else math.nan


def timing_of(stamps: Sequence[float]) -> Timing:
    """Rate and jitter (|interval − period| in ms) of send times ``stamps`` (seconds)."""
    if len(stamps) < 2:
        return Timing(len(stamps), math.nan, [])
    jitter = sorted(abs(b - a - PERIOD) * 1e3 for a, b in itertools.pairwise(stamps))
    rate = (len(stamps) - 1) / (stamps[-1] - stamps[0])
    return Timing(len(stamps), rate, jitter)


class SendStamps:
    """Wraps a transport's ``send`` (an instance attribute shadows the method) and records
    the ``time.perf_counter()`` of every packet handed to it."""

    def __init__(self, client: GcuClient) -> None:
        self.stamps: list[float] = []
        self._send = client.transport.send
        client.transport.send = self  # type: ignore[method-assign]

    def __call__(self, data: bytes) -> None:
        self.stamps.append(time.perf_counter())
        self._send(data)


# --- simulator in another process ---------------------------------------------------------
def _sim_command() -> list[str]:
    script = Path(sys.executable).with_name("gcu-async")
    if script.exists():
        return [str(script)]
    return [sys.executable, "-c", "import sys; from gcu_async.cli import main; sys.exit(main())"]


class SimProcess:
    """A GCU in a child process: ``gcu-async sim --listen udp://127.0.0.1:0 -q``, or with
    ``minimal=True`` this script's ``--serve-minimal`` (the minimal GCU, see
    :class:`_InstantGcu`). Its first line of output names the URL it listens on."""

    def __init__(self, proc: asyncio.subprocess.Process, url: str, name: str) -> None:
        self.proc = proc
        self.url = url
        self.name = name
        self._ticks = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100

    @classmethod
    async def start(cls, *, minimal: bool = False) -> SimProcess:
        if minimal:
            argv = [sys.executable, SCRIPT, "--serve-minimal"]
            name = "minimal GCU"
        else:
            argv = [*_sim_command(), "sim", "--listen", f"udp://{LOOPBACK}:0", "-q"]
            name = "gcu-async sim"
        proc = await asyncio.create_subprocess_exec(
            *argv, stdin=asyncio.subprocess.DEVNULL, stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.DEVNULL,
        )  # fmt: skip
        try:
            assert proc.stdout is not None
            line = (await asyncio.wait_for(proc.stdout.readline(), 3 * WAIT)).decode()
            url = line.rsplit(" ", 1)[-1].strip()
            if not url.startswith(f"udp://{LOOPBACK}:"):
                raise RuntimeError(f"{name} said {line!r}")
        except BaseException:
            await cls._stop(proc)
            raise
        return cls(proc, url, name)

    def cpu_seconds(self) -> float | None:
        """User + system CPU time of the child so far (Linux /proc), else None."""
        try:
            with open(f"/proc/{self.proc.pid}/stat", encoding="ascii") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            return None
        return (int(fields[11]) + int(fields[12])) / self._ticks

    async def stop(self) -> None:
        await self._stop(self.proc)

    @staticmethod
    async def _stop(proc: asyncio.subprocess.Process) -> None:
        if proc.returncode is None:
            proc.terminate()
            try:
                await asyncio.wait_for(proc.wait(), WAIT)
            except asyncio.TimeoutError:
                proc.kill()
                await asyncio.wait_for(proc.wait(), WAIT)
        if proc.stdout is not None:
            await asyncio.wait_for(proc.stdout.read(), WAIT)


# --- 1. command latency vs raw UDP echo ---------------------------------------------------
class _EchoServer(asyncio.DatagramProtocol):
    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport: Any = transport

    def datagram_received(self, data: bytes, addr: Any) -> None:
        self.transport.sendto(data, addr)


class _EchoClient(asyncio.DatagramProtocol):
    """Minimal request/response over a connected UDP socket, with a bounded wait."""

    def __init__(self) -> None:
        self.waiter: asyncio.Future[bytes] | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport: Any = transport

    def datagram_received(self, data: bytes, addr: Any) -> None:
        if self.waiter is not None and not self.waiter.done():
            self.waiter.set_result(data)

    async def round_trip(self, payload: bytes) -> float:
        loop = asyncio.get_running_loop()
        self.waiter = waiter = loop.create_future()
        timer = loop.call_later(WAIT, waiter.cancel)
        start = time.perf_counter()
        self.transport.sendto(payload)
        data = await waiter
        elapsed = time.perf_counter() - start
        timer.cancel()
        if data != payload:
            raise SystemExit("echo check failed: the reply differs from the request")
        return elapsed


class _InstantGcu(asyncio.DatagramProtocol):
    """A minimal GCU: answers every host packet with a pre-encoded GCU packet whose feedback
    is a success for the packet's opcode (byte 69) — the client's whole path (encode, send,
    receive, deframe, decode, match) without the simulator's model."""

    def __init__(self, replies: dict[int, bytes]) -> None:
        self.replies = replies

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport: Any = transport

    def datagram_received(self, data: bytes, addr: Any) -> None:
        reply = self.replies.get(data[OPCODE_OFFSET]) if len(data) > OPCODE_OFFSET else None
        if reply is not None:
            self.transport.sendto(reply, addr)


def instant_replies(sim: GcuSimulator, null_packet: bytes) -> dict[int, bytes]:
    """Replies for the null command, take_photo and focus, built from a real simulator reply."""
    telemetry = decode_gcu_packet(sim.model.handle_bytes(null_packet) or b"")
    replies = {int(Opcode.NULL): telemetry.encode()}
    for opcode in (Opcode.TAKE_PHOTO, Opcode.FOCUS):
        replies[int(opcode)] = telemetry._replace(feedback=Feedback(opcode, 0)).encode()
    return replies


async def serve_minimal() -> int:
    """``--serve-minimal``: the minimal GCU on 127.0.0.1 (ephemeral port) until SIGTERM."""
    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(sig, stop.set)
    null = HostPacket(AircraftState().main_frame(None, SubFrameRequest.STANDARD), None,
                      NullCommand()).encode()  # fmt: skip
    replies = instant_replies(GcuSimulator(), null)
    transport, _ = await loop.create_datagram_endpoint(
        lambda: _InstantGcu(replies), local_addr=(LOOPBACK, 0)
    )
    try:
        print("minimal GCU listening on udp://{}:{}".format(
            *transport.get_extra_info("sockname")[:2]), flush=True)  # fmt: skip
        await stop.wait()
    finally:
        transport.close()
        await asyncio.sleep(0)
    return 0


@dataclass
class LatencyResult:
    series: dict[str, tuple[list[float], list[float]]]
    """name -> (command latencies, the echo round trips interleaved with them), seconds."""
    photo_separated: int
    reorder_guard: float
    sim_us_per_packet: float
    payload: int


async def _timed(call: Callable[[], Awaitable[Any]]) -> float:
    start = time.perf_counter()
    await call()
    return time.perf_counter() - start


ISOLATED = "simulator, isolated"
MINIMAL = "minimal GCU, isolated"
ALTERNATING = "simulator, back to back, alternating"
PHOTOS = "simulator, back to back, take_photo"


async def measure_latency(samples: int, b2b_samples: int, block: int) -> LatencyResult:
    """``samples`` isolated commands (take_photo / focus alternately, each on an idle link)
    against the simulator and against the minimal GCU, ``b2b_samples`` of each back-to-back
    series; every command right after one echo round trip; the series take turns in rounds."""
    loop = asyncio.get_running_loop()
    main = AircraftState().main_frame(None, SubFrameRequest.STANDARD)
    payload = HostPacket(main, None, TakePhoto()).encode()
    if payload[OPCODE_OFFSET] != Opcode.TAKE_PHOTO:
        raise SystemExit("setup check failed: the opcode is not at byte 69")
    sim = GcuSimulator()
    replies = instant_replies(sim, HostPacket(main, None, NullCommand()).encode())
    handle_bytes = sim.model.handle_bytes
    sim_time = [0.0, 0]

    def timed_handle(packet: bytes) -> bytes | None:
        start = time.perf_counter()
        reply = handle_bytes(packet)
        sim_time[0] += time.perf_counter() - start
        sim_time[1] += 1
        return reply

    sim.model.handle_bytes = timed_handle  # type: ignore[method-assign]
    transports: list[asyncio.BaseTransport] = []
    try:
        echo_t, _ = await loop.create_datagram_endpoint(_EchoServer, local_addr=(LOOPBACK, 0))
        transports.append(echo_t)
        echo_addr = echo_t.get_extra_info("sockname")[:2]
        echo_c, echo = await loop.create_datagram_endpoint(_EchoClient, remote_addr=echo_addr)
        transports.append(echo_c)
        gcu_t, _ = await loop.create_datagram_endpoint(
            lambda: _InstantGcu(replies), local_addr=(LOOPBACK, 0)
        )
        transports.append(gcu_t)
        minimal_url = "udp://{}:{}".format(*gcu_t.get_extra_info("sockname")[:2])
        async with (
            sim.serve_udp(LOOPBACK, 0) as server,
            connect(server.url, local_port=0, command_timeout=WAIT) as gcu,
            connect(minimal_url, local_port=0, command_timeout=WAIT) as gcu2,
        ):
            guard = float(getattr(gcu.scheduler, "reorder_guard", 0.0))
            idle = guard + 0.002
            series: dict[str, tuple[list[float], list[float]]] = {
                name: ([], []) for name in (ALTERNATING, PHOTOS)
            }
            idle_echo: list[float] = []  # one echo per idle round, shared by both series
            series = {ISOLATED: ([], idle_echo), MINIMAL: ([], idle_echo), **series}
            rng = random.Random(2006)
            separated = 0
            stats = gcu.scheduler.stats

            async def sample(name: str, call: Callable[[], Awaitable[Any]]) -> None:
                series[name][1].append(await echo.round_trip(payload))
                series[name][0].append(await _timed(call))

            for _ in range(10):  # warm-up
                await echo.round_trip(payload)
                for client in (gcu, gcu2):
                    await client.focus()
                    await client.take_photo()
            await asyncio.sleep(idle)
            sim_time[:] = [0.0, 0]
            gc.collect()
            b2b_block = max(2, block // 4 // 2 * 2)
            while (len(series[ISOLATED][0]) < samples
                   or len(series[PHOTOS][0]) < b2b_samples):  # fmt: skip
                # on an idle link: the reordering guard of the previous command has passed
                # (echo, simulator, minimal GCU) in random order, so none is always first
                for i in range(block):
                    await asyncio.sleep(idle)
                    for what in rng.sample(range(3), 3):
                        if what == 0:
                            idle_echo.append(await echo.round_trip(payload))
                        else:
                            client, name = (gcu, ISOLATED) if what == 1 else (gcu2, MINIMAL)
                            call = client.take_photo if i % 2 else client.focus
                            series[name][0].append(await _timed(call))
                # focus / take_photo back to back: no null separation needed
                for i in range(b2b_block):
                    await sample(ALTERNATING, gcu.take_photo if i % 2 else gcu.focus)
                # take_photo after take_photo: a null must be acknowledged in between
                for _ in range(b2b_block):
                    waits = stats.null_waits
                    await sample(PHOTOS, gcu.take_photo)
                    separated += stats.null_waits != waits
            executed = sum(sim.model.executions.values())
            if executed < len(series[ISOLATED][0]) + 2 * len(series[PHOTOS][0]):
                raise SystemExit(f"latency check failed: the simulator executed {executed}")
        return LatencyResult(
            series, separated, guard, sim_time[0] / max(1, sim_time[1]) * 1e6, len(payload)
        )
    finally:
        for t in transports:
            t.close()
        await asyncio.sleep(0)  # let the transports release their sockets


def _lat(values: Sequence[float]) -> tuple[float, float]:
    s = sorted(values)
    return percentile(s, 50) * 1e6, percentile(s, 99) * 1e6


# --- sessions: a GcuClient, or the plain-asyncio floor ------------------------------------
class _Counter(asyncio.DatagramProtocol):
    def __init__(self) -> None:
        self.received = 0

    def datagram_received(self, data: bytes, addr: Any) -> None:
        self.received += 1


class ClientSession:
    """One ``GcuClient`` at 50 Hz, idle (heartbeat only), its sends time-stamped."""

    def __init__(self, url: str) -> None:
        self.client = connect(url, local_port=0, connect_timeout=3 * WAIT, silence_timeout=2.0)
        self.stamps = SendStamps(self.client).stamps

    async def open(self) -> None:
        await self.client.open()

    def counts(self) -> tuple[int, int, int]:
        """(datagrams received, datagrams sent, late heartbeat ticks) so far; cheap to read
        (``client.link`` would build a snapshot)."""
        t: Any = self.client.transport
        return t.rx_datagrams, t.tx_datagrams, self.client.heartbeat_late

    @property
    def up(self) -> bool:
        return self.client.link.up

    async def close(self) -> None:
        await self.client.close()


class RawSession:
    """The floor: plain asyncio sending a pre-encoded host packet at 50 Hz from its own
    socket, on the same monotonic-deadline loop as the client's heartbeat, counting (not
    decoding) the replies. With ``udp=False`` it only sleeps to the deadlines (no socket)."""

    PACKET = HostPacket(AircraftState().main_frame(None, SubFrameRequest.STANDARD), None,
                        NullCommand()).encode()  # fmt: skip

    def __init__(self, url: str, *, udp: bool = True) -> None:
        host, port = url.removeprefix("udp://").rsplit(":", 1)
        self.dest = (host, int(port))
        self.udp = udp
        self.stamps: list[float] = []
        self.sent = self.late = 0
        self._transport: asyncio.DatagramTransport | None = None
        self._proto = _Counter()
        self._task: asyncio.Task[None] | None = None

    async def open(self) -> None:
        if self.udp:
            loop = asyncio.get_running_loop()
            self._transport, _ = await loop.create_datagram_endpoint(
                lambda: self._proto, local_addr=("0.0.0.0", 0)
            )
        self._task = asyncio.create_task(self._beat(self._transport))

    async def _beat(self, transport: asyncio.DatagramTransport | None) -> None:
        packet, dest, stamps = self.PACKET, self.dest, self.stamps
        deadline = time.monotonic()
        while True:
            stamps.append(time.perf_counter())
            if transport is not None:
                transport.sendto(packet, dest)
            self.sent += 1
            deadline += PERIOD
            now = time.monotonic()
            if deadline < now:
                self.late += 1
                deadline = now
            await asyncio.sleep(deadline - now)

    def counts(self) -> tuple[int, int, int]:
        return self._proto.received, self.sent, self.late

    @property
    def up(self) -> bool:
        return self._proto.received > 0 or not self.udp

    async def close(self) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
        if self._transport is not None:
            self._transport.close()
            await asyncio.sleep(0)


Session = ClientSession | RawSession


@dataclass
class WindowResult:
    """N sessions over one window."""

    n: int
    seconds: float
    timings: list[Timing]
    cpu_pct: float
    sim_cpu_pct: float | None
    replies: int
    sent: int
    late: int
    down: int
    ctx_switches: tuple[int, int]

    @property
    def timing(self) -> Timing:
        return self.timings[0]

    @property
    def cpu_us_per_tick(self) -> float:
        sends = sum(t.sends for t in self.timings)
        return self.cpu_pct / 100.0 * self.seconds / max(1, sends) * 1e6

    @property
    def p99s(self) -> list[float]:
        return sorted(t.p(99) for t in self.timings)

    @property
    def pooled(self) -> list[float]:
        return sorted(j for t in self.timings for j in t.jitter_ms)


async def _open_all(sessions: Sequence[Session], spread: bool) -> None:
    """Open every session concurrently; with ``spread`` each starts after a random delay
    within one period (seeded), so the heartbeats have random phases."""
    rng = random.Random(2006)

    async def open_one(session: Session, delay: float) -> None:
        await asyncio.sleep(delay)
        await session.open()

    delays = [rng.uniform(0.0, PERIOD) if spread else 0.0 for _ in sessions]
    results = await asyncio.gather(
        *(open_one(c, d) for c, d in zip(sessions, delays, strict=True)), return_exceptions=True
    )
    errors = [r for r in results if isinstance(r, BaseException)]
    if errors:
        await asyncio.gather(*(c.close() for c in sessions))
        raise SystemExit(f"{len(errors)} of {len(sessions)} sessions failed to open: {errors[0]}")


async def measure_window(
    sim: SimProcess, n: int, seconds: float, warmup: float, *, raw: bool, spread: bool,
    udp: bool = True,
) -> WindowResult:
    """Open ``n`` sessions (``raw``: the plain-asyncio floor), wait ``warmup``, then measure
    one window of ``seconds``: send times, CPU of this process and of the GCU process,
    replies, packets sent, late ticks; close everything."""
    sessions: list[Session] = [RawSession(sim.url, udp=udp) if raw else ClientSession(sim.url)
                               for _ in range(n)]  # fmt: skip
    await _open_all(sessions, spread)
    try:
        await asyncio.sleep(warmup)
        for session in sessions:
            session.stamps.clear()
        gc.collect()
        await asyncio.sleep(3 * PERIOD)  # ticks delayed by the collection go out first
        counts0 = [session.counts() for session in sessions]
        ru0, sim0 = resource.getrusage(resource.RUSAGE_SELF), sim.cpu_seconds()
        cpu0, wall0 = time.process_time(), time.perf_counter()
        await asyncio.sleep(seconds)
        cpu1, wall1 = time.process_time(), time.perf_counter()
        ru1, sim1 = resource.getrusage(resource.RUSAGE_SELF), sim.cpu_seconds()
        counts1 = [session.counts() for session in sessions]
        windows = [[t for t in session.stamps if wall0 <= t <= wall1] for session in sessions]
        down = sum(not session.up for session in sessions)
    finally:
        await asyncio.gather(*(session.close() for session in sessions))
    delta = [sum(b[i] - a[i] for a, b in zip(counts0, counts1, strict=True)) for i in range(3)]
    wall = wall1 - wall0
    return WindowResult(
        n=n,
        seconds=wall,
        timings=[timing_of(w) for w in windows],
        cpu_pct=(cpu1 - cpu0) / wall * 100.0,
        sim_cpu_pct=None if sim0 is None or sim1 is None else (sim1 - sim0) / wall * 100.0,
        replies=delta[0],
        sent=delta[1],
        late=delta[2],
        down=down,
        ctx_switches=(ru1.ru_nvcsw - ru0.ru_nvcsw, ru1.ru_nivcsw - ru0.ru_nivcsw),
    )


# --- main ---------------------------------------------------------------------------------
def _met(ok: bool) -> str:
    return "met   " if ok else "MISSED"


def _sim_pct(value: float | None) -> str:
    return "?" if value is None else f"{value:.1f}"


async def run(args: argparse.Namespace) -> int:
    targets: list[tuple[str, bool, str]] = []
    print(f"  loop   : {type(asyncio.get_running_loop()).__name__}; loopback UDP only")

    # 1. latency
    if "1" in args.parts:
        lat = await measure_latency(args.latency_samples, args.b2b_samples, args.block)
        print(f"\n1. Command latency over loopback UDP (simulator in this process), each command"
              f" right after one raw echo round trip ({lat.payload}-B payload); take_photo and"
              f" focus; client reorder_guard {lat.reorder_guard * 1e3:g} ms")  # fmt: skip
        for name, (cmd, echo) in lat.series.items():
            c50, c99 = _lat(cmd)
            e50, e99 = _lat(echo)
            print(f"  {name:<37} {len(cmd):4d} x: p50 {c50:8.1f} us | p99 {c99:8.1f} us;"
                  f" echo p50 {e50:6.1f} us | p99 {e99:6.1f} us; ratio {c50 / e50:6.2f}x")
            targets.append((f"command p50 <= {TARGET_LATENCY_RATIO:g}x echo p50 ({name})",
                            c50 / e50 <= TARGET_LATENCY_RATIO, f"{c50 / e50:.2f}x"))  # fmt: skip
        print(f"  take_photo after take_photo waited for a null acknowledgement"
              f" {lat.photo_separated} of {len(lat.series[PHOTOS][0])} times")  # fmt: skip
        print(f"  simulator model time per packet, included above: {lat.sim_us_per_packet:.1f}"
              " us mean")  # fmt: skip
    if not set(args.parts) & set("234"):
        return _print_targets(targets)

    if set(args.parts) & set("23"):
        sim = await SimProcess.start()
        try:
            await part_session(sim, args, targets)
        finally:
            await sim.stop()
    if "4" in args.parts:
        for peer in ("sim", "minimal") if args.peer == "both" else (args.peer,):
            sim = await SimProcess.start(minimal=peer == "minimal")
            try:
                await part_sessions(sim, args, targets)
            finally:
                await sim.stop()
    return _print_targets(targets)


def _session_lines(label: str, s: WindowResult) -> None:
    t = s.timing
    print(f"  {label}: {t.sends} sends in {s.seconds:.3f} s, rate {t.rate_hz:.4f} Hz"
          f" ({t.rate_error_pct:+.4f} %); replies {s.replies} of {s.sent} sent;"
          f" late ticks {s.late}")  # fmt: skip
    print(f"    jitter |interval - 20 ms|: p50 {t.p(50):.3f} ms | p99 {t.p(99):.3f} ms |"
          f" max {t.max_ms:.3f} ms")  # fmt: skip
    print(f"    CPU of this process {s.cpu_pct:.3f} % of one core ({s.cpu_us_per_tick:.1f} us"
          f" per tick incl. its reply); GCU process {_sim_pct(s.sim_cpu_pct)} %;"
          f" context switches {s.ctx_switches[0]} voluntary,"
          f" {s.ctx_switches[1]} involuntary")  # fmt: skip


async def part_session(sim: SimProcess, args: argparse.Namespace, targets: list[Any]) -> None:
    print(f"\n2./3. One 50 Hz session against {sim.name} in another process ({sim.url});"
          f" {args.warmup:g} s warm-up before each window")  # fmt: skip
    sleep = await measure_window(sim, 1, args.baseline_seconds, args.warmup, raw=True,
                                 spread=False, udp=False)  # fmt: skip
    t = sleep.timing
    print(f"  asyncio task sleeping to 50 Hz deadlines, no I/O, {args.baseline_seconds:g} s:"
          f" CPU {sleep.cpu_pct:.3f} % of one core; jitter p99 {t.p(99):.3f} ms")  # fmt: skip
    raw = await measure_window(sim, 1, args.baseline_seconds, args.warmup, raw=True,
                               spread=False)  # fmt: skip
    _session_lines(f"plain asyncio floor, {args.baseline_seconds:g} s", raw)
    s = await measure_window(sim, 1, args.heartbeat_seconds, args.warmup, raw=False,
                             spread=False)  # fmt: skip
    _session_lines(f"GcuClient, {args.heartbeat_seconds:g} s", s)
    extra = (s.cpu_pct - raw.cpu_pct) / 100.0 / RATE_HZ * 1e6
    print(f"    GcuClient above the floor: {s.cpu_pct - raw.cpu_pct:+.3f} % of one core"
          f" ({extra:+.1f} us per tick)")  # fmt: skip
    t = s.timing
    targets.append((f"heartbeat rate error <= {TARGET_RATE_ERROR_PCT:g} %",
                    abs(t.rate_error_pct) <= TARGET_RATE_ERROR_PCT,
                    f"{t.rate_error_pct:+.4f} %"))  # fmt: skip
    targets.append((f"heartbeat jitter p99 <= {TARGET_JITTER_P99_MS:g} ms",
                    t.p(99) <= TARGET_JITTER_P99_MS, f"{t.p(99):.3f} ms"))  # fmt: skip
    targets.append((f"CPU of one session <= {TARGET_CPU_PCT:g} % of a core",
                    s.cpu_pct <= TARGET_CPU_PCT,
                    f"{s.cpu_pct:.3f} % (plain asyncio floor {raw.cpu_pct:.3f} %)"))  # fmt: skip


def _step_line(label: str, r: WindowResult) -> bool:
    p99s, pooled = r.p99s, r.pooled
    ok = p99s[-1] <= SESSIONS_JITTER_P99_MS
    sends = sum(t.sends for t in r.timings)
    rate_error = (sends / (r.n * r.seconds) - RATE_HZ) / RATE_HZ * 100.0
    print(f"  {label:>9} {r.n:4d} | {p99s[-1]:6.2f} {statistics.median(p99s):6.2f} |"
          f" {percentile(pooled, 99):6.2f} {pooled[-1]:6.1f} | {rate_error:+8.3f} % |"
          f" {r.cpu_pct:6.1f} {_sim_pct(r.sim_cpu_pct):>5} | {r.cpu_us_per_tick:6.1f} |"
          f" {r.replies / max(1, r.sent):7.1%} | {r.late:5d} | {r.down:4d}"
          f"  {'ok' if ok else 'over the limit'}")  # fmt: skip
    return ok


async def part_sessions(sim: SimProcess, args: argparse.Namespace, targets: list[Any]) -> None:
    spread = args.phase == "random"
    print(f"\n4. Concurrent 50 Hz sessions in this process against one {sim.name} endpoint in"
          f" another process; {args.step_seconds:g} s per step after {args.warmup:g} s warm-up;"
          f" limit: every session's jitter p99 <= {SESSIONS_JITTER_P99_MS:g} ms; sessions"
          f" opened {PHASES[args.phase]}")  # fmt: skip
    print("                N | jitter p99 ms | pooled ms     | rate err  |  CPU % of a core |"
          " us per | replies | late  | down")  # fmt: skip
    print("                  | worst median  | p99    max    | all sends | this   GCU proc  |"
          " tick   |         | ticks |")  # fmt: skip
    best, failed = 0, None
    for n in args.sessions:
        ok = False
        for _ in range(args.repeats):  # the step passes if one of its repeats does
            r = await measure_window(sim, n, args.step_seconds, args.warmup, raw=False,
                                     spread=spread)  # fmt: skip
            ok = _step_line("GcuClient", r) or ok
        if not ok:
            failed = n
            break
        best = n
    floor_n = failed if failed is not None else args.sessions[-1]
    r = await measure_window(sim, floor_n, args.step_seconds, args.warmup, raw=True,
                             spread=spread)  # fmt: skip
    _step_line("plain", r)
    print(f"  largest N with every session's jitter p99 <= {SESSIONS_JITTER_P99_MS:g} ms in at"
          f" least one of {args.repeats} windows: {best if best else 'none'}"
          f" (plain: plain asyncio at N = {floor_n}, for reference)")
    targets.append((f">= {TARGET_SESSIONS} sessions with jitter p99 <= "
                    f"{SESSIONS_JITTER_P99_MS:g} ms ({sim.name})", best >= TARGET_SESSIONS,
                    str(best)))  # fmt: skip


def _print_targets(targets: Sequence[tuple[str, bool, str]]) -> int:
    print(f"\nTargets (load average at the end: {load_average()}):")
    for name, ok, value in targets:
        print(f"  {_met(ok)} {name:<62} {value}")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="short run (< 30 s): fewer samples, 3 s heartbeat, N = 200 only")
    ap.add_argument("--latency-samples", type=int, default=None,
                    help="isolated commands per latency series [1000; quick 120]")
    ap.add_argument("--b2b-samples", type=int, default=None,
                    help="commands per back-to-back latency series [250; quick 30]")
    ap.add_argument("--parts", default="1234",
                    help="which parts to run: 1 latency, 2/3 one session, 4 sessions [1234]")
    ap.add_argument("--block", type=int, default=40,
                    help="isolated commands per round (back-to-back: a quarter) [40]")
    ap.add_argument("--heartbeat-seconds", type=float, default=None,
                    help="length of the one-session window [30; quick 3]")
    ap.add_argument("--baseline-seconds", type=float, default=None,
                    help="length of the plain-asyncio floor window [10; quick 1.5]")
    ap.add_argument("--step-seconds", type=float, default=None,
                    help="length of each concurrent-sessions step [5; quick 2.5]")
    ap.add_argument("--warmup", type=float, default=None,
                    help="seconds before each window [1; quick 0.4]")
    ap.add_argument("--sessions", type=lambda s: [int(x) for x in s.split(",")], default=None,
                    help="comma-separated N to ramp through, stopping at the first over the"
                    " limit [25,50,100,150,200,250,300,400,500; quick 200]")
    ap.add_argument("--peer", choices=("sim", "minimal", "both"), default="both",
                    help="GCU of the concurrent sessions: gcu-async sim, the minimal GCU of"
                    " part 1 (isolates the client's own cost), or both [both]")
    ap.add_argument("--repeats", type=int, default=None,
                    help="windows per concurrent-sessions step; a step passes if one does"
                    " [2; quick 1]")
    ap.add_argument("--phase", choices=tuple(PHASES), default="random",
                    help="concurrent sessions: open them each after a random delay within one"
                    " period (random heartbeat phases) or all at once [random]")
    ap.add_argument("--serve-minimal", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)  # fmt: skip
    if args.serve_minimal:
        return asyncio.run(serve_minimal())
    quick = args.quick
    if args.latency_samples is None:
        args.latency_samples = 120 if quick else 1000
    if args.b2b_samples is None:
        args.b2b_samples = 30 if quick else 250
    if args.heartbeat_seconds is None:
        args.heartbeat_seconds = 3.0 if quick else 30.0
    if args.baseline_seconds is None:
        args.baseline_seconds = 1.5 if quick else 10.0
    if args.step_seconds is None:
        args.step_seconds = 2.5 if quick else 5.0
    if args.warmup is None:
        args.warmup = 0.4 if quick else 1.0
    if args.repeats is None:
        args.repeats = 1 if quick else 2
    if args.sessions is None:
        args.sessions = [200] if quick else [25, 50, 100, 150, 200, 250, 300, 400, 500]
    if (args.latency_samples < 10 or args.b2b_samples < 2 or args.block < 2 or args.block % 2
            or args.heartbeat_seconds <= 0 or args.baseline_seconds <= 0
            or args.step_seconds <= 0 or args.warmup < 0 or min(args.sessions) < 1
            or args.repeats < 1):
        ap.error("need --latency-samples >= 10, --b2b-samples >= 2, an even --block >= 2,"
                 " positive durations, N >= 1")

    print("gcu_async client benchmark")
    print(f"  python : {platform.python_implementation()} {platform.python_version()}"
          f" ({sys.executable})")
    print(f"  cpu    : {cpu_model()} ({platform.machine()}, {os.cpu_count()} logical CPUs);"
          f" load average {load_average()} at the start")
    return asyncio.run(run(args))


if __name__ == "__main__":
    sys.exit(main())
