"""The fault-injecting UDP proxy (tests/helpers/transport/fault_proxy.py) between a raw UDP host
socket and the real simulator on 127.0.0.1; its policies also on their own, adversarially."""

from __future__ import annotations

import asyncio
import itertools
import socket
import time
from collections.abc import AsyncIterator

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcu_async.protocol import (
    Command,
    Feedback,
    GcuMainFrame,
    GcuPacket,
    HostMainFrame,
    HostPacket,
    NullCommand,
    Opcode,
    Record,
    TakePhoto,
    decode_gcu_packet,
)
from gcu_async.sim import GcuSimulator, SimulatorModel
from helpers.sim.support import UdpPeer, eventually, tag, tagged
from helpers.transport.fault_proxy import (
    DROP,
    FORWARD,
    Datagram,
    DelayNullRequests,
    DropFirstReplyOfEachCommand,
    Fate,
    FaultProxy,
    RandomFaults,
    delayed,
    duplicated,
)


@pytest.fixture
async def peer() -> AsyncIterator[UdpPeer]:
    p = await UdpPeer.open()
    yield p
    await p.close()


def recording_sim() -> GcuSimulator:
    return GcuSimulator(SimulatorModel(record_executions=True))


async def test_without_faults_everything_passes_in_order(peer: UdpPeer) -> None:
    sim = GcuSimulator()
    async with sim.serve_udp(port=0) as server, FaultProxy(server.address) as proxy:
        assert proxy.address[0] == "127.0.0.1" and proxy.address[1] != 0
        n = 20
        for i in range(n):
            peer.send(tagged(i), proxy.address)
        received = [await peer.receive(2.0) for _ in range(n)]
        assert await peer.nothing(0.1)
        assert proxy.host == peer.address
    assert [tag(decode_gcu_packet(d)) for d, _ in received] == list(range(n))
    assert all(source == proxy.address for _, source in received)
    for stats in (proxy.request_stats, proxy.reply_stats):
        assert (stats.datagrams, stats.sent, stats.dropped, stats.delayed) == (n, n, 0, 0)


async def test_delay_null_requests_lets_a_command_overtake_the_null(peer: UdpPeer) -> None:
    policy = DelayNullRequests()  # 10 ms
    sim = recording_sim()
    async with sim.serve_udp(port=0) as server, FaultProxy(
        server.address, requests=policy
    ) as proxy:
        started = time.monotonic()
        peer.send(tagged(1), proxy.address)  # null: held 10 ms
        peer.send(tagged(2, TakePhoto()), proxy.address)  # forwarded at once
        first, _ = await peer.receive(2.0)
        second, _ = await peer.receive(2.0)
        null_latency = time.monotonic() - started
    assert [tag(decode_gcu_packet(d)) for d in (first, second)] == [2, 1]
    assert decode_gcu_packet(first).feedback.opcode == Opcode.TAKE_PHOTO
    assert null_latency >= 0.010
    assert policy.delayed == 1
    assert proxy.request_stats.delayed == 1
    assert [type(r.command) for r in sim.model.execution_log] == [TakePhoto]


async def test_drop_first_reply_of_each_command_over_the_simulator(peer: UdpPeer) -> None:
    """A host that repeats each command once: the first reply of each command is lost, the
    repeat's reply gets through, and the GCU executes each command once."""
    policy = DropFirstReplyOfEachCommand()
    sim = recording_sim()
    plan: list[Command] = [NullCommand(), TakePhoto(), TakePhoto(), NullCommand(), Record(),
                           Record(), Record(), NullCommand(), TakePhoto(), TakePhoto()]  # fmt: skip
    got: list[int] = []
    async with sim.serve_udp(port=0) as server, FaultProxy(
        server.address, replies=policy
    ) as proxy:
        for i, command in enumerate(plan):  # one at a time: the order is the sender's
            peer.send(tagged(i, command), proxy.address)
            await eventually(lambda i=i: proxy.reply_stats.datagrams == i + 1)
        while not peer.queue.empty():
            got.append(tag(decode_gcu_packet(peer.queue.get_nowait()[0])))
        assert await peer.nothing(0.1)
    assert got == [0, 2, 3, 5, 6, 7, 9]  # 1, 4, 8: the first reply of each command
    assert proxy.reply_stats.dropped == policy.dropped == 3
    assert proxy.reply_stats.sent == len(plan) - 3
    assert [type(r.command) for r in sim.model.execution_log] == [TakePhoto, Record, TakePhoto]


