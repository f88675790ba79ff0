"""Rate-limited logging: a line that repeats while a condition lasts (a flood of hostile
input, a link that stays down) must not become a flood of log lines.

Used by the client (a send that fails on every heartbeat while the link is down, open
attempts that fail while the GCU is away) and the MAVLink bridge (docs/mavlink-bridge.md,
"The bridge contract", BG7).
"""

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
    """At most ``burst`` lines per *kind* (a fixed string chosen by the caller, never taken
    from input) every ``window`` seconds; the rest are counted and summed up in one line
    when the window ends (:meth:`flush`, or the next line of that kind).

    ``name`` starts the summary line (``"bridge: 12 more … lines suppressed in 10 s"``);
    ``summary_level`` is its level (``None``: the highest level of the lines it sums up)."""

    def __init__(self, logger: logging.Logger, *, burst: int = BURST, window: float = WINDOW,
                 clock: Callable[[], float] = time.monotonic, name: str = "",
                 summary_level: int | None = None) -> None:  # fmt: skip
        self.logger = logger
        self.burst = burst
        self.window = window
        self.name = name
        self.summary_level = summary_level
        self._clock = clock
        self._kinds: dict[str, list[float]] = {}
        """kind → [window start, lines logged, lines suppressed, highest suppressed level]."""
        self.suppressed = 0
        """Lines suppressed so far (all kinds)."""

    def log(self, level: int, kind: str, msg: str, *args: Any, exc_info: bool = False) -> None:
        now = self._clock()
        state = self._kinds.get(kind)
        if state is None or now - state[0] >= self.window:
            if state is not None:
                self._summary(kind, state)
            state = self._kinds[kind] = [now, 0, 0, 0]
        if state[1] < self.burst:
            state[1] += 1
            self.logger.log(level, msg, *args, exc_info=exc_info)
        else:
            state[2] += 1
            state[3] = max(state[3], level)
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
            level = self.summary_level if self.summary_level is not None else int(state[3])
            prefix = f"{self.name}: " if self.name else ""
            self.logger.log(level, "%s%d more %s lines suppressed in %g s", prefix,
                            int(state[2]), kind, self.window)  # fmt: skip
