"""Waiting for the physical world (docs/client.md, "Waiting for the gimbal, the zoom and the
link"): telemetry predicates, closed-loop moves, the link — against the simulator over UDP."""

from __future__ import annotations

import asyncio
import contextlib
import re
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

from gcu_async import GcuClient, LinkLost, Mode, WaitTimeout
from gcu_async.client.waiting import LINK_EVENTS_MAX, angle_error
from gcu_async.pytest_plugin import SimHandle
from gcu_async.transport.base import LinkEvent, LinkEventKind


@pytest.fixture
def gcu_client_options() -> dict[str, Any]:
    return {"silence_timeout": 0.3}


async def test_reach_attitude_returns_there_and_omitted_angles_keep_the_current_ones(
    gcu_client: GcuClient,
) -> None:
    sample = await gcu_client.reach_attitude(pitch=-20.0, yaw=40.0, timeout=15.0)
    assert sample.status.mode == Mode.EULER_CONTROL
    assert abs(sample.status.attitude.pitch + 20.0) <= 0.5
    assert angle_error(sample.status.attitude.yaw, 40.0) <= 0.5
    # only the pitch given: the yaw stays at 40 (not north, 0)
    await gcu_client.enter_euler_control(pitch=-45.0)
    there = await gcu_client.wait_attitude(pitch=-45.0, yaw=40.0, timeout=15.0)
    assert angle_error(there.status.attitude.yaw, 40.0) <= 0.5
    await asyncio.sleep(0.5)  # and it stays there
    assert angle_error(gcu_client.status.attitude.yaw, 40.0) <= 0.5
    assert abs(gcu_client.status.attitude.pitch + 45.0) <= 0.5


async def test_reach_attitude_with_no_angle_holds_the_current_attitude(
    gcu_client: GcuClient,
) -> None:
    await gcu_client.reach_attitude(yaw=120.0, pitch=-10.0, timeout=15.0)
    before = gcu_client.status.attitude
    sample = await gcu_client.reach_attitude(timeout=5.0)
    after = sample.status.attitude
    assert angle_error(after.yaw, before.yaw) <= 0.5
    assert abs(after.pitch - before.pitch) <= 0.5


async def test_reach_zoom_returns_at_the_ratio(gcu_client: GcuClient) -> None:
    sample = await gcu_client.reach_zoom(4.0, timeout=20.0)
    assert sample.info is not None and abs(sample.info.camera1_zoom - 4.0) <= 0.05
    sample = await gcu_client.reach_zoom(1.0, timeout=20.0)
    assert sample.info is not None and abs(sample.info.camera1_zoom - 1.0) <= 0.05


async def test_wait_for_returns_the_latest_sample_at_once_when_it_qualifies(
    gcu_client: GcuClient,
) -> None:
    calls: list[float] = []

    def always(sample: Any) -> bool:
        calls.append(sample.received_at)
        return True

    t0 = time.monotonic()
    sample = await gcu_client.wait_for(always, timeout=5.0)
    assert time.monotonic() - t0 < 0.015  # no wait for the next reply (one every 20 ms)
    assert sample.status is gcu_client.status
    assert len(calls) == 1


async def test_wait_for_times_out_with_what_and_the_last_sample(gcu_client: GcuClient) -> None:
    t0 = time.monotonic()
    with pytest.raises(WaitTimeout) as info:
        await gcu_client.wait_for(lambda s: False, timeout=0.3, what="a miracle")
    elapsed = time.monotonic() - t0
    assert 0.3 <= elapsed < 2.0
    err = info.value
    assert isinstance(err, TimeoutError)
    assert err.what == "a miracle" and err.timeout == 0.3
    assert err.last is not None and err.last.status is not None
    assert "a miracle: not reached within 0.3 s (last seen: mode" in str(err)


async def test_wait_attitude_timeout_names_the_target_and_what_was_seen(
    gcu_client: GcuClient,
) -> None:
    with pytest.raises(WaitTimeout, match=r"attitude pitch 89 \(±0\.1 deg\): not reached .*"
                                          r"last seen: mode .* pitch"):  # fmt: skip
        await gcu_client.wait_attitude(pitch=89.0, tolerance=0.1, timeout=0.2)


async def test_predicate_errors_reach_the_caller(gcu_client: GcuClient) -> None:
    def broken(sample: Any) -> bool:
        raise KeyError("boom")

    with pytest.raises(KeyError, match="boom"):
        await gcu_client.wait_for(broken, timeout=1.0)


async def test_the_link_waits_and_the_link_events_through_an_outage(
    gcu_sim: SimHandle, gcu_client: GcuClient
) -> None:
    events: list[LinkEvent] = []

    async def collect() -> None:
        async for event in gcu_client.link_events():
            events.append(event)

    collector = asyncio.create_task(collect())
    await asyncio.sleep(0)
    await gcu_client.wait_link(up=True, timeout=0.5)  # already up: at once
    gcu_sim.simulator.silence(1.0)
    t0 = time.monotonic()
    await gcu_client.wait_link(up=False, timeout=3.0)
    assert not gcu_client.link.up
    assert 0.25 <= time.monotonic() - t0 < 1.0  # silence_timeout 0.3 s
    # a wait on telemetry keeps going through the outage and succeeds after it
    sample = await gcu_client.wait_for(lambda s: True, timeout=5.0)
    assert gcu_client.link.up and sample.received_at >= t0 + 0.9
    await gcu_client.wait_link(up=True, timeout=0.5)
    await gcu_client.close()
    await asyncio.wait_for(collector, 2.0)  # the iterator ends when the client closes
    assert [e.kind for e in events] == [LinkEventKind.LOST, LinkEventKind.RESTORED]


