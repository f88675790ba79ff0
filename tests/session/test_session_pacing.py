"""The heartbeat on a late event loop (docs/session-contract.md, "Guarantees", G4 and G6), in
virtual time on a modelled asyncio loop (tests/helpers/session/vloop.py): the session and the
simulator's GCU model, the loop's iterations as the schedule says.

The old pacer restarted the slot phase at any packet a whole period late: on a loop whose
iterations take about a period every packet was that late, so the next slot moved a period
further each time and the heartbeat fell to half the iteration rate (25 packets/s on 20 ms
iterations, 10/s on 50 ms ones).
"""

from __future__ import annotations

import bisect
import itertools
import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gcu_async.session import Session
from gcu_async.session.pacing import MARGIN
from gcu_async.session.session import MIN_WAKE
from helpers.session.vloop import OVERHEAD, LoopRig, regular
from helpers.session.vtime import tagged_commands

GUARD = 0.015


def run_heartbeat(busy: list[float], seconds: float, rate_hz: float = 50.0,
                  guard: float = GUARD) -> LoopRig:  # fmt: skip
    rig = LoopRig(Session(rate_hz=rate_hz, reorder_guard=guard), busy)
    rig.open()
    rig.run_until(seconds)
    return rig


def check_floor(rig: LoopRig, period: float) -> int:
    """G6 as docs/client.md states it, checked on everything the rig did: after a packet
    sent at t for slot s, the next slot is due by s + period if t < s + period; else at
    once (the current slot, owed), unless the poll after it came within half a period of
    t (then the current slot is dropped: the one after it). Every loop iteration that begins
    after that packet, once the next slot is due and at least MIN_WAKE after a poll that
    sent nothing (``next_wakeup``'s smallest step), sends a packet, unless G4's window is
    full then. Returns how many iterations G4's window held."""
    held = 0
    sends, slots, polls = rig.sent, rig.slots, rig.poll_times
    sent_by = set(rig.sent_poll)
    k = 0  # packets that went out before the iteration began
    for i, it in enumerate(rig.iterations):
        while k < len(sends) and sends[k][0] < it.start:
            k += 1
        if k == 0:
            continue
        t, s = sends[k - 1][0], slots[k - 1]
        due = s + period
        if due <= t:  # owed: the current slot, unless the next poll came soon
            current = due + period * math.floor((t - due) / period)
            j = rig.sent_poll[k - 1] + 1  # the poll after the one that sent it
            prompt = j < len(polls) and polls[j] - t < period / 2
            due = current + period if prompt else current
        end = rig.iterations[i + 1].start if i + 1 < len(rig.iterations) else math.inf
        if it.start < due or (k < len(sends) and sends[k][0] < end):
            continue
        if it.window_full:
            held += 1
            continue
        last = bisect.bisect_left(polls, it.start) - 1  # the last poll before it began
        if last not in sent_by and it.start < polls[last] + MIN_WAKE:
            continue  # that poll sent nothing: it asked for MIN_WAKE ahead at least
        raise AssertionError(f"iteration at {it.start:.5f} (busy {it.busy * 1000:.3g} ms) sent "
                             f"nothing; last packet at {t:.5f} for slot {s:.5f}, next due "
                             f"{due:.5f}")  # fmt: skip
    return held


def test_a_loop_turning_every_20ms_keeps_50_packets_per_second() -> None:
    """Four 5 ms chunks of other work per iteration (the issue's busy loop): the old pacer
    sent 25 packets/s."""
    rig = run_heartbeat(regular(0.020, 12.0), 11.0)
    sent = rig.sends_between(1.0, 11.0)
    iterations = sum(1 for it in rig.iterations if 1.0 <= it.start < 11.0)
    print(f"\n20 ms iterations: {sent / 10:.2f} packets/s, {iterations / 10:.2f} iterations/s")
    assert sent >= 48 * 10
    assert rig.max_in_window() <= 51
    assert check_floor(rig, 0.02) == 0
    rig.check()


