"""The simulator over real UDP sockets on 127.0.0.1 (ephemeral ports): the server contract
(tests/helpers/sim/contract.py) on both receive paths, and what is UDP's own: replies to the
sender or a configured address, datagrams standing alone, the reply memo."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from typing import Any

import pytest

from gcu_async.protocol import (
    ControlValues,
    Mode,
    Opcode,
    PointingLock,
    TakePhoto,
    ZoomIn,
)
from gcu_async.sim import GcuSimulator, ManualClock, SimulatorModel
from helpers.sim.contract import Serve, ServerContract, on_udp
from helpers.sim.support import UdpPeer, host_bytes, sub_of


@pytest.fixture(autouse=True, params=["add_reader", "fallback"])
async def reader_path(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> str:
    """Every test on both of the server's receive paths: its own reader (``add_reader``),
    and asyncio's datagram transport, which it falls back to on loops without add_reader
    (Windows' proactor loop; simulated here by refusing add_reader on the running loop)."""
    if request.param == "fallback":

        def refuse(*args: object) -> None:
            raise NotImplementedError("add_reader is refused by this test")

        monkeypatch.setattr(asyncio.get_running_loop(), "add_reader", refuse)
    return str(request.param)


class TestUdpServer(ServerContract):
    stall_packets = 40  # far below what a default receive buffer holds (256 measured)

    @pytest.fixture
    def serve(self) -> Serve:
        return on_udp


@pytest.fixture
async def peer() -> AsyncIterator[UdpPeer]:
    p = await UdpPeer.open()
    yield p
    await p.close()


async def test_reply_comes_from_the_bound_port_to_the_sender(peer: UdpPeer) -> None:
    async with GcuSimulator().serve_udp(port=0) as server:
        assert server.address[0] == "127.0.0.1" and server.address[1] != 0
        peer.send(host_bytes(TakePhoto()), server.address)
        _, source = await peer.receive()
        assert source == server.address
        assert server.peers == {peer.address}
        assert server.url == f"udp://127.0.0.1:{server.address[1]}"


async def test_replies_go_to_the_configured_address(peer: UdpPeer) -> None:
    listener = await UdpPeer.open()
    try:
        sim = GcuSimulator()
        async with sim.serve_udp(port=0, reply_to=listener.address) as server:
            peer.send(host_bytes(TakePhoto()), server.address)
            _, source = await listener.receive()
            assert source == server.address
            assert await peer.nothing(0.1)
    finally:
        await listener.close()


async def test_modes_and_angles_over_udp_with_a_manual_clock(peer: UdpPeer) -> None:
    clock = ManualClock()
    sim = GcuSimulator(SimulatorModel(clock=clock))
    async with sim.serve_udp(port=0) as server:
        addr = server.address
        await peer.request(host_bytes(PointingLock()), addr)
        rates = ControlValues.rates(pitch=-10.0, yaw=30.0)
        for _ in range(20):
            await peer.request(host_bytes(control=rates), addr)
            clock.advance(0.05)
        reply = await peer.request(host_bytes(control=rates), addr)
        assert reply.main.mode == Mode.POINTING_LOCK
        assert reply.main.attitude.pitch == pytest.approx(-10.0, abs=0.01)
        assert reply.main.attitude.yaw == pytest.approx(30.0, abs=0.01)


async def test_zoom_moves_over_real_time(peer: UdpPeer) -> None:
    async with GcuSimulator().serve_udp(port=0) as server:
        first = await peer.request(host_bytes(ZoomIn()), server.address)
        seen = [sub_of(first).camera1_zoom]
        for _ in range(5):
            await peer.nothing(0.05)
            seen.append(sub_of(await peer.request(host_bytes(), server.address)).camera1_zoom)
        assert seen == sorted(seen)
        assert seen[-1] > seen[0] + 0.5  # 7.25×/s for ≥ 0.25 s
        assert seen[-1] < 30.0


async def test_a_truncated_datagram_is_not_completed_by_the_next(peer: UdpPeer) -> None:
    sim = GcuSimulator()
    async with sim.serve_udp(port=0) as server:
        photo = host_bytes(TakePhoto())
        peer.send(photo[:40], server.address)  # a datagram stands alone: no packet waits for
        peer.send(photo[40:], server.address)  # the rest, which is junk on its own
        assert await peer.nothing(0.15)
        reply = await peer.request(photo, server.address)
        assert reply.feedback.opcode == Opcode.TAKE_PHOTO
        assert await peer.nothing(0.1)
    assert sim.model.stats.answered == 1
    assert sim.model.stats.bytes_discarded >= len(photo)


async def test_bind_conflict_raises_oserror() -> None:
    async with GcuSimulator().serve_udp(port=0) as first:
        with pytest.raises(OSError, match=r"(?i)in use"):
            await GcuSimulator().serve_udp(port=first.address[1]).open()


async def test_replies_go_to_the_senders_host_at_a_fixed_port(peer: UdpPeer) -> None:
    listener = await UdpPeer.open()
    try:
        sim = GcuSimulator()
        async with sim.serve_udp(port=0, reply_port=listener.address[1]) as server:
            peer.send(host_bytes(TakePhoto()), server.address)
            _, source = await listener.receive()
            assert source == server.address
            assert await peer.nothing(0.1)
    finally:
        await listener.close()
    with pytest.raises(ValueError, match="at most one"):
        GcuSimulator().serve_udp(port=0, reply_to=("127.0.0.1", 1), reply_port=2)


async def test_an_idle_host_gets_the_replies_of_the_full_path(peer: UdpPeer) -> None:
    """The reply memo over a real socket: a heartbeat repeated 30 times, with a command run
    in between, answered byte for byte as a simulator without the memo answers it."""
    replies: dict[bool, list[bytes]] = {}
    models: dict[bool, SimulatorModel] = {}
    traffic = [host_bytes()] * 10 + [host_bytes(TakePhoto())] * 3 + [host_bytes()] * 17
    for memo in (True, False):
        clock = ManualClock()
        models[memo] = model = SimulatorModel(clock=clock, reply_memo=memo)
        replayed = 0
        replay = model.replay

        def counted(packet: bytes, replay: Any = replay) -> bytes | None:
            nonlocal replayed
            reply = replay(packet)
            replayed += reply is not None
            return reply

        model.replay = counted  # type: ignore[method-assign]
        async with GcuSimulator(model).serve_udp(port=0) as server:
            got = []
            for packet in traffic:
                peer.send(packet, server.address)
                got.append((await peer.receive())[0])
                clock.advance(0.02)
            replies[memo] = got
        assert replayed == (9 + 1 + 16 if memo else 0)
    assert replies[True] == replies[False]
    assert models[True].stats == models[False].stats
    assert models[True].conformance.report() == models[False].conformance.report()
