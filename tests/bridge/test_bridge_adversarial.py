"""The bridge contract under attack (docs/mavlink-bridge.md, "The bridge contract").

Real loopback sockets, a pymavlink ground station, the simulator in its own process
recording every execution and the time of every host packet it handles
(tests/helpers/bridge/sim_process.py), and floods from another process
(tests/helpers/bridge/mavlink_flood.py) into a
``udpin:`` link. A seeded generator builds schedules of
back-to-back commands that differ only in their parameters, retransmissions with rising
``confirmation``, stops; every command comes from its own (system, component), so each
answer is attributed. Checked after every step:

- every command gets final answers that agree, and nothing but ACCEPTED, CANCELLED or
  TEMPORARILY_REJECTED (FAILED only across a GCU link loss);
- ACCEPTED ⇔ executed exactly once (zoom ranges by their unique value; photos and
  continuous zooms by count); CANCELLED never executed; no double execution;
- every execution within COMMAND_WAIT + the wire timeout of its command's sending;
- a stop is never lost (always ACCEPTED, the last continuous zoom the GCU executed);
- the GCU host-packet rate in every whole second of the step, as the simulator received
  it: 45 ≤ n ≤ 51;
- bounded queue, memory (RSS) and thread count.
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import os
import pickle
import random
import subprocess
import sys
import threading
import time
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from gcu_async.bridge import CameraConfig, MavlinkBridge, admission
from gcu_async.bridge._mavlink import mavlink
from gcu_async.bridge.commands import CANCELLED
from gcu_async.client.connect import connect
from gcu_async.protocol import TakePhoto, ZoomIn, ZoomOut, ZoomStop, ZoomTo
from gcu_async.sim import ExecutionRecord
from helpers.bridge.link_rig import RATE_HIGH, RATE_LOW
from helpers.bridge.rig import AUTOPILOT, CAMERA, GCS, GIMBAL, Peer

ZOOM = mavlink.MAV_CMD_SET_CAMERA_ZOOM
PHOTO = mavlink.MAV_CMD_IMAGE_START_CAPTURE
CONTINUOUS = mavlink.ZOOM_TYPE_CONTINUOUS
RANGE = mavlink.ZOOM_TYPE_RANGE
ACCEPTED = mavlink.MAV_RESULT_ACCEPTED
IN_PROGRESS = mavlink.MAV_RESULT_IN_PROGRESS
REJECTED = mavlink.MAV_RESULT_TEMPORARILY_REJECTED
FAILED = mavlink.MAV_RESULT_FAILED
FLOOD = Path(__file__).parents[1] / "helpers" / "bridge" / "mavlink_flood.py"
SIM = Path(__file__).parents[1] / "helpers" / "bridge" / "sim_process.py"
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}
RSS_GROWTH_MIB = 30.0
THREAD_GROWTH = 2


def rss_mib() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096 / 2**20


class SimProcess:
    """The simulator in its own process (tests/helpers/bridge/sim_process.py): the bridge's load
    does not delay when it receives the host packets it counts."""

    def __init__(self, proc: asyncio.subprocess.Process, url: str) -> None:
        self.proc = proc
        self.url = url

    @classmethod
    async def start(cls, pod: str = "D-90Pro(TA)") -> SimProcess:
        proc = await asyncio.create_subprocess_exec(
            sys.executable, str(SIM), pod, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
            env=ENV)
        assert proc.stdout is not None
        url = (await asyncio.wait_for(proc.stdout.readline(), 20)).decode().strip()
        assert url.startswith("udp://"), url
        return cls(proc, url)

    async def ask(self, line: str) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(line.encode() + b"\n")
        await self.proc.stdin.drain()

    async def report(self) -> tuple[list[float], list[ExecutionRecord]]:
        await self.ask("report")
        assert self.proc.stdout is not None
        line = await asyncio.wait_for(self.proc.stdout.readline(), 10)
        times, log = pickle.loads(base64.b64decode(line))
        return times, log

    async def stop(self) -> None:
        with contextlib.suppress(OSError):
            await self.ask("quit")
        try:
            await asyncio.wait_for(self.proc.wait(), 5)
        except TimeoutError:
            self.proc.kill()
            await self.proc.wait()


@dataclass
class Rig:
    sim: SimProcess
    bridge: MavlinkBridge
    gcs: Peer
    packet_times: list[float] = field(default_factory=list)
    log: list[ExecutionRecord] = field(default_factory=list)

    async def refresh(self) -> None:
        self.packet_times, self.log = await self.sim.report()

    async def until(self, predicate: Callable[[], bool], timeout: float,
                    what: str) -> None:  # fmt: skip
        deadline = time.monotonic() + timeout
        while not predicate():
            if time.monotonic() > deadline:
                raise TimeoutError(f"{what}: not within {timeout} s")
            await asyncio.sleep(0.01)


@contextlib.asynccontextmanager
async def rig_with(extra_links: tuple[str, ...] = ()) -> AsyncIterator[Rig]:
    sim = await SimProcess.start()
    gcs = Peer(*GCS)
    autopilot = Peer(*AUTOPILOT)
    try:
        client = connect(sim.url, local_port=0, check_support=True)
        bridge = MavlinkBridge(client, [gcs.url, autopilot.url, *extra_links], system_id=1,
                               camera=CameraConfig(max_zoom=30.0))  # fmt: skip
        async with bridge:
            await gcs.wait("HEARTBEAT", lambda m: m.get_srcComponent() == GIMBAL
                           and m.system_status == mavlink.MAV_STATE_ACTIVE, timeout=10.0)
            yield Rig(sim, bridge, gcs)
    finally:
        gcs.close()
        autopilot.close()
        await sim.stop()


@dataclass
class Sent:
    source: tuple[int, int]
    command: int
    params: tuple[float, ...]
    at: float
    stop: bool = False
    unique: int | None = None
    """A zoom range's value in 1/10000 of the range (unique in the run): its execution is
    attributable."""


@dataclass
class Step:
    sent: list[Sent] = field(default_factory=list)
    started: float = 0.0


class Schedule:
    """Seeded generator of back-to-back command bursts from fresh (system, component)s."""

    def __init__(self, seed: int) -> None:
        self.rng = random.Random(seed)
        self.next_source = 0
        self.next_percent = 0

    def source(self) -> tuple[int, int]:
        n = self.next_source
        self.next_source += 1
        return 2 + n % 240, 100 + n // 240 % 100

    def command(self) -> tuple[int, tuple[float, ...], bool, int | None]:
        kind = self.rng.choice(["in", "out", "stop", "stop", "range", "range", "photo"])
        if kind == "photo":
            return PHOTO, (0, 0, 1), False, None
        if kind == "range":  # a value never used before in this run: attributable
            self.next_percent += 1
            percent = round(self.next_percent * 0.37 % 99 + 1, 2)
            return ZOOM, (RANGE, percent), False, round(percent * 100)
        value = {"in": 1.0, "out": -1.0, "stop": 0.0}[kind]
        return ZOOM, (CONTINUOUS, value), kind == "stop", None


async def send_burst(rig: Rig, schedule: Schedule, step: Step) -> None:
    """1–5 commands back to back, some followed by retransmissions (confirmation 1, 2)."""
    mav = rig.gcs.conn.mav
    burst = [(schedule.source(), *schedule.command()) for _ in range(schedule.rng.randint(1, 5))]
    for source, command, params, stop, unique in burst:
        mav.srcSystem, mav.srcComponent = source
        values = [*params, *([0.0] * (7 - len(params)))]
        mav.command_long_send(1, CAMERA, command, 0, *values)
        step.sent.append(Sent(source, command, tuple(values), time.monotonic(), stop, unique))
    for confirmation in (1, 2):
        if schedule.rng.random() < 0.5:
            await asyncio.sleep(schedule.rng.choice([0.0, 0.05, 0.3]))
            for s in schedule.rng.sample(step.sent, k=min(2, len(step.sent))):
                mav.srcSystem, mav.srcComponent = s.source
                mav.command_long_send(1, CAMERA, s.command, confirmation, *s.params)


def final_answers(rig: Rig, since: int) -> dict[tuple[int, int], list[int]]:
    rig.gcs.poll()
    out: dict[tuple[int, int], list[int]] = {}
    for m in rig.gcs.messages[since:]:
        if m.get_type() == "COMMAND_ACK" and m.result != IN_PROGRESS:
            out.setdefault((m.target_system, m.target_component), []).append(m.result)
    return out


async def check_rate(rig: Rig, start: float, end: float,
                     figures: dict[str, list[int]]) -> None:  # fmt: skip
    await rig.refresh()
    times = [t for t in rig.packet_times if start <= t < end]
    seconds = int(end - start)
    counts = [0] * seconds
    for t in times:
        k = int(t - start)
        if k < seconds:
            counts[k] += 1
    figures.setdefault("rate", []).extend(counts)
    assert all(RATE_LOW <= n <= RATE_HIGH for n in counts), counts


async def run_step(rig: Rig, schedule: Schedule, figures: dict[str, list[int]],
                   *, link_loss: bool = False, foreign_photos: bool = False) -> None:  # fmt: skip
    step = Step(started=time.monotonic())
    since = len(rig.gcs.messages)
    await rig.refresh()
    log_start = len(rig.log)
    await send_burst(rig, schedule, step)
    sources = {s.source for s in step.sent}
    bound = admission.COMMAND_WAIT + rig.bridge.client.command_timeout
    await rig.until(lambda: sources <= final_answers(rig, since).keys(), bound + 3.0,
                    "every command answered")  # fmt: skip
    await asyncio.sleep(0.05)  # retransmissions' answers
    answers = final_answers(rig, since)
    await rig.refresh()
    runs = rig.log[log_start:]
    allowed = {ACCEPTED, CANCELLED, REJECTED} | ({FAILED} if link_loss else set())
    result: dict[tuple[int, int], int] = {}
    for s in step.sent:
        results = answers[s.source]
        assert len(set(results)) == 1, (s, results)  # re-answers agree
        assert results[0] in allowed, (s, results)
        result[s.source] = results[0]
        if s.stop and not link_loss:
            assert results[0] == ACCEPTED, f"a stop was lost: {s} -> {results}"
    # attributable executions: each unique zoom range at most once, ⇔ ACCEPTED
    for s in step.sent:
        if s.unique is not None:
            ran = [r for r in runs if isinstance(r.command, ZoomTo)
                   and r.command.fraction is not None
                   and round(r.command.fraction * 10000) == s.unique]  # fmt: skip
            assert len(ran) <= 1, f"executed twice: {s}"
            if result[s.source] == ACCEPTED:
                assert len(ran) == 1, f"ACCEPTED without execution: {s}"
            elif result[s.source] != FAILED:
                assert not ran, f"executed but answered {result[s.source]}: {s}"
    photos = [s for s in step.sent if s.command == PHOTO]
    accepted_photos = sum(result[s.source] == ACCEPTED for s in photos)
    if not foreign_photos:  # (a flood's photos run too: then only the answers count)
        assert sum(isinstance(r.command, TakePhoto) for r in runs) == accepted_photos
    continuous = [s for s in step.sent if s.command == ZOOM and s.params[0] == CONTINUOUS]
    moves = [r for r in runs if isinstance(r.command, (ZoomIn, ZoomOut, ZoomStop))]
    assert len(moves) == sum(result[s.source] == ACCEPTED for s in continuous)
    if continuous and continuous[-1].stop and not link_loss:
        assert isinstance(moves[-1].command, ZoomStop)
    for r in runs:  # nothing later than the bound (counted from before the first send)
        assert r.time - step.started <= bound, r
    assert all(len(waiting) <= admission.MAX_WAITING_PER_SHARE
               for waiting in rig.bridge.executor.queue.shares.values())  # fmt: skip
    for share in rig.bridge.shares():
        assert len(share.memory.keys) <= admission.MAX_REMEMBERED + 1


def flood(port: int, kind: str, rate: int, seconds: float, pairs: int) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, str(FLOOD), str(port), kind, str(rate),
                             str(seconds), str(pairs)], stdout=subprocess.PIPE, text=True)


async def steps_for(rig: Rig, schedule: Schedule, seconds: float,
                    figures: dict[str, list[int]], **options: bool) -> None:  # fmt: skip
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        await run_step(rig, schedule, figures, **options)


@pytest.mark.parametrize("seed", [1, 2])
async def test_generated_schedules_keep_the_contract(seed: int) -> None:
    schedule = Schedule(seed)
    figures: dict[str, list[int]] = {}
    async with rig_with() as rig:
        threads, rss = threading.active_count(), rss_mib()
        start = time.monotonic()
        await steps_for(rig, schedule, 6.0, figures)
        await check_rate(rig, start + 0.5, time.monotonic(), figures)
        assert threading.active_count() <= threads + THREAD_GROWTH
        assert rss_mib() - rss < RSS_GROWTH_MIB
        print(f"\nseed {seed}: {schedule.next_source} commands, rate/s {figures['rate']}")


@pytest.mark.parametrize(("kind", "rate", "pairs"), [("command", 5000, 4000),
                                                      ("attitude", 5000, 2000)])
async def test_floods_from_thousands_of_senders(kind: str, rate: int, pairs: int) -> None:
    """A ground station keeps the contract while another process floods a udpin: link;
    the GCU rate holds, and a SET_ATTITUDE flood asking for another mode in every message
    changes the pod's mode a bounded number of times."""
    schedule = Schedule(7)
    figures: dict[str, list[int]] = {}
    seconds = 4.0
    async with rig_with(extra_links=("udpin:127.0.0.1:0",)) as rig:
        port = rig.bridge.links[-1].local_address[1]  # type: ignore[attr-defined]
        threads, rss = threading.active_count(), rss_mib()
        await rig.refresh()
        log_start = len(rig.log)
        proc = flood(port, kind, rate, seconds, pairs)
        try:
            start = time.monotonic()
            await steps_for(rig, schedule, seconds, figures, foreign_photos=True)
            end = time.monotonic()
        finally:
            out, _ = await asyncio.to_thread(proc.communicate, timeout=20)
        await check_rate(rig, start + 0.5, min(end, start + seconds), figures)
        modes = [r for r in rig.log[log_start:]
                 if type(r.command).__name__ in ("PointingLock", "PointingFollow")]  # fmt: skip
        assert threading.active_count() <= threads + THREAD_GROWTH
        growth = rss_mib() - rss
        assert growth < RSS_GROWTH_MIB
        assert all(len(waiting) <= admission.MAX_WAITING_PER_SHARE
                   for waiting in rig.bridge.executor.queue.shares.values())  # fmt: skip
        print(f"\n{kind} flood: {out.strip()} sent, {rig.bridge.stats['messages']} received, "
              f"rate/s {figures['rate']}, mode changes {len(modes)}, RSS +{growth:.1f} MiB, "
              f"stats {rig.bridge.stats}")
        if kind == "attitude":
            assert len(modes) <= seconds / admission.MESSAGE_MODE_INTERVAL + 2


async def test_gcu_link_loss_mid_command_is_never_accepted() -> None:
    schedule = Schedule(11)
    figures: dict[str, list[int]] = {}
    async with rig_with() as rig:
        await rig.sim.ask("silence 3")  # the GCU stops answering (and executing) mid-schedule
        await run_step(rig, schedule, figures, link_loss=True)
        await asyncio.sleep(3.0)
        await rig.until(lambda: rig.bridge.view().link_up, 8.0, "GCU link back")
        await steps_for(rig, schedule, 2.0, figures)  # and it keeps the contract after
