"""``Session.next_wakeup`` never lies: ``poll`` and ``next_wakeup`` read one gate
(``Session._gate``), and this checks the promise between them in virtual time, from
hypothesis-generated session states (commands of one or several opcodes, state-checked
record toggles, cancels, a lossy and reordering network, a GCU that falls silent):

- polled at any time before the wake-up it named, the session does nothing: no packet, no
  event, and afterwards it names no earlier wake-up;
- polled at the wake-up, it does what it said: it sends the packet the gate allows then,
  fires the timer due then (an event: a command's end, the link lost), or, when the last
  packet went out late, settles it.
"""

from __future__ import annotations

import copy
import math
from typing import Any

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gcu_async.protocol import Record, TakePhoto
from gcu_async.session import LinkDown, Session, SessionState, TicketDone
from gcu_async.session.session import MIN_WAKE
from helpers.scale import scaled
from helpers.session.vtime import Direction, Rig, tagged_commands

Action = tuple[str, float]


def _fingerprint(s: Session) -> tuple[Any, ...]:
    p = s._pacer
    return (s.state, s.pending, p.next_slot, p.late, s._kick, s.stats.submitted)


def clone(session: Session, shared: list[Any]) -> Session:
    """A deep copy of ``session`` that shares ``shared`` (the tickets' errors: exceptions
    cannot be deep-copied, and nothing changes them)."""
    return copy.deepcopy(session, {id(x): x for x in shared})


def check_wakeup(session: Session, now: float, probes: list[float], shared: list[Any]) -> None:
    """The promise of ``next_wakeup(now)``, on copies of ``session``."""
    wake = session.next_wakeup(now)
    assert wake >= now
    if wake == math.inf:
        return
    floored = wake == now + MIN_WAKE  # the due time lies within MIN_WAKE: it may be earlier
    gate = session._gate(now)[0]
    timers = session._timers_due_at(now)
    times = [now] if floored else [now + (wake - now) * f for f in probes]
    if not floored:
        times.append(math.nextafter(wake, -math.inf))  # the last instant before it
    for t in times:
        if not now <= t < wake:
            continue
        c = clone(session, shared)
        assert c.poll(t) is None, f"next_wakeup({now}) = {wake}, but poll({t}) sent"
        assert not c.events(), f"next_wakeup({now}) = {wake}, but poll({t}) had events"
        assert c.next_wakeup(t) >= wake, "a poll before the wake-up moved it earlier"
    c = clone(session, shared)
    late = c._pacer.late
    data = c.poll(wake)
    events = c.events()
    head = session._queue[0] if session._queue else None
    settles = head is not None and head.recording_target is not None and (
        now < session._recording.settles_at() <= wake)  # fmt: skip
    if late:  # the driver's next turn: it settles the late packet (and may send)
        assert not c._pacer.late
    elif timers <= wake and not settles:  # a timer fell due: its event
        assert any(isinstance(e, (TicketDone, LinkDown)) for e in events), (wake, events)
    elif gate <= wake:  # the gate opened: the packet goes
        assert data is not None, f"next_wakeup said a packet at {wake}; poll sent none"
    else:  # the recording belief settled: the head command is re-read
        assert settles, (wake, timers, gate)


def errors(rig: Rig) -> list[Any]:
    return [t.error for t in rig.tickets if t.error is not None]


actions = st.lists(
    st.tuples(
        st.sampled_from(["run", "submit", "submit", "record", "photo", "cancel", "silence"]),
        st.floats(0.0, 0.3),
    ),
    min_size=1, max_size=40,
)  # fmt: skip


@settings(max_examples=scaled(150, 25), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    rate=st.sampled_from([2.0, 7.5, 30.0, 50.0, 200.0]),
    guard=st.sampled_from([0.0, 0.015, 0.1]),
    drop=st.sampled_from([0.0, 0.2]),
    bound=st.sampled_from([0.0, 0.01]),
    seed=st.integers(0, 2**16),
    steps=actions,
    timeouts=st.tuples(st.floats(0.05, 0.6), st.floats(0.05, 1.5)),
    probes=st.lists(st.floats(0.0, 1.0, exclude_max=True), min_size=1, max_size=4),
)
def test_next_wakeup_never_lies(rate: float, guard: float, drop: float, bound: float,
                                seed: int, steps: list[Action], timeouts: tuple[float, float],
                                probes: list[float]) -> None:  # fmt: skip
    session = Session(rate_hz=rate, reorder_guard=guard, command_timeout=timeouts[0],
                      queue_timeout=timeouts[1], silence_timeout=max(0.6, 2.0 / rate),
                      record_settle=0.2)  # fmt: skip
    rig = Rig(session, bound=bound, latency=0.001, seed=seed,
              replies=Direction(loss=drop, jitter=0.5, seed=seed),
              requests=Direction(loss=drop, jitter=0.5, seed=seed + 1))  # fmt: skip
    rig.open()
    commands = tagged_commands("mixed", seed)
    rig.run_until(0.3)
    for kind, amount in steps:
        now = rig.now
        if session.state is SessionState.UP:
            if kind == "submit":
                rig.submit(next(commands))
            elif kind == "record":
                rig.submit(Record(), recording_target=amount > 0.15)
            elif kind == "photo":
                rig.submit(TakePhoto())
            elif kind == "cancel" and session.pending:
                ticket = next(t for t in reversed(rig.tickets) if not t.done)
                session.cancel(ticket, now)
                rig._drain()
                rig._reschedule()
        if kind == "silence":
            rig.replies = Direction(loss=1.0)
        check_wakeup(session, rig.now, probes, errors(rig))
        rig.run_until(rig.now + amount)
        check_wakeup(session, rig.now, probes, errors(rig))


def test_the_silence_timer_fires_at_the_wakeup_it_named() -> None:
    """``next_wakeup`` names the instant the silence exceeds ``silence_timeout``, and a poll
    then loses the link (it used to wake at exactly ``last + silence_timeout``, when the
    silence only equals it, and again 0.1 ms later)."""
    session = Session(rate_hz=50.0, silence_timeout=0.25)
    rig = Rig(session, latency=0.001)
    rig.open()
    rig.run_until(0.2)
    assert session.state is SessionState.UP
    rig.replies = Direction(loss=1.0)
    rig.run_until(0.3)
    last = session.link_health(rig.now).last_reply_age
    assert last is not None
    wakes = []
    now = rig.now
    while session.state is SessionState.UP and len(wakes) < 100:
        now = session.next_wakeup(now)
        wakes.append(now)
        if session.poll(now) is None and session.state is SessionState.UP:
            raise AssertionError(f"poll at its wake-up {now} did nothing")
        session.events()
    assert session.state is SessionState.DOWN
