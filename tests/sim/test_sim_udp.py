"""The simulator over real UDP sockets on 127.0.0.1 (ephemeral ports)."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from typing import Any

import pytest

from gcu_async.protocol import (
    ControlValues,
    Mode,
    NullCommand,
    Opcode,
    Palette,
    PointingLock,
    TakePhoto,
    ZoomIn,
)
from gcu_async.sim import GcuSimulator, ManualClock, SimulatorModel
from helpers.sim.support import FAMILIES, UdpPeer, host_bytes, sub_of


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


@pytest.fixture
async def peer() -> AsyncIterator[UdpPeer]:
    p = await UdpPeer.open()
    yield p
    await p.close()


async def test_every_command_family_answered_with_its_status(peer: UdpPeer) -> None:
    sim = GcuSimulator()
    async with sim.serve_udp(port=0) as server:
        assert server.address[0] == "127.0.0.1"
        assert server.address[1] != 0
        for command, status in FAMILIES:
            null = await peer.request(host_bytes(), server.address)
            assert null.feedback.opcode == 0
            reply = await peer.request(host_bytes(command), server.address)
            assert (reply.feedback.opcode, reply.feedback.status) == (command.opcode, status)
    assert sim.model.stats.answered == 2 * len(FAMILIES)


async def test_reply_comes_from_the_bound_port_to_the_sender(peer: UdpPeer) -> None:
    async with GcuSimulator().serve_udp(port=0) as server:
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


async def test_same_opcode_rule_over_udp(peer: UdpPeer) -> None:
    sim = GcuSimulator()
    async with sim.serve_udp(port=0) as server:
        for _ in range(3):
            reply = await peer.request(host_bytes(TakePhoto()), server.address)
            assert reply.feedback.status == 0
        await peer.request(host_bytes(NullCommand()), server.address)
        await peer.request(host_bytes(TakePhoto()), server.address)
    assert sim.model.executions[Opcode.TAKE_PHOTO] == 2


async def test_unsupported_command_fails_on_a_non_thermal_model(peer: UdpPeer) -> None:
    async with GcuSimulator(pod="Z-6A").serve_udp(port=0) as server:
        reply = await peer.request(host_bytes(Palette(3)), server.address)
        assert (reply.feedback.opcode, reply.feedback.status) == (Opcode.PALETTE, 0x02)
        assert sub_of(reply).pod_code == 0


async def test_unknown_subframe_request_over_udp(peer: UdpPeer) -> None:
    async with GcuSimulator().serve_udp(port=0) as server:
        peer.send(host_bytes(subframe_request=0x05), server.address)
        data, _ = await peer.receive()
        assert data[37:69] == bytes(32)


async def test_garbage_is_ignored(peer: UdpPeer) -> None:
    sim = GcuSimulator()
    async with sim.serve_udp(port=0) as server:
        peer.send(b"\xa8\xe5 definitely not a packet", server.address)
        truncated = host_bytes(TakePhoto())[:40]
        peer.send(truncated, server.address)  # the rest never comes: a datagram stands alone
        assert await peer.nothing(0.15)
        reply = await peer.request(b"junk" + host_bytes(TakePhoto()), server.address)
        assert reply.feedback.opcode == Opcode.TAKE_PHOTO
    assert sim.model.stats.answered == 1
    assert sim.model.stats.bytes_discarded >= 26 + 40 + 4


async def test_silence_stops_answers_for_n_seconds(peer: UdpPeer) -> None:
    clock = ManualClock()
    sim = GcuSimulator(SimulatorModel(clock=clock))
    async with sim.serve_udp(port=0) as server:
        await peer.request(host_bytes(), server.address)
        sim.silence(5.0)
        peer.send(host_bytes(TakePhoto()), server.address)
        assert await peer.nothing(0.15)
        clock.advance(4.9)
        peer.send(host_bytes(TakePhoto()), server.address)
        assert await peer.nothing(0.1)
        clock.advance(0.2)
        reply = await peer.request(host_bytes(TakePhoto()), server.address)
        assert reply.feedback.opcode == Opcode.TAKE_PHOTO
    assert sim.stats.ignored_while_silent == 2
    assert sim.model.executions[Opcode.TAKE_PHOTO] == 1  # nothing ran while silent


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
