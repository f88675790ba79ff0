"""The command scheduler (sans-I/O): ordering, repetition, confirmed null separation."""

from __future__ import annotations

from gcu_async.client.scheduler import CommandScheduler, Ticket
from gcu_async.protocol import (
    Calibration,
    Centre,
    ExecutionStatus,
    Feedback,
    NullCommand,
    Opcode,
    TakePhoto,
    ZoomIn,
    ZoomTo,
)

NULL = NullCommand()


def ticket(command: object, deadline: float = 100.0) -> Ticket:
    return Ticket(command, deadline)  # type: ignore[arg-type]


def test_idle_sends_null() -> None:
    s = CommandScheduler()
    assert s.next_command() == NULL
    assert s.in_flight is None


def test_command_repeats_until_feedback_then_idle() -> None:
    s = CommandScheduler()
    t = ticket(TakePhoto())
    s.submit(t)
    assert [s.next_command() for _ in range(3)] == [TakePhoto()] * 3
    assert t.sent == 3
    assert s.on_feedback(Feedback(Opcode.TAKE_PHOTO, 0)) is t
    assert t.done
    assert t.feedback == Feedback(Opcode.TAKE_PHOTO, 0)
    assert s.next_command() == NULL


def test_fifo_order_and_one_in_flight() -> None:
    s = CommandScheduler()
    a, b, c = ticket(TakePhoto()), ticket(ZoomIn()), ticket(Centre())
    for t in (a, b, c):
        s.submit(t)
    assert s.next_command() == TakePhoto()
    assert s.pending == 3
    s.on_feedback(Feedback(Opcode.TAKE_PHOTO, 0))
    assert s.next_command() == ZoomIn()
    s.on_feedback(Feedback(Opcode.ZOOM_IN, 0))
    assert s.next_command() == Centre()
    assert s.control_blocked  # centre needs invalid control values
    s.on_feedback(Feedback(Opcode.CENTRE, 0))
    assert not s.control_blocked
    assert s.pending == 0


def test_same_opcode_waits_for_null_ack_not_just_a_null_sent() -> None:
    s = CommandScheduler()
    first, second = ticket(TakePhoto()), ticket(TakePhoto())
    s.submit(first)
    s.submit(second)
    assert s.next_command() == TakePhoto()
    s.on_feedback(Feedback(Opcode.TAKE_PHOTO, 0))
    # the null packets may be lost: keep sending null until one is acknowledged
    assert s.waiting_for_null_ack
    assert [s.next_command() for _ in range(4)] == [NULL] * 4
    assert s.in_flight is None
    s.on_feedback(Feedback(Opcode.NULL))
    assert not s.waiting_for_null_ack
    assert s.next_command() == TakePhoto()
    assert s.in_flight is second


def test_null_reply_older_than_the_command_is_no_ack() -> None:
    s = CommandScheduler()
    s.submit(ticket(TakePhoto()))
    s.submit(ticket(TakePhoto()))
    assert s.next_command() == TakePhoto()
    s.on_feedback(Feedback(Opcode.TAKE_PHOTO, 0))
    # a reordered reply to a null sent *before* the photo proves nothing
    s.on_feedback(Feedback(Opcode.NULL))
    assert s.waiting_for_null_ack
    assert s.next_command() == NULL
    s.on_feedback(Feedback(Opcode.NULL))
    assert s.next_command() == TakePhoto()


def test_different_opcode_needs_no_null() -> None:
    s = CommandScheduler()
    s.submit(ticket(TakePhoto()))
    s.submit(ticket(ZoomTo(ratio=2.0)))
    s.next_command()
    s.on_feedback(Feedback(Opcode.TAKE_PHOTO, 0))
    assert s.next_command() == ZoomTo(ratio=2.0)


def test_late_replies_to_a_finished_command_are_not_unmatched() -> None:
    s = CommandScheduler()
    s.submit(ticket(TakePhoto()))
    s.next_command()
    s.next_command()  # repeated: two replies will come
    s.on_feedback(Feedback(Opcode.TAKE_PHOTO, 0))
    s.on_feedback(Feedback(Opcode.TAKE_PHOTO, 0))
    assert s.stats.late_feedback == 1
    assert s.stats.unmatched_feedback == 0


