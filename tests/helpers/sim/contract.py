"""The simulator-server contract (docs/simulator.md, "Endpoints" and "Silence and stall"),
written once: :class:`ServerContract` holds what every endpoint of :class:`GcuSimulator` shows
a host (every command answered with its status, the same-opcode rule, junk discarded,
silence, stall, a capture of the exchange); :class:`StreamServerContract` adds what the
byte-stream endpoints (TCP, a pty, the in-memory link) show: any chunking. Each endpoint's
test file subclasses one with a ``serve`` fixture (:data:`Serve`: a simulator in, a
:class:`Host` on its endpoint out) and keeps only what is its own, as the transports do with
tests/helpers/transport/contract.py.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import AsyncIterator, Callable
from contextlib import AbstractAsyncContextManager
from pathlib import Path
from typing import Any, Protocol

import pytest

from gcu_async.cli.decode import decode_capture
from gcu_async.protocol import (
    Deframer,
    GcuPacket,
    NullCommand,
    Opcode,
    Palette,
    TakePhoto,
    ZoomIn,
    decode_gcu_packet,
    decode_host_packet,
)
from gcu_async.sim import GcuSimulator, ManualClock, SimulatorModel
from gcu_async.sim.stall import POLL_SECONDS
from gcu_async.transport import MemoryTransport
from helpers.sim.support import (
    FAMILIES,
    FdPeer,
    StreamPeer,
    UdpPeer,
    host_bytes,
    sub_of,
    tag,
    tagged,
)

GARBAGE = [b"\xa8\xe5 definitely not a packet", b"\x00\xff garbage \xa8\xe5\x48"]
"""Junk a host might send, each with a header's first bytes in it."""


class Host(Protocol):
    """The host's side of an endpoint: bounded waits."""

    def send(self, data: bytes) -> None:
        """Send ``data`` (one datagram on UDP)."""

    async def reply(self, timeout: float = 2.0) -> GcuPacket:
        """The next GCU packet; ``asyncio.TimeoutError`` after ``timeout`` seconds."""


Serve = Callable[[GcuSimulator], AbstractAsyncContextManager[Host]]
"""What a subclass's ``serve`` fixture gives: the simulator served on its endpoint, opened,
and a host on it; both closed on leaving."""


async def request(host: Host, data: bytes, timeout: float = 2.0) -> GcuPacket:
    host.send(data)
    return await host.reply(timeout)


async def nothing(host: Host, within: float) -> bool:
    """True when no reply arrives within ``within`` seconds."""
    try:
        await host.reply(within)
    except asyncio.TimeoutError:
        return True
    return False


class _MemoryHost:
    """A host on the in-memory link: deframes what it reads into a queue."""

    def __init__(self, transport: MemoryTransport) -> None:
        self.transport = transport
        self.deframer = Deframer.for_gcu_packets()
        self.queue: asyncio.Queue[bytes] = asyncio.Queue()
        transport.set_handlers(self.feed)

    def send(self, data: bytes) -> None:
        self.transport.send(data)

    def feed(self, data: bytes) -> None:
        for packet in self.deframer.feed(data):
            self.queue.put_nowait(packet)

    async def reply(self, timeout: float = 2.0) -> GcuPacket:
        return decode_gcu_packet(await asyncio.wait_for(self.queue.get(), timeout))


class _UdpHost:
    def __init__(self, peer: UdpPeer, address: tuple[str, int]) -> None:
        self.peer, self.address = peer, address

    def send(self, data: bytes) -> None:
        self.peer.send(data, self.address)

    async def reply(self, timeout: float = 2.0) -> GcuPacket:
        return decode_gcu_packet((await self.peer.receive(timeout))[0])


class _StreamHost:
    def __init__(self, peer: StreamPeer) -> None:
        self.peer = peer

    def send(self, data: bytes) -> None:
        self.peer.writer.write(data)

    async def reply(self, timeout: float = 2.0) -> GcuPacket:
        return await self.peer.reply(timeout)


