"""What both conformance reports are made of: deviations, their examples and their text.

A :class:`Deviation` is one kind of departure from V2.0.6 (a key, a title, a count of the
packets that show it, a diagnosis) with a few :class:`Example` packets; :class:`Findings`
collects them by key while packets are fed, keeping at most ``examples`` examples each;
:func:`deviation_lines` writes them for a terminal. The host's report
(:mod:`~gcu_async.conformance.host`) and the GCU's (:mod:`~gcu_async.conformance.gcu`)
share them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from gcu_async._checks import check_int

EXAMPLES = 3
"""Examples kept per deviation by default."""


class ByKey:
    """Lookup of a report's deviations by key (both reports' base)."""

    deviations: tuple[Deviation, ...]

    @property
    def keys(self) -> tuple[str, ...]:
        """The keys of the deviations found, in the report's order."""
        return tuple(d.key for d in self.deviations)

    def get(self, key: str) -> Deviation | None:
        """The deviation of ``key``, ``None`` if none was found."""
        return next((d for d in self.deviations if d.key == key), None)


@dataclass(frozen=True)
class Example:
    """One packet that shows a deviation."""

    time: float
    """Seconds since the first packet (NaN: the input had no times)."""
    raw_hex: str
    """The packet as received (empty when only the decoded packet was given)."""
    decoded: str
    """The values concerned, decoded."""

    def as_dict(self) -> dict[str, Any]:
        time = round(self.time, 3) if math.isfinite(self.time) else None
        return {"time_s": time, "raw_hex": self.raw_hex, "decoded": self.decoded}


@dataclass
class Deviation:
    """One kind of deviation: ``count`` of the ``total`` packets examined show it (gaps:
    of the intervals between packets; velocity: of the windows compared; the rate: 1 of 0,
    a property of the whole run)."""

    key: str
    """Stable name, e.g. ``main.aircraft_yaw_raw``, ``command.RECORD.cameras``,
    ``opcode.standing``, ``main.all_zero``, ``ins_valid.toggles``, ``velocity.scale``."""
    title: str
    count: int = 0
    total: int = 0
    examples: list[Example] = field(default_factory=list)
    diagnosis: str = ""

    def as_dict(self) -> dict[str, Any]:
        return {
            "key": self.key, "title": self.title, "count": self.count, "total": self.total,
            "diagnosis": self.diagnosis, "examples": [e.as_dict() for e in self.examples],
        }  # fmt: skip


def when(t: float | None) -> float:
    """An example's time: NaN when the input had none."""
    return math.nan if t is None else t


class Findings:
    """The deviations found so far, by key, each with its first few examples."""

    __slots__ = ("devs", "examples")

    def __init__(self, examples: int = EXAMPLES,
                 devs: dict[str, Deviation] | None = None) -> None:  # fmt: skip
        self.examples = check_int("examples", examples, 0, 100)
        """Examples kept per deviation."""
        self.devs: dict[str, Deviation] = {} if devs is None else devs

    def dev(self, key: str, title: str) -> Deviation:
        """The deviation ``key``, made with ``title`` the first time."""
        d = self.devs.get(key)
        if d is None:
            d = self.devs[key] = Deviation(key, title)
        return d

    def example(self, d: Deviation, t: float | None, raw: bytes, decoded: str) -> None:
        """Keep the first few examples of ``d`` that read differently."""
        if len(d.examples) < self.examples and all(e.decoded != decoded for e in d.examples):
            d.examples.append(Example(when(t), raw.hex(" "), decoded))

    def flag(self, key: str, title: str, t: float | None, raw: bytes, decoded: str) -> None:
        """One more packet shows deviation ``key``; ``decoded`` is its example."""
        d = self.dev(key, title)
        d.count += 1
        self.example(d, t, raw, decoded)

    def copy(self, total: int) -> dict[str, Deviation]:
        """The deviations as they stand, copied (a report may add to them), each of
        ``total`` packets."""
        return {k: Deviation(d.key, d.title, d.count, total, list(d.examples), d.diagnosis)
                for k, d in self.devs.items()}  # fmt: skip


def ordered(devs: dict[str, Deviation]) -> tuple[Deviation, ...]:
    """The deviations as a report lists them: the most frequent first, then by key."""
    return tuple(sorted(devs.values(), key=lambda d: (-d.count, d.key)))


def deviation_lines(deviations: tuple[Deviation, ...]) -> list[str]:
    """The text of each deviation: its key, title and share, diagnosis, examples."""
    lines: list[str] = []
    for d in deviations:
        share = f": {d.count} of {d.total} ({100 * d.count / d.total:.1f} %)" if d.total else ""
        lines.append(f"- {d.key}: {d.title}{share}")
        if d.diagnosis:
            lines.append(f"  diagnosis: {d.diagnosis}")
        for e in d.examples:
            at = f" t={e.time:.3f} s" if math.isfinite(e.time) else ""
            lines.append(f"  e.g.{at}: {e.decoded}")
            if e.raw_hex:
                lines.append(f"       {e.raw_hex}")
    return lines


__all__ = ["EXAMPLES", "Deviation", "Example", "Findings", "deviation_lines", "ordered", "when"]
