"""Reconnect schedules shared by the TCP, serial and UDP transports and the client's start-up:
exponential backoff with full jitter, capped; unbounded unless asked (docs/transports.md,
"Reconnecting")."""

from __future__ import annotations

import asyncio
import random
from collections.abc import Awaitable, Callable
from dataclasses import dataclass

from gcu_async.errors import LinkLost
from gcu_async.transport._common import check_positive
from gcu_async.transport.base import LinkEvent, LinkEventKind


@dataclass(frozen=True)
class Backoff:
    """Reconnect schedule: exponential backoff with full jitter, capped.

    ``base`` and ``cap`` are seconds, ``factor`` >= 1: before attempt *n* (0-based) a random
    delay in ``[0, min(cap, base * factor**n)]``. By default there is no bound: attempts go
    on, at most ``cap`` apart, until the transport is closed (a GCU may be away for
    minutes: a power cycle, a 60 s boot). The bounds are opt-in: ``max_attempts``
    (attempts per outage) and ``max_total`` (seconds since the loss after which no new
    attempt starts); when one runs out the transport gives up
    (:attr:`~gcu_async.transport.LinkEventKind.GAVE_UP`).
    """

    base: float = 0.05
    factor: float = 2.0
    cap: float = 2.0
    max_attempts: int | None = None
    max_total: float | None = None

    def __post_init__(self) -> None:
        check_positive("backoff_base", self.base)
        check_positive("backoff_cap", self.cap)
        if check_positive("backoff_factor", self.factor) < 1:
            raise ValueError(f"backoff_factor: {self.factor!r} is out of range (allowed >= 1)")
        if self.cap < self.base:
            raise ValueError(
                f"backoff_cap: {self.cap!r} is smaller than backoff_base {self.base!r}"
            )
        ma = self.max_attempts
        if ma is not None and (isinstance(ma, bool) or not isinstance(ma, int) or ma < 1):
            raise ValueError(f"max_attempts: {ma!r} is out of range (allowed: integer >= 1)")
        if self.max_total is not None:
            check_positive("max_total", self.max_total)

    @property
    def bounded(self) -> bool:
        """True when the schedule can run out (``max_attempts`` or ``max_total`` set)."""
        return self.max_attempts is not None or self.max_total is not None

    def ceiling(self, attempt: int) -> float:
        """Upper bound of the delay before attempt ``attempt`` (0-based)."""
        try:
            return min(self.cap, self.base * self.factor**attempt)
        except OverflowError:
            return self.cap

    def delay(self, attempt: int, rng: random.Random) -> float:
        """Full jitter: ``rng.random() * ceiling(attempt)``."""
        return rng.random() * self.ceiling(attempt)



async def retry(attempt: Callable[[float], Awaitable[None]], backoff: Backoff,
                rng: random.Random, timeout: float,
                counted: Callable[[int], None] | None = None) -> LinkLost | None:  # fmt: skip
    """Call ``attempt(timeout)`` until it returns, sleeping ``backoff.delay(n)`` before
    attempt *n* (0-based), within ``backoff``'s bounds if it has any (the last attempt's
    timeout is cut to what ``max_total`` leaves; without bounds it goes on until cancelled).
    ``counted(n)`` is told the attempt number before each. Returns None on success, else
    the last :class:`LinkLost` (or a LinkLost saying the time ran out before the first
    attempt)."""
    loop = asyncio.get_running_loop()
    deadline = None if backoff.max_total is None else loop.time() + backoff.max_total
    attempts = 0
    last: LinkLost | None = None
    while backoff.max_attempts is None or attempts < backoff.max_attempts:
        delay = backoff.delay(attempts, rng)
        limit = timeout
        if deadline is not None:
            left = deadline - loop.time() - delay
            if left <= 0:
                break
            limit = min(limit, left)
        await asyncio.sleep(delay)
        attempts += 1
        if counted is not None:
            counted(attempts)
        try:
            await attempt(limit)
        except LinkLost as exc:
            last = exc
            continue
        return None
    return last if last is not None else LinkLost("no attempt fitted in max_total")


async def cancel_and_wait(task: asyncio.Task[None] | None) -> None:
    """Cancel a reconnect task (if running) and return once it has ended."""
    if task is not None and not task.done():
        task.cancel()
        await asyncio.wait({task})


def giving_up(url: str, attempts: int, last: LinkLost) -> LinkEvent:
    """The ``GAVE_UP`` event of a reconnection that ran out of attempts or time."""
    plural = "s" if attempts != 1 else ""
    return LinkEvent(LinkEventKind.GAVE_UP,
                     f"giving up after {attempts} reconnect attempt{plural}: last error: {last}"
                     f" ({url})")  # fmt: skip


def not_reconnecting(url: str) -> LinkEvent:
    """The ``GAVE_UP`` event of a transport made with ``reconnect=False``, after a loss."""
    return LinkEvent(LinkEventKind.GAVE_UP, f"giving up at once: reconnect is off ({url})")


__all__ = ["Backoff", "cancel_and_wait", "giving_up", "not_reconnecting", "retry"]
