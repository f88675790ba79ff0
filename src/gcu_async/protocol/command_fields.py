"""The kinds of command parameter a command's schema is made of (the parameter codecs).

A command's schema (:mod:`gcu_async.protocol.commands`) lists its parameters in wire order as
kinds: :class:`Cameras`, :class:`Switch`, :class:`Integer`, :class:`Choice`, :class:`Real`,
:class:`Point`, :class:`Box`, :class:`Thresholds`, :class:`ZoomValue`. Each maps one or more
attributes of the command class to one or more
:class:`~gcu_async.protocol.fields.WireField` and implements, once for every command that uses
it, the interface of :class:`~gcu_async.protocol.command_schema.ParamKind`: the send-side
check (``encode``), the receive side (``decode``, ``anomalies``), the JSON form and the
catalogue's :class:`~gcu_async.protocol.command_schema.Parameter`.

A real parameter is checked in engineering units against its range as given, then rounded to
the wire resolution (:class:`RealRange`): ``ZoomTo(ratio=3276.84)`` is refused, as the client
method refuses it.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import Any, ClassVar, NamedTuple

from gcu_async._checks import check_bool, check_int, check_real
from gcu_async.errors import FieldRangeError
from gcu_async.protocol.anomalies import Anomaly, check_raw
from gcu_async.protocol.command_schema import REQUIRED, Kind, Parameter, ParamKind
from gcu_async.protocol.enums import CameraMask
from gcu_async.protocol.fields import WireField
from gcu_async.protocol.units import ImageBox, ImagePoint, check_member, check_tuple


class RealRange(NamedTuple):
    """The send side of a real field: its range in engineering units and its scale."""

    name: str
    low: float
    high: float
    scale: float
    unit: str

    @classmethod
    def of(cls, w: WireField) -> RealRange:
        return cls(w.name, w.raw_low / w.scale, w.raw_high / w.scale, w.scale, w.unit)

    def check(self, value: Any, name: str | None = None) -> float:
        """``value`` checked against the range as given, not rounded first (``TypeError`` /
        :class:`~gcu_async.errors.FieldRangeError` naming ``name`` or the field)."""
        if type(value) is float and self.low <= value <= self.high:
            return value
        return check_real(name or self.name, value, self.low, self.high, self.unit)

    def raw(self, value: Any) -> int:
        """``value`` checked, rounded to the raw integer."""
        return round(self.check(value) * self.scale)


@dataclass(frozen=True)
class _Reals(ParamKind):
    """A kind whose wire fields carry real numbers."""

    limits: tuple[RealRange, ...] = field(init=False, repr=False, compare=False)
    """Each wire field's send side, in wire order."""

    def _set(self, attrs: tuple[str, ...], wire: tuple[WireField, ...]) -> None:
        super()._set(attrs, wire)
        object.__setattr__(self, "limits", tuple(RealRange.of(w) for w in wire))


def _in_range(w: WireField, raw: int) -> int:
    if not w.raw_low <= raw <= w.raw_high:
        raise ValueError(f"{w.name}: {raw} is outside {w.raw_low}..{w.raw_high}")
    return raw


def _real_parameter(w: WireField, name: str, default: object) -> Parameter:
    return Parameter(name, Kind.REAL, w.doc, w.unit, w.raw_low / w.scale, w.raw_high / w.scale,
                     default=default)  # fmt: skip


CAMERA_MASK = WireField("cameras", "B", "camera mask", 1, 0xFF, raw_unit="camera mask")
"""The camera mask's one field: one bit per camera, at least one set (0x00 selects none)."""
_CAMERA_MASKS = range(CAMERA_MASK.raw_low, CAMERA_MASK.raw_high + 1)
"""Every valid camera mask, for the encoder's one-test common case."""