def test_unmatched_feedback_is_counted_never_given_to_another_waiter() -> None:
    s = CommandScheduler()
    t = ticket(TakePhoto())
    s.submit(t)
    s.next_command()
    assert s.on_feedback(Feedback(Opcode.ZOOM_IN, 0)) is None
    assert s.stats.unmatched_feedback == 1
    assert not t.done


def test_in_progress_keeps_waiting_and_repeating() -> None:
    s = CommandScheduler()
    t = ticket(Calibration())
    s.submit(t)
    s.next_command()
    assert s.on_feedback(Feedback(Opcode.CALIBRATION, 2)) is None
    assert t.progress == [Feedback(Opcode.CALIBRATION, 2)]
    assert s.next_command() == Calibration()
    assert s.on_feedback(Feedback(Opcode.CALIBRATION, 0)) is t
    assert t.feedback is not None
    assert t.feedback.result is ExecutionStatus.SUCCESS


def test_failure_completes_the_ticket() -> None:
    s = CommandScheduler()
    t = ticket(ZoomIn())
    s.submit(t)
    s.next_command()
    assert s.on_feedback(Feedback(Opcode.ZOOM_IN, 0x03)) is t
    assert t.feedback is not None
    assert t.feedback.result is ExecutionStatus.FAILED


def test_timeout_and_cancel_leave_scheduler_consistent() -> None:
    s = CommandScheduler()
    a, b, c = ticket(TakePhoto(), 1.0), ticket(ZoomIn(), 5.0), ticket(TakePhoto(), 5.0)
    for t in (a, b, c):
        s.submit(t)
    s.next_command()
    assert s.expire(2.0) == [a]
    assert a.timed_out
    assert s.in_flight is None
    s.cancel(b)  # queued caller cancelled
    assert b.done
    assert s.pending == 1
    # c has the opcode of the timed-out a: it may still have run, so null first
    assert s.next_command() == NULL
    s.on_feedback(Feedback(Opcode.NULL))
    assert s.next_command() == TakePhoto()
    s.cancel(c)  # in-flight caller cancelled
    assert s.in_flight is None
    assert s.pending == 0
    assert s.stats.commands_cancelled == 2
    assert s.stats.commands_timed_out == 1


def test_time_out_single_ticket() -> None:
    s = CommandScheduler()
    t = ticket(TakePhoto())
    s.submit(t)
    assert s.time_out(t) is True
    assert s.time_out(t) is False
    assert s.pending == 0


def test_drain_returns_every_unfinished_ticket() -> None:
    s = CommandScheduler()
    a, b = ticket(TakePhoto()), ticket(ZoomIn())
    s.submit(a)
    s.submit(b)
    s.next_command()
    assert s.drain() == [a, b]
    assert a.done
    assert b.done
    assert s.pending == 0
    assert s.next_command() == NULL


def test_reorder_guard_holds_the_packet_after_a_finished_command() -> None:
    s = CommandScheduler(reorder_guard=0.015)
    s.submit(ticket(TakePhoto()))
    s.submit(ticket(ZoomIn()))
    assert s.next_command(1.000) == TakePhoto()
    assert s.next_command(1.020) == TakePhoto()
    s.on_feedback(Feedback(Opcode.TAKE_PHOTO, 0), 1.021)
    # a late copy of the photo packet sent at 1.020 must not arrive after a zoom packet
    assert s.hold_until == 1.020 + 0.015
    assert s.next_command(1.035) == ZoomIn()


def test_reorder_guard_after_null_ack_before_same_opcode() -> None:
    s = CommandScheduler(reorder_guard=0.015)
    s.submit(ticket(TakePhoto()))
    s.submit(ticket(TakePhoto()))
    s.next_command(1.0)
    s.on_feedback(Feedback(Opcode.TAKE_PHOTO, 0), 1.001)
    assert s.next_command(1.016) == NULL
    s.on_feedback(Feedback(Opcode.NULL), 1.017)
    # late replies to the first photo may still arrive: wait the guard after the ack
    assert s.next_command(1.020) == NULL
    assert s.next_command(1.033) == TakePhoto()


def test_reorder_guard_zero_is_immediate() -> None:
    s = CommandScheduler()
    s.submit(ticket(TakePhoto()))
    s.next_command(5.0)
    s.on_feedback(Feedback(Opcode.TAKE_PHOTO, 0), 5.0)
    assert s.hold_until == 5.0


def test_reorder_guard_validation() -> None:
    import pytest

    with pytest.raises(ValueError, match="reorder_guard"):
        CommandScheduler(reorder_guard=-0.1)