@contextlib.asynccontextmanager
async def on_udp(sim: GcuSimulator) -> AsyncIterator[Host]:
    peer = await UdpPeer.open()
    try:
        async with sim.serve_udp(port=0) as server:
            yield _UdpHost(peer, server.address)
    finally:
        await peer.close()


@contextlib.asynccontextmanager
async def on_tcp(sim: GcuSimulator) -> AsyncIterator[Host]:
    async with sim.serve_tcp(port=0) as server:
        peer = await StreamPeer.connect(server.address)
        try:
            yield _StreamHost(peer)
        finally:
            await peer.close()


@contextlib.asynccontextmanager
async def on_pty(sim: GcuSimulator) -> AsyncIterator[Host]:
    async with sim.serve_pty() as server:
        peer = FdPeer.open_path(server.device_path)
        try:
            yield peer
        finally:
            peer.close()


@contextlib.asynccontextmanager
async def on_memory(sim: GcuSimulator) -> AsyncIterator[Host]:
    async with sim.serve_memory() as server:
        host = _MemoryHost(server.transport)
        await server.transport.open()
        try:
            yield host
        finally:
            await server.transport.close()


def manual() -> tuple[GcuSimulator, ManualClock]:
    clock = ManualClock()
    return GcuSimulator(SimulatorModel(clock=clock)), clock


