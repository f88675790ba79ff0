"""One command from one caller, from submission to its outcome."""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

from gcu_async.errors import GcuError
from gcu_async.protocol.commands import Command
from gcu_async.protocol.feedback import Feedback
from gcu_async.session.runs import Run


class TicketState(enum.Enum):
    """Where a command is. The last five are final."""

    QUEUED = "queued"
    """Waiting for the commands before it, for the GCU to be ready, or for its proof of
    separation; nothing of it was sent."""
    SENT = "sent"
    """In flight: repeated in every packet until its feedback arrives."""
    SUCCEEDED = "succeeded"
    SKIPPED = "skipped"
    """A state-checked command found the state already as asked: nothing was sent."""
    FAILED = "failed"
    """The GCU answered with a failure status."""
    NOT_SENT = "not sent"
    """Ended before any packet carried it (queue timeout, link down, cancelled, closed)."""
    UNKNOWN = "unknown"
    """Ended after it was sent but without feedback (timeout, link lost, cancelled)."""


FINAL = frozenset({TicketState.SUCCEEDED, TicketState.SKIPPED, TicketState.FAILED,
                   TicketState.NOT_SENT, TicketState.UNKNOWN})  # fmt: skip


@dataclass(eq=False)
class Ticket:
    """A submitted command (see :meth:`Session.submit`). Read-only for callers."""

    command: Command
    opcode: int
    submitted_at: float
    timeout: float
    """Seconds allowed on the wire, from its first packet to its final feedback."""
    queue_deadline: float
    """Time by which its first packet must have gone out, or it ends ``NOT_SENT``."""
    state: TicketState = TicketState.QUEUED
    first_sent: float | None = None
    packets: int = 0
    """Packets that carried it."""
    run: Run | None = None
    feedback: Feedback | None = None
    """The final feedback (success or failure)."""
    progress: list[Feedback] = field(default_factory=list)
    """"In progress" feedbacks seen (calibration)."""
    error: GcuError | None = None
    """Why it did not succeed (set with every final state but SUCCEEDED and SKIPPED)."""
    finished_at: float | None = None
    recording_target: bool | None = None
    """For a state-checked record toggle: the recording state it must bring about."""
    expect_recording: bool | None = None
    """For a record toggle: the state the camera will be in once it executed."""

    @property
    def done(self) -> bool:
        return self.state in FINAL
