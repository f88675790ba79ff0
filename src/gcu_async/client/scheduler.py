"""Which command goes in the next host packet, and which waiter a feedback belongs to.

Sans-I/O (no asyncio): the session asks :meth:`CommandScheduler.next_command` for every
packet it sends and hands every received feedback to :meth:`CommandScheduler.on_feedback`.

Rules (NOTES §3):
- One command in flight at a time; other callers wait in FIFO order.
- The in-flight command is repeated in consecutive packets until its feedback arrives: the
  GCU executes consecutive same-opcode packets once, so repeats survive packet loss safely.
- Before an opcode is sent again, the GCU must have *seen* a null command after the previous
  one. A null packet can be lost, so sending one is not enough: the scheduler sends null
  packets until a null feedback (opcode 0x00) comes back, and only then the command. Without
  this, a lost null makes the GCU skip the second command and answer with the first one's
  feedback — a silent loss.
- Feedback is matched by opcode to the in-flight command only; anything else is counted as
  unmatched, never given to another waiter. "In progress" keeps the command in flight.
- Reordering guard (``reorder_guard`` seconds, for links that may reorder, i.e. UDP): the
  packets of a finished command may still be on their way. If one arrived after a packet
  with another opcode, the GCU would run the command again. So the first packet after a
  command finishes goes out no earlier than ``reorder_guard`` after the last packet that
  carried it (:attr:`CommandScheduler.hold_until`), and after a null acknowledgement the
  same opcode waits ``reorder_guard`` too, so late replies to the old command have arrived
  before the new one is sent and cannot be mistaken for its feedback. The protocol has no
  sequence numbers: exactly-once holds for reordering delays shorter than the guard.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

from gcu_async.protocol.commands import Command, NullCommand, command_code
from gcu_async.protocol.enums import ExecutionStatus, Opcode
from gcu_async.protocol.feedback import Feedback

NULL = NullCommand()
CONTROL_INVALID_WHILE = frozenset({Opcode.CENTRE, Opcode.CLICK_TO_PAN})
"""Commands during which the control values must be sent invalid (NOTES §5)."""


@dataclass(eq=False)
class Ticket:
    """One command from one caller, from submission to its outcome."""

    command: Command
    deadline: float
    """Monotonic time after which the command times out."""
    feedback: Feedback | None = None
    """Final feedback (success or failure) once done."""
    progress: list[Feedback] = field(default_factory=list)
    """"In progress" feedbacks seen so far."""
    sent: int = 0
    """Packets that carried this command."""
    done: bool = False
    timed_out: bool = False

    @property
    def opcode(self) -> int:
        return command_code(self.command)


@dataclass
class SchedulerStats:
    commands_submitted: int = 0
    commands_completed: int = 0
    commands_timed_out: int = 0
    commands_cancelled: int = 0
    unmatched_feedback: int = 0
    """Feedback for an opcode that is neither in flight nor just finished."""
    late_feedback: int = 0
    """Feedback for the command that just finished (replies to its repeats): expected."""
    null_waits: int = 0


class CommandScheduler:
    """FIFO of commands; one in flight; null separation confirmed by the GCU."""

    def __init__(self, reorder_guard: float = 0.0) -> None:
        if not 0 <= reorder_guard < math.inf:
            raise ValueError(f"reorder_guard: {reorder_guard!r} must be >= 0 seconds")
        self.reorder_guard = reorder_guard
        self._hold_until = -math.inf
        self._last_sent_at = -math.inf
        """When the in-flight command was last put in a packet."""
        self._finished_opcode: int | None = None
        """Opcode of the command that finished last (its repeats' replies may still come)."""
        self._separated: tuple[int, float] | None = None
        """(opcode, time) of the last null acknowledgement that cleared ``_last_opcode``."""
        self._queue: deque[Ticket] = deque()
        self._in_flight: Ticket | None = None
        self._last_opcode: int | None = None
        """Opcode the GCU may still consider "last executed" (None once a null was acked)."""
        self._nulls_since_last = 0
        """Null packets sent since ``_last_opcode`` was set: only their replies count as an
        acknowledgement (an older null reply, reordered, proves nothing)."""
        self.stats = SchedulerStats()

    # -- inspection --------------------------------------------------------------------
    @property
    def in_flight(self) -> Ticket | None:
        return self._in_flight

    @property
    def pending(self) -> int:
        """Commands queued or in flight."""
        return len(self._queue) + (self._in_flight is not None)

    @property
    def control_blocked(self) -> bool:
        """True while a command that needs invalid control values is in flight."""
        t = self._in_flight
        return t is not None and t.opcode in CONTROL_INVALID_WHILE

    @property
    def hold_until(self) -> float:
        """No packet may be sent before this time (the reordering guard after a command)."""
        return self._hold_until

    @property
    def waiting_for_null_ack(self) -> bool:
        """True when the next command repeats the last opcode and no null was acked yet."""
        head = self._queue[0] if self._queue else None
        return (
            self._in_flight is None
            and head is not None
            and self._last_opcode is not None
            and head.opcode == self._last_opcode
        )

    # -- input -------------------------------------------------------------------------
    def submit(self, ticket: Ticket) -> None:
        """Queue a command; it goes in flight when everything before it is done."""
        self.stats.commands_submitted += 1
        self._queue.append(ticket)

    def next_command(self, now: float = 0.0) -> Command:
        """The command for the packet sent at ``now`` (NULL when idle or separating).
        Callers must not send before :attr:`hold_until`."""
        t = self._in_flight
        if t is None:
            t = self._promote(now)
        if t is None:
            if self._last_opcode is not None:
                self._nulls_since_last += 1
            return NULL
        t.sent += 1
        self._last_sent_at = now
        return t.command

    def on_feedback(self, feedback: Feedback, now: float = 0.0) -> Ticket | None:
        """Account for one received feedback; return the ticket it completed, if any."""
        opcode = feedback.opcode
        if opcode == Opcode.NULL:
            # the GCU has seen a null sent after the last command: any opcode runs next
            if self._in_flight is None and self._nulls_since_last and self._last_opcode is not None:
                self._separated = (self._last_opcode, now)
                self._last_opcode = None
            return None
        t = self._in_flight
        if t is None or opcode != t.opcode:
            if opcode == self._finished_opcode:
                self.stats.late_feedback += 1
            else:
                self.stats.unmatched_feedback += 1
            return None
        if feedback.result is ExecutionStatus.IN_PROGRESS:
            t.progress.append(feedback)
            return None
        t.feedback = feedback
        self._finish(t)
        self.stats.commands_completed += 1
        return t

    def expire(self, now: float) -> list[Ticket]:
        """Time out every ticket whose deadline has passed; return them."""
        tickets = [] if self._in_flight is None else [self._in_flight]
        expired = [t for t in [*tickets, *self._queue] if now >= t.deadline]
        for t in expired:
            self.time_out(t)
        return expired

    def time_out(self, ticket: Ticket) -> bool:
        """Give up on ``ticket`` (its deadline passed); False if it was already done."""
        if ticket.done:
            return False
        ticket.timed_out = True
        if ticket is self._in_flight:
            self._finish(ticket)
        else:
            self._queue.remove(ticket)
            ticket.done = True
        self.stats.commands_timed_out += 1
        return True

    def cancel(self, ticket: Ticket) -> None:
        """Withdraw a ticket (its caller was cancelled). Safe for done tickets."""
        if ticket.done:
            return
        if ticket is self._in_flight:
            self._finish(ticket)
        else:
            try:
                self._queue.remove(ticket)
            except ValueError:
                return
            ticket.done = True
        self.stats.commands_cancelled += 1

    def drain(self) -> list[Ticket]:
        """Remove and return every unfinished ticket (link lost / client closing)."""
        tickets = [] if self._in_flight is None else [self._in_flight]
        if self._in_flight is not None:
            self._finish(self._in_flight)
        tickets.extend(self._queue)
        for t in self._queue:
            t.done = True
        self._queue.clear()
        return tickets

    # -- internals ---------------------------------------------------------------------
    def _promote(self, now: float) -> Ticket | None:
        if not self._queue:
            return None
        head = self._queue[0]
        if self._last_opcode is not None and head.opcode == self._last_opcode:
            self.stats.null_waits += 1
            return None  # send NULL until the GCU acknowledges one
        separated = self._separated
        if separated is not None and head.opcode == separated[0]:
            if now < separated[1] + self.reorder_guard:
                return None  # late replies to the previous one may still arrive
            self._separated = None
        self._queue.popleft()
        self._in_flight = head
        return head

    def _finish(self, ticket: Ticket) -> None:
        ticket.done = True
        if ticket is self._in_flight:
            self._in_flight = None
            if ticket.sent:
                self._finished_opcode = ticket.opcode
                self._last_opcode = ticket.opcode
                self._nulls_since_last = 0
                self._separated = None
                self._hold_until = self._last_sent_at + self.reorder_guard
