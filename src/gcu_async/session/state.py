"""Where a session is (:class:`SessionState`) and what it has counted (:class:`SessionStats`)."""

from __future__ import annotations

import enum
from dataclasses import dataclass

from gcu_async.session.tickets import TicketState


class SessionState(enum.Enum):
    """The session's lifecycle: one state, not a set of flags."""

    CLOSED = "closed"
    """Not open (never opened, or closed: it may be opened again)."""
    OPENING = "opening"
    """Open; the heartbeat runs; no reply yet."""
    UP = "up"
    """Replies arrive; commands are accepted."""
    DOWN = "down"
    """The link was lost; the heartbeat goes on; commands fail at once until replies return."""


@dataclass
class SessionStats:
    """Counters of one session (since it was created). A command that ends is counted in
    the field named after its final :class:`~gcu_async.session.TicketState`."""

    submitted: int = 0
    succeeded: int = 0
    skipped: int = 0
    failed: int = 0
    not_sent: int = 0
    unknown: int = 0
    cancelled: int = 0
    late_feedback: int = 0
    """Replies to an earlier run of the same opcode as the command in flight (expected:
    the GCU answers every repeat of the previous command)."""
    separator_packets: int = 0
    """Null packets sent because the next command had to wait for proof of separation."""
    early_packets: int = 0
    """Commands sent before their heartbeat slot (the phase moved instead)."""
    aircraft_stale: int = 0
    """Episodes in which packets withheld aircraft data because it was older than
    ``aircraft_timeout`` (one per run of such packets; docs/client.md, "Aircraft data:
    what the packets claim")."""

    def ended(self, state: TicketState) -> None:
        """Count a command that ended in ``state`` (a final one)."""
        name = state.name.lower()
        setattr(self, name, getattr(self, name) + 1)