async def test_waits_end_with_link_lost_when_the_client_closes(gcu_client: GcuClient) -> None:
    waits = [
        asyncio.create_task(gcu_client.wait_for(lambda s: False, timeout=10.0)),
        asyncio.create_task(gcu_client.wait_link(up=False, timeout=10.0)),
    ]
    await asyncio.sleep(0.1)
    await gcu_client.close()
    for wait in waits:
        with pytest.raises(LinkLost, match="closed while waiting"):
            await asyncio.wait_for(wait, 2.0)
    with pytest.raises(LinkLost, match="not open"):
        await gcu_client.wait_for(lambda s: True)
    with pytest.raises(LinkLost, match="not open"):
        await gcu_client.wait_link()
    with pytest.raises(LinkLost, match="not open"):
        async for _ in gcu_client.link_events():
            pass


async def test_wait_link_times_out(gcu_client: GcuClient) -> None:
    with pytest.raises(WaitTimeout, match=r"the link down: not reached within 0\.2 s"):
        await gcu_client.wait_link(up=False, timeout=0.2)


@pytest.mark.parametrize(
    ("call", "error", "match"),
    [
        (lambda g: g.wait_for(42), TypeError, "predicate"),
        (lambda g: g.wait_for(lambda s: True, timeout=0), ValueError, "timeout: 0"),
        (lambda g: g.wait_for(lambda s: True, timeout=True), TypeError, "timeout"),
        (lambda g: g.wait_for(lambda s: True, what=3), TypeError, "what"),
        (lambda g: g.wait_attitude(), ValueError, "at least one of roll, pitch, yaw"),
        (lambda g: g.wait_attitude(pitch=181.0), ValueError, r"pitch: 181\.0 .*\[-180, 180\]"),
        (lambda g: g.wait_attitude(yaw="north"), TypeError, "yaw"),
        (lambda g: g.wait_attitude(yaw=10.0, tolerance=0.0), ValueError, "tolerance: 0"),
        (lambda g: g.wait_attitude(yaw=10.0, tolerance=-1.0), ValueError, "tolerance"),
        (lambda g: g.wait_zoom(0.5), ValueError, r"ratio: 0\.5"),
        (lambda g: g.wait_zoom(2.0, tolerance=float("nan")), ValueError, "tolerance"),
        (lambda g: g.wait_link(up=1), TypeError, "up"),
        (lambda g: g.wait_link(timeout=-1.0), ValueError, "timeout"),
        (lambda g: g.reach_attitude(pitch=-180.5), ValueError, "pitch"),
        (lambda g: g.reach_attitude(pitch=-10.0, timeout=0.0), ValueError, "timeout"),
        (lambda g: g.reach_zoom(2.0, tolerance=0), ValueError, "tolerance"),
        (lambda g: g.enter_euler_control(yaw=1e30), ValueError, "yaw"),
    ],
)
async def test_wait_arguments_are_checked_before_anything_is_sent(
    gcu_sim: SimHandle, gcu_client: GcuClient, call: Any, error: type[Exception], match: str
) -> None:
    executed = dict(gcu_sim.simulator.model.executions)
    with pytest.raises(error, match=match):
        await call(gcu_client)
    await asyncio.sleep(0.1)
    assert dict(gcu_sim.simulator.model.executions) == executed  # nothing was sent


async def test_link_events_iterators_are_independent_and_bounded(
    gcu_sim: SimHandle, gcu_client: GcuClient
) -> None:
    first, second = gcu_client.link_events(), gcu_client.link_events()
    a = asyncio.create_task(first.__anext__())
    b = asyncio.create_task(second.__anext__())
    await asyncio.sleep(0)
    gcu_sim.simulator.silence(0.6)
    got = await asyncio.wait_for(asyncio.gather(a, b), 3.0)
    assert [e.kind for e in got] == [LinkEventKind.LOST, LinkEventKind.LOST]
    await first.aclose()
    await second.aclose()
    # a consumer that never reads keeps at most LINK_EVENTS_MAX events
    slow = gcu_client.link_events()
    c = asyncio.create_task(slow.__anext__())
    await asyncio.sleep(0)
    for _ in range(LINK_EVENTS_MAX + 10):
        gcu_client._links.emit(LinkEvent(LinkEventKind.PEER, "test"))
    assert (await c).kind is LinkEventKind.PEER
    received = 0
    with contextlib.suppress(asyncio.TimeoutError):
        while True:
            await asyncio.wait_for(slow.__anext__(), 0.1)
            received += 1
    assert received == LINK_EVENTS_MAX - 1 or received == LINK_EVENTS_MAX
    await slow.aclose()


def test_the_docs_waiting_example_runs(tmp_path: Path) -> None:
    """The example in docs/client.md ("Waiting for …") runs as a reader would run it."""
    text = (Path(__file__).resolve().parents[2] / "docs" / "client.md").read_text("utf-8")
    start = text.index("[start:waiting]")
    block = re.search(r"```python\n(.*?)```", text[start:], re.DOTALL)
    assert block is not None
    script = tmp_path / "waiting.py"
    script.write_text(block.group(1), encoding="utf-8")
    done = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                          timeout=60, check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].startswith("there: pitch -")
    assert abs(float(lines[0].split()[-1]) + 30.0) <= 0.5
    assert lines[1] == "zoom 4.0x"
    assert lines[2] == "timed out: the camera looking up"
