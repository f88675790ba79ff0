"""When the next host packet may go out: heartbeat slots, the rate bound and the edge guard.

Sans-I/O; times are seconds on the caller's monotonic clock (docs/session-contract.md, "The session
contract", G4 and G6). Three rules, each checked by :class:`Pacer` alone:

- **Heartbeat slots.** Packets go out on slots ``period = 1 / rate_hz`` apart, on a fixed
  phase: a late packet does not move the next slot. A packet sent half a period or more
  after its slot marks the driver late (:attr:`Pacer.late`): the session then asks for the
  driver's next turn, which on a busy event loop is the next iteration, late enough for
  the next slot. A packet a period or more late skips the slots it missed but leaves the
  current one *owed*, due at once, so a loop that runs each due poll an iteration late
  still sends a packet every iteration. The first poll after a late packet settles it
  (:meth:`Pacer.settle`): a driver back within half a period was stalled once, not running
  late, and the owed slot is dropped (sending it as well would put ``floor(rate_hz) + 2``
  packets into the second that follows on phase). Only a command that goes out early
  restarts the phase, at that packet.
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

    __slots__ = ("_sent", "guard", "last_early", "last_opcode", "last_slot", "last_time",
                 "late", "limit", "next_slot", "period")  # fmt: skip

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
        self.last_slot = -math.inf
        """The slot the last packet went out for (its own time if it started a phase)."""
        self.late = False
        """The last packet went out half a period or more after its slot: the driver runs
        late, and the next poll (its next turn) settles what that means."""

    def reset(self) -> None:
        """Forget every send (a new session starts)."""
        self._sent.clear()
        self.next_slot = -math.inf
        self.last_time = -math.inf
        self.last_opcode = None
        self.last_early = -math.inf
        self.last_slot = -math.inf
        self.late = False

    def window_open_at(self) -> float:
        """Earliest time the rate bound allows another packet."""
        sent = self._sent
        return sent[0] + (WINDOW + MARGIN) if len(sent) == self.limit else -math.inf

    def open_at(self, opcode: int) -> float:
        """Earliest time the rate bound and the edge guard both allow a packet with
        ``opcode``: :meth:`window_open_at` and, for an opcode other than the last packet's,
        that packet plus the guard (in one call: the session asks twice per heartbeat)."""
        sent = self._sent
        when = sent[0] + (WINDOW + MARGIN) if len(sent) == self.limit else -math.inf
        last = self.last_opcode
        if last is not None and opcode != last and self.last_time + self.guard > when:
            when = self.last_time + self.guard
        return when

    def early_open_at(self) -> float:
        """Earliest time a packet may go before its slot (one per :data:`WINDOW`)."""
        return self.last_early + WINDOW

    def record(self, now: float, opcode: int, *, early: bool) -> None:
        """A packet with ``opcode`` went out at ``now`` (on its slot, or ``early``)."""
        self._sent.append(now)
        self.last_time = now
        self.last_opcode = opcode
        period = self.period
        slot = self.next_slot
        self.late = False
        if early or slot == -math.inf:
            if early:
                self.last_early = now
            self.last_slot = now
            self.next_slot = now + period  # a new phase: an early command, or the first packet
            return
        self.last_slot = slot
        self.late = now - slot >= period / 2
        slot += period
        if slot <= now:  # a period late or more: skip the missed slots, owe the current one
            slot += period * math.floor((now - slot) / period)
        self.next_slot = slot

    def settle(self, now: float) -> None:
        """The first poll after a late packet: a driver back within half a period of it is
        not running late (a single stall ended): an owed slot is dropped. Otherwise the
        slots stand."""
        if self.late:
            self.late = False
            if now - self.last_time < self.period / 2 and self.next_slot <= self.last_time:
                self.next_slot += self.period