@dataclass(frozen=True)
class Cameras(ParamKind):
    """The camera mask (KK / NN), an ``int`` in :data:`CAMERA_MASK`'s range
    (docs/protocol-notes.md §3)."""

    enum: ClassVar[type[CameraMask]] = CameraMask
    """The flags its bits name (the dissector's rows carry the name)."""

    def __post_init__(self) -> None:
        self._set(("cameras",), (CAMERA_MASK,))

    def encode(self, value: Any) -> tuple[int]:
        if type(value) is int and value in _CAMERA_MASKS:  # the common case, one test
            return (value,)
        w = CAMERA_MASK
        return (check_int(w.name, value, w.raw_low, w.raw_high, w.raw_unit),)

    def decode(self, raw: int) -> tuple[CameraMask]:  # type: ignore[override]
        return (CameraMask(_in_range(CAMERA_MASK, raw)),)

    def anomalies(self, raw: int) -> tuple[Anomaly, ...]:  # type: ignore[override]
        w = CAMERA_MASK
        return check_raw(w.name, raw, w.raw_low, w.raw_high, w.raw_unit, "0x00 selects no camera")

    def json(self, value: Any) -> Any:
        return int(value)

    def parameters(self, defaults: dict[str, object]) -> dict[str, Parameter]:
        w = CAMERA_MASK
        return {w.name: Parameter(w.name, Kind.CAMERAS, w.doc, "", w.raw_low, w.raw_high,
                                  default=defaults[w.name])}  # fmt: skip


@dataclass(frozen=True)
class Switch(ParamKind):
    """A ``bool`` sent as one byte: ``on`` for ``True``, ``off`` for ``False``, nothing else."""

    name: str = "enabled"
    doc: str = ""
    on: int = 1
    off: int = 0
    meaning: str = ""
    """What the two bytes mean, for the anomaly (default ``"0x00 = off, 0x01 = on"``)."""

    def __post_init__(self) -> None:
        self._set((self.name,), (WireField(self.name, "B", self.doc, min(self.on, self.off),
                                           max(self.on, self.off)),))  # fmt: skip

    def encode(self, value: Any) -> tuple[int]:
        return (self.on if check_bool(self.name, value) else self.off,)

    def decode(self, raw: int) -> tuple[bool]:  # type: ignore[override]
        if raw == self.on or raw == self.off:
            return (raw == self.on,)
        raise ValueError(f"{self.name}: byte 0x{raw:02X} is neither 0x{self.off:02X} nor "
                         f"0x{self.on:02X}")  # fmt: skip

    def anomalies(self, raw: int) -> tuple[Anomaly, ...]:  # type: ignore[override]
        if raw in (self.on, self.off):
            return ()
        meaning = self.meaning or f"0x{self.off:02X} = off, 0x{self.on:02X} = on"
        return (Anomaly(self.name, raw, 0, max(self.on, self.off, 1), "", f"only {meaning}"),)

    def parameters(self, defaults: dict[str, object]) -> dict[str, Parameter]:
        return {self.name: Parameter(self.name, Kind.SWITCH, self.doc,
                                     default=defaults[self.name])}  # fmt: skip


@dataclass(frozen=True)
class Integer(ParamKind):
    """An ``int`` in the field's range; ``detail`` tells which values mean what."""

    field_: WireField = field(default=None)  # type: ignore[assignment]
    detail: str = ""
    bounds: tuple[int, int] = field(init=False, repr=False, compare=False)
    """The raw range (``field_``'s)."""

    def __post_init__(self) -> None:
        self._set((self.field_.name,), (self.field_,))
        object.__setattr__(self, "bounds", (self.field_.raw_low, self.field_.raw_high))

    def encode(self, value: Any) -> tuple[int]:
        low, high = self.bounds
        if type(value) is int and low <= value <= high:  # the common case, one test
            return (value,)
        return (check_int(self.field_.name, value, low, high, self.field_.unit),)

    def decode(self, raw: int) -> tuple[int]:  # type: ignore[override]
        return (_in_range(self.field_, raw),)

    def anomalies(self, raw: int) -> tuple[Anomaly, ...]:  # type: ignore[override]
        w = self.field_
        return check_raw(w.name, raw, w.raw_low, w.raw_high, w.raw_unit or w.unit, self.detail)

    def parameters(self, defaults: dict[str, object]) -> dict[str, Parameter]:
        w = self.field_
        return {w.name: Parameter(w.name, Kind.INTEGER, w.doc, w.unit, w.raw_low, w.raw_high,
                                  default=defaults[w.name])}  # fmt: skip