async def test_random_faults_are_deterministic_for_a_seed(peer: UdpPeer) -> None:
    async def run(seed: int) -> tuple[list[int], tuple[int, ...]]:
        sim = GcuSimulator()
        policy = RandomFaults(seed=seed, loss=0.2, duplicate=0.2, reorder=0.3, delay=0.005)
        async with sim.serve_udp(port=0) as server, FaultProxy(
            server.address, requests=policy
        ) as proxy:
            for i in range(40):
                peer.send(tagged(i), proxy.address)
                await asyncio.sleep(0.002)
            tags = []
            while True:
                try:
                    data, _ = await peer.receive(0.3)
                except asyncio.TimeoutError:
                    break
                tags.append(tag(decode_gcu_packet(data)))
        s = proxy.request_stats
        return sorted(tags), (s.dropped, s.duplicated, s.delayed, s.sent)

    first, again, other = await run(5), await run(5), await run(6)
    assert first == again
    assert first != other
    tags, (dropped, duplicated_, _, sent) = first
    assert 0 < dropped < 40 and duplicated_ > 0
    assert sent == 40 - dropped + duplicated_
    assert len(tags) == sent  # the simulator answered every datagram that reached it


async def test_loss_one_reaches_nothing_and_duplicate_one_doubles(peer: UdpPeer) -> None:
    sim = GcuSimulator()
    async with sim.serve_udp(port=0) as server:
        async with FaultProxy(server.address, requests=RandomFaults(seed=1, loss=1.0)) as p:
            for i in range(5):
                peer.send(tagged(i), p.address)
            assert await peer.nothing(0.2)
        assert sim.model.stats.received == 0
        async with FaultProxy(server.address,
                              replies=RandomFaults(seed=1, duplicate=1.0)) as p:  # fmt: skip
            peer.send(tagged(9), p.address)
            replies = [await peer.receive(1.0), await peer.receive(1.0)]
            assert await peer.nothing(0.1)
        assert [tag(decode_gcu_packet(d)) for d, _ in replies] == [9, 9]
        assert sim.model.stats.received == 1


async def test_undecodable_datagrams_pass_through_without_the_policy(peer: UdpPeer) -> None:
    seen: list[Datagram] = []

    def policy(datagram: Datagram) -> Fate:
        seen.append(datagram)
        return DROP

    sim = GcuSimulator()
    async with sim.serve_udp(port=0) as server, FaultProxy(
        server.address, requests=policy
    ) as proxy:
        garbage = b"\xa8\xe5 not a packet"
        peer.send(garbage, proxy.address)
        await eventually(lambda: sim.model.stats.bytes_discarded >= len(garbage))
        peer.send(tagged(1), proxy.address)  # decodes: the policy drops it
        await eventually(lambda: len(seen) == 1)
    assert proxy.request_stats.undecodable == 1
    assert proxy.request_stats.dropped == 1
    assert isinstance(seen[0].packet, HostPacket)
    assert seen[0].seq == 1  # the undecodable datagram was number 0
    assert sim.model.stats.received == 0


async def test_closing_cancels_delayed_datagrams_and_frees_the_sockets(peer: UdpPeer) -> None:
    sim = GcuSimulator()
    async with sim.serve_udp(port=0) as server:
        proxy = FaultProxy(server.address, requests=lambda d: delayed(0.3))
        await proxy.open()
        peer.send(tagged(1), proxy.address)
        await eventually(lambda: proxy.request_stats.delayed == 1)
        await asyncio.wait_for(proxy.close(), 3.0)
        await asyncio.wait_for(proxy.close(), 3.0)  # idempotent
        assert proxy.request_stats.cancelled == 1
        await asyncio.sleep(0.4)
        assert sim.model.stats.received == 0
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(proxy.address)  # the port is free again


