"""Heading fields: U16, 0.01°, [0, 36000) in V2.0.6 — and how devices in the field fill them.

V2.0.6 gives both headings of the protocol, the aircraft yaw (host bytes 16–17) and the
camera's absolute yaw (GCU bytes 22–23), as a U16 in [0, 36000). Devices in the field write
a signed S16 ±18000 into them instead: ArduPilot 4.7 its aircraft yaw (docs/protocol-notes.md
§15), the Z-1Pro (firmware 6.7) its camera yaw ("What real pods do"). So a raw value reads
one of three ways, by range alone (:class:`Reading`):

- ``0 … 35999``: the document's U16 (a signed value 0 … 179.99° looks the same);
- ``47536 … 65535``: only a signed S16 explains it: −18000 … −1, −180° … −0.01°;
- ``36000 … 47535``: neither (U16 past 360°, S16 below −180°): read as an angle past 360°,
  wrapped.

:meth:`HeadingRule.degrees` turns any raw value into a heading in [0°, 360°) by that rule;
the raw value itself is never changed, and the last two readings are flagged.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from functools import cached_property

from gcu_async.protocol.fields import WIRE_RANGES, WireField


class Reading(enum.Enum):
    """How a raw heading value is read."""

    U16 = "U16"
    """In V2.0.6's [0, 36000)."""
    SIGNED = "S16"
    """A signed ±18000 value's negative half (−180° … −0.01°) in the U16 field."""
    PAST_TURN = "past 360"
    """Neither: an angle past 360° (wrapped), the reading that needs no sign."""


SIGNED_DETAIL = ("read as a signed S16 heading, -180 to -0.01 deg, as devices in the field "
                 "send it; shown wrapped into [0, 360) deg")  # fmt: skip
"""The anomaly detail of a raw value only the signed reading explains (ASCII: the dissector
shows the same words)."""
PAST_TURN_DETAIL = ("neither U16 [0, 36000) nor signed S16 -18000 to -1; read as an angle past "
                    "360 deg, shown wrapped into [0, 360) deg")  # fmt: skip
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
        """Raw steps in a full turn: the field's range, 36000."""
        return self.field.raw_high + 1

    @cached_property
    def span(self) -> int:
        """Raw values the wire type carries: 65536."""
        return WIRE_RANGES[self.field.fmt][1] + 1

    @cached_property
    def signed_low(self) -> int:
        """The first raw value only a signed reading explains: −18000 as a U16, 47536."""
        return self.span - self.turn // 2

    def reading(self, raw: int) -> Reading:
        if raw < self.turn:
            return Reading.U16
        return Reading.SIGNED if raw >= self.signed_low else Reading.PAST_TURN

    def signed(self, raw: int) -> int:
        """The raw value as the rule reads it, before wrapping: ``raw − 65536`` from
        :attr:`signed_low` on, else ``raw``."""
        return raw - self.span if raw >= self.signed_low else raw

    def degrees(self, raw: int) -> float:
        """The heading in [0°, 360°) of any raw value 0 … 65535."""
        turn = self.turn
        if raw < turn:  # the document's range: most values
            return raw / self.field.scale
        return (self.signed(raw) % turn) / self.field.scale

    def signed_raw(self, degrees: float) -> int:
        """What a device sending the signed S16 puts in the field for the heading ``degrees``
        (any finite angle): rounded to the field's step, wrapped into [−180°, 180°), as a U16
        (−0.01° is 65535)."""
        half = self.turn // 2
        return ((round(degrees * self.field.scale) + half) % self.turn - half) % self.span

    def detail(self, raw: int) -> str:
        """The anomaly detail of ``raw`` (``""`` in the document's range)."""
        reading = self.reading(raw)
        if reading is Reading.U16:
            return ""
        return SIGNED_DETAIL if reading is Reading.SIGNED else PAST_TURN_DETAIL


__all__ = ["PAST_TURN_DETAIL", "SIGNED_DETAIL", "HeadingRule", "Reading"]