@dataclass(frozen=True)
class Choice(ParamKind):
    """A member of ``enum`` (or its exact value), one byte; the range is the enum's."""

    name: str = ""
    enum: type[enum.IntEnum] = None  # type: ignore[assignment]
    doc: str = ""
    detail: str = ""
    normalizes: ClassVar[bool] = True

    def __post_init__(self) -> None:
        codes = [int(m) for m in self.enum]
        self._set((self.name,), (WireField(self.name, "B", self.doc, min(codes), max(codes)),))

    def normalize(self, value: Any) -> Any:
        return check_member(self.name, value, self.enum)

    def encode(self, value: Any) -> tuple[int]:
        return (int(value),)

    def decode(self, raw: int) -> tuple[Any]:  # type: ignore[override]
        return (self.enum(_in_range(self.wire[0], raw)),)

    def anomalies(self, raw: int) -> tuple[Anomaly, ...]:  # type: ignore[override]
        w = self.wire[0]
        return check_raw(self.name, raw, w.raw_low, w.raw_high, "", self.detail)

    def json(self, value: Any) -> Any:
        return value.name

    def parameters(self, defaults: dict[str, object]) -> dict[str, Parameter]:
        return {self.name: Parameter(self.name, Kind.CHOICE, self.doc, default=defaults[self.name],
                                     choices=self.enum)}  # fmt: skip


@dataclass(frozen=True)
class Real(_Reals):
    """A real number in engineering units, rounded to the field's resolution (``scale``)."""

    field_: WireField = field(default=None)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        self._set((self.field_.name,), (self.field_,))

    def encode(self, value: Any) -> tuple[int]:
        return (self.limits[0].raw(value),)

    def decode(self, raw: int) -> tuple[float]:  # type: ignore[override]
        return (_in_range(self.field_, raw) / self.field_.scale,)

    def parameters(self, defaults: dict[str, object]) -> dict[str, Parameter]:
        w = self.field_
        return {w.name: _real_parameter(w, w.name, defaults[w.name])}


IMAGE_SCALE = 10000
"""Image coordinates: U16 from 0 to this scale (both ends included), origin top-left."""
IMAGE_UNIT = "1/10000 of the image"


def _image(name: str, doc: str = "") -> WireField:
    return WireField(name, "H", doc, 0, IMAGE_SCALE, IMAGE_SCALE, "image fraction", IMAGE_UNIT)


@dataclass(frozen=True)
class Point(_Reals):
    """An :class:`~gcu_async.protocol.ImagePoint` (image fractions), two U16 1/10000."""

    name: str = "point"
    normalizes: ClassVar[bool] = True

    def __post_init__(self) -> None:
        self._set((self.name,), (_image(f"{self.name}.x", "from the left"),
                                 _image(f"{self.name}.y", "from the top")))  # fmt: skip

    def normalize(self, value: Any) -> ImagePoint:
        return check_tuple(self.name, value, ImagePoint)

    def encode(self, value: ImagePoint) -> tuple[int, int]:
        x, y = self.limits
        return (x.raw(value.x), y.raw(value.y))

    def decode(self, *raw: int) -> tuple[ImagePoint]:
        x, y = self.wire
        return (ImagePoint(x.from_raw(_in_range(x, raw[0])), y.from_raw(_in_range(y, raw[1]))),)

    def json(self, value: Any) -> Any:
        return value._asdict()

    def parameters(self, defaults: dict[str, object]) -> dict[str, Parameter]:
        point = defaults[self.name]
        return {axis: _real_parameter(w, axis, REQUIRED if point is REQUIRED
                                      else getattr(point, axis))
                for w, axis in zip(self.wire, ImagePoint._fields, strict=True)}  # fmt: skip


