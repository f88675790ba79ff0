"""Link health: reply rate, age of the last reply, counters, lost/restored episodes."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, fields
from typing import TypedDict, cast

from gcu_async.protocol.deframer import DeframerStats
from gcu_async.session.runs import RunStats


class LinkHealthDict(TypedDict):
    """:meth:`LinkHealth.as_dict`: the fields by name (JSON-ready)."""

    up: bool
    reply_rate: float
    last_reply_age: float | None
    packets_sent: int
    packets_received: int
    send_errors: int
    crc_errors: int
    length_errors: int
    bytes_discarded: int
    other_versions: int
    unmatched_feedback: int
    ambiguous_feedback: int
    lost_count: int
    restored_count: int
    restarted_count: int

RATE_WINDOW_S = 1.0
"""Seconds of replies :attr:`LinkHealth.reply_rate` counts (a rate shown less than this
long after the first reply is still warming up)."""


@dataclass(frozen=True)
class LinkHealth:
    """A snapshot of the link's health (times in seconds on the session's clock)."""

    up: bool
    """True while replies arrive (no silence longer than ``silence_timeout``)."""
    reply_rate: float
    """Replies per second over the last :data:`RATE_WINDOW_S` (one second)."""
    last_reply_age: float | None
    """Seconds since the last valid reply, ``None`` before the first."""
    packets_sent: int
    packets_received: int
    send_errors: int
    crc_errors: int
    length_errors: int
    bytes_discarded: int
    other_versions: int
    """Replies whose version byte is neither 1 nor 2: decoded with the V2.0.6 layout and
    used like any other (docs/client.md, "Liberal receive, strict send"); the first one is
    logged as a warning."""
    unmatched_feedback: int
    """Replies that answer no packet this session could still be waiting for."""
    ambiguous_feedback: int
    """Replies that could answer more than one run of packets (used as proof of nothing)."""
    lost_count: int
    restored_count: int
    restarted_count: int = 0
    """Times the GCU came back from a loss with its state reset (docs/client.md, "GCU
    restarts")."""

    def as_dict(self) -> LinkHealthDict:
        """Every field by name: numbers, a bool and ``None`` (JSON-ready, e.g. for a web
        page)."""
        return cast(LinkHealthDict, {f.name: getattr(self, f.name) for f in fields(self)})


class HealthTracker:
    """Counts and timestamps behind :class:`LinkHealth` (no I/O, no clock of its own)."""

    __slots__ = ("_recent", "last_reply", "lost_count", "other_versions", "packets_received",
                 "packets_sent", "restarted_count", "restored_count", "send_errors")  # fmt: skip

    def __init__(self) -> None:
        self.last_reply: float | None = None
        self._recent: deque[float] = deque(maxlen=1024)
        self.packets_sent = 0
        self.packets_received = 0
        self.send_errors = 0
        self.other_versions = 0
        self.lost_count = 0
        self.restored_count = 0
        self.restarted_count = 0

    def on_reply(self, now: float) -> None:
        self.packets_received += 1
        self.last_reply = now
        self._recent.append(now)

    def silent_for(self, now: float) -> float:
        """Seconds since the last reply (infinite before the first)."""
        return float("inf") if self.last_reply is None else now - self.last_reply

    def reply_rate(self, now: float) -> float:
        recent = self._recent
        while recent and now - recent[0] > RATE_WINDOW_S:
            recent.popleft()
        return float(len(recent))

    def snapshot(self, now: float, up: bool, deframer: DeframerStats,
                 runs: RunStats) -> LinkHealth:  # fmt: skip
        """The :class:`LinkHealth` at ``now``: these counts, the deframer's and the run
        ledger's."""
        last = self.last_reply
        return LinkHealth(
            up=up, reply_rate=self.reply_rate(now),
            last_reply_age=None if last is None else now - last,
            packets_sent=self.packets_sent, packets_received=self.packets_received,
            send_errors=self.send_errors, crc_errors=deframer.crc_errors,
            length_errors=deframer.length_errors, bytes_discarded=deframer.bytes_discarded,
            other_versions=self.other_versions, unmatched_feedback=runs.unmatched,
            ambiguous_feedback=runs.ambiguous, lost_count=self.lost_count,
            restored_count=self.restored_count, restarted_count=self.restarted_count,
        )  # fmt: skip