@pytest.mark.parametrize("busy", [0.0201, 0.021, 0.025, 0.030, 0.050, 0.070, 0.200])
def test_a_slower_loop_sends_a_packet_every_iteration(busy: float) -> None:
    """Iterations longer than a period: one packet per iteration, the most a loop that runs
    the heartbeat's timer once per iteration can send (the old pacer: one every two; on
    50 ms iterations 10 packets/s against the loop's 20)."""
    rig = run_heartbeat(regular(busy, 32.0), 30.0)
    its = [it for it in rig.iterations if 2.0 <= it.start < 30.0]
    sent = rig.sends_between(its[0].start, its[-1].start + busy + OVERHEAD)
    print(f"\n{busy * 1000:g} ms iterations: {sent} packets in {len(its)} iterations")
    assert sent >= len(its)
    assert rig.max_in_window() <= 51
    assert check_floor(rig, 0.02) == 0


@pytest.mark.parametrize("busy", [0.001, 0.005, 0.0099, 0.0101, 0.0149, 0.019, 0.0199, 0.02])
def test_a_loop_turning_within_a_period_sends_every_slot(busy: float) -> None:
    """Iterations of at most a period: every slot's packet, except where G4's window is full
    (slots sent up to two iterations late on a loop of nearly a period's iterations make
    floor(rate_hz) + 1 packets within WINDOW + MARGIN now and then: that packet waits)."""
    rig = run_heartbeat(regular(busy, 32.0), 30.0)
    held = check_floor(rig, 0.02)
    sent = rig.sends_between(2.0, 30.0)
    print(f"\n{busy * 1000:g} ms iterations: {sent / 28:.2f} packets/s, G4 held {held}")
    assert sent >= 28 * 50 - 1 - held
    assert rig.max_in_window() <= 51


def test_uneven_iterations_that_average_a_period_keep_the_rate() -> None:
    """15 and 25 ms iterations in turn: a packet every iteration (a pacer that never owed a
    slot sent one every other iteration: 25/s)."""
    rig = run_heartbeat([0.015, 0.025] * 600, 20.0)
    sent = rig.sends_between(2.0, 20.0)
    print(f"\n15/25 ms iterations: {sent / 18:.2f} packets/s")
    assert sent >= 18 * 50 - 1
    assert rig.max_in_window() <= 51
    assert check_floor(rig, 0.02) == 0


@pytest.mark.parametrize("stall", [0.045, 0.067, 0.31, 0.319, 1.013, 2.537])
def test_after_a_stall_one_packet_then_the_old_phase(stall: float) -> None:
    """An idle loop, one iteration of ``stall`` s. After it: one packet at once (for the
    missed slots), none at the driver's next turn (the owed slot is dropped: sending it too
    would make floor(rate_hz) + 2 packets in the second that follows), then the slots on
    their old phase, no catch-up burst; G4 holds in every window, its check delaying a
    packet by at most MARGIN."""
    busy = [0.0] * 200 + [stall] + [0.0] * 600
    rig = run_heartbeat(busy, 8.0, guard=0.0)
    stalled = next(it for it in rig.iterations if it.busy == stall)
    end = stalled.start + stall
    times = [t for t, _, _ in rig.sent]
    before = [t for t in times if t < end]
    after = [t for t in times if t >= end]
    assert after[0] - end < 0.001
    phase = before[-1]
    for t in after[1:150]:  # the old phase (slots 20 ms apart), or G4's short delay
        offset = (t - phase) % 0.02
        assert min(offset, 0.02 - offset) < 1e-6 or offset <= MARGIN + 1e-6, (t - end, offset)
    assert after[1] - after[0] > 2 * OVERHEAD  # none at the driver's next turn: dropped
    assert rig.max_in_window() <= 51
    assert max(b - a for a, b in itertools.pairwise(after)) <= 0.02 + MARGIN + 1e-6
    assert check_floor(rig, 0.02) <= 2


# -- G4 and G6 as properties: random loop latency -------------------------------------------
class Schedule:
    def __init__(self, rate_hz: float, busy: list[float], commands: bool) -> None:
        self.rate_hz, self.busy, self.commands = rate_hz, busy, commands

    def __repr__(self) -> str:  # what hypothesis prints for a counterexample: the gist
        runs = [(len(list(g)), round(k * 1000, 3)) for k, g in itertools.groupby(self.busy)]
        return (
            f"Schedule(rate_hz={self.rate_hz}, busy=<(iterations, ms) runs "
            f"{runs[:30]}{' ...' if len(runs) > 30 else ''}>, commands={self.commands})"
        )


