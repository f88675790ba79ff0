"""Each failure the "Command session v2" issue measured on the old session, replayed in
virtual time against the sans-I/O session and the simulator's GCU model (the same scenarios
run over real sockets in test_session_sockets.py)."""

from __future__ import annotations

import itertools
from collections import Counter

import pytest

from gcu_async.errors import CommandTimeout, Outcome
from gcu_async.protocol import (
    ControlValues,
    EulerControl,
    HostPacket,
    Mode,
    Opcode,
    PointingLock,
    Record,
    TakePhoto,
    ZoomTo,
)
from gcu_async.session import Session, SessionState, TicketState
from helpers.session.vtime import Direction, Fate, Rig, tagged_commands

GUARD = 0.015


def udp_session(**options: object) -> Session:
    return Session(reorder_guard=GUARD, **options)  # type: ignore[arg-type]


def drop_first_reply_of_each_command() -> object:
    previous = [0]

    def rule(packet: HostPacket | None, opcode: int, fate: Fate) -> Fate:
        first = opcode != 0 and opcode != previous[0]
        previous[0] = opcode
        return Fate(True) if first else fate

    return rule


def delay_nulls(seconds: float) -> object:
    return lambda p, op, f: Fate(f.drop, f.corrupt, seconds if op == 0 else 0.0, f.copy_delay)


def run_commands(rig: Rig, commands: list, burst: int = 1) -> None:
    rig.open()
    rig.run_until(0.5)
    it = iter(commands)
    while chunk := list(itertools.islice(it, burst)):
        for command in chunk:
            rig.submit(command)
        rig.run_while(rig.pending, 30.0)
    rig.run_until(rig.now + 1.0)


def zooms(n: int) -> list[ZoomTo]:
    """``n`` zoom-to commands with distinct ratios (one opcode: each needs a separation)."""
    return [ZoomTo(ratio=1.0 + i / 10) for i in range(n)]


def test_nulls_delayed_10ms_and_first_replies_lost_execute_once() -> None:
    """The issue's link: every null held 10 ms, each command's first reply lost. The old
    session let the GCU see ZOOM_TO → NULL → ZOOM_TO (13 of 40 executed twice)."""
    rig = Rig(udp_session(), bound=0.010,
              requests=Direction(override=delay_nulls(0.010)),  # type: ignore[arg-type]
              replies=Direction(override=drop_first_reply_of_each_command()))  # type: ignore[arg-type]  # fmt: skip
    run_commands(rig, zooms(40))
    rig.check()
    assert Counter(t.state for t in rig.tickets) == {TicketState.SUCCEEDED: 40}
    assert len(rig.executions) == 40


@pytest.mark.parametrize("hold", [0.005, 0.010, 0.013])
def test_reordering_held_below_the_guard_executes_once(hold: float) -> None:
    """20 % of packets held ``hold`` s in both directions (the old session: 3/600, 4/300 and
    6/300 executed twice at 5, 10 and 13 ms)."""
    def direction(seed: int) -> Direction:
        return Direction(extreme=0.2, seed=seed)

    rig = Rig(udp_session(), bound=hold, requests=direction(1), replies=direction(2))
    commands = list(itertools.islice(tagged_commands("same"), 300))
    commands += list(itertools.islice(tagged_commands("mixed", 10_000), 300))
    run_commands(rig, commands, burst=3)
    rig.check()
    assert all(t.state in (TicketState.SUCCEEDED, TicketState.FAILED) for t in rig.tickets)


@pytest.mark.parametrize("guard", [GUARD, 0.0])
def test_packet_rate_stays_bounded_under_command_traffic(guard: float) -> None:
    """1,000 mixed and same-opcode commands, 20 queued at a time: the old session sent ~60
    packets per same-opcode command on UDP (2,200 in one second) and 155 in 100 ms on TCP,
    answering every reply at once."""
    rig = Rig(Session(reorder_guard=guard), latency=0.0002)
    commands = list(itertools.islice(tagged_commands("same"), 500))
    commands += list(itertools.islice(tagged_commands("mixed", 10_000), 500))
    run_commands(rig, commands, burst=20)
    rig.check()
    assert rig.max_in_window() <= 51
    times = [t for t, _, _ in rig.sent]
    most_in_100ms = max(
        sum(1 for u in times[i:i + 10] if u < t + 0.1) for i, t in enumerate(times)
    )
    assert most_in_100ms <= 7  # 5 slots + the spare packet + one boundary
    per_command = len(rig.sent) / len(commands)
    print(f"\nguard {guard}: {per_command:.2f} host packets per command, "
          f"{rig.max_in_window()} in the busiest second")  # fmt: skip
    assert per_command < 5


def test_200_concurrent_commands_complete_with_default_timeouts() -> None:
    """The old default (2 s counted from the call) timed 74 of 200 out in the queue."""
    rig = Rig(udp_session())
    run_commands(rig, [TakePhoto() for _ in range(200)], burst=200)
    assert Counter(t.state for t in rig.tickets) == {TicketState.SUCCEEDED: 200}
    rig.check_counts()
    assert len(rig.executions) == 200


