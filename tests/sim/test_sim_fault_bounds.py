"""The documented bound of the fault model, checked in virtual time.

Every packet that gets through a direction is delivered between 0 and ``delay +
reorder_hold`` seconds after it entered, and both copies of a duplicate at the same time.
The exchange's timers run on a virtual event loop here, so the check is exact (the real
event loop only adds its own latency on top; test_sim_cli checks that over real sockets).
"""

from __future__ import annotations

import math
from collections import defaultdict

from hypothesis import given
from hypothesis import strategies as st

from gcu_async.protocol import decode_gcu_packet
from gcu_async.sim import FaultConfig, FaultPlan, GcuSimulator
from gcu_async.sim.exchange import Exchange
from helpers.sim.support import host_bytes
from helpers.sim.timers import VirtualLoop

EPS = 1e-9


def virtual_exchange(sim: GcuSimulator) -> tuple[Exchange, VirtualLoop]:
    loop = VirtualLoop()
    exchange = Exchange(sim, stream=False)
    exchange._loop = lambda: loop  # type: ignore[method-assign]
    return exchange, loop


CONFIGS = st.builds(
    FaultConfig,
    drop=st.sampled_from([0.0, 0.2]),
    corrupt=st.sampled_from([0.0, 0.3]),
    duplicate=st.floats(0, 1),
    reorder=st.floats(0, 1),
    delay=st.floats(0, 0.05),
    seed=st.integers(0, 2**32),
    reorder_hold=st.floats(0, 0.03),
)


@given(
    config=CONFIGS,
    gaps=st.lists(st.floats(0, 0.02), min_size=1, max_size=80),
    replies=st.booleans(),
)
def test_every_packet_is_delivered_within_delay_plus_hold(
    config: FaultConfig, gaps: list[float], replies: bool
) -> None:
    plan = FaultPlan(replies=config) if replies else FaultPlan(requests=config)
    sim = GcuSimulator(faults=plan)
    exchange, loop = virtual_exchange(sim)
    direction = exchange._replies if replies else exchange._requests
    sent: list[float] = []
    arrivals: dict[int, list[float]] = defaultdict(list)
    t = 0.0
    for i, gap in enumerate(gaps):
        t += gap
        loop.run_until(t)
        sent.append(loop.now)
        exchange._route(direction, bytes(72), lambda _d, i=i: arrivals[i].append(loop.now))
    loop.run_until(math.inf)
    bound = config.delay + config.reorder_hold
    for i, times in arrivals.items():
        assert len(times) in (1, 2)
        assert times[0] == times[-1]  # the copies of a duplicate leave together
        assert -EPS <= times[0] - sent[i] <= bound + EPS, (i, times, sent[i], bound)
    stats = (sim.reply_faults if replies else sim.request_faults).stats
    assert len(gaps) - len(arrivals) == stats.dropped
    assert sum(len(v) == 2 for v in arrivals.values()) == stats.duplicated
    # so a packet is only ever overtaken by packets sent less than ``bound`` after it
    for i in arrivals:
        for j in arrivals:
            if i < j and arrivals[j][0] < arrivals[i][0]:
                assert sent[j] - sent[i] < bound + EPS


def test_the_bound_is_reached_not_just_respected() -> None:
    config = FaultConfig(reorder=0.5, delay=0.01, reorder_hold=0.005, seed=4)
    sim = GcuSimulator(faults=FaultPlan(requests=config))
    exchange, loop = virtual_exchange(sim)
    latencies: list[float] = []
    for i in range(2000):
        loop.run_until(i * 0.02)
        start = loop.now
        exchange._route(exchange._requests, bytes(72),
                        lambda _d, s=start: latencies.append(loop.now - s))  # fmt: skip
    loop.run_until(math.inf)
    assert len(latencies) == 2000
    assert max(latencies) > 0.014  # close to 0.015 = delay + hold
    assert min(latencies) < 0.001
    held = [x for x in latencies if x >= 0.005]
    assert 0.4 < len(held) / 2000 < 0.8  # reordered half the time (plus large delays)


@given(config=CONFIGS, n=st.integers(1, 40))
def test_a_round_trip_is_within_twice_the_bound(config: FaultConfig, n: int) -> None:
    """Requests and replies both faulty: each reply leaves within 2 × (delay + hold) of
    its request (the model answers at once)."""
    config = FaultConfig(**{**config.__dict__, "corrupt": 0.0})
    sim = GcuSimulator(faults=config)  # both directions (replies: seed + 1)
    exchange, loop = virtual_exchange(sim)
    sent: list[float] = []
    replies: list[tuple[int, float]] = []

    def send(data: bytes) -> None:
        replies.append((round(decode_gcu_packet(data).main.attitude.yaw), loop.now))

    for i in range(n):
        loop.run_until(i * 0.01)
        sent.append(loop.now)
        exchange.feed(host_bytes(attitude=(0.0, 0.0, float(i))), send)
    loop.run_until(math.inf)
    bound = 2 * (config.delay + config.reorder_hold)
    for i, at in replies:
        assert -EPS <= at - sent[i] <= bound + EPS
    assert len(replies) <= 4 * n  # a duplicated request answered twice, each reply doubled