class ServerContract:
    """What every simulator endpoint shows a host."""

    stall_packets = 10
    """How many packets the host sends during a stall: well inside the endpoint's buffer (a
    pty's 16 KiB is the smallest)."""
    os_buffered = True
    """Whether a stalled endpoint leaves what the host sends in an OS buffer (it stops
    reading), or holds it itself (the in-memory link has no OS buffer)."""

    async def test_every_command_answered_with_its_status(self, serve: Serve) -> None:
        sim = GcuSimulator()
        async with serve(sim) as host:
            for command, status in FAMILIES:
                assert (await request(host, host_bytes())).feedback.opcode == 0
                reply = await request(host, host_bytes(command))
                assert (reply.feedback.opcode, reply.feedback.status) == (command.opcode, status)
        assert sim.model.stats.answered == 2 * len(FAMILIES)

    async def test_same_opcode_rule(self, serve: Serve) -> None:
        sim = GcuSimulator()
        async with serve(sim) as host:
            for _ in range(3):
                assert (await request(host, host_bytes(TakePhoto()))).feedback.status == 0
            await request(host, host_bytes(NullCommand()))
            await request(host, host_bytes(TakePhoto()))
        assert sim.model.executions[Opcode.TAKE_PHOTO] == 2

    async def test_unsupported_command_fails_on_a_non_thermal_model(self, serve: Serve) -> None:
        async with serve(GcuSimulator(pod="Z-6A")) as host:
            reply = await request(host, host_bytes(Palette(3)))
            assert (reply.feedback.opcode, reply.feedback.status) == (Opcode.PALETTE, 0x02)
            assert sub_of(reply).pod_code == 0

    async def test_unknown_sub_frame_request_gets_no_sub_frame(self, serve: Serve) -> None:
        async with serve(GcuSimulator()) as host:
            assert (await request(host, host_bytes(subframe_request=0x05))).sub is None
            assert (await request(host, host_bytes())).sub is not None

    async def test_garbage_is_discarded(self, serve: Serve) -> None:
        sim = GcuSimulator()
        async with serve(sim) as host:
            for junk in GARBAGE:
                host.send(junk)
            assert await nothing(host, 0.15)
            reply = await request(host, b"junk" + host_bytes(TakePhoto()))
            assert reply.feedback.opcode == Opcode.TAKE_PHOTO
            assert await nothing(host, 0.05)
        assert sim.model.stats.answered == 1
        assert sim.model.stats.bytes_discarded >= sum(map(len, GARBAGE)) + 4

    async def test_silence_stops_answers_for_n_seconds(self, serve: Serve) -> None:
        sim, clock = manual()
        async with serve(sim) as host:
            await request(host, host_bytes())
            sim.silence(5.0)
            host.send(host_bytes(TakePhoto()))
            assert await nothing(host, 0.15)
            clock.advance(4.9)
            host.send(host_bytes(TakePhoto()))
            assert await nothing(host, 0.1)
            clock.advance(0.2)
            reply = await request(host, host_bytes(TakePhoto()))
            assert reply.feedback.opcode == Opcode.TAKE_PHOTO
        assert sim.stats.ignored_while_silent == 2
        assert sim.model.executions[Opcode.TAKE_PHOTO] == 1  # nothing ran while silent

    async def test_a_stall_keeps_requests_and_answers_them_in_order_after_it(
        self, serve: Serve
    ) -> None:
        """Nothing is answered or run during the stall, half way included; afterwards every
        request is, in the order sent (every other one a photo, so each one executes)."""
        sim, clock = manual()
        n = self.stall_packets
        async with serve(sim) as host:
            await request(host, tagged(0))
            sim.stall(2.0)
            assert sim.stalled
            for i in range(1, n + 1):
                host.send(tagged(i, TakePhoto() if i % 2 else None))
            assert await nothing(host, 0.3)
            # an OS buffer holds the packets (the endpoint stopped reading), or the endpoint
            if self.os_buffered:
                assert sim.stats.held_while_stalled == 0
            else:
                assert sim.stats.held_while_stalled == n
            assert (sim.model.stats.received, sim.model.stats.answered) == (1, 1)
            clock.advance(1.0)
            assert await nothing(host, 3 * POLL_SECONDS)  # half way: still stalled
            clock.advance(1.0)
            replies = [await host.reply(2.0) for _ in range(n)]
            assert await nothing(host, 0.1)
        assert [tag(r) for r in replies] == list(range(1, n + 1))
        assert [r.feedback.opcode for r in replies] == [
            Opcode.TAKE_PHOTO if i % 2 else Opcode.NULL for i in range(1, n + 1)
        ]
        assert sim.model.executions[Opcode.TAKE_PHOTO] == (n + 1) // 2
        assert not sim.stalled
        assert sim.stalls.count == 1


    async def test_a_capture_records_every_request_and_reply_in_order(
        self, serve: Serve, tmp_path: Path
    ) -> None:
        pytest.importorskip("dpkt", reason="the capture extra")
        path = tmp_path / "sim.pcapng"
        sim = GcuSimulator(capture=path)
        exchanged: list[dict[str, Any]] = []
        async with serve(sim) as host:
            for command in (None, TakePhoto(), ZoomIn(), None):
                data = host_bytes(command)
                reply = await request(host, data)
                exchanged += [decode_host_packet(data).as_dict(), reply.as_dict()]
        assert sim.capture is not None and not sim.capture.active  # closed with the endpoint
        records = decode_capture(path.read_bytes())
        assert [{k: v for k, v in r.items() if k != "capture"} for r in records] == exchanged
        assert len({r["capture"]["link"] for r in records}) == 1


class StreamServerContract(ServerContract):
    """What the byte-stream endpoints add: a packet in any chunks, several in one write."""

    async def test_any_chunking(self, serve: Serve) -> None:
        sim = GcuSimulator()
        async with serve(sim) as host:
            for byte in host_bytes(TakePhoto()):
                host.send(bytes([byte]))
                await asyncio.sleep(0)  # each its own write
            assert (await host.reply()).feedback.opcode == Opcode.TAKE_PHOTO
            data = b"noise" + host_bytes() + host_bytes(TakePhoto()) + b"\xa8"
            for i in range(0, len(data), 7):
                host.send(data[i : i + 7])
            assert (await host.reply()).feedback.opcode == Opcode.NULL
            assert (await host.reply()).feedback.opcode == Opcode.TAKE_PHOTO
            assert await nothing(host, 0.05)
        assert sim.model.executions[Opcode.TAKE_PHOTO] == 2
        assert sim.model.stats.bytes_discarded >= 6  # the noise and the dangling header byte


__all__ = ["GARBAGE", "Host", "Serve", "ServerContract", "StreamServerContract", "manual",
           "nothing", "on_memory", "on_pty", "on_tcp", "on_udp", "request"]  # fmt: skip
