"""The schema's building block: one field on the wire, written once.

A :class:`WireField` says everything the library knows about one little-endian integer field
of a frame or a command's parameters: its name, its struct code, its raw range, and how raw
integers map to engineering units (``value = raw / scale``). Frame and command schemas are
tuples of these; struct formats, offsets, send-side checks, receive-side anomalies, unit
conversions, ``as_dict``, the catalogue, the dissector's tables, the docs' tables and the tests'
range tables are all derived from them, so a range or an offset is written in exactly one place.
"""

from __future__ import annotations

import struct
from collections.abc import Iterable
from dataclasses import dataclass, field

from gcu_async.protocol.anomalies import Anomaly, check_raw
from gcu_async.protocol.units import quantize

WIRE_RANGES: dict[str, tuple[int, int]] = {
    "B": (0, 0xFF),
    "b": (-(2**7), 2**7 - 1),
    "H": (0, 0xFFFF),
    "h": (-(2**15), 2**15 - 1),
    "I": (0, 0xFFFF_FFFF),
    "i": (-(2**31), 2**31 - 1),
}
"""Every struct code a field may have, with the raw range of its wire type."""
LONGITUDE_RANGE = (-1_800_000_000, 1_800_000_000)
"""A WGS-84 longitude in 1e-7° steps, east and west: the aircraft's, the ranged target's
(what a GCU can physically report) and a gaze command's."""
LATITUDE_RANGE = (-900_000_000, 900_000_000)
"""A WGS-84 latitude in 1e-7° steps, pole to pole (as :data:`LONGITUDE_RANGE`)."""
ANGLE_RANGE = (-18000, 18000)
"""An angle of up to half a turn either way in 0.01° steps, as the document gives it to the
camera's relative angles and pitch, the aircraft's roll and the control values."""
TILT_RANGE = (-9000, 9000)
"""Up to a quarter turn either way in 0.01° steps: the camera's roll, the aircraft's pitch."""
CENTIDEGREE = "0.01 deg"
"""The raw unit of every angle field (one step of :data:`ANGLE_RANGE`, a heading's, ...)."""


@dataclass(frozen=True, slots=True)
class WireField:
    """One integer field on the wire.

    ``low``/``high`` is the raw range V2.0.6 gives (inclusive; ``high_open`` excludes
    ``high``); left ``None`` it is the wire type's own range. ``scale`` maps raw to
    engineering units (``value = raw / scale``), ``unit`` names the engineering unit and
    ``raw_unit`` the unit of one raw step (``"0.01 deg"``)."""

    name: str
    fmt: str
    doc: str = ""
    low: int | None = None
    high: int | None = None
    scale: float = 1
    unit: str = ""
    raw_unit: str = ""
    high_open: bool = False
    raw_low: int = field(init=False, repr=False, compare=False)
    """The smallest raw value allowed."""
    raw_high: int = field(init=False, repr=False, compare=False)
    """The largest raw value allowed (``high - 1`` when ``high_open``)."""

    def __post_init__(self) -> None:
        if self.fmt not in WIRE_RANGES:
            raise ValueError(f"{self.name}: struct code {self.fmt!r} is not one of "
                             f"{''.join(WIRE_RANGES)}")  # fmt: skip
        wire_low, wire_high = WIRE_RANGES[self.fmt]
        low = wire_low if self.low is None else self.low
        high = (wire_high if self.high is None else self.high) - self.high_open
        object.__setattr__(self, "raw_low", low)
        object.__setattr__(self, "raw_high", high)
        if not wire_low <= low <= high <= wire_high:
            raise ValueError(f"{self.name}: range {low}..{high} is not "
                             f"inside the wire type's {wire_low}..{wire_high}")  # fmt: skip

    @property
    def size(self) -> int:
        """Bytes on the wire."""
        return struct.calcsize("<" + self.fmt)

    @property
    def limits(self) -> tuple[float, float]:
        """The range in engineering units as the document writes it (``high`` itself
        excluded when ``high_open``)."""
        return self.raw_low / self.scale, (self.raw_high + self.high_open) / self.scale

    def anomalies(self, raw: int) -> tuple[Anomaly, ...]:
        """Receive side: ``()`` if ``raw`` is in range, else the one :class:`Anomaly`."""
        return check_raw(self.name, raw, self.raw_low, self.raw_high, self.raw_unit)

    def to_raw(self, value: float, name: str | None = None) -> int:
        """Send side: ``value`` in engineering units → the raw integer, rounded and
        range-checked (``FieldRangeError`` names ``name`` or the field, range and value)."""
        if type(value) is float or type(value) is int:  # the usual case, checked at once
            try:
                raw = round(value * self.scale)
            except (OverflowError, ValueError):  # inf, nan: quantize raises the error
                raw = self.raw_low - 1
            if self.raw_low <= raw <= self.raw_high:
                return raw
        return quantize(name or self.name, value, self.scale, self.raw_low,
                        self.raw_high + self.high_open, self.unit,
                        high_open=self.high_open)  # fmt: skip

    def from_raw(self, raw: int) -> float:
        """Receive side: the engineering value of ``raw``."""
        return raw / self.scale


def struct_of(fields: Iterable[WireField], prefix: str = "<") -> struct.Struct:
    """The little-endian struct of ``fields`` in wire order."""
    return struct.Struct(prefix + "".join(f.fmt for f in fields))


def offsets(fields: Iterable[WireField], start: int = 0) -> dict[str, int]:
    """Each field's byte offset, the first at ``start``."""
    found: dict[str, int] = {}
    at = start
    for f in fields:
        found[f.name] = at
        at += f.size
    return found


CAMERA_ZOOM = WireField("camera_zoom_raw", "H", "camera zoom ratio", scale=10, unit="x",
                        raw_unit="0.1x")
"""A zoom ratio as the GCU reports it in its sub frame (the field of both cameras' zooms),
and so the largest zoom the control rates can be scaled by (:attr:`WireField.limits`)."""
