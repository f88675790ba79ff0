"""The session contract over real sockets: the client against the simulator (in a process of
its own where the fault timing matters), faults from the simulator or a proxy; and the
issue's other failures on real links (a stalled TCP peer, a busy event loop, concurrent
callers, reopening)."""

from __future__ import annotations

import asyncio
import itertools
import random
import statistics
import time
from collections import Counter
from typing import Any

import pytest

from gcu_async import (
    CommandError,
    CommandLinkLost,
    GcuClient,
    LinkLost,
    Outcome,
    connect,
)
from gcu_async.protocol import Command, HostPacket, Mode, Opcode, ZoomTo, decode_host_packet
from gcu_async.sim import GcuSimulator, SimulatorModel
from helpers.scale import FULL, scaled
from helpers.session.vtime import tagged_commands
from helpers.sim.process import SimProcess
from helpers.transport.fault_proxy import DelayNullRequests, DropFirstReplyOfEachCommand, FaultProxy


def key(command: Command) -> tuple[str, str]:
    """How the simulator's log names an execution."""
    return command.OPCODE.name, command.encode_params().hex(" ") or "-"


async def drive(gcu: GcuClient, commands: list[Command], seed: int) -> list[tuple[Command, Any]]:
    """Run ``commands`` in small concurrent bursts; (command, result or error) each."""
    rng = random.Random(seed)
    results: list[tuple[Command, Any]] = []
    it = iter(commands)
    while burst := list(itertools.islice(it, rng.choice([1, 1, 2, 5]))):
        outcomes = await asyncio.gather(*(gcu.execute(c) for c in burst), return_exceptions=True)
        results += zip(burst, outcomes, strict=True)
        while not gcu.link.up:  # an outage: commands fail at once until replies return
            await asyncio.sleep(0.05)
    return results


def check_truthful(
    results: list[tuple[Command, Any]], executed: Counter[tuple[str, str]]
) -> Counter[str]:
    """No command executed twice; successes and failures executed once, "not sent" never."""
    doubles = {k: n for k, n in executed.items() if n > 1}
    assert not doubles, f"executed more than once: {doubles}"
    outcomes: Counter[str] = Counter()
    for command, result in results:
        n = executed[key(command)]
        if isinstance(result, CommandError):
            outcomes[result.outcome.name] += 1
            if result.outcome is Outcome.NOT_SENT:
                assert n == 0, (command, result)
            elif result.outcome is Outcome.FAILED:
                assert n == 1, (command, result)
        elif isinstance(result, BaseException):
            raise result
        else:
            outcomes["SUCCEEDED"] += 1
            assert n == 1 and result.status == 0, f"false success: {command} executed {n}x"
    return outcomes


