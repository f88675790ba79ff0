"""When the next host packet may go out: heartbeat slots, the rate bound and the edge guard.

Sans-I/O; times are seconds on the caller's monotonic clock (docs/client.md, "The session
contract"). Three rules, each checked by :class:`Pacer` alone:

- **Heartbeat slots.** Packets go out on slots ``period = 1 / rate_hz`` apart, kept on a
  fixed phase (a late packet does not shift the next slot) unless a packet is later than a
  whole period, or a command goes out early: then the phase restarts at that packet.
- **Rate bound.** No packet is sent if it would make more than ``floor(rate_hz) + 1``
  packets within any one-second window (a sliding window over the last sends, with
  :data:`MARGIN` to spare for the time a packet takes from this decision to the wire).
  Strictly periodic slots never use the spare packet; an early command does, and at most
  one packet per :data:`WINDOW` goes early, so commands that follow each other cannot
  turn into a burst that then stalls for the rest of the second.
- **Edge guard.** A packet whose opcode differs from the previous packet's goes out no
  earlier than ``guard`` seconds after that packet, so on a link that delays packets by
  at most ``guard`` more than others, runs of one opcode reach the GCU in the order sent.
"""

from __future__ import annotations

import math
from collections import deque

WINDOW = 1.0
"""Seconds over which the rate bound counts packets."""
MARGIN = 0.005
"""Seconds the window check keeps to spare: a packet reaches the transport a little after
the session decided to send it."""


class Pacer:
    """Slot schedule, sliding-window rate bound and edge guard for one session."""

    __slots__ = ("_sent", "guard", "last_early", "last_opcode", "last_time", "limit",
                 "next_slot", "period")  # fmt: skip

    def __init__(self, rate_hz: float, guard: float) -> None:
        self.period = 1.0 / rate_hz
        self.limit = math.floor(rate_hz) + 1
        """Most packets allowed in any window of :data:`WINDOW` seconds."""
        self.guard = guard
        self._sent: deque[float] = deque(maxlen=self.limit)
        self.next_slot = -math.inf
        self.last_time = -math.inf
        self.last_opcode: int | None = None
        self.last_early = -math.inf

    def reset(self) -> None:
        """Forget every send (a new session starts)."""
        self._sent.clear()
        self.next_slot = -math.inf
        self.last_time = -math.inf
        self.last_opcode = None
        self.last_early = -math.inf

    def window_open_at(self) -> float:
        """Earliest time the rate bound allows another packet."""
        sent = self._sent
        return sent[0] + (WINDOW + MARGIN) if len(sent) == self.limit else -math.inf

    def early_open_at(self) -> float:
        """Earliest time a packet may go before its slot (one per :data:`WINDOW`)."""
        return self.last_early + WINDOW

    def edge_open_at(self, opcode: int) -> float:
        """Earliest time a packet with ``opcode`` may follow the previous packet."""
        if opcode == self.last_opcode or self.last_opcode is None:
            return -math.inf
        return self.last_time + self.guard

    def record(self, now: float, opcode: int, *, early: bool) -> None:
        """A packet with ``opcode`` went out at ``now`` (on its slot, or ``early``)."""
        self._sent.append(now)
        self.last_time = now
        self.last_opcode = opcode
        if early:
            self.last_early = now
        period = self.period
        if early or self.next_slot == -math.inf:
            self.next_slot = now + period  # a new phase: an early command, or the first packet
            return
        slot = self.next_slot + period
        if slot <= now:  # behind: owe the current slot only (the one at or before now)
            slot += period * math.floor((now - slot) / period)
        self.next_slot = slot