@dataclass(frozen=True)
class Box(_Reals):
    """An :class:`~gcu_async.protocol.ImageBox`, four U16 1/10000; right not left of left,
    bottom not above top."""

    name: str = "box"
    doc: str = "(left, top, right, bottom) image fractions 0-1"
    normalizes: ClassVar[bool] = True

    def __post_init__(self) -> None:
        self._set((self.name,), tuple(_image(f"{self.name}.{e}") for e in ImageBox._fields))

    def normalize(self, value: Any) -> ImageBox:
        return check_tuple(self.name, value, ImageBox)

    def encode(self, box: ImageBox) -> tuple[int, int, int, int]:
        x0, y0, x1, y1 = (r.raw(v) for r, v in zip(self.limits, box, strict=True))
        n = self.name
        if x1 < x0:
            detail = "right edge must not be left of the left edge"
            raise FieldRangeError(f"{n}.right", box.right, box.left, 1.0, "image fraction",
                                  detail=detail)  # fmt: skip
        if y1 < y0:
            raise FieldRangeError(f"{n}.bottom", box.bottom, box.top, 1.0, "image fraction",
                                  detail="bottom edge must not be above the top edge")  # fmt: skip
        return x0, y0, x1, y1

    def decode(self, *raw: int) -> tuple[ImageBox]:
        if self.anomalies(*raw):
            raise ValueError(f"{self.name}: {raw} is not a box")
        return (ImageBox(*(r / IMAGE_SCALE for r in raw)),)

    def anomalies(self, *raw: int) -> tuple[Anomaly, ...]:
        found = super().anomalies(*raw)
        x0, y0, x1, y1 = raw
        if x1 < x0:
            found += (Anomaly(f"{self.name}.right", x1, x0, IMAGE_SCALE, IMAGE_UNIT,
                              "right edge must not be left of the left edge"),)  # fmt: skip
        if y1 < y0:
            found += (Anomaly(f"{self.name}.bottom", y1, y0, IMAGE_SCALE, IMAGE_UNIT,
                              "bottom edge must not be above the top edge"),)  # fmt: skip
        return found

    def json(self, value: Any) -> Any:
        return value._asdict()

    def parameters(self, defaults: dict[str, object]) -> dict[str, Parameter]:
        default = defaults[self.name]
        if default is not REQUIRED:
            default = tuple(default)  # type: ignore[arg-type]
        return {self.name: Parameter(self.name, Kind.BOX, self.doc, default=default)}


TEMPERATURE = WireField("temperature", "h", "", scale=10, unit="degC", raw_unit="0.1 degC")
"""A temperature threshold: S16, 0.1 °C."""


@dataclass(frozen=True)
class Thresholds(_Reals):
    """``high`` and ``low`` temperature thresholds (S16 0.1 °C each), ``low`` not above
    ``high``."""

    def __post_init__(self) -> None:
        t = TEMPERATURE
        self._set(("high", "low"), tuple(
            WireField(n, t.fmt, f"{n} threshold, 0.1 degC steps; low <= high", t.low, t.high,
                      t.scale, t.unit, t.raw_unit) for n in ("high", "low")))  # fmt: skip

    def encode(self, high: Any, low: Any) -> tuple[int, int]:
        h, lo = self.limits
        hh, ll = h.raw(high), lo.raw(low)
        if ll > hh:
            raise FieldRangeError("low", low, lo.low, high, lo.unit,
                                  detail="low must not exceed high")  # fmt: skip
        return hh, ll

    def decode(self, hh: int, ll: int) -> tuple[float, float]:  # type: ignore[override]
        if ll > hh:
            raise ValueError(f"low {ll} exceeds high {hh}")
        return hh / TEMPERATURE.scale, ll / TEMPERATURE.scale

    def anomalies(self, hh: int, ll: int) -> tuple[Anomaly, ...]:  # type: ignore[override]
        if ll <= hh:
            return ()
        lo = self.wire[1]
        return (Anomaly("low", ll, lo.raw_low, hh, lo.raw_unit, "low must not exceed high"),)

    def parameters(self, defaults: dict[str, object]) -> dict[str, Parameter]:
        return {w.name: _real_parameter(w, w.name, defaults[w.name]) for w in self.wire}