@st.composite
def schedules(draw: st.DrawFn) -> Schedule:
    """Stretches of iterations: idle, regular, jittered around a length, single stalls."""
    rate_hz = draw(st.sampled_from([50.0, 30.0, 100.0, 20.0, 50.5, 7.3]))
    busy: list[float] = []
    total = 0.0
    while total < 6.0:
        kind = draw(st.sampled_from(["idle", "regular", "jitter", "stall"]))
        if kind == "stall":
            stretch = [draw(st.sampled_from([0.03, 0.1, 0.45, 1.1]))]
        else:
            n = draw(st.integers(1, 150))
            if kind == "idle":
                stretch = [0.0] * n
            else:
                centre = draw(st.sampled_from([0.002, 0.009, 0.0199, 0.02, 0.0201, 0.025,
                                               0.033, 0.05, 0.08]))  # fmt: skip
                if kind == "regular":
                    stretch = [centre] * n
                else:
                    spread = draw(st.sampled_from([0.1, 0.5, 0.9]))
                    u = draw(st.lists(st.floats(0, 1), min_size=n, max_size=n))
                    stretch = [centre * (1 + spread * (2 * x - 1)) for x in u]
        busy += stretch
        total += sum(stretch) + 0.02 * stretch.count(0.0)
    return Schedule(rate_hz, busy, draw(st.booleans()))


@settings(max_examples=60, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])  # fmt: skip
@given(schedules())
def test_g4_and_the_heartbeat_floor_hold_on_any_loop_latency(sc: Schedule) -> None:
    """Any schedule of loop iterations, with or without commands (guard 0: no edge to wait
    for; a command submitted with nothing in flight goes early and restarts the phase):
    G4 in every window, the floor of G6, and the rest of the contract (exactly-once,
    truthful outcomes, no busy wake-up, poll and next_wakeup in agreement)."""
    session = Session(rate_hz=sc.rate_hz, reorder_guard=0.0 if sc.commands else GUARD,
                      command_timeout=1.0)  # fmt: skip
    rig = LoopRig(session, sc.busy)
    rig.open()
    if sc.commands:
        source = tagged_commands("mixed")

        def submit() -> None:
            rig.submit(next(source))

        for i in range(40):
            rig.at(0.3 + i * 0.13, submit)
    rig.run_until(sum(sc.busy) + 1.0)
    rig.check()
    assert rig.max_in_window() <= math.floor(sc.rate_hz) + 1
    check_floor(rig, 1.0 / sc.rate_hz)
    check_every_long_iteration(rig, 1.0 / sc.rate_hz)


def check_every_long_iteration(rig: LoopRig, period: float) -> None:
    """G6's first consequence, for the heartbeat alone: where iterations last a period or
    more, each sends a packet. Not checked: the first of such a stretch (it may begin
    before its slot), one that G4's window holds or that begins within MIN_WAKE of a poll
    G4 held, and one after an iteration in which a command was submitted (its poll may
    start it early, moving the phase, or be the poll that settles a late packet within
    half a period of it)."""
    its, polls = rig.iterations, rig.poll_times
    sends = [t for t, _, _ in rig.sent]
    sent_by = set(rig.sent_poll)
    for i in range(2, len(its) - 1):
        if any(it.busy < period for it in its[i - 2 : i + 1]) or its[i].window_full:
            continue
        before = its[i - 1]
        polled = bisect.bisect_left(polls, its[i].start) - bisect.bisect_left(polls, before.start)
        if polled > int(before.polled):
            continue  # polls other than the timer's: submitted commands
        last = bisect.bisect_left(polls, its[i].start) - 1
        if last not in sent_by and its[i].start < polls[last] + MIN_WAKE:
            continue  # the poll before sent nothing (G4 held it): MIN_WAKE ahead at least
        sent = bisect.bisect_left(sends, its[i + 1].start) - bisect.bisect_left(sends, its[i].start)
        assert sent, f"iteration at {its[i].start:.5f} ({its[i].busy * 1000:.3g} ms) sent nothing"
