"""An asyncio event loop on virtual time, for the client and transports' timing rules in the
fast tier: ``loop.time()`` jumps to the next timer whenever nothing else is ready, so an
hour-long outage runs in as long as its work takes.

Only for code that does no real I/O (in-memory transports, the simulator's model, fakes):
the loop polls its real selector without waiting, and a file descriptor that becomes ready a
moment later would find virtual time already moved on. A loop with nothing ready and no timer
would wait forever: :func:`run` raises instead.

    run(main(), timeout=3600.0)   # main's clock: asyncio.get_running_loop().time
"""

from __future__ import annotations

import asyncio
import selectors
from collections.abc import Coroutine
from typing import Any, TypeVar

T = TypeVar("T")


class _VirtualSelector(selectors.DefaultSelector):
    """A selector that never waits: with nothing ready it advances the loop's time by the
    timeout asyncio asked for (the time to its next timer)."""

    def __init__(self) -> None:
        super().__init__()
        self.loop: VirtualClockLoop | None = None

    def select(self, timeout: float | None = None) -> list[tuple[selectors.SelectorKey, int]]:
        events = super().select(0)
        if events or timeout == 0:
            return events
        if timeout is None:
            raise RuntimeError("virtual clock: nothing is ready and no timer is due (deadlock)")
        assert self.loop is not None
        self.loop.advance(timeout)
        return []


class VirtualClockLoop(asyncio.SelectorEventLoop):
    """A selector event loop whose :meth:`time` is virtual (starts at 0)."""

    def __init__(self) -> None:
        selector = _VirtualSelector()
        super().__init__(selector)
        selector.loop = self
        self._now = 0.0
        self._clock_resolution = 1e-9

    def time(self) -> float:
        return self._now

    def advance(self, seconds: float) -> None:
        self._now += max(0.0, seconds)


def run(main: Coroutine[Any, Any, T], *, timeout: float = 7200.0) -> T:
    """Run ``main`` on a new virtual-clock loop; ``TimeoutError`` after ``timeout`` virtual
    seconds."""
    loop = VirtualClockLoop()
    try:
        return loop.run_until_complete(asyncio.wait_for(main, timeout))
    finally:
        loop.run_until_complete(loop.shutdown_asyncgens())
        loop.close()


class LoopClock:
    """The running loop's time as a simulator :class:`~gcu_async.sim.Clock`."""

    def now(self) -> float:
        return asyncio.get_running_loop().time()