ZOOM_RATIO = WireField("ratio", "i", "zoom ratio, 0.1 steps", 10, 32768, 10, "x")
"""``ZoomTo.ratio``: sent as −(ratio × 10) in the S16 ZZ ZZ."""
ZOOM_FRACTION = WireField("fraction", "h", "1/10000 steps", 1, 10000, 10000, "of maximum ratio")
"""``ZoomTo.fraction``: sent as fraction × 10000 in the S16 ZZ ZZ."""
_RATIO, _FRACTION = RealRange.of(ZOOM_RATIO), RealRange.of(ZOOM_FRACTION)


@dataclass(frozen=True)
class ZoomValue(ParamKind):
    """The S16 ZZ ZZ of zoom-to: a ``ratio`` (sent negative, ×10) or a ``fraction`` of the
    maximum ratio (×10000); exactly one is given."""

    def __post_init__(self) -> None:
        self._set(("ratio", "fraction"), (WireField("raw_value", "h", "", -ZOOM_RATIO.raw_high,
                                                    ZOOM_FRACTION.raw_high),))  # fmt: skip

    def encode(self, ratio: Any, fraction: Any) -> tuple[int]:
        if fraction is None and ratio is not None:
            return (-_RATIO.raw(ratio),)
        if ratio is None and fraction is not None:
            return (_FRACTION.raw(fraction),)
        raise ValueError("ZoomTo: give exactly one of ratio= or fraction=")

    def decode(self, zz: int) -> tuple[float | None, float | None]:  # type: ignore[override]
        if zz <= -ZOOM_RATIO.raw_low:
            return -zz / ZOOM_RATIO.scale, None
        if ZOOM_FRACTION.raw_low <= zz <= ZOOM_FRACTION.raw_high:
            return None, zz / ZOOM_FRACTION.scale
        raise ValueError(f"ZOOM_TO: value {zz} is in neither [{-ZOOM_RATIO.raw_high}, "
                         f"{-ZOOM_RATIO.raw_low}] nor [{ZOOM_FRACTION.raw_low}, "
                         f"{ZOOM_FRACTION.raw_high}]")  # fmt: skip

    def anomalies(self, zz: int) -> tuple[Anomaly, ...]:  # type: ignore[override]
        try:
            self.decode(zz)
        except ValueError:
            r, f = ZOOM_RATIO, ZOOM_FRACTION
            detail = (f"a ratio {-r.raw_high} to {-r.raw_low} (-{1 / r.scale:g}x) or a "
                      f"fraction {f.raw_low} to {f.raw_high}")  # fmt: skip
            return (Anomaly("raw_value", zz, -r.raw_high, f.raw_high, "", detail),)
        return ()

    def parameters(self, defaults: dict[str, object]) -> dict[str, Parameter]:
        return {w.name: _real_parameter(w, w.name, defaults[w.name])
                for w in (ZOOM_RATIO, ZOOM_FRACTION)}  # fmt: skip


def integer(name: str, fmt: str, doc: str = "", low: int | None = None, high: int | None = None,
            unit: str = "", detail: str = "") -> Integer:  # fmt: skip
    """An :class:`Integer` parameter."""
    return Integer(WireField(name, fmt, doc, low, high, unit=unit), detail)


def real(name: str, fmt: str, doc: str, low: int | None, high: int | None, scale: float,
         unit: str, raw_unit: str = "") -> Real:  # fmt: skip
    """A :class:`Real` parameter."""
    return Real(WireField(name, fmt, doc, low, high, scale, unit, raw_unit))


def choice(name: str, enum_: type[enum.IntEnum], doc: str, detail: str) -> Choice:
    """A :class:`Choice` parameter."""
    return Choice(name, enum_, doc, detail)
