"""Injectable time for the simulator: a monotonic clock, or a manual one for tests."""

from __future__ import annotations

import time
from typing import Protocol


class Clock(Protocol):
    """Anything with ``now()`` giving monotonic seconds."""

    def now(self) -> float: ...


class MonotonicClock:
    """Real time: :func:`time.monotonic`."""

    def now(self) -> float:
        return time.monotonic()


class ManualClock:
    """Time that moves only when told to (deterministic tests)."""

    def __init__(self, start: float = 0.0) -> None:
        self._now = float(start)

    def now(self) -> float:
        return self._now

    def advance(self, seconds: float) -> float:
        """Move time forward by ``seconds`` (≥ 0); return the new time."""
        if not seconds >= 0:
            raise ValueError(f"seconds: {seconds!r} is outside the allowed range [0, inf)")
        self._now += seconds
        return self._now
