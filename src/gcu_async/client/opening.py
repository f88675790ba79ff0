"""Bringing a client's link up: one open attempt, or attempts with backoff until
``open_timeout`` runs out, waited for or in the background (``wait=False``;
docs/client.md, "Lifecycle")."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import random
from collections.abc import Callable

from gcu_async._lograte import LogLimiter
from gcu_async.client.driver import ClientState, Driver
from gcu_async.client.telemetry import Callbacks
from gcu_async.errors import ClientStateError, LinkLost
from gcu_async.transport.backoff import Backoff
from gcu_async.transport.base import LinkEvent, LinkEventKind

log = logging.getLogger("gcu_async.client")

OPEN_BACKOFF = Backoff(base=0.25, factor=2.0, cap=5.0)
"""Delays between the open attempts (``open_timeout``, ``wait=False``)."""
OPEN_ATTEMPT_LOG_WINDOW = 60.0
"""Seconds between two log lines of failed open attempts (a GCU away for hours)."""


class Opener:
    """Opens one client's driver: its attempts, their backoff and their events."""

    def __init__(self, driver: Driver, links: Callbacks[LinkEvent],
                 clock: Callable[[], float]) -> None:  # fmt: skip
        self._driver = driver
        self._links = links
        self._url = driver.transport.url
        self._rng = random.Random()
        self._logs = LogLimiter(log, burst=1, window=OPEN_ATTEMPT_LOG_WINDOW, clock=clock,
                                name=self._url)  # fmt: skip
        self._task: asyncio.Task[None] | None = None

    async def open(self, connect_timeout: float, open_timeout: float | None,
                   wait: bool) -> None:  # fmt: skip
        """:meth:`GcuClient.open <gcu_async.client.GcuClient.open>` with these options."""
        driver = self._driver
        if driver.state not in (ClientState.CLOSED, ClientState.FAILED):
            raise ClientStateError(
                f"GcuClient is {driver.state.value}: a client is reusable but not reentrant "
                "(close it before opening it again; `async with` does both)",
                state=driver.state.value,
            )
        driver.begin()
        if not wait:
            log.info("opening %s (in the background)", self._url)
            self._task = asyncio.get_running_loop().create_task(
                self._in_background(connect_timeout, open_timeout),
                name=f"gcu_async open {self._url}")  # fmt: skip
            return
        log.info("opening %s", self._url)
        try:
            await self._attempts(connect_timeout, open_timeout)
        except BaseException:
            await driver.shutdown("open failed")
            raise

    async def stop(self) -> None:
        """Cancel the attempts running in the background (if any); returns once they
        ended."""
        task, self._task = self._task, None
        if task is not None and not task.done():
            task.cancel()
            await asyncio.wait({task})

    async def _attempts(self, connect_timeout: float, limit: float | None) -> None:
        """Open attempts until one succeeds (``OPEN``); :class:`LinkLost` when the client
        closes meanwhile, when ``limit`` (``open_timeout``) runs out, or, with no limit,
        when the one attempt fails."""
        driver, url = self._driver, self._url
        loop = asyncio.get_running_loop()
        deadline = None if limit is None else loop.time() + limit
        closed = driver.closed_event
        assert closed is not None
        attempts = 0
        while True:
            try:
                await driver.open_once(connect_timeout)
                return
            except LinkLost as exc:
                attempts += 1
                if driver.state is not ClientState.OPENING or closed.is_set():
                    raise LinkLost(f"{url}: closed while opening") from exc
                if deadline is None:
                    raise
                delay = min(OPEN_BACKOFF.delay(attempts - 1, self._rng), deadline - loop.time())
                if delay <= 0:  # the last try was at the end
                    raise LinkLost(f"{url}: no GCU within open_timeout {limit:g} s "
                                   f"({attempts} attempts; last: {exc})") from exc
                self._logs.log(logging.INFO, "failed open attempt",
                               "%s: attempt %d failed (%s); next in %.2f s",
                               url, attempts, exc, delay)  # fmt: skip
                self._links.emit(LinkEvent(
                    LinkEventKind.RETRYING,
                    f"attempt {attempts} failed: {exc}; next in {delay:.2f} s"))  # fmt: skip
                with contextlib.suppress(asyncio.TimeoutError):
                    await asyncio.wait_for(closed.wait(), delay)
                if closed.is_set():
                    raise LinkLost(f"{url}: closed while opening") from exc

    async def _in_background(self, connect_timeout: float, limit: float | None) -> None:
        """``wait=False``: the attempts, until one succeeds or ``limit`` (``open_timeout``,
        default: none) runs out (``GAVE_UP``, ``FAILED``); :meth:`stop` cancels them."""
        driver = self._driver
        try:
            await self._attempts(connect_timeout, math.inf if limit is None else limit)
        except LinkLost as exc:
            if driver.state is ClientState.OPENING:  # open_timeout ran out
                self._links.emit(LinkEvent(LinkEventKind.GAVE_UP, str(exc)))
                await driver.fail(str(exc))
        except Exception as exc:  # a bug, not a missing GCU: say so, do not spin
            log.exception("%s: opening in the background failed", self._url)
            await driver.fail(f"opening failed: {exc!r}")
