"""Link health: reply rate, age of the last reply, error counters, lost/restored state."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass


@dataclass(frozen=True)
class LinkHealth:
    """A snapshot of the link's health (all times in seconds, monotonic clock)."""

    up: bool
    """True while replies arrive (no silence longer than ``silence_timeout``)."""
    reply_rate: float
    """Replies per second over the last second."""
    last_reply_age: float | None
    """Seconds since the last valid reply, ``None`` before the first."""
    packets_sent: int
    packets_received: int
    send_errors: int
    crc_errors: int
    length_errors: int
    bytes_discarded: int
    decode_errors: int
    unmatched_feedback: int
    lost_count: int
    restored_count: int


class HealthTracker:
    """Counts and timestamps behind :class:`LinkHealth` (no I/O, no clock of its own)."""

    def __init__(self, silence_timeout: float) -> None:
        if not silence_timeout > 0:
            raise ValueError(f"silence_timeout: {silence_timeout!r} must be > 0 seconds")
        self.silence_timeout = silence_timeout
        self.up = False
        self.last_reply: float | None = None
        self._recent: deque[float] = deque(maxlen=1024)
        self.packets_sent = 0
        self.packets_received = 0
        self.send_errors = 0
        self.decode_errors = 0
        self.lost_count = 0
        self.restored_count = 0

    def on_reply(self, now: float) -> bool:
        """Record a valid reply; True if this reply brought the link (back) up."""
        self.packets_received += 1
        self.last_reply = now
        self._recent.append(now)
        if self.up:
            return False
        self.up = True
        return True

    def silent(self, now: float) -> bool:
        """True if the link is up but no reply came for ``silence_timeout``."""
        return (
            self.up
            and self.last_reply is not None
            and now - self.last_reply > self.silence_timeout
        )

    def reply_rate(self, now: float) -> float:
        recent = self._recent
        while recent and now - recent[0] > 1.0:
            recent.popleft()
        return float(len(recent))
