"""The session's restart rule (docs/client.md, "GCU restarts"; gcu_async.session.restart) in
virtual time, against the simulator's GCU model: outages of 2 s to an hour, with and without
the GCU restarting (a fresh model: its state reset) while it was away; commands whose
outcome was unknown at the loss; changes under way. Nothing ever executes twice."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest

from gcu_async.protocol import (
    ControlValues,
    EulerControl,
    Mode,
    Opcode,
    PointingLock,
    Ranging,
    Record,
    ZoomIn,
    ZoomStop,
    ZoomTo,
)
from gcu_async.session import (
    LinkDown,
    LinkUp,
    Restarted,
    Session,
    SessionState,
    StateChange,
    TicketState,
)
from gcu_async.sim import SimulatorModel
from helpers.session.vtime import Rig

OUTAGES = (2.0, 30.0, 120.0)
EULER = EulerControl()
ANGLES = ControlValues.angles(0.0, -30.0, 90.0)


def rig_with_state(*, tcp: bool = False) -> Rig:
    """A rig whose GCU was put out of its defaults: Euler control, zoom 5x, ranging on."""
    rig = Rig(Session(reorder_guard=0.0 if tcp else 0.015))
    rig.open()
    rig.run_until(0.5)
    for command, extra in ((EULER, {"control": ANGLES}), (ZoomTo(ratio=5.0), {}),
                           (Ranging(enabled=True), {})):  # fmt: skip
        ticket = rig.submit(command, **extra)
        rig.run_while(rig.pending, 5.0)
        assert ticket is not None and ticket.state is TicketState.SUCCEEDED, ticket
    rig.run_until(rig.now + 8.0)  # the zoom travels to 5x and settles
    info = rig.session.info
    assert info is not None and info.camera1_zoom == pytest.approx(5.0)
    status = rig.session.status
    assert status is not None and status.mode is Mode.EULER_CONTROL
    rig.events.clear()
    return rig


def restart(rig: Rig) -> None:
    """The GCU restarts: a new model (its state at power-on) on the same clock, whose
    executions join the rig's log."""
    log = rig.executions
    model = SimulatorModel(rig.model.profile.model, clock=rig.clock, record_executions=True)
    model.execution_log = log
    rig.model = model


def outage(rig: Rig, seconds: float, *, restarted: bool,
           during: Callable[[Rig], None] | None = None) -> None:  # fmt: skip
    """Nothing gets through either way for ``seconds``; the GCU restarts in the middle if
    ``restarted``; then the rig runs until the link is up again (and 2 s more)."""
    start = rig.now
    for direction in (rig.requests, rig.replies):
        direction.blackouts.append((start, start + seconds))
    if restarted:
        rig.at(start + seconds / 2, lambda: restart(rig))
    if during is not None:
        rig.at(start + min(1.5, seconds / 2), lambda: during(rig))
    rig.run_until(start + seconds)
    rig.run_while(lambda: rig.session.state is not SessionState.UP, 5.0)
    assert rig.session.state is SessionState.UP
    rig.run_until(rig.now + 2.0)


def of(rig: Rig, kind: type) -> list[Any]:
    return [e for e in rig.events if isinstance(e, kind)]


@pytest.mark.parametrize("seconds", OUTAGES)
def test_an_outage_is_not_a_restart(seconds: float) -> None:
    rig = rig_with_state()
    outage(rig, seconds, restarted=False)
    assert len(of(rig, LinkDown)) == 1
    assert [e.restored for e in of(rig, LinkUp)] == [True]
    assert of(rig, Restarted) == []
    assert rig.session.link_health(rig.now).restarted_count == 0
    rig.check()


