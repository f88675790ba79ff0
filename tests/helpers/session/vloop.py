"""The virtual-time rig (helpers/session/vtime.py) with the host side on a modelled asyncio loop.

asyncio runs a timer in the first loop iteration that *begins* after the timer is due, and
only after the callbacks already queued for that iteration (other tasks' steps, then I/O):
a loop whose tasks keep it busy runs each poll late by the rest of the iteration, and a
timer due a moment after an iteration began waits for the next one. :class:`LoopRig` models
exactly that: iteration *i* begins at ``starts[i]``; the replies that arrived and the calls
that were due by then run at its end (after ``busy`` seconds of other work), then the poll
whose wake-up was due by then. The next iteration begins ``OVERHEAD`` later (the loop's own
bookkeeping and ``epoll_wait(0)``); an iteration with no busy work waits, as ``select``
does, for the next wake-up, reply or call.

Timers follow :class:`~gcu_async.client.GcuClient`: a poll (timer-driven, or a submit's)
replaces the pending timer with the next wake-up; anything else (a reply, an API call) only
ever brings it earlier. The GCU side (model and network) keeps exact time, as another
machine does.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from typing import Any

from gcu_async.session import Session
from helpers.session.vtime import Rig

OVERHEAD = 2e-5
"""Seconds from the end of one iteration's callbacks to the start of the next: CPython's
``_run_once`` bookkeeping plus ``epoll_wait(0)`` (tens of microseconds)."""


@dataclass
class Iteration:
    start: float
    busy: float
    polled: bool = False
    """A timer-driven poll ran in this iteration (its wake-up was due at ``start``)."""
    window_full: bool = False
    """G4's window held packets back when the iteration began or when its poll ran."""


class LoopRig(Rig):
    """:class:`Rig` whose host side runs on a modelled asyncio event loop (see the module).

    ``busy``: the seconds of other work in each iteration, in order (0: an idle iteration,
    which waits for the next event); when it runs out the loop goes idle."""

    def __init__(self, session: Session, busy: Iterable[float], **kwargs: Any) -> None:
        super().__init__(session, **kwargs)
        self._busy: Iterator[float] = iter(busy)
        self._next_start = 0.0
        self._armed = False
        self.iterations: list[Iteration] = []
        self.slots: list[float] = []
        self.poll_times: list[float] = []
        """When the session was polled (timer-driven or not)."""
        self.sent_poll: list[int] = []
        """For each packet in ``sent``, the index of its poll in ``poll_times``."""
        """The slot each packet in ``sent`` went out for (its own time if early)."""

    def run_until(self, end: float) -> None:
        heap = self._heap
        while True:
            start = self._next_start
            busy = next(self._busy, 0.0)
            if busy <= 0.0:  # idle: select() sleeps until the first wake-up, reply or call
                host = [t for t, _, kind, _ in heap if kind != "gcu"]
                start = max(start, min([self.wakeup, *host]))
            if start > end:
                break
            self._gcu_until(start)
            ready = []
            while True:  # what select() and the timer heap hand this iteration
                item = next(((t, s, k, p) for t, s, k, p in sorted(heap)
                             if k != "gcu" and t <= start), None)  # fmt: skip
                if item is None:
                    break
                heap.remove(item)
                heapq.heapify(heap)
                ready.append(item)
            self._armed = self.wakeup <= start  # the timer's handle joins this iteration
            wakeup = self.wakeup
            it = Iteration(start, busy)
            it.window_full = self.session._pacer.window_open_at() > start
            self.iterations.append(it)
            self._gcu_until(start + busy)  # the GCU works while the host loop is busy
            self.clock.advance(max(0.0, start + busy - self.now))
            for _, _, kind, payload in ready:  # I/O callbacks, then timers (asyncio's order)
                if kind == "host":
                    self._host_receives(payload[0], arrival=payload[2])
                else:
                    payload()
                    self._reschedule()
            if self._armed:  # unless a poll from a call in this iteration cancelled it
                self._rx_bound = wakeup  # GcuClient: a later reply arrived after it was due
                it.polled = True
                it.window_full |= self.session._pacer.window_open_at() > self.now
                self._poll()
            self._next_start = self.now + OVERHEAD
        self._gcu_until(end)
        self.clock.advance(max(0.0, end - self.now))

    def _poll(self) -> None:
        self.wakeup = math.inf  # GcuClient._pump: this poll replaces the pending timer,
        self._armed = False  # even one already due in this iteration (a cancelled handle)
        pacer, now = self.session._pacer, self.now
        promised = self.session.next_wakeup(now) <= now and not pacer.late
        before = len(self.sent)
        self.poll_times.append(now)
        super()._poll()
        if len(self.sent) > before:
            self.slots.append(pacer.last_slot)
            self.sent_poll.append(len(self.poll_times) - 1)
        elif promised:
            self.violations.append(f"t={now:.6f}: next_wakeup said now, poll sent nothing")

    def _reschedule(self) -> None:
        # GcuClient._schedule: a timer only ever moves earlier until it runs
        self.wakeup = min(self.wakeup, self.session.next_wakeup(self.now))

    def _gcu_until(self, t: float) -> None:
        """Let the GCU side handle everything that reaches it by ``t``, at its own times."""
        heap = self._heap
        while True:
            item = next(((w, s, k, p) for w, s, k, p in sorted(heap)
                         if k == "gcu" and w <= t), None)  # fmt: skip
            if item is None:
                return
            heap.remove(item)
            heapq.heapify(heap)
            self.clock.advance(max(0.0, item[0] - self.now))
            self._gcu_receives(item[3])

    def sends_between(self, a: float, b: float) -> int:
        return sum(1 for t, _, _ in self.sent if a <= t < b)


def regular(busy: float, seconds: float) -> list[float]:
    """Iterations of ``busy`` seconds of work, for about ``seconds``."""
    return [busy] * math.ceil(seconds / (busy + OVERHEAD))


__all__ = ["OVERHEAD", "Iteration", "LoopRig", "regular"]
