"""Heading fields: U16, 0.01°, one full turn from 0 in V2.0.6 — and how devices fill them.

V2.0.6 gives both headings of the protocol, the aircraft yaw and the camera's absolute yaw,
as a U16 from 0 up to a full turn (:func:`heading`). Devices in the field write a signed S16
of half a turn either way into them instead: ArduPilot 4.7 its aircraft yaw
(docs/protocol-notes.md §15), the Z-1Pro (firmware 6.7) its camera yaw ("What real pods
do"). So a raw value reads one of three ways, by range alone (:class:`Reading`):

- below a full turn: the document's U16 (a signed value's positive half looks the same);
- from :attr:`HeadingRule.signed_low` (minus half a turn as a U16) to the wire type's top:
  only a signed S16 explains it, a heading west of north;
- in between: neither (U16 past a full turn, S16 below minus half a turn): read as an angle
  past a full turn, wrapped.

:meth:`HeadingRule.degrees` turns any raw value into a heading of the document's range by
that rule; the raw value itself is never changed, and the last two readings are flagged.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from functools import cached_property

from gcu_async.protocol.fields import CENTIDEGREE, WIRE_RANGES, WireField

TURN = 36000
"""A full turn in raw heading steps (0.01°)."""


def heading(name: str, doc: str) -> WireField:
    """A heading field as V2.0.6 gives it: U16, 0.01° steps, from 0 up to a full turn."""
    return WireField(name, "H", doc, 0, TURN, 100, "deg", CENTIDEGREE, high_open=True)


class Reading(enum.Enum):
    """How a raw heading value is read."""

    U16 = "U16"
    """In V2.0.6's range: below a full turn."""
    SIGNED = "S16"
    """A signed value's negative half (west of north) in the U16 field."""
    PAST_TURN = "past 360"
    """Neither: an angle past a full turn (wrapped), the reading that needs no sign."""


_STEP, _HALF = 1 / 100, TURN // 2 / 100
_SHOWN = f"shown wrapped into [0, {TURN / 100:g}) deg"
SIGNED_DETAIL = (f"read as a signed S16 heading, {-_HALF:g} to {-_STEP:g} deg, as devices in "
                 f"the field send it; {_SHOWN}")  # fmt: skip
"""The anomaly detail of a raw value only the signed reading explains (ASCII: the dissector
shows the same words)."""
PAST_TURN_DETAIL = (f"neither U16 [0, {TURN}) nor signed S16 {-TURN // 2} to -1; read as an "
                    f"angle past {TURN / 100:g} deg, {_SHOWN}")  # fmt: skip
"""The anomaly detail of a raw value neither reading explains."""


@dataclass(frozen=True)
class HeadingRule:
    """The reading of one heading ``field`` (a U16 whose range is one full turn)."""

    field: WireField

    def __post_init__(self) -> None:
        f = self.field
        if f.fmt != "H" or f.raw_low != 0:
            raise ValueError(f"{f.name}: a heading is a U16 field from 0, not {f.fmt!r} "
                             f"from {f.raw_low}")  # fmt: skip

    @cached_property
    def turn(self) -> int:
        """Raw steps in a full turn: the field's range (:data:`TURN`)."""
        return self.field.raw_high + 1

    @cached_property
    def span(self) -> int:
        """Raw values the wire type carries (a U16's)."""
        return WIRE_RANGES[self.field.fmt][1] + 1

    @cached_property
    def signed_low(self) -> int:
        """The first raw value only a signed reading explains: minus half a turn as a U16."""
        return self.span - self.turn // 2

    def reading(self, raw: int) -> Reading:
        if raw < self.turn:
            return Reading.U16
        return Reading.SIGNED if raw >= self.signed_low else Reading.PAST_TURN

    def signed(self, raw: int) -> int:
        """The raw value as the rule reads it, before wrapping: ``raw − span`` from
        :attr:`signed_low` on, else ``raw``."""
        return raw - self.span if raw >= self.signed_low else raw

    def degrees(self, raw: int) -> float:
        """The heading in the document's range, degrees, of any raw value of the wire type."""
        turn = self.turn
        if raw < turn:  # the document's range: most values
            return raw / self.field.scale
        return (self.signed(raw) % turn) / self.field.scale

    def signed_raw(self, degrees: float) -> int:
        """What a device sending the signed S16 puts in the field for the heading ``degrees``
        (any finite angle): rounded to the field's step, wrapped into half a turn either way,
        as a U16 (one step west of north is the U16's largest value)."""
        half = self.turn // 2
        return ((round(degrees * self.field.scale) + half) % self.turn - half) % self.span

    def detail(self, raw: int) -> str:
        """The anomaly detail of ``raw`` (``""`` in the document's range)."""
        reading = self.reading(raw)
        if reading is Reading.U16:
            return ""
        return SIGNED_DETAIL if reading is Reading.SIGNED else PAST_TURN_DETAIL


__all__ = ["PAST_TURN_DETAIL", "SIGNED_DETAIL", "TURN", "HeadingRule", "Reading", "heading"]
