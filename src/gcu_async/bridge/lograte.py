"""Rate-limited logging: a flood of hostile or broken input must not become a flood of
log lines (docs/mavlink-bridge.md, "The bridge contract", BG7)."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import Any

BURST = 5
"""Lines per kind logged in one window."""
WINDOW = 10.0
"""Seconds of one window; what the window suppressed is reported in one line after it."""


class LogLimiter:
    """At most :data:`BURST` lines per *kind* (a fixed string chosen by the caller, never
    taken from input) every :data:`WINDOW` seconds; the rest are counted and summed up in
    one line when the window ends (:meth:`flush`, or the next line of that kind)."""

    def __init__(self, logger: logging.Logger, *, burst: int = BURST, window: float = WINDOW,
                 clock: Callable[[], float] = time.monotonic) -> None:  # fmt: skip
        self.logger = logger
        self.burst = burst
        self.window = window
        self._clock = clock
        self._kinds: dict[str, list[float]] = {}
        """kind → [window start, lines logged, lines suppressed]."""
        self.suppressed = 0
        """Lines suppressed so far (all kinds)."""

    def log(self, level: int, kind: str, msg: str, *args: Any, exc_info: bool = False) -> None:
        now = self._clock()
        state = self._kinds.get(kind)
        if state is None or now - state[0] >= self.window:
            if state is not None:
                self._summary(kind, state)
            state = self._kinds[kind] = [now, 0, 0]
        if state[1] < self.burst:
            state[1] += 1
            self.logger.log(level, msg, *args, exc_info=exc_info)
        else:
            state[2] += 1
            self.suppressed += 1

    def flush(self) -> None:
        """Report the windows that ended with lines suppressed."""
        now = self._clock()
        for kind, state in list(self._kinds.items()):
            if now - state[0] >= self.window:
                self._summary(kind, state)
                del self._kinds[kind]

    def _summary(self, kind: str, state: list[float]) -> None:
        if state[2]:
            self.logger.warning("bridge: %d more %s lines suppressed in %g s", state[2], kind,
                                self.window)  # fmt: skip
