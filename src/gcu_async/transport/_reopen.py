"""Reopening a lost link on a :class:`~gcu_async.transport.backoff.Backoff` schedule: the part
the serial transport (an unplugged adapter) and the UDP transport (a socket closed under it)
share (docs/transports.md, "Serial" and "UDP errors and reopening"; TCP reconnects in its own
way, since a connection can come up while an attempt is timing out)."""

from __future__ import annotations

import asyncio
import random
from collections.abc import Awaitable, Callable

from gcu_async._checks import check_bool, type_error
from gcu_async.transport._common import call_guarded
from gcu_async.transport.backoff import (
    Backoff,
    cancel_and_wait,
    giving_up,
    not_reconnecting,
    retry,
)
from gcu_async.transport.base import LinkEvent, LinkEventKind


class Reopener:
    """Runs ``attempt(timeout)`` in a task on :attr:`backoff`'s schedule after a loss, emits
    ``RESTORED`` ("``what`` after N attempt(s)") or, when opt-in bounds run out, ``GAVE_UP``,
    and counts both; :meth:`stop` cancels it. ``reconnect=False`` never starts it: it emits
    ``GAVE_UP`` at once."""

    def __init__(self, reconnect: bool, backoff: Backoff | None,
                 rng: random.Random | None) -> None:  # fmt: skip
        self.enabled = check_bool("reconnect", reconnect)
        if backoff is not None and not isinstance(backoff, Backoff):
            raise type_error("backoff", "a Backoff or None", backoff)
        self.backoff = backoff if backoff is not None else Backoff()
        self._rng = rng if rng is not None else random.Random()
        self._task: asyncio.Task[None] | None = None
        self.closing = False
        self.attempts = 0
        self.reopened = 0

    @property
    def running(self) -> bool:
        return self._task is not None and not self._task.done()

    def start(self, url: str, attempt: Callable[[float], Awaitable[None]], timeout: float,
              what: str, emit: Callable[[LinkEvent], None]) -> None:  # fmt: skip
        """After a loss: start reopening, unless closing; disabled, give up at once."""
        if not self.enabled and not self.closing:
            call_guarded(emit, not_reconnecting(url), "event")
        elif not self.closing:
            self._task = asyncio.get_running_loop().create_task(
                self._run(url, attempt, timeout, what, emit), name=f"gcu_async reopen {url}"
            )

    async def stop(self) -> None:
        """Cancel a running reopen task and return once it has ended."""
        task, self._task = self._task, None
        await cancel_and_wait(task)

    async def _run(self, url: str, attempt: Callable[[float], Awaitable[None]], timeout: float,
                   what: str, emit: Callable[[LinkEvent], None]) -> None:  # fmt: skip
        self.attempts = 0

        def counted(n: int) -> None:
            self.attempts = n

        try:
            last = await retry(attempt, self.backoff, self._rng, timeout, counted)
            if self.closing:
                return
            if last is None:
                self.reopened += 1
                detail = f"{what} after {self.attempts} attempt(s)"
                event = LinkEvent(LinkEventKind.RESTORED, detail)
            else:
                event = giving_up(url, self.attempts, last)
            call_guarded(emit, event, "event")
        finally:
            if self._task is asyncio.current_task():
                self._task = None


class Reopening:
    """What a transport that reopens itself reports (serial: the device; UDP: the socket)."""

    _reopen: Reopener

    @property
    def connected(self) -> bool:  # pragma: no cover - every transport defines it
        raise NotImplementedError

    @property
    def backoff(self) -> Backoff:
        """The reopening schedule after a loss: by default every 0–2 s until closed."""
        return self._reopen.backoff

    @property
    def reconnect_attempts(self) -> int:
        """Attempts to reopen during the current (or last) loss."""
        return self._reopen.attempts

    @property
    def reconnects(self) -> int:
        """Losses ended by reopening."""
        return self._reopen.reopened

    @property
    def reconnecting(self) -> bool:
        """True while the link is lost and the background task tries to reopen it."""
        return self._reopen.running and not self.connected
