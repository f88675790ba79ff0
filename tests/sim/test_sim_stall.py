"""Stalls: the simulator stops reading its sockets / pty, the OS buffers what the host sends,
and when the stall ends every buffered packet is answered, in order — on every endpoint, in
the server contract (tests/helpers/sim/contract.py); here the rest. Real sockets on
127.0.0.1; the stall is timed on a ManualClock, so no assertion depends on the machine's
speed (the stall ends within POLL_SECONDS of the clock passing its end)."""

from __future__ import annotations

import asyncio
import time

import pytest

from gcu_async.protocol import decode_gcu_packet
from gcu_async.sim import FaultConfig, FaultPlan, GcuSimulator, ManualClock, StallSwitch
from gcu_async.sim.stall import POLL_SECONDS
from helpers.sim.support import StreamPeer, UdpPeer, eventually, tag, tagged


def manual_sim(**kw: object) -> tuple[GcuSimulator, ManualClock]:
    clock = ManualClock()
    return GcuSimulator(clock=clock, **kw), clock  # type: ignore[arg-type]


async def test_a_real_time_stall_lasts_at_least_its_duration() -> None:
    """Monotonic clock: no reply before the stall's end (a lower bound: robust on a slow
    machine), and the replies do come (within a generous bound)."""
    sim = GcuSimulator()
    peer = await UdpPeer.open()
    try:
        async with sim.serve_udp(port=0) as server:
            await peer.request(tagged(0), server.address)
            started = time.monotonic()
            sim.stall(0.3)
            peer.send(tagged(1), server.address)
            reply, _ = await peer.receive(timeout=5.0)
            waited = time.monotonic() - started
    finally:
        await peer.close()
    assert tag(decode_gcu_packet(reply)) == 1
    assert 0.3 <= waited < 5.0


async def test_silence_loses_what_a_stall_keeps() -> None:
    sim, clock = manual_sim()
    peer = await UdpPeer.open()
    try:
        async with sim.serve_udp(port=0) as server:
            sim.silence(1.0)
            peer.send(tagged(1), server.address)
            assert await peer.nothing(0.2)
            clock.advance(1.0)
            assert await peer.nothing(0.2)  # silence: read and dropped
            sim.stall(1.0)
            peer.send(tagged(2), server.address)
            assert await peer.nothing(0.2)
            sim.stall(0)  # ends a stall early
            reply, _ = await peer.receive(2.0)
    finally:
        await peer.close()
    assert tag(decode_gcu_packet(reply)) == 2
    assert sim.stats.ignored_while_silent == 1


async def test_a_client_connecting_during_a_stall_is_not_read_until_it_ends() -> None:
    sim, clock = manual_sim()
    async with sim.serve_tcp(port=0) as server:
        sim.stall(1.0)
        peer = await StreamPeer.connect(server.address)
        try:
            peer.writer.write(tagged(7))
            with pytest.raises(asyncio.TimeoutError):
                await peer.reply(timeout=0.3)
            assert sim.model.stats.received == 0
            clock.advance(1.0)
            assert tag(await peer.reply(timeout=2.0)) == 7
        finally:
            await peer.close()


async def test_requests_delayed_by_faults_into_a_stall_are_held_then_answered() -> None:
    plan = FaultPlan(requests=FaultConfig(reorder=1.0, reorder_hold=0.1))
    sim, clock = manual_sim(faults=plan)
    peer = await UdpPeer.open()
    try:
        async with sim.serve_udp(port=0) as server:
            peer.send(tagged(1), server.address)
            await eventually(lambda: sim.request_faults.stats.packets == 1)
            sim.stall(1.0)  # the request is on its 0.1 s hold: it lands in the stall
            await eventually(lambda: sim.stats.held_while_stalled == 1)
            assert sim.model.stats.received == 0
            clock.advance(1.0)
            reply, _ = await peer.receive(2.0)
    finally:
        await peer.close()
    assert tag(decode_gcu_packet(reply)) == 1


async def test_closing_during_a_stall_releases_everything() -> None:
    sim, _ = manual_sim()
    peer = await UdpPeer.open()
    try:
        server = sim.serve_udp(port=0)
        await server.open()
        sim.stall(60.0)
        peer.send(tagged(1), server.address)
        await asyncio.wait_for(server.close(), 2.0)
    finally:
        await peer.close()
    assert sim.stalls._members == {}  # no endpoint or exchange left behind
    sim.stall(0)
    assert not sim.stalled


class Member:
    def __init__(self) -> None:
        self.calls: list[str] = []

    def pause(self) -> None:
        self.calls.append("pause")

    def resume(self) -> None:
        self.calls.append("resume")


async def test_switch_extends_replaces_and_counts() -> None:
    clock = ManualClock()
    switch = StallSwitch(clock)
    a = Member()
    switch.join(a)
    switch.stall(5.0)
    clock.advance(3.0)
    switch.stall(1.0)  # replaces the end: now 4.0
    b = Member()
    switch.join(b)  # joining during a stall pauses at once
    assert (a.calls, b.calls) == (["pause"], ["pause"])
    clock.advance(0.5)
    await asyncio.sleep(3 * POLL_SECONDS)
    assert switch.stalled
    clock.advance(0.5)
    await eventually(lambda: not switch.stalled)
    assert (a.calls, b.calls) == (["pause", "resume"], ["pause", "resume"])
    assert switch.count == 1
    switch.leave(a)
    switch.stall(1.0)
    switch.stall(0)
    assert a.calls == ["pause", "resume"]
    assert b.calls == ["pause", "resume", "pause", "resume"]
    assert switch.count == 2


@pytest.mark.parametrize("seconds", [-1.0, float("nan"), float("inf"), True, "1"])
async def test_bad_durations_are_rejected_naming_the_field(seconds: object) -> None:
    switch = StallSwitch(ManualClock())
    with pytest.raises(ValueError, match=r"seconds: .* \[0, inf\)"):
        switch.stall(seconds)  # type: ignore[arg-type]
    assert not switch.stalled


def test_a_stall_needs_the_running_loop() -> None:
    switch = StallSwitch(ManualClock())
    with pytest.raises(RuntimeError):
        switch.stall(1.0)
    assert not switch.stalled
