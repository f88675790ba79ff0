"""Test helper for the transport suites: records what a transport delivers, with bounded
waits (never a bare ``await`` that could hang)."""

from __future__ import annotations

import asyncio
import contextlib
import os
from collections.abc import Callable

from gcu_async.transport import LinkEvent, LinkEventKind, Transport


class Recorder:
    """Handlers for a transport: every delivery and event, in arrival order, with the loop
    time it arrived at."""

    def __init__(self, transport: Transport | None = None) -> None:
        self.loop = asyncio.get_running_loop()
        self.chunks: list[bytes] = []
        self.events: list[LinkEvent] = []
        self.event_times: list[float] = []
        self.log: list[tuple[str, object]] = []
        self._changed = asyncio.Event()
        if transport is not None:
            transport.set_handlers(self.on_data, self.on_event)

    @property
    def data(self) -> bytes:
        return b"".join(self.chunks)

    def kinds(self) -> list[LinkEventKind]:
        return [e.kind for e in self.events]

    def on_data(self, data: bytes) -> None:
        self.chunks.append(data)
        self.log.append(("data", data))
        self._changed.set()

    def on_event(self, event: LinkEvent) -> None:
        self.events.append(event)
        self.event_times.append(self.loop.time())
        self.log.append(("event", event))
        self._changed.set()

    async def wait_until(self, predicate: Callable[[], bool], timeout: float = 2.0) -> None:
        """Return once ``predicate()`` holds; AssertionError after ``timeout`` seconds."""
        deadline = self.loop.time() + timeout
        while not predicate():
            left = deadline - self.loop.time()
            if left <= 0:
                raise AssertionError(
                    f"condition not met within {timeout} s; events={self.events!r}, "
                    f"data={self.data[:80]!r}"
                )
            self._changed.clear()
            with contextlib.suppress(asyncio.TimeoutError):
                await asyncio.wait_for(self._changed.wait(), left)

    async def wait_bytes(self, n: int, timeout: float = 2.0) -> bytes:
        await self.wait_until(lambda: len(self.data) >= n, timeout)
        return self.data

    async def wait_events(self, n: int, timeout: float = 2.0) -> list[LinkEvent]:
        await self.wait_until(lambda: len(self.events) >= n, timeout)
        return self.events


def other_tasks() -> set[asyncio.Task[object]]:
    """Tasks other than the running test's own."""
    return {t for t in asyncio.all_tasks() if t is not asyncio.current_task() and not t.done()}


def open_fds() -> set[int]:
    """The process's open file descriptors (Linux /proc), without the one used to list
    them (closed again by the time we look at it)."""
    fds = set()
    for name in os.listdir("/proc/self/fd"):
        try:
            os.readlink(f"/proc/self/fd/{name}")
        except OSError:
            continue
        fds.add(int(name))
    return fds