@pytest.mark.parametrize("seconds", OUTAGES)
def test_a_restart_is_reported_with_what_changed_and_what_to_restore(seconds: float) -> None:
    rig = rig_with_state()
    executed = len(rig.executions)
    outage(rig, seconds, restarted=True)
    (event,) = of(rig, Restarted)
    assert event.changes == (StateChange("mode", "EULER_CONTROL", "POINTING_FOLLOW"),
                             StateChange("zoom", "5x", "1x"),
                             StateChange("ranging", "on", "off"))  # fmt: skip
    assert event.reason == "mode EULER_CONTROL -> POINTING_FOLLOW, zoom 5x -> 1x, ranging on -> off"
    assert (event.mode, event.control, event.zoom) == (EULER, ANGLES, 5.0)
    # in order: the loss, the first reply after it, then the restart it revealed
    kinds = [type(e) for e in rig.events if isinstance(e, (LinkDown, LinkUp, Restarted))]
    assert kinds == [LinkDown, LinkUp, Restarted]
    assert rig.session.link_health(rig.now).restarted_count == 1
    assert len(rig.executions) == executed  # the session re-sends nothing by itself
    rig.check()


def test_the_session_never_sends_control_values_of_a_mode_the_restarted_gcu_left() -> None:
    rig = rig_with_state()
    assert rig.sent[-1][1].main.control_valid
    outage(rig, 5.0, restarted=True)
    after = [p for t, p, _ in rig.sent if t >= rig.now - 1.5]
    assert after and not any(p.main.control_valid for p in after)
    assert rig.session.control_mode == Opcode.EULER_CONTROL  # known, but not the reported one
    rig.check()


def test_a_restart_over_a_connection_loss() -> None:
    """TCP: the transport reports the loss (its connection reset), then reconnects."""
    rig = rig_with_state(tcp=True)
    rig.session.connection_lost(rig.now, "peer closed the connection")
    outage(rig, 20.0, restarted=True)
    (event,) = of(rig, Restarted)
    assert {c.aspect for c in event.changes} == {"mode", "zoom", "ranging"}
    rig.check()


def test_recording_reset_by_a_restart() -> None:
    rig = rig_with_state()
    ticket = rig.submit(Record(), recording_target=True)
    rig.run_while(rig.pending, 5.0)
    assert ticket is not None and ticket.state is TicketState.SUCCEEDED
    rig.run_until(rig.now + 3.0)
    outage(rig, 10.0, restarted=True)
    (event,) = of(rig, Restarted)
    assert StateChange("recording", "on", "off") in event.changes
    rig.check()


def test_a_command_of_unknown_outcome_explains_its_change() -> None:
    """The replies stop while a zoom is in flight: the GCU executes it, the session cannot
    know (outcome UNKNOWN at the loss). The zoom reported after the outage differs from the
    last one before it, and that is no restart."""
    rig = rig_with_state()
    start = rig.now
    rig.replies.blackouts.append((start, start + 15.0))
    ticket = rig.submit(ZoomTo(ratio=9.0))
    rig.run_until(start + 15.0)
    assert ticket is not None and ticket.state is TicketState.UNKNOWN
    assert [e.command for e in rig.executions][-1] == ZoomTo(ratio=9.0)  # it did execute
    rig.run_while(lambda: rig.session.state is not SessionState.UP, 5.0)
    rig.run_until(rig.now + 1.0)
    info = rig.session.info
    assert info is not None and info.camera1_zoom == pytest.approx(9.0)
    assert of(rig, Restarted) == []
    rig.check()


def test_commands_of_unknown_outcome_explain_a_mode_and_a_ranging_change() -> None:
    """A mode command and ranging off go out as the replies stop: both execute, neither is
    confirmed. After the outage the mode and ranging differ from the last report before it;
    the two commands whose outcome is unknown explain it: no restart."""
    rig = rig_with_state()
    start = rig.now
    rig.replies.blackouts.append((start, start + 15.0))
    mode = rig.submit(PointingLock())
    ranging = rig.submit(Ranging(enabled=False))
    rig.run_until(start + 15.0)
    assert mode is not None and mode.state is TicketState.UNKNOWN
    assert ranging is not None and ranging.state in (TicketState.UNKNOWN, TicketState.NOT_SENT)
    rig.run_while(lambda: rig.session.state is not SessionState.UP, 5.0)
    rig.run_until(rig.now + 1.0)
    status = rig.session.status
    assert status is not None and status.mode is Mode.POINTING_LOCK
    assert of(rig, Restarted) == []
    rig.check()


