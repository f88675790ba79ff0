"""Which run of host packets a reply answers, and when an opcode may start a new run.

The protocol has no sequence numbers. What the session knows instead (docs/session-contract.md, "The
session contract"):

- Host packets form **runs**: maximal stretches of consecutive packets with one opcode.
  The edge guard (:mod:`gcu_async.session.pacing`) sends the first packet of a run at least
  ``guard`` after the last packet of the previous run, so on a link whose delay varies by
  less than ``guard`` the GCU receives runs in the order they were sent (packets inside a
  run may still be lost, duplicated or swapped: they carry one opcode, so that is harmless).
- The GCU answers the packets it processes in that order, and its replies too are delayed
  by at most ``guard`` more than one another. So once a reply is known to answer run *k*
  (it arrived at ``t``), every reply to an older run arrives before ``t + guard``: from then
  on, older runs are **stale** and replies can only answer run *k* or newer ones.
- A reply with opcode *o* answers some run with opcode *o*. If exactly one run with that
  opcode was already sent and is not stale, the reply is **identified** with it, and that run
  is known to have reached the GCU (**delivered**). Otherwise the reply proves nothing
  (ambiguous or unmatched) and is only counted.
- Runs whose last packet is older than ``reply_window`` count as stale too (no reply takes
  longer than that: an assumption, used only when no later reply anchors the order, e.g.
  after a command that got no reply at all).

The GCU executes a packet's command unless the packet before it (as received) had the same
opcode. A command with opcode *o* may therefore start a new run only if no run since the
latest delivered one has opcode *o* (:meth:`RunLedger.may_start`): whatever the GCU received
last, it was not *o*. When that does not hold, the session sends null packets, and their
identified reply is the proof it waits for.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

MAX_RUNS = 4096
"""Runs older than the newest delivered one are forgotten beyond this many."""


@dataclass(slots=True, eq=False)
class Run:
    """A maximal stretch of consecutive host packets with one opcode."""

    index: int
    opcode: int
    first_sent: float
    last_sent: float
    stale_after: float = math.inf
    """Replies arriving at or after this time cannot answer this run."""
    delivered: bool = False
    """A reply was identified with this run: the GCU received at least one of its packets."""
    packets: int = 1


@dataclass
class RunStats:
    identified: int = 0
    ambiguous: int = 0
    """Replies that could answer more than one run (not used as proof of anything)."""
    unmatched: int = 0
    """Replies that answer no run still possible (stale, or never sent by this session)."""


class RunLedger:
    """The runs sent so far and what the replies proved about them."""

    def __init__(self, guard: float, reply_window: float) -> None:
        self.guard = guard
        self.reply_window = reply_window
        self._runs: deque[Run] = deque()
        self._next_index = 0
        self._stale_upto = 0
        """Runs with a lower index already have a finite ``stale_after``."""
        self.delivered_index = -1
        """Index of the newest run known to have reached the GCU (-1: none yet)."""
        self._split = False
        """The next packet starts a new run even with the same opcode (after a reset)."""
        self.stats = RunStats()

    @property
    def current(self) -> Run | None:
        """The run the last packet belongs to."""
        return self._runs[-1] if self._runs else None

    def sent(self, opcode: int, now: float) -> Run:
        """Account for a packet with ``opcode`` sent at ``now``; return its run."""
        runs = self._runs
        if runs and not self._split:
            last = runs[-1]
            if last.opcode == opcode:
                last.last_sent = now
                last.packets += 1
                return last
        run = Run(self._next_index, opcode, now, now)
        self._next_index += 1
        self._split = False
        runs.append(run)
        return run

    def identify(self, opcode: int, now: float, earliest: float | None = None) -> Run | None:
        """The run a reply with ``opcode`` answers, if only one can.

        The reply arrived at some time in ``[earliest, now]``: ``now`` is when it is
        processed; ``earliest`` (default ``now``) bounds its arrival from below (a driver
        whose event loop was busy processes replies late; the end of its previous read of
        the link is such a bound). A run is excluded when the reply arrived before the run
        began (``now < first_sent``) or surely after the run went stale (``earliest >=
        stale_after``, or ``earliest`` later than ``reply_window`` after its last packet).
        """
        if earliest is None or earliest > now:
            earliest = now
        found: Run | None = None
        horizon = earliest - self.reply_window
        for run in reversed(self._runs):
            if run.opcode != opcode or run.first_sent > now:
                continue
            if earliest >= run.stale_after or run.last_sent <= horizon:
                continue
            if found is not None:
                self.stats.ambiguous += 1
                return None
            found = run
        if found is None:
            self.stats.unmatched += 1
            return None
        self.stats.identified += 1
        found.delivered = True
        if found.index > self.delivered_index:
            self.delivered_index = found.index
        if found.index > self._stale_upto:
            self._mark_stale_before(found.index, now + self.guard)
        if self._runs[0].index < self.delivered_index:
            self._prune(earliest)
        return found

    def may_start(self, opcode: int) -> bool:
        """May a new run with ``opcode`` start now, sure the GCU will execute it?"""
        for run in reversed(self._runs):
            if run.index < self.delivered_index:
                return True
            if run.opcode == opcode:
                return False
        return True

    def connection_reset(self, now: float) -> None:
        """The connection carrying replies was replaced (TCP reconnect): no reply to any
        run sent so far can arrive any more, and the next packet starts a new run (on the
        new connection) even if it repeats the last opcode."""
        for run in self._runs:
            if run.stale_after > now:
                run.stale_after = now
        self._stale_upto = self._next_index
        self._split = True

    def _mark_stale_before(self, index: int, when: float) -> None:
        runs = self._runs
        if not runs or index <= self._stale_upto:
            return
        first = runs[0].index
        for i in range(max(self._stale_upto, first) - first, index - first):
            run = runs[i]
            if run.stale_after > when:
                run.stale_after = when
        self._stale_upto = index

    def _prune(self, earliest: float) -> None:
        """Forget runs older than the newest delivered one once no later reply can answer
        them (later replies arrive after ``earliest``), or once more than :data:`MAX_RUNS`
        are kept; :meth:`may_start` never looks at those."""
        runs = self._runs
        horizon = earliest - self.reply_window
        while runs and runs[0].index < self.delivered_index:
            run = runs[0]
            if (run.stale_after > earliest and run.last_sent > horizon
                    and len(runs) <= MAX_RUNS):  # fmt: skip
                break
            runs.popleft()