async def test_replies_before_any_request_are_unroutable() -> None:
    sim = GcuSimulator()
    async with sim.serve_udp(port=0) as server, FaultProxy(server.address) as proxy:
        # the upstream socket is connected to the simulator: play the GCU from its port
        assert proxy._up is not None
        local = proxy._up.get_extra_info("sockname")
        await server.close()
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as gcu:
            gcu.bind(server.address)
            gcu.sendto(b"\x8a\x5e stray", local)
            await eventually(lambda: proxy.reply_stats.datagrams == 1)
    assert proxy.reply_stats.unroutable == 1


# -- the policies on their own ----------------------------------------------------------------
def reply(opcode: int) -> Datagram:
    packet = GcuPacket(GcuMainFrame.build(), None, Feedback(opcode, 0))
    return Datagram(b"", packet, 0.0, 0)


def expected_drops(opcodes: list[int]) -> list[bool]:
    """Reference: within each maximal run of equal opcodes, the first one, if non-null."""
    out: list[bool] = []
    for opcode, run in itertools.groupby(opcodes):
        n = len(list(run))
        out += [opcode != 0] + [False] * (n - 1)
    return out


@given(st.lists(st.sampled_from([0, 0x20, 0x21, 0x22, 0x01]), max_size=60))
def test_drop_first_reply_matches_a_run_based_reference(opcodes: list[int]) -> None:
    policy = DropFirstReplyOfEachCommand()
    fates = [policy(reply(op)) for op in opcodes]
    assert [f == DROP for f in fates] == expected_drops(opcodes)
    assert all(f in (DROP, FORWARD) for f in fates)
    assert policy.dropped == sum(expected_drops(opcodes))


@given(st.lists(st.sampled_from([NullCommand(), TakePhoto(), Record()]), max_size=30))
def test_delay_null_requests_delays_exactly_the_nulls(commands: list[Command]) -> None:
    policy = DelayNullRequests(0.01)
    for command in commands:
        packet = HostPacket(HostMainFrame.build(), None, command)
        fate = policy(Datagram(b"", packet, 0.0, 0))
        assert fate == (delayed(0.01) if isinstance(command, NullCommand) else FORWARD)
    assert policy.delayed == sum(isinstance(c, NullCommand) for c in commands)


@given(
    seed=st.integers(0, 2**32),
    loss=st.floats(0, 1),
    duplicate=st.floats(0, 1),
    reorder=st.floats(0, 1),
    hold=st.floats(0, 0.05),
    delay=st.floats(0, 0.05),
)
def test_random_faults_stay_within_their_bound(
    seed: int, loss: float, duplicate: float, reorder: float, hold: float, delay: float
) -> None:
    policy = RandomFaults(seed=seed, loss=loss, duplicate=duplicate, reorder=reorder,
                          reorder_hold=hold, delay=delay)  # fmt: skip
    again = RandomFaults(seed=seed, loss=loss, duplicate=duplicate, reorder=reorder,
                         reorder_hold=hold, delay=delay)  # fmt: skip
    datagram = Datagram(bytes(72), HostPacket(HostMainFrame.build()), 0.0, 0)
    fates = [policy(datagram) for _ in range(50)]
    assert fates == [again(datagram) for _ in range(50)]
    for fate in fates:
        assert fate.copies in (0, 1, 2)
        assert 0 <= fate.delay <= policy.bound


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [({"copies": -1}, "copies"), ({"copies": 1.0}, "copies"), ({"delay": -0.1}, "delay"),
     ({"delay": float("nan")}, "delay"), ({"delay": True}, "delay")],
)  # fmt: skip
def test_bad_fates_are_rejected_naming_the_field(kwargs: dict[str, object], field: str) -> None:
    with pytest.raises(ValueError, match=f"{field}: "):
        Fate(**kwargs)  # type: ignore[arg-type]


def test_fate_helpers() -> None:
    assert delayed(0.5) == Fate(1, 0.5)
    assert duplicated() == Fate(2, 0.0)
    assert duplicated(3, 0.1) == Fate(3, 0.1)
