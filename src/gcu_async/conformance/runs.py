"""The host's commands as the GCU answers them: feedback timing and the same-opcode rule.

A *run* is a stretch of consecutive host packets with one opcode (the client repeats a
command until its feedback comes; docs/protocol-notes.md §4 "The same-opcode rule"). For each
command run :class:`CommandRuns` measures the time from its first packet to the first reply
carrying its opcode as feedback, counts the runs no feedback answered within
:data:`FEEDBACK_GRACE_S` of the host moving on, the feedback for opcodes the host never sent,
and how the GCU answers repeats: the replies during a run that carry its feedback, and the
runs of an opcode sent again after null packets (V2.0.6: it executes again). Bounded memory:
counters, a latency histogram, two runs, a few examples.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass

from gcu_async.protocol.enums import Opcode, opcode_name

FEEDBACK_GRACE_S = 1.0
"""A command's feedback may still come this long after the host sent another opcode."""
LATENCY_BUCKETS_MS = (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000)
"""Upper bounds (ms) of the feedback-latency histogram; slower ones go in one more bucket."""


@dataclass
class Run:
    """One command run."""

    opcode: int
    start: float | None
    """When its first packet went out (``None``: no times given)."""
    again: bool
    """The previous command run had this opcode too, only null packets between."""
    packets: int = 1
    answered: bool = False
    ended: float | None = None


class Latencies:
    """Seconds from a command's first packet to its feedback: count, min, max, mean and a
    histogram over :data:`LATENCY_BUCKETS_MS`."""

    def __init__(self) -> None:
        self.count = 0
        self.total = 0.0
        self.low = float("inf")
        self.high = 0.0
        self.buckets = [0] * (len(LATENCY_BUCKETS_MS) + 1)

    def add(self, seconds: float) -> None:
        seconds = max(seconds, 0.0)
        self.count += 1
        self.total += seconds
        self.low = min(self.low, seconds)
        self.high = max(self.high, seconds)
        self.buckets[bisect.bisect_left(LATENCY_BUCKETS_MS, seconds * 1000)] += 1

    def median_bound_ms(self) -> int | None:
        """The histogram bound within which half the feedback came (``None``: beyond the
        last bound, or no feedback)."""
        seen = 0
        for bound, n in zip(LATENCY_BUCKETS_MS, self.buckets, strict=False):
            seen += n
            if 2 * seen >= self.count > 0:
                return bound
        return None

    def text(self) -> str:
        if not self.count:
            return "no command answered"
        half = self.median_bound_ms()
        within = f"half within {half} ms" if half is not None else "half beyond 5 s"
        return (f"feedback {self.low * 1000:.1f}–{self.high * 1000:.1f} ms after the command's "
                f"first packet (mean {self.total / self.count * 1000:.1f} ms, {within}; "
                f"{self.count} commands)")  # fmt: skip

    def as_dict(self) -> dict[str, object]:
        return {
            "count": self.count,
            "min_ms": round(self.low * 1000, 3) if self.count else None,
            "max_ms": round(self.high * 1000, 3) if self.count else None,
            "mean_ms": round(self.total / self.count * 1000, 3) if self.count else None,
            "histogram_ms": {str(b): n for b, n in zip((*LATENCY_BUCKETS_MS, "more"),
                                                       self.buckets, strict=True) if n},
        }  # fmt: skip


class CommandRuns:
    """Feed it every host packet's opcode (:meth:`sent`) and every reply's feedback opcode
    (:meth:`reply`), in the order they happened; ``time`` in seconds on any clock, or
    ``None`` when unknown (then nothing is timed and a run's feedback is awaited until the
    next run ends)."""

    def __init__(self, examples: int) -> None:
        self._examples = examples
        self.host_packets = 0
        self.current: Run | None = None
        """The command run going on (``None``: null packets, or none yet)."""
        self.previous: Run | None = None
        """The last command run, while its feedback may still come."""
        self._last_command: int | None = None
        self._nulls_since = False
        self._sent = 0
        """Bit n set: opcode n was sent."""
        self.latency = Latencies()
        self.missing = 0
        self.missing_examples: list[tuple[float | None, str]] = []
        self.unsolicited = 0
        self.unsolicited_examples: list[tuple[float | None, str]] = []
        self.again = 0
        self.again_answered = 0
        self.run_replies = 0
        """Replies that came while a command run was going on."""
        self.run_feedback = 0
        """Of those, the ones carrying the run's opcode as feedback."""

    # -- input --------------------------------------------------------------------------------
    def sent(self, opcode: int, time: float | None) -> None:
        self.host_packets += 1
        self._sent |= 1 << opcode
        self._expire(time)
        run = self.current
        if run is not None and run.opcode == opcode:
            run.packets += 1
            return
        if run is not None:
            run.ended = time
            self._settle(self.previous)
            self.previous = run if not run.answered else None
            self._last_command, self._nulls_since = run.opcode, False
        if opcode == Opcode.NULL:
            self.current = None
            self._nulls_since = True
            return
        again = opcode == self._last_command and self._nulls_since
        self.again += again
        self.current = Run(opcode, time, again)

    def reply(self, opcode: int, time: float | None) -> None:
        """One reply whose feedback carries ``opcode``."""
        self._expire(time)
        run = self.current
        if run is not None:
            self.run_replies += 1
            if opcode == run.opcode:
                self.run_feedback += 1
                self._answer(run, time)
                return
        if opcode == Opcode.NULL:
            return
        prev = self.previous
        if prev is not None and prev.opcode == opcode:
            self._answer(prev, time)
            self.previous = None
        elif self.host_packets and not self._sent >> opcode & 1:
            self.unsolicited += 1
            self._note(self.unsolicited_examples, time,
                       f"feedback 0x{opcode:02X} {opcode_name(opcode)}: the host never sent it")

    # -- internals ----------------------------------------------------------------------------
    def _answer(self, run: Run, time: float | None) -> None:
        if run.answered:
            return
        run.answered = True
        self.again_answered += run.again
        if time is not None and run.start is not None:
            self.latency.add(time - run.start)

    def _expire(self, time: float | None) -> None:
        prev = self.previous
        if (prev is not None and time is not None and prev.ended is not None
                and time - prev.ended > FEEDBACK_GRACE_S):  # fmt: skip
            self._settle(prev)
            self.previous = None

    def _settle(self, run: Run | None) -> None:
        """``run`` had its last chance: count it if no feedback answered it."""
        if run is None or run.answered:
            return
        self.missing += 1
        self._note(self.missing_examples, run.start,
                   f"0x{run.opcode:02X} {opcode_name(run.opcode)} in {run.packets} packet(s): "
                   "no reply carried its feedback")  # fmt: skip

    def _note(self, examples: list[tuple[float | None, str]], time: float | None,
              text: str) -> None:  # fmt: skip
        if len(examples) < self._examples:
            examples.append((time, text))

    def pending_missing(self, now: float | None) -> int:
        """Runs without feedback so far, counting those still waiting whose grace is over at
        ``now`` (what :meth:`report` would settle), without changing anything."""
        extra = 0
        for run in (self.previous, self.current):
            if run is None or run.answered or run.start is None or now is None:
                continue
            since = run.ended if run.ended is not None else run.start
            extra += now - since > FEEDBACK_GRACE_S
        return self.missing + extra


__all__ = ["FEEDBACK_GRACE_S", "LATENCY_BUCKETS_MS", "CommandRuns", "Latencies", "Run"]
