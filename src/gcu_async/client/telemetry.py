"""What the client reports: telemetry fan-out (bounded per-subscriber queues where the newest
sample wins) and callbacks (telemetry, link events)."""

from __future__ import annotations

import asyncio
import inspect
import logging
from collections import deque
from collections.abc import AsyncGenerator, Callable
from typing import Generic, TypeVar

from gcu_async._checks import type_error
from gcu_async.session.events import TelemetrySample

__all__ = ["Callbacks", "Telemetry", "TelemetrySample", "TelemetrySubscription"]

log = logging.getLogger("gcu_async.client")
_T = TypeVar("_T")


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


class Callbacks(Generic[_T]):
    """Callbacks of one kind (``what`` names it in the log when one raises): each is called
    with every value emitted; one that raises is logged and the others still run."""

    def __init__(self, what: str, changed: Callable[[], None] | None = None) -> None:
        self._what = what
        self._changed = changed
        self.callbacks: list[Callable[[_T], None]] = []

    def add(self, callback: Callable[[_T], None]) -> Callable[[], None]:
        """Add ``callback`` (a callable taking one argument); returns a function that
        removes it once (calling it again does nothing)."""
        _check_callback(callback)
        callbacks = self.callbacks
        callbacks.append(callback)
        changed = self._changed
        if changed is not None:
            changed()

        def unsubscribe() -> None:
            if callback in callbacks:
                callbacks.remove(callback)
                if changed is not None:
                    changed()

        return unsubscribe

    def emit(self, value: _T) -> None:
        for callback in list(self.callbacks):
            try:
                callback(value)
            except Exception:
                log.exception("%s callback failed", self._what)


class Telemetry:
    """Telemetry samples fanned out to subscriptions (iterators) and callbacks. ``consumed``
    is told whether anyone consumes samples (the session builds them only then)."""

    def __init__(self, consumed: Callable[[bool], None]) -> None:
        self._consumed = consumed
        self.subscriptions: set[TelemetrySubscription] = set()
        self.callbacks: Callbacks[TelemetrySample] = Callbacks("telemetry", self._changed)
        self.dropped = 0
        """Samples dropped by subscriptions that fell behind, all together."""

    def _changed(self) -> None:
        self._consumed(bool(self.subscriptions or self.callbacks.callbacks))

    def subscribe(self, maxsize: int) -> TelemetrySubscription:
        sub = TelemetrySubscription(maxsize)
        self.subscriptions.add(sub)
        self._changed()
        return sub

    def unsubscribe(self, sub: TelemetrySubscription) -> None:
        self.subscriptions.discard(sub)
        self._changed()

    async def samples(self, maxsize: int, ended: bool) -> AsyncGenerator[TelemetrySample, None]:
        """Samples as they arrive, through a subscription of ``maxsize`` (``ended``: the
        client is closed or closing: none come, the iterator ends)."""
        sub = self.subscribe(maxsize)
        if ended:
            sub.close()
        try:
            while (sample := await sub.get()) is not None:
                yield sample
        finally:
            self.unsubscribe(sub)

    def publish(self, sample: TelemetrySample) -> None:
        for sub in self.subscriptions:
            before = sub.dropped
            sub.put(sample)
            self.dropped += sub.dropped - before
        if self.callbacks.callbacks:
            self.callbacks.emit(sample)

    def close(self) -> None:
        """End every subscription (its iterator ends once it read what it holds)."""
        for sub in self.subscriptions:
            sub.close()


def _check_callback(callback: object) -> None:
    """A callable that takes one positional argument (the sample or the event)."""
    if not callable(callback):
        raise type_error("callback", "a callable taking one argument", callback)
    try:
        signature = inspect.signature(callback)
    except (TypeError, ValueError):  # some builtins have none: trust them
        return
    try:
        signature.bind(None)
    except TypeError:
        raise type_error("callback", f"a callable taking one argument (not {signature})",
                         callback) from None  # fmt: skip
