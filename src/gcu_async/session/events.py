"""What the session tells its driver: events, in the order they happened."""

from __future__ import annotations

from typing import NamedTuple

from gcu_async.protocol.command_base import Command
from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.gcu_frames import GcuMainFrame, GcuSubFrame
from gcu_async.protocol.host_frame_tables import ControlValues
from gcu_async.session.restart import StateChange
from gcu_async.session.tickets import Ticket


class TelemetrySample(NamedTuple):
    """One GCU reply as telemetry."""

    status: GcuMainFrame
    """Main frame: mode, pod status, angles, rates."""
    info: GcuSubFrame | None
    """The latest sub frame: versions, pod model, faults, ranging, zoom, flags (None until
    one arrived)."""
    feedback: Feedback
    """The reply's feedback, in every sample: the command it answers and its status; a
    reply to the null command (nothing in flight) has ``opcode`` 0 and ``status`` None."""
    received_at: float
    """Time of arrival (the session's clock)."""


class TicketDone(NamedTuple):
    """A command reached its final state (``ticket.state``, ``ticket.feedback``,
    ``ticket.error``)."""

    ticket: Ticket


class LinkUp(NamedTuple):
    """Replies arrive: the first one after opening, or the first after a loss."""

    restored: bool
    """False for the first reply after opening, True after a loss."""
    reason: str


class LinkDown(NamedTuple):
    """The link counts as lost (no reply for ``silence_timeout``, or the transport lost its
    connection). Every command still pending ended with it."""

    reason: str


class ResetLink(NamedTuple):
    """Ask the transport to discard whatever it still queues towards the GCU and start over
    (TCP: reset and reconnect; serial: flush): sent together with :class:`LinkDown`."""

    reason: str


class Restarted(NamedTuple):
    """The GCU came back from a link loss with its state reset: the first reply after the
    loss reports ``changes`` that no command explains (:mod:`~gcu_async.session.restart`).
    Follows the :class:`LinkUp` of that reply. The rest is what the host had before the
    loss, for a driver that restores it."""

    changes: tuple[StateChange, ...]
    mode: Command | None
    """The mode command the GCU had confirmed last, when the mode changed and the GCU was
    in that mode before the loss (None otherwise)."""
    control: ControlValues | None
    """The control values given for that mode (None: sent invalid)."""
    zoom: float | None
    """Camera 1's zoom ratio reported before the loss, when the zoom changed (None
    otherwise)."""

    @property
    def reason(self) -> str:
        """The changes, as one line: ``"mode GAZE -> POINTING_FOLLOW, zoom 5x -> 1x"``."""
        return ", ".join(str(change) for change in self.changes)


Event = TelemetrySample | TicketDone | LinkUp | LinkDown | ResetLink | Restarted
