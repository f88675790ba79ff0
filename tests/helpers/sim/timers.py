"""Just enough of an event loop for the simulator's exchange and stalls: ``call_later`` on
virtual time, each timer run with the clock set to its time (deterministic, no asyncio)."""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable
from typing import Any

from gcu_async.sim import ManualClock


class _Timer:
    def __init__(self, when: float, seq: int, fn: Callable[..., None], args: tuple[Any, ...]):
        self.when, self.seq, self.fn, self.args = when, seq, fn, args
        self.cancelled = False

    def cancel(self) -> None:
        self.cancelled = True

    def __lt__(self, other: _Timer) -> bool:
        return (self.when, self.seq) < (other.when, other.seq)


class VirtualLoop:
    """``call_later`` on ``clock`` (a fresh :class:`ManualClock` if none is given): the
    timers run in time order, first scheduled first, the clock moved to each one's time.
    A negative delay fails the test, or with ``clamp`` runs the timer now."""

    def __init__(self, clock: ManualClock | None = None, *, clamp: bool = False) -> None:
        self.clock = ManualClock() if clock is None else clock
        self._clamp = clamp
        self._heap: list[_Timer] = []
        self._seq = 0

    @property
    def now(self) -> float:
        return self.clock.now()

    def call_later(self, delay: float, fn: Callable[..., None], *args: Any) -> _Timer:
        if self._clamp:
            delay = max(delay, 0.0)
        assert delay >= 0, delay
        self._seq += 1
        timer = _Timer(self.now + delay, self._seq, fn, args)
        heapq.heappush(self._heap, timer)
        return timer

    def run_until(self, t: float) -> None:
        """Run every timer due by ``t``; then the clock is at ``t`` (unless infinite)."""
        while self._heap and self._heap[0].when <= t:
            timer = heapq.heappop(self._heap)
            if not timer.cancelled:
                self.clock.advance(max(0.0, timer.when - self.now))
                timer.fn(*timer.args)
        if t < math.inf:
            self.clock.advance(max(0.0, t - self.now))

    def advance(self, seconds: float) -> None:
        self.run_until(self.now + seconds)