@pytest.mark.parametrize("restarted", [False, True])
def test_a_command_of_unknown_outcome_explains_only_its_own_effect(restarted: bool) -> None:
    """Pointing lock goes out as the replies stop (outcome unknown). Without a restart the
    GCU reports pointing lock: explained. With one, it reports its default mode, which the
    command does not lead to: a restart, not explained away."""
    rig = rig_with_state()
    start = rig.now
    rig.replies.blackouts.append((start, start + 15.0))
    mode = rig.submit(PointingLock())
    if restarted:
        rig.at(start + 7.0, lambda: restart(rig))
    rig.run_until(start + 15.0)
    assert mode is not None and mode.state is TicketState.UNKNOWN
    rig.run_while(lambda: rig.session.state is not SessionState.UP, 5.0)
    rig.run_until(rig.now + 1.0)
    status = rig.session.status
    assert status is not None
    if not restarted:
        assert status.mode is Mode.POINTING_LOCK
        assert of(rig, Restarted) == []
    else:
        assert status.mode is Mode.POINTING_FOLLOW
        (event,) = of(rig, Restarted)
        assert StateChange("mode", "EULER_CONTROL", "POINTING_FOLLOW") in event.changes
    rig.check()


def test_a_continuous_zoom_under_way_explains_its_change() -> None:
    rig = rig_with_state()
    ticket = rig.submit(ZoomIn())
    rig.run_while(rig.pending, 5.0)
    assert ticket is not None and ticket.state is TicketState.SUCCEEDED
    rig.run_until(rig.now + 2.0)  # zooming for a while, then the outage
    outage(rig, 30.0, restarted=False)
    assert of(rig, Restarted) == []
    stop = rig.submit(ZoomStop())
    rig.run_while(rig.pending, 5.0)
    assert stop is not None and stop.state is TicketState.SUCCEEDED
    rig.check()


def test_the_same_change_without_an_explanation_is_a_restart() -> None:
    """The control case of the two above: the zoom stopped and settled before the outage,
    and the restarted GCU reports 1x."""
    rig = rig_with_state()
    ticket = rig.submit(ZoomTo(ratio=2.0))
    rig.run_while(rig.pending, 5.0)
    assert ticket is not None and ticket.state is TicketState.SUCCEEDED
    rig.run_until(rig.now + 6.0)
    outage(rig, 30.0, restarted=True)
    (event,) = of(rig, Restarted)
    assert StateChange("zoom", "2x", "1x") in event.changes
    rig.check()


@pytest.mark.parametrize("settled", [True, False])
def test_a_zoom_to_a_fraction_is_judged_by_its_reports(settled: bool) -> None:
    """A fraction's ratio is unknown to the host: once the reported zoom stopped changing
    for REPORT_SETTLE the zoom counts as still, and a restart to 1x is seen; while it still
    changes, the change is explained."""
    rig = rig_with_state()
    ticket = rig.submit(ZoomTo(fraction=0.5))
    rig.run_while(rig.pending, 5.0)
    assert ticket is not None and ticket.state is TicketState.SUCCEEDED
    rig.run_until(rig.now + (8.0 if settled else 0.3))
    outage(rig, 30.0, restarted=True)
    events = of(rig, Restarted)
    if settled:
        (event,) = events
        assert any(c.aspect == "zoom" and c.after == "1x" for c in event.changes), event
    else:
        assert all(c.aspect != "zoom" for e in events for c in e.changes), events
    rig.check()


def test_a_restart_that_changes_nothing_is_not_seen() -> None:
    """A GCU in its power-on state restarts: no aspect differs, nothing to restore."""
    rig = Rig(Session(reorder_guard=0.015))
    rig.open()
    rig.run_until(1.0)
    outage(rig, 30.0, restarted=True)
    assert of(rig, Restarted) == []
    assert [e.restored for e in of(rig, LinkUp)] == [False, True]
    rig.check()


def test_one_restart_event_per_loss() -> None:
    rig = rig_with_state()
    outage(rig, 10.0, restarted=True)
    outage(rig, 10.0, restarted=False)  # back to its defaults already: nothing changes
    assert len(of(rig, Restarted)) == 1
    assert len(of(rig, LinkDown)) == 2
    rig.check()
