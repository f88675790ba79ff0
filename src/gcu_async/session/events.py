"""What the session tells its driver: events, in the order they happened."""

from __future__ import annotations

from typing import NamedTuple

from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.gcu_frames import GcuMainFrame, GcuSubFrame
from gcu_async.session.tickets import Ticket


class TelemetrySample(NamedTuple):
    """One GCU reply as telemetry."""

    status: GcuMainFrame
    """Main frame: mode, pod status, angles, rates."""
    info: GcuSubFrame | None
    """The latest sub frame: versions, pod model, faults, ranging, zoom, flags (None until
    one arrived)."""
    feedback: Feedback
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


Event = TelemetrySample | TicketDone | LinkUp | LinkDown | ResetLink
