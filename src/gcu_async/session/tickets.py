"""One command from one caller, from submission to its outcome."""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

from gcu_async._checks import check_bool, check_instance, check_positive
from gcu_async.errors import CommandError, CommandFailed, CommandTimeout, GcuError, Outcome
from gcu_async.protocol.command_base import Command
from gcu_async.protocol.command_decode import AnomalousCommand, command_code
from gcu_async.protocol.commands import NullCommand
from gcu_async.protocol.enums import ExecutionStatus, Opcode, opcode_name
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

    @classmethod
    def new(cls, command: Command, now: float, timeout: float, queue_timeout: float,
            recording_target: bool | None) -> Ticket:  # fmt: skip
        """A ticket for ``command`` submitted at ``now``, its arguments checked: TypeError or
        ValueError naming the one that is wrong (an anomalous or a null command is none a
        host may send)."""
        check_instance("command", command, Command, "a Command")
        if isinstance(command, AnomalousCommand):  # decoded, never sent: send is strict
            raise command.error()
        if isinstance(command, NullCommand):
            raise ValueError("command: the null command is the session's own separator")
        opcode = command_code(command)
        timeout = check_positive("timeout", timeout)
        queue_timeout = check_positive("queue_timeout", queue_timeout)
        if recording_target is not None:
            check_bool("recording_target", recording_target)
            if opcode != Opcode.RECORD:
                raise ValueError(f"recording_target: only for RECORD, not {opcode_name(opcode)}")
        return cls(command, opcode, now, timeout, now + queue_timeout,
                   recording_target=recording_target)  # fmt: skip

    @property
    def done(self) -> bool:
        return self.state in FINAL

    def start(self, now: float, recording: bool | None) -> None:
        """Its first packet goes out at ``now`` (``recording``: whether the camera records,
        as far as the session can tell, which a record toggle will reverse)."""
        self.state = TicketState.SENT
        self.first_sent = now
        if self.opcode == Opcode.RECORD:
            self.expect_recording = None if recording is None else not recording

    def answered(self, feedback: Feedback) -> tuple[TicketState, CommandFailed | None] | None:
        """A reply identified with its run carries ``feedback``: ``None`` while in progress
        (kept in :attr:`progress`), else its final state and, for a failure, the error."""
        result = feedback.result
        if result is ExecutionStatus.IN_PROGRESS:
            self.progress.append(feedback)
            return None
        self.feedback = feedback
        if result is ExecutionStatus.SUCCESS:
            return TicketState.SUCCEEDED, None
        return TicketState.FAILED, CommandFailed(feedback.opcode, feedback.status,
                                                 feedback.failed_cameras, command=self.command,
                                                 name=feedback.command)  # fmt: skip

    def timeout_error(self, now: float) -> CommandTimeout:
        """Why it ends at ``now`` by a timeout: on the wire (sent: ``UNKNOWN``) or in the
        queue (``NOT_SENT``)."""
        name = opcode_name(self.opcode)
        if self.state is TicketState.SENT:
            progress = " (last status: in progress)" if self.progress else ""
            return CommandTimeout(f"{name}: no feedback within {self.timeout:g} s of its first "
                                  f"packet{progress}; outcome unknown (it may have executed)",
                                  outcome=Outcome.UNKNOWN, opcode=self.opcode,
                                  command=self.command)  # fmt: skip
        return CommandTimeout(f"{name}: not sent: still queued after "
                              f"{now - self.submitted_at:.3g} s (queue_timeout)",
                              outcome=Outcome.NOT_SENT, opcode=self.opcode,
                              command=self.command)  # fmt: skip

    def end_error(self, reason: str, cls: type[CommandError]) -> CommandError:
        """Why it ends from outside (``reason``): ``UNKNOWN`` if it was sent, else
        ``NOT_SENT``."""
        sent = self.state is TicketState.SENT
        what = "outcome unknown (it may have executed)" if sent else "not sent (it did not execute)"
        return cls(f"{opcode_name(self.opcode)}: {reason}; {what}",
                   outcome=Outcome.UNKNOWN if sent else Outcome.NOT_SENT, opcode=self.opcode,
                   command=self.command)  # fmt: skip