def test_queue_timeout_is_never_sent_and_wire_timeout_is_unknown() -> None:
    rig = Rig(udp_session())
    rig.open()
    rig.run_until(0.3)
    rig.replies.blackouts.append((rig.now, rig.now + 10.0))  # every reply lost from now on
    first = rig.submit(TakePhoto(), timeout=0.2)
    queued = rig.submit(ZoomTo(ratio=2.0), queue_timeout=0.1)
    rig.run_until(rig.now + 0.5)
    assert first is not None and queued is not None
    assert queued.state is TicketState.NOT_SENT and queued.packets == 0
    assert isinstance(queued.error, CommandTimeout)
    assert queued.error.outcome is Outcome.NOT_SENT and not queued.error.sent
    assert first.state is TicketState.UNKNOWN and first.packets > 0
    assert isinstance(first.error, CommandTimeout)
    assert first.error.outcome is Outcome.UNKNOWN
    assert [e.command for e in rig.executions] == [TakePhoto()]  # it did execute: "unknown"


def test_concurrent_mode_commands_never_send_one_modes_values_in_another() -> None:
    """gather(enter_euler_control(...), enter_pointing_lock(...)) sent Euler angles marked
    valid inside pointing-lock packets (read as rates)."""
    rig = Rig(udp_session(), bound=0.010, requests=Direction(extreme=0.3, seed=3),
              replies=Direction(extreme=0.3, seed=4))  # fmt: skip
    rig.open()
    rig.run_until(0.5)
    for _ in range(30):
        a = rig.submit(EulerControl(), control=ControlValues.angles(0.0, -45.0, 30.0))
        b = rig.submit(PointingLock(), control=ControlValues.rates(0.0, 5.0, -5.0))
        rig.run_while(rig.pending, 5.0)
        assert a is not None and b is not None
        assert a.state is b.state is TicketState.SUCCEEDED
        rig.run_until(rig.now + 0.1)
    rig.check_counts()  # includes the control-value rule, checked at the GCU
    valid = [(t, p) for t, p, mode in rig.sent if p.main.control_valid]
    assert valid, "the values of the confirmed mode did go out valid"
    assert rig.model.state.mode is Mode.POINTING_LOCK


def test_concurrent_start_recording_records_once() -> None:
    """Two concurrent start_recording() toggled recording twice: the camera ended up idle."""
    rig = Rig(udp_session())
    rig.open()
    rig.run_until(0.5)
    a = rig.submit(Record(), recording_target=True)
    b = rig.submit(Record(), recording_target=True)
    rig.run_while(rig.pending, 5.0)
    assert a is not None and b is not None
    assert {a.state, b.state} == {TicketState.SUCCEEDED, TicketState.SKIPPED}
    assert rig.model.state.recording
    assert [e.command.OPCODE for e in rig.executions] == [Opcode.RECORD]
    c = rig.submit(Record(), recording_target=False)
    d = rig.submit(Record(), recording_target=False)
    rig.run_while(rig.pending, 5.0)
    assert c is not None and d is not None
    assert {c.state, d.state} == {TicketState.SUCCEEDED, TicketState.SKIPPED}
    assert not rig.model.state.recording


def test_control_values_go_invalid_when_replies_stop() -> None:
    """Packets queued towards a GCU that stopped answering must not steer it later."""
    rig = Rig(udp_session())
    rig.open()
    rig.run_until(0.5)
    rig.submit(PointingLock(), control=ControlValues.rates(0.0, 2.0, 0.0))
    rig.run_while(rig.pending, 2.0)
    rig.run_until(rig.now + 0.2)
    assert rig.sent[-1][1].main.control_valid
    rig.replies.blackouts.append((rig.now, rig.now + 10.0))
    silent_from = rig.now
    rig.run_until(rig.now + 0.5)
    late = [p for t, p, _ in rig.sent if t > silent_from + 0.2 + 0.02]
    assert late and not any(p.main.control_valid for p in late)


def test_after_a_connection_reset_a_repeated_opcode_waits_for_proof_on_the_new_one() -> None:
    """TCP: the link is lost while a command is in flight, the transport reconnects; the
    same opcode must not go out before a reply on the new connection proves a null reached
    the GCU after it (and the session must not wait forever for it)."""
    rig = Rig(Session(reorder_guard=0.0))
    rig.open()
    rig.run_until(0.5)
    rig.replies.blackouts.append((rig.now, rig.now + 1.5))  # replies stop: the link is lost
    first = rig.submit(ZoomTo(ratio=3.0))
    rig.run_until(rig.now + 1.2)
    assert first is not None and first.state is TicketState.UNKNOWN
    rig.session.connection_lost(rig.now, "peer reset")  # what TcpTransport reports
    rig.run_while(lambda: rig.session.state is not SessionState.UP, 3.0)
    second = rig.submit(ZoomTo(ratio=3.5))
    rig.run_while(rig.pending, 3.0)
    assert second is not None and second.state is TicketState.SUCCEEDED
    rig.check()
    zooms = [e.command for e in rig.executions if e.command.OPCODE == Opcode.ZOOM_TO]
    assert zooms == [ZoomTo(ratio=3.0), ZoomTo(ratio=3.5)]