@pytest.mark.timeout(300)
async def test_udp_loss_corruption_duplication_and_reordering_below_the_guard() -> None:
    """30 % loss, 5 % corruption, 5 % duplication each way, 20 % of packets held 5 or 10 ms
    (below the 15 ms guard): 500 commands per hold, half of them repeating one opcode (each
    needs a proven null separation). 0 executed twice, 0 false outcomes. A reduced-size run
    (tests/helpers/scale.py): the 10 ms hold only, 200 commands.

    The hold is a timer in another Python process, so the delay a packet really gets is the
    hold plus that process's event-loop latency (reading the datagram, firing the timer),
    which this test cannot see. A 13 ms hold left 2 ms for that latency, and on the shared
    2-core CI machine a command was executed twice at 13 ms (3.13, one of 200 commands)
    with nothing else running: the run broke assumption A4, not the client. So the holds
    keep at least 5 ms of slack; the boundary itself (13 ms, and the guard x 0.999) is
    tested in virtual time, where delays are exact (test_session_contract.py,
    test_session_regressions.py)."""

    holds = [(0.005, 1), (0.010, 2)] if FULL else [(0.010, 3)]
    n = scaled(500, 200)

    async def one(hold: float, seed: int) -> Counter[str]:
        sim = SimProcess("--listen", "udp://127.0.0.1:0", "--loss", "0.3", "--corrupt", "0.05",
                         "--duplicate", "0.05", "--reorder", "0.2", "--reorder-hold", str(hold),
                         "--seed", str(seed))  # fmt: skip
        try:
            same = list(itertools.islice(tagged_commands("same", seed * 1000), n // 2))
            mixed = list(itertools.islice(tagged_commands("mixed", seed * 1000 + 500), n // 2))
            commands = [c for pair in zip(same, mixed, strict=True) for c in pair]
            async with connect(sim.url, local_port=0) as gcu:
                results = await drive(gcu, commands, seed)
                assert gcu.link.packets_sent > 0
        finally:
            executed = sim.executions()
        return check_truthful(results, executed)

    outcomes = await asyncio.gather(*(one(hold, seed) for hold, seed in holds))
    for counts in outcomes:
        assert sum(counts.values()) == n
        assert counts["SUCCEEDED"] > n * 0.9, counts


async def test_nulls_delayed_10ms_and_each_first_reply_dropped_by_a_proxy() -> None:
    """The issue's link through a real proxy: every null request held 10 ms, the first reply
    of each command dropped. 40 zoom-to commands (one opcode, each separated by nulls)."""
    sim = SimProcess("--listen", "udp://127.0.0.1:0")
    try:
        host, _, port = sim.url.removeprefix("udp://").rpartition(":")
        nulls, first = DelayNullRequests(0.010), DropFirstReplyOfEachCommand()
        async with FaultProxy((host, int(port)), requests=nulls, replies=first) as proxy:
            url = f"udp://{proxy.address[0]}:{proxy.address[1]}"
            async with connect(url, local_port=0) as gcu:
                commands: list[Command] = [ZoomTo(ratio=1.0 + i / 10) for i in range(40)]
                results = [(c, await gcu.execute(c)) for c in commands]
        assert nulls.delayed > 0 and first.dropped >= 40
    finally:
        executed = sim.executions()
    assert check_truthful(results, executed) == Counter(SUCCEEDED=40)


class Recorder:
    """Wraps a simulator model's ``handle`` to record (time, packet, mode before)."""

    def __init__(self, sim: GcuSimulator) -> None:
        self.packets: list[tuple[float, HostPacket, Mode]] = []
        model = sim.model
        original = model.handle

        def handle(packet: HostPacket) -> Any:
            self.packets.append((time.monotonic(), packet, model.state.mode))
            return original(packet)

        model.handle = handle  # type: ignore[method-assign]


async def test_tcp_peer_that_stalls_cannot_run_stale_control_packets_later() -> None:
    """A GCU that stops reading for 3 s: the command in flight fails as "outcome unknown",
    the link is reset (RST) and reconnected, and control values go out valid for at most
    ``control_silence`` (0.2 s) after the last reply (docs/client.md, rule 4): so of what the
    GCU processes when it resumes, only packets sent in that window steer it.

    The rule is checked on the client's own clock (send times against the arrival of the
    latest reply), which a loaded machine cannot blur; counting the GCU's packets by the
    simulator's processing time cannot bound them exactly (a late timer on a busy loop puts
    one more heartbeat into the window: 14 were seen under load against 10-13 idle)."""
    sim = GcuSimulator(SimulatorModel(record_executions=True))
    recorder = Recorder(sim)
    sends: list[tuple[float, bytes]] = []
    replies: list[float] = []
    async with sim.serve_tcp("127.0.0.1", 0) as server:
        lost = asyncio.Event()
        async with connect(server.url) as gcu:
            send, receive = gcu.transport.send, gcu.session.receive

            def tap_send(data: bytes) -> None:
                sends.append((time.monotonic(), bytes(data)))
                send(data)

            def tap_receive(data: bytes, *args: Any, **kwargs: Any) -> None:
                replies.append(time.monotonic())
                receive(data, *args, **kwargs)

            gcu.transport.send = tap_send  # type: ignore[method-assign]
            gcu.session.receive = tap_receive  # type: ignore[method-assign]
            gcu.on_link_change(lambda e: lost.set() if e.kind.value == "lost" else None)
            await gcu.enter_pointing_lock(yaw_rate=5.0)
            await asyncio.sleep(0.2)
            assert gcu.control_valid
            sim.stall(3.0)
            stalled_at = time.monotonic()
            with pytest.raises(CommandLinkLost) as info:
                await gcu.take_photo()
            assert info.value.outcome is Outcome.UNKNOWN  # it may still execute: and it does
            await asyncio.wait_for(lost.wait(), 2.0)
            deadline = time.monotonic() + 10.0
            while not gcu.link.up:
                assert time.monotonic() < deadline, "the link never came back"
                await asyncio.sleep(0.05)
            await gcu.take_photo()  # the session works again
    # Rule 4 on the client's clock: every packet with valid control values went out at most
    # control_silence after the latest reply bytes (5 ms for the two clock reads around it).
    late = []
    for sent_at, data in sends:
        if not decode_host_packet(data).main.control_valid:
            continue
        before = [r for r in replies if r <= sent_at]
        if not before or sent_at - before[-1] > 0.2 + 0.005:
            late.append((sent_at - stalled_at, sent_at - before[-1] if before else None))
    assert not late, late
    window = [d for t, d in sends if stalled_at - 0.1 <= t < stalled_at + 3.5]
    valid_sent = [d for d in window if decode_host_packet(d).main.control_valid]
    assert 0 < len(valid_sent) < len(window)  # valid at first, then invalid
    # What the GCU processed when it resumed: valid packets only from that short window
    resumed = [(t, p) for t, p, _ in recorder.packets if t > stalled_at + 2.5]
    stale_valid = [p for t, p in resumed if p.main.control_valid and t < stalled_at + 3.5]
    assert resumed
    assert 0 < len(stale_valid) <= len(valid_sent), (len(stale_valid), len(valid_sent))
    photos = [e for e in sim.model.execution_log if e.command.OPCODE == Opcode.TAKE_PHOTO]
    assert len(photos) == 2  # the one reported "unknown" (it ran late) and the last one


async def test_busy_event_loop_does_not_make_replies_fall_behind() -> None:
    """20 ms event-loop iterations: the old client read one datagram per iteration, and
    command latency grew from 0.2 s to 1.4 s in 60 s while the link reported up."""
    sim = SimProcess("--listen", "udp://127.0.0.1:0", "--quiet")
    stop = asyncio.Event()

    async def hog() -> None:
        while not stop.is_set():
            time.sleep(0.02)  # noqa: ASYNC251 - a blocking 20 ms step, as busy applications have
            await asyncio.sleep(0)

    try:
        async with connect(sim.url, local_port=0) as gcu:
            task = asyncio.create_task(hog())
            latencies: list[tuple[float, float]] = []
            start = time.monotonic()
            while time.monotonic() - start < 8.0:
                t = time.monotonic()
                await gcu.take_photo()
                latencies.append((t - start, time.monotonic() - t))
            stop.set()
            await task
            assert gcu.link.lost_count == 0
    finally:
        sim.kill()
    first = statistics.median(lat for at, lat in latencies if at < 2.0)
    last = statistics.median(lat for at, lat in latencies if at > 6.0)
    assert last < first * 2 + 0.05, (first, last)


async def test_concurrent_mode_commands_never_cross_their_control_values() -> None:
    sim = GcuSimulator()
    recorder = Recorder(sim)
    async with sim.serve_udp("127.0.0.1", 0) as server, connect(server.url, local_port=0) as gcu:
        for _ in range(10):
            await asyncio.gather(
                gcu.enter_euler_control(pitch=-45.0, yaw=30.0),
                gcu.enter_pointing_lock(pitch_rate=5.0, yaw_rate=-5.0),
            )
            await asyncio.sleep(0.05)
            await asyncio.gather(gcu.enter_pointing_lock(pitch_rate=5.0, yaw_rate=-5.0),
                                 gcu.enter_euler_control(pitch=-45.0, yaw=30.0))  # fmt: skip
            await asyncio.sleep(0.05)
    angles = (0, -4500, 3000)
    valid = [(p.main.control, mode) for _, p, mode in recorder.packets if p.main.control_valid]
    assert valid
    for values, mode in valid:
        if tuple(values) == angles:
            assert mode is Mode.EULER_CONTROL, (values, mode)
        else:
            assert mode is Mode.POINTING_LOCK, (values, mode)


async def test_concurrent_start_recording_starts_it_once() -> None:
    sim = GcuSimulator(SimulatorModel(record_executions=True))
    async with sim.serve_udp("127.0.0.1", 0) as server, connect(server.url, local_port=0) as gcu:
        results = await asyncio.gather(gcu.start_recording(), gcu.start_recording(),
                                       gcu.start_recording())  # fmt: skip
        assert sum(r is not None for r in results) == 1
        assert sim.model.state.recording and gcu.recording is True
        results = await asyncio.gather(gcu.stop_recording(), gcu.stop_recording())
        assert sum(r is not None for r in results) == 1
        assert not sim.model.state.recording
    records = [e for e in sim.model.execution_log if e.command.OPCODE == Opcode.RECORD]
    assert len(records) == 2


async def test_200_concurrent_commands_with_default_timeouts_all_complete() -> None:
    sim = GcuSimulator(SimulatorModel(record_executions=True))
    async with sim.serve_udp("127.0.0.1", 0) as server, connect(server.url, local_port=0) as gcu:
        results = await asyncio.gather(*(gcu.take_photo() for _ in range(100)),
                                       *(gcu.focus() for _ in range(100)))  # fmt: skip
        assert all(r.status == 0 for r in results)
    assert len(sim.model.execution_log) == 200


async def test_a_client_is_reusable_but_not_reentrant() -> None:
    sim = GcuSimulator()
    async with sim.serve_udp("127.0.0.1", 0) as server:
        gcu = connect(server.url, local_port=0)
        for _ in range(3):  # close, then open again: works
            async with gcu:
                await gcu.take_photo()
            with pytest.raises(LinkLost):
                await gcu.take_photo()
        async with gcu:
            with pytest.raises(RuntimeError, match="not reentrant"):
                await gcu.open()
            with pytest.raises(RuntimeError, match="not reentrant"):
                async with gcu:
                    pass
            await gcu.take_photo()  # the failed entry did not disturb the open client
        opening = asyncio.create_task(gcu.open())
        await asyncio.sleep(0)
        with pytest.raises(RuntimeError, match="opening"):
            await gcu.open()
        await opening
        await gcu.close()
