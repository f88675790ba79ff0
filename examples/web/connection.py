"""Getting the app's one client up, and keeping it up: :class:`GcuConnection`.

The app may start before the GCU is powered, or the GCU may vanish for good (a serial
adapter unplugged, a TCP transport that gave up reconnecting). ``GcuConnection`` runs one
background task around the client the app owns:

1. **waiting** — it calls :meth:`GcuClient.open` (which waits ``connect_timeout`` for the
   first reply) until it succeeds; after each failure it waits ``retry_initial`` seconds,
   doubling up to ``retry_max``, and keeps the failure's message for the page.
2. **connected** — the client is open. Short outages are the client's business: the link
   goes down after ``silence_timeout`` without replies and comes back with the next one
   (``gcu.link.up``); a TCP transport reconnects by itself. Every ``WATCH_SECONDS`` the task
   checks whether the transport is gone for good (link down, transport not connected and
   not reconnecting); then it closes the client and goes back to 1.

The client's own start-up retry (``open_timeout``) is bounded in time and does not reopen a
client whose transport gave up; a web app keeps serving its page however long the GCU
takes, so it runs this loop instead (each ``open()`` one attempt). Only
:class:`~gcu_async.LinkLost` and ``OSError`` count as "GCU not there yet"; anything else
is a bug and ends the task (logged).
"""

from __future__ import annotations

import asyncio
import contextlib
import enum
import logging
import math
import time
from collections.abc import Callable
from types import TracebackType
from typing import Any

from gcu_async import GcuClient, LinkLost
from gcu_async.client import ClientState

log = logging.getLogger("gcu_async.examples.web")

WATCH_SECONDS = 0.25
"""How often a connected client's transport is checked for having given up."""


class ConnectionState(enum.Enum):
    """Where :class:`GcuConnection` is."""

    WAITING = "waiting"
    """The client is not open: an attempt to open it runs, or the next one is due."""
    CONNECTED = "connected"
    """The client is open (its link may still be down for a while: ``gcu.link.up``)."""
    STOPPED = "stopped"
    """:meth:`GcuConnection.stop` was called (the app is shutting down)."""


