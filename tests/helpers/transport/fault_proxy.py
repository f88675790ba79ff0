"""A fault-injecting UDP proxy for tests: host → proxy → GCU (e.g. the simulator) and back.

``FaultProxy(upstream=(host, port), requests=policy, replies=policy)`` listens on
127.0.0.1, an ephemeral port (``.address``: point the host there). Each datagram from the
host goes upstream from the proxy's own socket; each datagram coming back on that socket
goes to the host (the address that sent the latest request). Real sockets, asyncio.

Per direction, every datagram is decoded (host packets on the way up, GCU packets on the
way back, with :mod:`gcu_async.protocol`); one that does not decode passes through at once,
counted, without asking the policy. A policy is a callable taking a :class:`Datagram`
(bytes, decoded packet, arrival time on the loop's clock, sequence number in its
direction) and returning a :class:`Fate`: forward now, drop, delay by ``d`` seconds,
duplicate (copies leave together), optionally with one bit flipped. Ready-made policies:

- :class:`DelayNullRequests` — delay every host packet carrying the null command (10 ms);
- :class:`DropFirstReplyOfEachCommand` — drop the first reply of each run of replies with
  one non-null feedback opcode, forward the rest;
- :class:`RandomFaults` — seeded loss / corruption / duplication / delay / reorder-hold,
  the simulator's fault model (same bound: a datagram leaves at most ``delay +
  reorder_hold`` after it arrived).

``request_stats`` / ``reply_stats`` count what the proxy did. ``async with`` starts it and
closes both sockets, cancelling every datagram still delayed; waits are bounded.
"""

from __future__ import annotations

import asyncio
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple

from gcu_async._lifecycle import OpenClose
from gcu_async.errors import RemoteProtocolError
from gcu_async.protocol import (
    GcuPacket,
    HostPacket,
    Opcode,
    command_code,
    decode_gcu_packet,
    decode_host_packet,
)
from gcu_async.sim import FaultConfig, FaultInjector

CLOSE_TIMEOUT = 2.0


@dataclass(frozen=True)
class Fate:
    """What happens to one datagram: ``copies`` (0 = dropped) leave after ``delay`` s."""

    copies: int = 1
    delay: float = 0.0
    corrupt_at: tuple[int, int] | None = None
    """(byte index, bit mask) to flip, or ``None``."""

    def __post_init__(self) -> None:
        if type(self.copies) is not int or not 0 <= self.copies <= 16:
            raise ValueError(f"copies: {self.copies!r} is outside the allowed range [0, 16]")
        if isinstance(self.delay, bool) or not isinstance(self.delay, (int, float)) or not (
            0 <= self.delay < math.inf
        ):
            raise ValueError(f"delay: {self.delay!r} is outside the allowed range [0, inf) s")


FORWARD = Fate()
DROP = Fate(copies=0)


def delayed(seconds: float) -> Fate:
    return Fate(delay=seconds)


def duplicated(copies: int = 2, delay: float = 0.0) -> Fate:
    return Fate(copies=copies, delay=delay)


Packet = HostPacket | GcuPacket


class Datagram(NamedTuple):
    """One datagram as a policy sees it."""

    data: bytes
    packet: Packet
    """Decoded: a HostPacket on the request path, a GcuPacket on the reply path."""
    time: float
    """When it reached the proxy (event-loop clock, seconds)."""
    seq: int
    """Its number in its direction, from 0 (undecodable datagrams included)."""


Policy = Callable[[Datagram], Fate]


def forward(datagram: Datagram) -> Fate:
    """The default policy: everything passes at once."""
    return FORWARD


class DelayNullRequests:
    """Requests: delay every host packet carrying the null command by ``seconds``."""

    def __init__(self, seconds: float = 0.010) -> None:
        self.fate = delayed(seconds)
        self.delayed = 0

    def __call__(self, datagram: Datagram) -> Fate:
        packet = datagram.packet
        if isinstance(packet, HostPacket) and command_code(packet.command) == Opcode.NULL:
            self.delayed += 1
            return self.fate
        return FORWARD


class DropFirstReplyOfEachCommand:
    """Replies: drop a reply whose feedback opcode is non-null and differs from the
    previous reply's (the first reply of each run of one opcode); forward the rest. Every
    reply, dropped or not, becomes "the previous reply"."""

    def __init__(self) -> None:
        self.previous: int | None = None
        self.dropped = 0

    def __call__(self, datagram: Datagram) -> Fate:
        packet = datagram.packet
        if not isinstance(packet, GcuPacket):
            return FORWARD
        opcode = packet.feedback.opcode
        first = opcode != Opcode.NULL and opcode != self.previous
        self.previous = opcode
        if first:
            self.dropped += 1
            return DROP
        return FORWARD


class RandomFaults:
    """Seeded random faults with the simulator's model (:class:`~gcu_async.sim.FaultConfig`
    semantics and determinism: the fate of the n-th datagram depends on the seed and n)."""

    def __init__(
        self,
        *,
        seed: int,
        loss: float = 0.0,
        corrupt: float = 0.0,
        duplicate: float = 0.0,
        reorder: float = 0.0,
        reorder_hold: float = 0.005,
        delay: float = 0.0,
    ) -> None:
        self.config = FaultConfig(drop=loss, corrupt=corrupt, duplicate=duplicate,
                                  reorder=reorder, delay=delay, seed=seed,
                                  reorder_hold=reorder_hold)  # fmt: skip
        self.injector = FaultInjector(self.config)

    @property
    def bound(self) -> float:
        """Latest a datagram leaves after it arrived: ``delay + reorder_hold``."""
        return self.config.delay + self.config.reorder_hold

    def __call__(self, datagram: Datagram) -> Fate:
        d = self.injector.decide(len(datagram.data))
        if d.drop:
            return DROP
        hold = self.config.reorder_hold if d.hold else 0.0
        return Fate(copies=d.copies, delay=d.delay + hold, corrupt_at=d.corrupt_at)


