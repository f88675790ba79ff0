"""Rig for the bridge's link tests: the simulator in-process with every host packet it gets
timed (the GCU side's count of the host rate), the bridge on the given MAVLink connections
plus a ``udpout`` ground station that records when each component's HEARTBEAT arrived."""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import os
import socket
import threading
import time
from collections.abc import AsyncIterator, Sequence
from dataclasses import dataclass, field
from typing import Any

from gcu_async.bridge import CameraConfig, MavlinkBridge
from gcu_async.bridge._mavlink import mavlink
from gcu_async.client.connect import connect
from gcu_async.sim import GcuSimulator
from helpers.bridge.rig import CAMERA, GCS, GIMBAL, SYSTEM, Peer

RATE_LOW, RATE_HIGH = 45, 51
"""The host rate every 1-s window at the GCU must stay within."""
HEARTBEAT_GAP = 1.5
"""Longest gap between two heartbeats of one component at the ground station (nominal 1 s)."""


@dataclass
class LinkRig:
    sim: GcuSimulator
    bridge: MavlinkBridge
    gcs: Peer
    host_packets: list[float] = field(default_factory=list)
    heartbeats: dict[int, list[float]] = field(default_factory=dict)
    wakeups: list[tuple[float, float]] = field(default_factory=list)
    """(monotonic, process CPU time) at each wake-up of a 5 ms sleeper on the loop."""

    async def watch_loop(self) -> None:
        """Record the loop's wake-ups: a failure report then tells the loop being held
        (CPU used) from the process not being scheduled (no CPU used)."""
        while True:
            self.wakeups.append((time.monotonic(), time.process_time()))
            if len(self.wakeups) > 20000:
                del self.wakeups[:10000]
            await asyncio.sleep(0.005)

    def loop_report(self, start: float, end: float) -> str:
        """The longest gap between the loop's wake-ups in [start, end] and the CPU time the
        process used during it."""
        marks = [w for w in self.wakeups if start <= w[0] <= end]
        if len(marks) < 2:
            return "no loop wake-ups recorded"
        gap, a, b = max((b[0] - a[0], a, b) for a, b in itertools.pairwise(marks))
        return (f"longest loop gap {gap * 1000:.0f} ms, the process used "
                f"{(b[1] - a[1]) * 1000:.0f} ms CPU in it")

    async def pump(self, seconds: float) -> None:
        """Let everything run ``seconds``, recording the ground station's heartbeats."""
        end = time.monotonic() + seconds
        while True:
            self.poll_gcs()
            if time.monotonic() >= end:
                return
            await asyncio.sleep(0.01)

    def poll_gcs(self) -> None:
        before = len(self.gcs.messages)
        self.gcs.poll()
        now = time.monotonic()
        for msg in self.gcs.messages[before:]:
            if msg.get_type() == "HEARTBEAT" and msg.get_srcSystem() == SYSTEM:
                self.heartbeats.setdefault(msg.get_srcComponent(), []).append(now)
        if len(self.gcs.messages) > 5000:
            del self.gcs.messages[:-1000]

    def rate_range(self, start: float, end: float) -> tuple[int, int]:
        """The fewest and most host packets the GCU got in a 1-s window in [start, end]."""
        times = [t for t in self.host_packets if start <= t <= end]
        counts = []
        t = start
        while t + 1.0 <= end:
            counts.append(sum(1 for x in times if t <= x < t + 1.0))
            t += 0.1
        return min(counts), max(counts)

    def check_rates(self, start: float, end: float) -> None:
        """Every 1-s window in [start, end] saw 45–51 host packets at the GCU, and each
        component's heartbeat reached the ground station at most 1.5 s apart."""
        low, high = self.rate_range(start, end)
        assert low >= RATE_LOW and high <= RATE_HIGH, (low, high, self.loop_report(start, end))
        for component in (GIMBAL, CAMERA):
            beats = [start] + [b for b in self.heartbeats.get(component, []) if start <= b <= end]
            beats.append(end)
            gaps = [b - a for a, b in itertools.pairwise(beats)]
            assert max(gaps) <= HEARTBEAT_GAP, (component, max(gaps))


def rss_mib() -> float:
    with open(f"/proc/{os.getpid()}/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    import resource  # POSIX only: the suite collects without it (tests/project/test_platforms.py)

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # pragma: no cover


def thread_count() -> int:
    return threading.active_count()


@contextlib.asynccontextmanager
async def link_rig(connections: Sequence[str], **options: Any) -> AsyncIterator[LinkRig]:
    """The simulator, the bridge on ``connections`` + a ground station, both heartbeats seen."""
    sim = GcuSimulator()
    gcs = Peer(*GCS)
    rig_times: list[float] = []
    handle = sim.model.handle_bytes

    def timed(data: bytes) -> Any:
        rig_times.append(time.monotonic())
        return handle(data)

    sim.model.handle_bytes = timed  # type: ignore[method-assign]
    try:
        async with sim.serve_udp("127.0.0.1", 0) as server:
            client = connect(server.url, local_port=0, check_support=True)
            bridge = MavlinkBridge(client, [*connections, gcs.url], system_id=SYSTEM,
                                   camera=CameraConfig(max_zoom=30.0), **options)  # fmt: skip
            async with bridge:
                await gcs.wait("HEARTBEAT", lambda m: m.get_srcComponent() == GIMBAL
                               and m.system_status == mavlink.MAV_STATE_ACTIVE, timeout=8.0)
                rig = LinkRig(sim, bridge, gcs, rig_times)
                watcher = asyncio.ensure_future(rig.watch_loop())
                try:
                    yield rig
                finally:
                    watcher.cancel()
                    with contextlib.suppress(asyncio.CancelledError):
                        await watcher
    finally:
        gcs.close()


def free_port(kind: int = socket.SOCK_DGRAM) -> int:
    with socket.socket(socket.AF_INET, kind) as sock:
        sock.bind(("127.0.0.1", 0))
        port: int = sock.getsockname()[1]
        return port
