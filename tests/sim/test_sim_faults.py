"""Fault injection: seeded, deterministic, per direction; end to end over real UDP."""

from __future__ import annotations

import asyncio

import pytest

from gcu_async.errors import RemoteProtocolError
from gcu_async.protocol import decode_gcu_packet
from gcu_async.sim import FaultConfig, FaultInjector, FaultPlan, GcuSimulator
from helpers.sim.support import UdpPeer, host_bytes


def decisions(config: FaultConfig, n: int = 200) -> list[object]:
    injector = FaultInjector(config)
    return [injector.decide(72) for _ in range(n)]


def test_same_seed_same_decisions_other_seed_others() -> None:
    config = FaultConfig(drop=0.2, corrupt=0.2, duplicate=0.2, reorder=0.2, delay=0.05, seed=7)
    assert decisions(config) == decisions(config)
    assert decisions(config) != decisions(FaultConfig(**{**config.__dict__, "seed": 8}))


def test_probabilities_are_roughly_honoured() -> None:
    injector = FaultInjector(FaultConfig(drop=0.25, duplicate=0.5, seed=1))
    for _ in range(4000):
        injector.decide(72)
    s = injector.stats
    assert 800 <= s.dropped <= 1200
    assert 1300 <= s.duplicated <= 1700  # half of the ~3000 not dropped
    assert s.corrupted == s.reordered == s.delayed == 0


def test_corruption_flips_exactly_one_bit() -> None:
    injector = FaultInjector(FaultConfig(corrupt=1.0, seed=3))
    data = host_bytes()
    for _ in range(50):
        decision = injector.decide(len(data))
        changed = injector.apply(data, decision)
        diff = [a ^ b for a, b in zip(data, changed, strict=True) if a != b]
        assert len(diff) == 1
        assert bin(diff[0]).count("1") == 1


def test_no_faults_means_no_change() -> None:
    config = FaultConfig()
    assert not config.active
    assert all(d == decisions(config, 1)[0] for d in decisions(config, 20))
    assert not decisions(config, 1)[0].drop  # type: ignore[attr-defined]


def test_plan_for_both_directions_uses_distinct_seeds() -> None:
    plan = FaultPlan.both(FaultConfig(drop=0.5, seed=10))
    assert plan.requests.seed == 10
    assert plan.replies.seed == 11
    assert plan.replies.drop == 0.5


@pytest.mark.parametrize(
    "kwargs",
    [
        {"drop": 1.5},
        {"corrupt": -0.1},
        {"reorder": float("nan")},
        {"delay": -1.0},
        {"delay": float("inf")},
    ],
)
def test_invalid_configurations_are_rejected(kwargs: dict[str, float]) -> None:
    with pytest.raises(ValueError, match=next(iter(kwargs))):
        FaultConfig(**kwargs)


async def _exchange(plan: FaultPlan, n: int = 40) -> tuple[list[int], int]:
    """Send ``n`` packets (aircraft yaw i×5° identifies packet i) and collect the replies:
    the sorted list of yaws answered and the number of replies that did not decode."""
    sim = GcuSimulator(faults=plan)
    peer = await UdpPeer.open()
    yaws: list[int] = []
    bad = 0
    try:
        async with sim.serve_udp(port=0) as server:
            for i in range(n):
                peer.send(host_bytes(attitude=(0.0, 0.0, i * 5.0)), server.address)
                await asyncio.sleep(0.002)
            while True:
                try:
                    data, _ = await peer.receive(timeout=0.4)
                except asyncio.TimeoutError:
                    break
                try:
                    yaws.append(round(decode_gcu_packet(data).main.attitude.yaw / 5))
                except RemoteProtocolError:
                    bad += 1
    finally:
        await peer.close()
    return sorted(yaws), bad


async def test_faults_over_udp_are_deterministic_for_a_seed() -> None:
    def plan(seed: int) -> FaultPlan:
        return FaultPlan(
            requests=FaultConfig(drop=0.2, corrupt=0.1, duplicate=0.1, seed=seed),
            replies=FaultConfig(drop=0.2, corrupt=0.1, reorder=0.2, seed=seed + 100),
        )

    first = await _exchange(plan(42))
    again = await _exchange(plan(42))
    other = await _exchange(plan(43))
    assert first == again
    assert first != other
    answered, _ = first
    assert 10 < len(answered) < 40  # some lost, some through


async def test_reply_faults_leave_requests_alone() -> None:
    plan = FaultPlan(replies=FaultConfig(drop=1.0))
    sim = GcuSimulator(faults=plan)
    peer = await UdpPeer.open()
    try:
        async with sim.serve_udp(port=0) as server:
            for i in range(5):
                peer.send(host_bytes(attitude=(0.0, 0.0, i * 5.0)), server.address)
            assert await peer.nothing(0.2)
    finally:
        await peer.close()
    assert sim.model.stats.answered == 5  # every request reached the model
    assert sim.reply_faults.stats.dropped == 5
    assert sim.request_faults.stats.packets == 0


async def test_delay_and_duplicate_requests_over_udp() -> None:
    sim = GcuSimulator(faults=FaultPlan(requests=FaultConfig(duplicate=1.0, delay=0.05)))
    peer = await UdpPeer.open()
    try:
        async with sim.serve_udp(port=0) as server:
            peer.send(host_bytes(), server.address)
            await peer.receive(timeout=1.0)
            await peer.receive(timeout=1.0)  # the duplicate is answered too
            assert await peer.nothing(0.15)
    finally:
        await peer.close()
    assert sim.request_faults.stats.duplicated == 1


async def test_faults_can_change_while_serving() -> None:
    sim = GcuSimulator()
    peer = await UdpPeer.open()
    try:
        async with sim.serve_udp(port=0) as server:
            await peer.request(host_bytes(), server.address)
            sim.set_faults(FaultConfig(drop=1.0))
            peer.send(host_bytes(), server.address)
            assert await peer.nothing(0.15)
            sim.set_faults(None)
            await peer.request(host_bytes(), server.address)
    finally:
        await peer.close()
    assert sim.model.stats.answered == 2  # the dropped request never reached the model


async def test_reorder_holds_a_packet_back_for_reorder_hold_seconds() -> None:
    """Reordering is a bounded extra delay: packets sent meanwhile overtake the held one,
    packets sent after ``reorder_hold`` do not."""
    from gcu_async.sim.exchange import Exchange

    sim = GcuSimulator()
    sim.set_faults(FaultPlan(replies=FaultConfig(reorder=1.0, reorder_hold=0.05, seed=1)))
    exchange = Exchange(sim, stream=False)
    arrived: list[tuple[str, float]] = []
    loop = asyncio.get_running_loop()
    t0 = loop.time()

    def deliver(tag: str) -> None:
        arrived.append((tag, loop.time() - t0))

    direction = exchange._replies
    exchange._route(direction, b"first", lambda d: deliver("first"))
    sim.set_faults(FaultPlan())  # the next packets pass straight through
    exchange._route(direction, b"second", lambda d: deliver("second"))
    await asyncio.sleep(0.1)
    exchange._route(direction, b"third", lambda d: deliver("third"))
    exchange.close()
    assert [tag for tag, _ in arrived] == ["second", "first", "third"]
    assert 0.045 <= arrived[1][1] < 0.1