@dataclass
class ProxyStats:
    """What the proxy did in one direction."""

    datagrams: int = 0
    undecodable: int = 0
    """Passed through without asking the policy."""
    dropped: int = 0
    delayed: int = 0
    duplicated: int = 0
    corrupted: int = 0
    sent: int = 0
    """Datagrams (copies) handed to the socket."""
    unroutable: int = 0
    """Replies that came before any request (no host to send them to)."""
    cancelled: int = 0
    """Delayed copies still pending when the proxy closed."""


class _Endpoint(asyncio.DatagramProtocol):
    def __init__(self, received: Callable[[bytes, Any], None]) -> None:
        self._received = received
        self.closed: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        self.errors = 0

    def datagram_received(self, data: bytes, addr: Any) -> None:
        self._received(data, addr)

    def error_received(self, exc: Exception) -> None:
        self.errors += 1  # e.g. ICMP port unreachable when the GCU is not there

    def connection_lost(self, exc: Exception | None) -> None:
        if not self.closed.done():
            self.closed.set_result(None)


class FaultProxy(OpenClose):
    """A UDP proxy between one host and ``upstream``, faults by policy per direction."""

    def __init__(
        self,
        upstream: tuple[str, int],
        *,
        requests: Policy = forward,
        replies: Policy = forward,
        host: str = "127.0.0.1",
    ) -> None:
        self.upstream = upstream
        self.requests = requests
        self.replies = replies
        self._host = host
        self.address: tuple[str, int] = (host, 0)
        """Where the host sends (bound after start)."""
        self.host: tuple[str, int] | None = None
        """The host's address: the sender of the latest request."""
        self.request_stats = ProxyStats()
        self.reply_stats = ProxyStats()
        self._down: asyncio.DatagramTransport | None = None
        self._up: asyncio.DatagramTransport | None = None
        self._protocols: list[_Endpoint] = []
        self._timers: dict[asyncio.TimerHandle, ProxyStats] = {}

    @property
    def errors(self) -> int:
        """Socket errors reported (ICMP unreachable and the like)."""
        return sum(p.errors for p in self._protocols)

    async def open(self) -> None:
        loop = asyncio.get_running_loop()
        down, down_protocol = await loop.create_datagram_endpoint(
            lambda: _Endpoint(self._from_host), local_addr=(self._host, 0)
        )
        try:
            up, up_protocol = await loop.create_datagram_endpoint(
                lambda: _Endpoint(self._from_upstream), remote_addr=self.upstream
            )
        except BaseException:
            down.close()
            raise
        self._down, self._up = down, up
        self._protocols = [down_protocol, up_protocol]
        host, port = down.get_extra_info("sockname")[:2]
        self.address = (str(host), int(port))

    async def close(self) -> None:
        """Cancel the delayed datagrams, close both sockets (idempotent, bounded)."""
        for timer, stats in self._timers.items():
            timer.cancel()
            stats.cancelled += 1
        self._timers.clear()
        transports = [t for t in (self._down, self._up) if t is not None]
        self._down = self._up = None
        for transport in transports:
            transport.close()
        waits = [asyncio.shield(p.closed) for p in self._protocols]
        self._protocols = []
        if waits:
            await asyncio.wait_for(asyncio.gather(*waits), CLOSE_TIMEOUT)

    # -- the two directions -------------------------------------------------------------------
    def _from_host(self, data: bytes, addr: Any) -> None:
        self.host = (str(addr[0]), int(addr[1]))
        up = self._up

        def send(payload: bytes) -> None:
            if up is not None and not up.is_closing():
                up.sendto(payload)
                self.request_stats.sent += 1

        self._route(data, decode_host_packet, self.requests, self.request_stats, send)

    def _from_upstream(self, data: bytes, addr: Any) -> None:
        down, host = self._down, self.host
        if host is None:
            self.reply_stats.datagrams += 1
            self.reply_stats.unroutable += 1
            return

        def send(payload: bytes) -> None:
            if down is not None and not down.is_closing():
                down.sendto(payload, host)
                self.reply_stats.sent += 1

        self._route(data, decode_gcu_packet, self.replies, self.reply_stats, send)

    def _route(
        self,
        data: bytes,
        decode: Callable[[bytes], Packet],
        policy: Policy,
        stats: ProxyStats,
        send: Callable[[bytes], None],
    ) -> None:
        index = stats.datagrams
        stats.datagrams += 1
        try:
            packet = decode(data)
        except RemoteProtocolError:
            stats.undecodable += 1
            send(data)
            return
        loop = asyncio.get_running_loop()
        fate = policy(Datagram(data, packet, loop.time(), index))
        if fate.copies == 0:
            stats.dropped += 1
            return
        if fate.corrupt_at is not None:
            at, bit = fate.corrupt_at
            buf = bytearray(data)
            buf[at] ^= bit
            data = bytes(buf)
            stats.corrupted += 1
        stats.duplicated += fate.copies > 1
        if fate.delay <= 0:
            for _ in range(fate.copies):
                send(data)
            return
        stats.delayed += 1
        for _ in range(fate.copies):
            self._later(loop, fate.delay, send, data, stats)

    def _later(
        self,
        loop: asyncio.AbstractEventLoop,
        delay: float,
        send: Callable[[bytes], None],
        data: bytes,
        stats: ProxyStats,
    ) -> None:
        def fire() -> None:
            self._timers.pop(timer, None)
            send(data)

        timer = loop.call_later(delay, fire)
        self._timers[timer] = stats
