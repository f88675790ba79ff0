"""The bridge through GCU outages over real parts (docs/mavlink-bridge.md, "Robustness"): the
GCU is a simulator process (tests/helpers/sim/outage_rig.py) on UDP, TCP and a pty behind a symlink,
power-cycled while the bridge runs with a pymavlink ground station; outages of 2 s on each
transport, and 30 s and 120 s on each, all six at once (the suite's wall time grows by one
outage).

For each: the gimbal's HEARTBEAT says ``MAV_STATE_CRITICAL`` while the GCU is away and
``MAV_STATE_ACTIVE`` again within :data:`RECOVERY` seconds of its return; the client below
the bridge reports the loss, the return and the restart (the station had zoomed to 15x: the
GCU came back at 1x); the station's zoom and photo are ACCEPTED before, a photo after, and
each run of the GCU executes exactly what was asked of it (nothing twice, nothing the station
did not ask)."""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections import Counter
from collections.abc import AsyncIterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from gcu_async import connect
from gcu_async.bridge import CameraConfig, MavlinkBridge
from gcu_async.bridge._mavlink import mavlink
from gcu_async.transport import LinkEvent, LinkEventKind
from helpers.bridge.rig import CAMERA, GCS, GIMBAL, SYSTEM, Peer
from helpers.sim.outage_rig import SCHEMES, OutageRig

pytestmark = pytest.mark.subprocess

K = LinkEventKind
RECOVERY = 10.0
"""Seconds within which the bridge says ACTIVE again after the GCU returns."""
PHOTO = Counter({"TAKE_PHOTO": 1})
ZOOM = 15.0
"""The ratio the station zooms to before the outage: half of CameraConfig's 30x."""


def gimbal(state: int) -> Any:
    return lambda m: m.get_srcComponent() == GIMBAL and m.system_status == state


@dataclass
class Cycle:
    """What one power cycle under the bridge showed."""

    scheme: str
    down: float
    acks: list[int] = field(default_factory=list)
    recovered_in: float = -1.0
    events: list[LinkEvent] = field(default_factory=list)
    runs: list[Counter[str]] = field(default_factory=list)

    def check(self) -> None:
        label = f"{self.scheme}, {self.down:g} s"
        assert self.acks == [mavlink.MAV_RESULT_ACCEPTED] * 3, (label, self.acks)
        assert 0.0 <= self.recovered_in <= RECOVERY, (label, self.recovered_in)
        kinds = [e.kind for e in self.events if e.kind is not K.ERROR]
        assert kinds == [K.LOST, K.RESTORED, K.RESTARTED], (label, self.events)
        assert f"zoom {ZOOM:g}x -> 1x" in self.events[-1].detail, (label, self.events[-1])
        assert self.runs == [PHOTO + Counter({"ZOOM_TO": 1}), PHOTO], (label, self.runs)


@contextlib.asynccontextmanager
async def polled(peer: Peer) -> AsyncIterator[None]:
    """Keep reading ``peer``'s socket (a long outage fills no buffer unread)."""
    async def poll() -> None:
        while True:
            peer.poll()
            await asyncio.sleep(0.02)

    task = asyncio.create_task(poll())
    try:
        yield
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task


async def photo(gcs: Peer) -> int:
    ack = await gcs.run(CAMERA, mavlink.MAV_CMD_IMAGE_START_CAPTURE, 0, 0, 1, 0, timeout=8.0)
    return int(ack.result)


async def cycle(rig: OutageRig, down: float) -> Cycle:
    """A bridge up against ``rig`` (running), a photo, a power cycle of ``down`` seconds, the
    bridge back, a photo."""
    result = Cycle(rig.scheme, down)
    gcs = Peer(*GCS)
    client = connect(rig.url, check_support=True, max_zoom=2 * ZOOM,
                     **({"local_port": 0} if rig.scheme == "udp" else {}))  # fmt: skip
    client.on_link_change(result.events.append)
    try:
        async with MavlinkBridge(client, [gcs.url], system_id=SYSTEM,
                                 camera=CameraConfig(max_zoom=2 * ZOOM)), polled(gcs):
            await gcs.wait("HEARTBEAT", gimbal(mavlink.MAV_STATE_ACTIVE), timeout=15.0)
            result.events.clear()  # the first UP: not part of the outage
            zoom = await gcs.run(CAMERA, mavlink.MAV_CMD_SET_CAMERA_ZOOM, mavlink.ZOOM_TYPE_RANGE,
                                 50, timeout=8.0)  # fmt: skip
            result.acks.append(int(zoom.result))
            await client.wait_zoom(ZOOM, timeout=30.0)
            result.acks.append(await photo(gcs))
            await asyncio.sleep(1.5)  # still: no change under way when the GCU goes
            off = asyncio.create_task(rig.restart(down))
            await gcs.wait("HEARTBEAT", gimbal(mavlink.MAV_STATE_CRITICAL),
                           timeout=min(down, 5.0) + 5.0)  # fmt: skip
            await off
            back = rig.started_at[-1]
            await gcs.wait("HEARTBEAT", gimbal(mavlink.MAV_STATE_ACTIVE), timeout=RECOVERY + 5.0)
            result.recovered_in = time.monotonic() - back
            result.acks.append(await photo(gcs))
            await asyncio.sleep(0.5)
    finally:
        gcs.close()
    await rig.stop()
    result.runs = rig.runs
    return result


@contextlib.asynccontextmanager
async def rigs(tmp_path: Path, names: list[str]) -> AsyncIterator[list[OutageRig]]:
    made: list[OutageRig] = []
    try:
        for name in names:
            directory = tmp_path / name
            directory.mkdir()
            made.append(OutageRig(name.partition("-")[0], directory))
        yield made
    finally:
        for rig in made:
            await rig.close()


@pytest.mark.parametrize("scheme", SCHEMES)
async def test_a_2_s_power_cycle(scheme: str, tmp_path: Path) -> None:
    async with rigs(tmp_path, [scheme]) as (rig,):
        await rig.start()
        result = await cycle(rig, 2.0)
    result.check()


@pytest.mark.timeout(600)
async def test_30_s_and_120_s_power_cycles_on_every_transport(tmp_path: Path) -> None:
    cases = [(scheme, down) for scheme in SCHEMES for down in (30.0, 120.0)]
    async with rigs(tmp_path, [f"{scheme}-{down:g}" for scheme, down in cases]) as made:
        await asyncio.gather(*(rig.start() for rig in made))
        results = await asyncio.gather(*(
            cycle(rig, down) for rig, (_, down) in zip(made, cases, strict=True)))
    for result in results:
        result.check()
