"""Telemetry fan-out: bounded per-subscriber queues where the newest sample wins."""

from __future__ import annotations

import asyncio
from collections import deque

from gcu_async.session.events import TelemetrySample

__all__ = ["TelemetrySample", "TelemetrySubscription"]


class TelemetrySubscription:
    """A bounded queue of samples; when full, the oldest is dropped (and counted)."""

    def __init__(self, maxsize: int) -> None:
        if maxsize < 1:
            raise ValueError(f"maxsize: {maxsize!r} must be >= 1")
        self._items: deque[TelemetrySample] = deque(maxlen=maxsize)
        self._event = asyncio.Event()
        self._closed = False
        self.dropped = 0

    def put(self, sample: TelemetrySample) -> None:
        if len(self._items) == self._items.maxlen:
            self.dropped += 1
        self._items.append(sample)
        self._event.set()

    def close(self) -> None:
        self._closed = True
        self._event.set()

    async def get(self) -> TelemetrySample | None:
        """Next sample, or ``None`` once closed and empty."""
        while not self._items:
            if self._closed:
                return None
            self._event.clear()
            await self._event.wait()
        return self._items.popleft()