def _positive(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{name}: expected a finite number of seconds > 0, got {value!r}")
    if value <= 0:
        raise ValueError(f"{name}: {value!r} is outside the allowed range (0, inf) s")
    return float(value)


def check_retry(retry_initial: object, retry_max: object) -> tuple[float, float]:
    """The retry delays, checked: both finite seconds > 0, ``retry_max >= retry_initial``.
    Raises ``ValueError`` naming the parameter, its allowed range and the value."""
    initial = _positive("retry_initial", retry_initial)
    maximum = _positive("retry_max", retry_max)
    if maximum < initial:
        raise ValueError(f"retry_max: {retry_max!r} is outside the allowed range "
                         f"[retry_initial = {retry_initial!r}, inf) s")  # fmt: skip
    return initial, maximum


class GcuConnection:
    """Opens ``gcu`` in the background, retrying with backoff; reopens it when its transport
    gives up. Use as ``async with GcuConnection(gcu) as connection:`` (starts the task;
    on exit stops it and closes the client)."""

    def __init__(
        self,
        gcu: GcuClient,
        *,
        retry_initial: float = 0.5,
        retry_max: float = 5.0,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.gcu = gcu
        self.retry_initial, self.retry_max = check_retry(retry_initial, retry_max)
        self._clock = clock
        self._state = ConnectionState.WAITING
        self._connected = asyncio.Event()
        self._task: asyncio.Task[None] | None = None
        self.attempts = 0
        """Calls of ``open()`` that failed since the client was last open."""
        self.connects = 0
        """Times the client was opened."""
        self.reopens = 0
        """Times the client was closed because its transport had given up."""
        self.last_error: str | None = None
        """Why the last attempt failed (``None`` once connected)."""
        self._next_attempt: float | None = None

    # -- lifecycle -------------------------------------------------------------------------
    async def __aenter__(self) -> GcuConnection:
        self.start()
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        await self.stop()

    def start(self) -> None:
        """Start the background task (on the running loop). Once only."""
        if self._task is not None:
            raise RuntimeError("GcuConnection.start: already started")
        name = f"gcu-connection {self.gcu.transport.url}"
        self._task = asyncio.create_task(self._run(), name=name)

    async def stop(self) -> None:
        """Stop the task and close the client. Idempotent."""
        self._state = ConnectionState.STOPPED
        self._connected.clear()
        task, self._task = self._task, None
        if task is not None and not task.done():
            task.cancel()
        if task is not None:
            with contextlib.suppress(asyncio.CancelledError):
                await task
        await self.gcu.close()

    # -- state -----------------------------------------------------------------------------
    @property
    def state(self) -> ConnectionState:
        return self._state

    @property
    def connected(self) -> bool:
        return self._state is ConnectionState.CONNECTED

    async def wait_connected(self, timeout: float) -> bool:
        """True once the client is open; False after ``timeout`` seconds or when stopped."""
        if self._state is ConnectionState.STOPPED:
            return False
        with contextlib.suppress(asyncio.TimeoutError):
            await asyncio.wait_for(self._connected.wait(), timeout)
        return self.connected

    def snapshot(self) -> dict[str, Any]:
        """JSON view: ``state``, ``url``, failed ``attempts``, ``last_error``, ``retry_in``
        (seconds until the next attempt, ``None`` while one runs or when connected),
        ``connects``, ``reopens``."""
        retry_in = None
        if self._next_attempt is not None:
            retry_in = round(max(0.0, self._next_attempt - self._clock()), 2)
        return {
            "state": self._state.value,
            "url": self.gcu.transport.url,
            "attempts": self.attempts,
            "last_error": self.last_error,
            "retry_in": retry_in,
            "connects": self.connects,
            "reopens": self.reopens,
        }

    def describe(self) -> str:
        """One line for an error message: what the connection is waiting for."""
        text = f"waiting for the GCU at {self.gcu.transport.url}"
        if self.attempts:
            text += f" ({self.attempts} attempt{'s' if self.attempts != 1 else ''}"
            text += f", last: {self.last_error})" if self.last_error else ")"
        return text

    # -- the task --------------------------------------------------------------------------
    async def _run(self) -> None:
        try:
            while True:
                await self._open()
                await self._watch()
                self.reopens += 1
                log.warning("%s: the transport gave up; reopening the client",
                            self.gcu.transport.url)  # fmt: skip
                self._state = ConnectionState.WAITING
                self._connected.clear()
                await self.gcu.close()
        except Exception:  # a bug, not a missing GCU: say so, do not spin
            log.exception("the GCU connection task failed")
            raise

    async def _open(self) -> None:
        """Open the client, retrying with exponential backoff until it answers."""
        delay = self.retry_initial
        self.attempts = 0
        while True:
            try:
                await self.gcu.open()
            except (LinkLost, OSError) as exc:
                self.attempts += 1
                self.last_error = str(exc) or type(exc).__name__
                log.info("GCU not answering (attempt %d): %s; retrying in %.2g s",
                         self.attempts, self.last_error, delay)  # fmt: skip
                self._next_attempt = self._clock() + delay
                await asyncio.sleep(delay)
                self._next_attempt = None
                delay = min(delay * 2.0, self.retry_max)
                continue
            self.connects += 1
            self.last_error = None
            self._state = ConnectionState.CONNECTED
            self._connected.set()
            log.info("connected to %s after %d failed attempt(s)", self.gcu.transport.url,
                     self.attempts)  # fmt: skip
            return

    async def _watch(self) -> None:
        """Return when the open client's transport has given up (or the client closed)."""
        gcu = self.gcu
        while True:
            await asyncio.sleep(WATCH_SECONDS)
            if gcu.state is not ClientState.OPEN:
                return
            transport = gcu.transport
            reconnecting = bool(getattr(transport, "reconnecting", False))
            if not gcu.link.up and not transport.connected and not reconnecting:
                return
