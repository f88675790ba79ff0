"""The client over bad links, against the simulator: loss, corruption, duplication,
reordering, TCP connection kills, silence. (Bad arguments, which must never be sent: the
misuse cases in test_client_boundary.py.)"""

from __future__ import annotations

import asyncio
import time
import warnings
from collections import Counter
from collections.abc import Awaitable, Callable
from typing import Any

import pytest

from gcu_async import GcuClient, LinkLost, Opcode
from gcu_async.pytest_plugin import SimHandle
from gcu_async.sim import FaultConfig, FaultPlan
from helpers.scale import FULL

Step = tuple[Opcode, Callable[[GcuClient], Awaitable[Any]]]
STEPS: list[Step] = [
    (Opcode.TAKE_PHOTO, lambda g: g.take_photo()),
    (Opcode.FOCUS, lambda g: g.focus()),
    (Opcode.ZOOM_STOP, lambda g: g.stop_zoom()),
    (Opcode.OSD, lambda g: g.set_osd(True)),
    (Opcode.TAKE_PHOTO, lambda g: g.take_photo()),  # same opcode twice in a row
    (Opcode.DIGITAL_ZOOM, lambda g: g.set_digital_zoom(True)),
    (Opcode.TARGET_DETECTION, lambda g: g.set_target_detection(False)),
]


def bad_link(seed: int) -> FaultPlan:
    def one(s: int) -> FaultConfig:
        # reordering holds a packet back 5 ms (+ up to 3 ms delay); the client's guard
        # (25 ms here) must exceed that plus the event loop's lag on a loaded machine
        return FaultConfig(
            drop=0.3, corrupt=0.05, duplicate=0.05, reorder=0.05, delay=0.003,
            reorder_hold=0.005, seed=s,
        )  # fmt: skip

    return FaultPlan(requests=one(seed), replies=one(seed + 1))


@pytest.fixture
def gcu_sim_transport() -> str:
    return "udp"


def client(gcu_sim: SimHandle, rate_hz: float = 200.0, **options: Any) -> GcuClient:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # > 50 Hz to keep the test short
        return gcu_sim.client(rate_hz=rate_hz, **options)


@pytest.mark.parametrize("seed", [11, 29] if FULL else [11])  # see tests/helpers/scale.py
async def test_500_commands_over_a_bad_link_run_exactly_once(gcu_sim: SimHandle, seed: int) -> None:
    gcu_sim.set_faults(bad_link(seed))
    model = gcu_sim.simulator.model
    submitted: Counter[int] = Counter()
    async with client(
        gcu_sim, command_timeout=10.0, connect_timeout=5.0, reorder_guard=0.025
    ) as gcu:
        stalls = 0

        async def watch_heartbeat() -> None:
            # the heartbeat never stops: every quarter second brings new ticks
            nonlocal stalls
            while True:
                before = gcu.link.packets_sent
                await asyncio.sleep(0.25)
                stalls += gcu.link.packets_sent == before

        watcher = asyncio.create_task(watch_heartbeat())
        try:
            for i in range(500):
                opcode, call = STEPS[i % len(STEPS)]
                submitted[opcode] += 1
                feedback = await call(gcu)
                assert feedback.opcode == opcode
            assert not watcher.done(), watcher  # it watched all along (did not crash)
        finally:
            watcher.cancel()
        assert stalls == 0
        assert gcu.link.lost_count == 0
        faults = gcu_sim.simulator.request_faults.stats
    # every command ran exactly once on the GCU: none twice, none skipped
    assert {op: model.executions[op] for op in submitted} == dict(submitted)
    assert faults.dropped > 0  # the link really was bad
    assert model.stats.crc_errors > 0


@pytest.fixture
def tcp_options() -> dict[str, Any]:
    return {}


@pytest.mark.parametrize("gcu_sim_transport", ["tcp"])
async def test_tcp_connection_killed_20_times(gcu_sim: SimHandle) -> None:
    model = gcu_sim.simulator.model
    ok: Counter[int] = Counter()
    attempted: Counter[int] = Counter()
    lost_fast = 0
    async with client(gcu_sim, rate_hz=50.0, silence_timeout=2.0) as gcu:
        for kill in range(20):
            for i in range(3):
                opcode, call = STEPS[(kill * 3 + i) % len(STEPS)]
                attempted[opcode] += 1
                await call(gcu)
                ok[opcode] += 1
            assert gcu_sim.kill_connection()
            # the link is lost at once: a command now fails fast instead of hanging
            deadline = time.monotonic() + 2.0
            while gcu.link.up and time.monotonic() < deadline:
                await asyncio.sleep(0.005)
            assert not gcu.link.up
            t0 = time.monotonic()
            with pytest.raises(LinkLost):
                await gcu.take_photo()
            assert time.monotonic() - t0 < 0.05
            lost_fast += 1
            # ... and comes back by itself
            deadline = time.monotonic() + 5.0
            while not gcu.link.up and time.monotonic() < deadline:
                await asyncio.sleep(0.01)
            assert gcu.link.up, f"no reconnect after kill {kill + 1}"
        await gcu.take_photo()
        ok[Opcode.TAKE_PHOTO] += 1
        attempted[Opcode.TAKE_PHOTO] += 1
        assert gcu.link.lost_count == 20
        assert gcu.link.restored_count == 20
    assert lost_fast == 20
    for opcode in attempted:
        assert ok[opcode] <= model.executions[opcode] <= attempted[opcode]


async def test_waiting_command_fails_fast_when_link_goes_down(gcu_sim: SimHandle) -> None:
    async with client(gcu_sim, rate_hz=50.0, silence_timeout=0.3) as gcu:
        await gcu.take_photo()
        gcu_sim.silence(3.0)
        t0 = time.monotonic()
        with pytest.raises(LinkLost) as info:
            await gcu.execute(gcu_command_focus(), timeout=10.0)
        waited = time.monotonic() - t0
        assert isinstance(info.value, ConnectionError)
        assert waited < 1.5  # the silence timeout, not the 10 s command timeout
        t0 = time.monotonic()
        with pytest.raises(LinkLost):
            await gcu.take_photo()
        assert time.monotonic() - t0 < 0.05
        gcu_sim.silence(0)
        deadline = time.monotonic() + 3.0
        while not gcu.link.up and time.monotonic() < deadline:
            await asyncio.sleep(0.01)
        assert gcu.link.up
        assert gcu.link.restored_count == 1
        await gcu.take_photo()


def gcu_command_focus() -> Any:
    from gcu_async.protocol import Focus

    return Focus()
