"""The kinds of command parameter the schema (:mod:`gcu_async.protocol.commands`) is made of.

A command's schema lists its parameters in wire order as kinds: :class:`Cameras`,
:class:`Switch`, :class:`Integer`, :class:`Choice`, :class:`Real`, :class:`Point`,
:class:`Box`, :class:`Thresholds`, :class:`ZoomValue`. Each kind maps one or more attributes
of the command class to one or more :class:`~gcu_async.protocol.fields.WireField` and knows,
once for every command that uses it, the send-side check (``encode``), the receive side
(``decode``, which raises ``ValueError`` for a value V2.0.6 does not allow, and
``anomalies``, which lists them), the JSON form and the catalogue's :class:`Parameter`. The
command codecs are compiled from these at import time (:mod:`gcu_async.protocol.commands`).
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, ClassVar, Literal, NamedTuple

from gcu_async._checks import check_bool, check_int
from gcu_async.errors import FieldRangeError
from gcu_async.protocol.anomalies import Anomaly, check_raw
from gcu_async.protocol.enums import CameraMask, Mode
from gcu_async.protocol.fields import WireField
from gcu_async.protocol.units import check_member, check_tuple, quantize


# -- the catalogue's description of a parameter (re-exported by protocol.catalogue) ---------
class Required(enum.Enum):
    """The marker of a parameter without a default (:data:`REQUIRED`)."""

    REQUIRED = "required"

    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED = Required.REQUIRED
"""``Parameter.default`` of a parameter the caller must give."""


class Kind(enum.Enum):
    """What a parameter takes (the package rule, :mod:`gcu_async.protocol`)."""

    REAL = "real"
    """A finite ``int`` or ``float`` in ``[low, high]``."""
    INTEGER = "integer"
    """An ``int`` (not a bool) in ``[low, high]``."""
    SWITCH = "switch"
    """``True`` or ``False``."""
    CAMERAS = "cameras"
    """A camera mask, an ``int`` 1–255 (docs/protocol-notes.md §3 "Camera masks")."""
    CHOICE = "choice"
    """A member of ``Parameter.choices`` or its exact value."""
    BOX = "box"
    """An :class:`~gcu_async.protocol.ImageBox` or a plain 4-tuple of image fractions."""


@dataclass(frozen=True, slots=True)
class Parameter:
    """One parameter of a command method, as the caller writes it."""

    name: str
    kind: Kind
    doc: str
    """A few words: what it is, beyond unit and range."""
    unit: str = ""
    low: float | None = None
    """Smallest value (``None``: no numeric range: switches, boxes, choices)."""
    high: float | None = None
    low_open: bool = False
    """``low`` itself is excluded."""
    high_open: bool = False
    """``high`` itself is excluded."""
    default: object = REQUIRED
    choices: type[enum.IntEnum] | None = None
    """The enum of a :attr:`Kind.CHOICE` parameter."""

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    def range_text(self) -> str:
        """The range in words (``"-180 to 180"``, ``"OFF, ON or AUTO"``), ``""`` if none."""
        if self.choices is not None:
            names = [m.name for m in self.choices]
            return f"{', '.join(names[:-1])} or {names[-1]}"
        if self.low is None or self.high is None:
            return ""
        low = f"{self.low:.12g}" + (" (excluded)" if self.low_open else "")
        high = "no limit" if math.isinf(self.high) else f"{self.high:.12g}"
        return f"{low} to {high}" + (" (excluded)" if self.high_open else "")


class StatusRule(enum.Enum):
    """How the execution status of a command's feedback reads (docs/protocol-notes.md §2
    "Execution status per command"); the value is the rule in words."""

    STANDARD = "0x00 success, any other value failure (0x01)"
    CALIBRATION = "0x00 success, 0x02 in progress (a later reply brings the result), else failure"
    THERMAL = "0x00 success, any other value failure (0x02)"
    ZOOM = "0x00 success, else the camera mask of the cameras that failed"

    @classmethod
    def of(cls, opcode: int) -> StatusRule:
        """The rule for ``opcode`` (a command's schema says it; unknown opcodes: standard)."""
        from gcu_async.protocol.commands import COMMAND_TYPES  # the schema imports this module

        command = COMMAND_TYPES.get(opcode)
        return cls.STANDARD if command is None else command.SCHEMA.status


ControlReads = Literal["angles", "rates", "none"]
"""What a mode reads from the control values (session ``ControlKind`` values)."""


class ModeSpec(NamedTuple):
    """What a mode command does: the mode byte the GCU then reports (GCU main frame byte 5)
    and what that mode reads from the control values."""

    mode: Mode
    control: ControlReads


class Method(NamedTuple):
    """One client method (and ``gcu-async send`` subcommand) sending a command.

    ``params``: the method's parameters, each the name of a command attribute (a
    :class:`Point` gives ``x`` and ``y``) or an explicit :class:`Parameter` (control values,
    timeouts); ``None`` means every attribute in the class's order. ``required`` names the
    ones without a default though the class has one."""

    name: str
    doc: str
    params: tuple[str | Parameter, ...] | None = None
    required: tuple[str, ...] = ()


@dataclass(frozen=True, slots=True)
class CommandSchema:
    """Everything about one command but its opcode and attributes (the class has those)."""

    params: tuple[ParamKind, ...] = ()
    """The parameters in wire order."""
    methods: tuple[Method, ...] = ()
    """The client methods sending it, in the docs' order (none: the client sends it itself)."""
    status: StatusRule = StatusRule.STANDARD
    mode: ModeSpec | None = None
    """Set for a command that switches the pod's working mode."""
    matrix_row: int | None = None
    """Its row in Appendix 8 (the support matrix, :mod:`gcu_async.protocol.pods`); ``None``:
    every pod model supports it."""
    needs_ins: bool = False
    """The GCU executes it only with valid aircraft INS data (host byte 11 B0)."""
    changes_mode: bool = False
    """Control values must be sent invalid while it is queued or in flight (besides the mode
    commands)."""
    catalogue_order: int = 0
    """Where its methods appear in the catalogue (ascending; ties by opcode)."""

    @property
    def wire(self) -> tuple[WireField, ...]:
        return tuple(w for p in self.params for w in p.wire)


# -- parameter kinds ----------------------------------------------------------------------------
IMAGE_SCALE = 10000
"""Image coordinates: U16 [0, 10000], origin top-left."""
IMAGE_UNIT = "1/10000 of the image"


@dataclass(frozen=True)
class ParamKind:
    """One parameter of a command: ``attrs`` of the class ↔ ``wire`` fields."""

    attrs: tuple[str, ...] = field(init=False)
    wire: tuple[WireField, ...] = field(init=False)
    scalar: ClassVar[bool] = True
    """One attribute ↔ one wire field: ``encode``/``decode`` take and give one value."""
    normalizes: ClassVar[bool] = False
    """``normalize`` stores a different value (a NamedTuple, an enum member)."""

    def normalize(self, value: Any) -> Any:
        return value

    def encoder(self) -> Callable[..., Any]:
        """``encode`` with this parameter's constants bound (the compiled codec calls it)."""
        return self.encode

    def encode(self, *values: Any) -> Any:
        """Send side: the raw integer(s), checked (``TypeError`` / ``FieldRangeError``)."""
        raise NotImplementedError

    def decode(self, *raw: int) -> Any:
        """Receive side: the attribute value(s); ``ValueError`` if V2.0.6 does not allow it."""
        raise NotImplementedError

    def anomalies(self, *raw: int) -> tuple[Anomaly, ...]:
        found: tuple[Anomaly, ...] = ()
        for w, r in zip(self.wire, raw, strict=True):
            found += w.anomalies(r)
        return found

    def json(self, value: Any) -> Any:
        return value

    def parameters(self, defaults: dict[str, object]) -> dict[str, Parameter]:
        """The catalogue's parameter(s), by name, given each attribute's default."""
        raise NotImplementedError

    def _set(self, attrs: tuple[str, ...], wire: tuple[WireField, ...]) -> None:
        object.__setattr__(self, "attrs", attrs)
        object.__setattr__(self, "wire", wire)


def _in_range(w: WireField, raw: int) -> int:
    if not w.raw_low <= raw <= w.raw_high:
        raise ValueError(f"{w.name}: {raw} is outside {w.raw_low}..{w.raw_high}")
    return raw


CAMERA_MASK = WireField("cameras", "B", "camera mask", 1, 0xFF, raw_unit="camera mask")
"""The camera mask's one field: 1–255, one bit per camera (0x00 selects none)."""


@dataclass(frozen=True)
class Cameras(ParamKind):
    """The camera mask (KK / NN), an ``int`` 1–255 (docs/protocol-notes.md §3)."""

    enum: ClassVar[type[CameraMask]] = CameraMask
    """The flags its bits name (the dissector's rows carry the name)."""

    def __post_init__(self) -> None:
        self._set(("cameras",), (CAMERA_MASK,))

    def encode(self, value: Any) -> int:
        return check_int("cameras", value, CAMERA_MASK.raw_low, CAMERA_MASK.raw_high,
                         "camera mask")  # fmt: skip

    def encoder(self) -> Callable[[Any], int]:
        low, high = CAMERA_MASK.raw_low, CAMERA_MASK.raw_high

        def encode(value: Any) -> int:
            if type(value) is int and low <= value <= high:  # the common case, one test
                return value
            return check_int("cameras", value, low, high, "camera mask")

        return encode

    def decode(self, raw: int) -> Any:  # type: ignore[override]
        return CameraMask(_in_range(self.wire[0], raw))

    def anomalies(self, raw: int) -> tuple[Anomaly, ...]:  # type: ignore[override]
        return check_raw("cameras", raw, CAMERA_MASK.raw_low, CAMERA_MASK.raw_high,
                         "camera mask", "0x00 selects no camera")  # fmt: skip

    def json(self, value: Any) -> Any:
        return int(value)

    def parameters(self, defaults: dict[str, object]) -> dict[str, Parameter]:
        w = self.wire[0]
        return {"cameras": Parameter("cameras", Kind.CAMERAS, w.doc, "", w.raw_low, w.raw_high,
                                     default=defaults["cameras"])}  # fmt: skip


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

    def encode(self, value: Any) -> int:
        return self.on if check_bool(self.name, value) else self.off

    def decode(self, raw: int) -> bool:  # type: ignore[override]
        if raw == self.on:
            return True
        if raw == self.off:
            return False
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

    def __post_init__(self) -> None:
        self._set((self.field_.name,), (self.field_,))

    def encode(self, value: Any) -> int:
        w = self.field_
        return check_int(w.name, value, w.raw_low, w.raw_high, w.unit)

    def decode(self, raw: int) -> int:  # type: ignore[override]
        return _in_range(self.field_, raw)

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

    def encode(self, value: Any) -> int:
        return int(value)

    def decode(self, raw: int) -> Any:  # type: ignore[override]
        return self.enum(_in_range(self.wire[0], raw))

    def anomalies(self, raw: int) -> tuple[Anomaly, ...]:  # type: ignore[override]
        w = self.wire[0]
        return check_raw(self.name, raw, w.raw_low, w.raw_high, "", self.detail)

    def json(self, value: Any) -> Any:
        return value.name

    def parameters(self, defaults: dict[str, object]) -> dict[str, Parameter]:
        return {self.name: Parameter(self.name, Kind.CHOICE, self.doc, default=defaults[self.name],
                                     choices=self.enum)}  # fmt: skip


@dataclass(frozen=True)
class Real(ParamKind):
    """A real number in engineering units, rounded to the field's resolution (``scale``)."""

    field_: WireField = field(default=None)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        self._set((self.field_.name,), (self.field_,))

    def encode(self, value: Any) -> int:
        w = self.field_
        return quantize(w.name, value, w.scale, w.raw_low, w.raw_high, w.unit)

    def encoder(self) -> Callable[[Any], int]:
        w = self.field_
        name, scale, low, high, unit = w.name, w.scale, w.raw_low, w.raw_high, w.unit

        def encode(value: Any) -> int:
            return quantize(name, value, scale, low, high, unit)

        return encode

    def decode(self, raw: int) -> float:  # type: ignore[override]
        return _in_range(self.field_, raw) / self.field_.scale

    def parameters(self, defaults: dict[str, object]) -> dict[str, Parameter]:
        w = self.field_
        return {w.name: Parameter(w.name, Kind.REAL, w.doc, w.unit, w.raw_low / w.scale,
                                  w.raw_high / w.scale, default=defaults[w.name])}  # fmt: skip


def _image(name: str, doc: str = "") -> WireField:
    return WireField(name, "H", doc, 0, IMAGE_SCALE, IMAGE_SCALE, "image fraction", IMAGE_UNIT)


@dataclass(frozen=True)
class Point(ParamKind):
    """An :class:`~gcu_async.protocol.ImagePoint` (image fractions), two U16 1/10000."""

    name: str = "point"
    scalar: ClassVar[bool] = False
    normalizes: ClassVar[bool] = True

    def __post_init__(self) -> None:
        self._set((self.name,), (_image(f"{self.name}.x", "from the left"),
                                 _image(f"{self.name}.y", "from the top")))  # fmt: skip

    def normalize(self, value: Any) -> Any:
        from gcu_async.protocol.commands import ImagePoint

        return check_tuple(self.name, value, ImagePoint)

    def encode(self, value: Any) -> tuple[int, int]:
        x, y = self.wire
        return (x.to_raw(value.x), y.to_raw(value.y))

    def decode(self, *raw: int) -> Any:
        from gcu_async.protocol.commands import ImagePoint

        x, y = self.wire
        return ImagePoint(x.from_raw(_in_range(x, raw[0])), y.from_raw(_in_range(y, raw[1])))

    def json(self, value: Any) -> Any:
        return value._asdict()

    def parameters(self, defaults: dict[str, object]) -> dict[str, Parameter]:
        point = defaults[self.name]
        found = {}
        for w, axis in zip(self.wire, ("x", "y"), strict=True):
            default = REQUIRED if point is REQUIRED else getattr(point, axis)
            found[axis] = Parameter(axis, Kind.REAL, w.doc, w.unit, w.raw_low / w.scale,
                                    w.raw_high / w.scale, default=default)  # fmt: skip
        return found


_EDGES = ("left", "top", "right", "bottom")


@dataclass(frozen=True)
class Box(ParamKind):
    """An :class:`~gcu_async.protocol.ImageBox`, four U16 1/10000; right not left of left,
    bottom not above top."""

    name: str = "box"
    doc: str = "(left, top, right, bottom) image fractions 0-1"
    scalar: ClassVar[bool] = False
    normalizes: ClassVar[bool] = True

    def __post_init__(self) -> None:
        self._set((self.name,), tuple(_image(f"{self.name}.{e}") for e in _EDGES))

    def normalize(self, value: Any) -> Any:
        from gcu_async.protocol.commands import ImageBox

        return check_tuple(self.name, value, ImageBox)

    def encode(self, box: Any) -> tuple[int, int, int, int]:
        x0, y0, x1, y1 = (w.to_raw(v) for w, v in zip(self.wire, box, strict=True))
        n = self.name
        if x1 < x0:
            detail = "right edge must not be left of the left edge"
            raise FieldRangeError(f"{n}.right", box.right, box.left, 1.0, "image fraction",
                                  detail=detail)  # fmt: skip
        if y1 < y0:
            raise FieldRangeError(f"{n}.bottom", box.bottom, box.top, 1.0, "image fraction",
                                  detail="bottom edge must not be above the top edge")  # fmt: skip
        return x0, y0, x1, y1

    def decode(self, *raw: int) -> Any:
        from gcu_async.protocol.commands import ImageBox

        if self.anomalies(*raw):
            raise ValueError(f"{self.name}: {raw} is not a box")
        return ImageBox(*(r / IMAGE_SCALE for r in raw))

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
class Thresholds(ParamKind):
    """``high`` and ``low`` temperature thresholds (S16 0.1 °C each), ``low`` not above
    ``high``."""

    scalar: ClassVar[bool] = False

    def __post_init__(self) -> None:
        t = TEMPERATURE
        self._set(("high", "low"), tuple(
            WireField(n, t.fmt, f"{n} threshold, 0.1 degC steps; low <= high", t.low, t.high,
                      t.scale, t.unit, t.raw_unit) for n in ("high", "low")))  # fmt: skip

    def encode(self, high: Any, low: Any) -> tuple[int, int]:
        h, lo = self.wire
        hh, ll = h.to_raw(high), lo.to_raw(low)
        if ll > hh:
            raise FieldRangeError("low", low, lo.raw_low / lo.scale, high, lo.unit,
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
        return {w.name: Parameter(w.name, Kind.REAL, w.doc, w.unit, w.raw_low / w.scale,
                                  w.raw_high / w.scale, default=defaults[w.name])
                for w in self.wire}  # fmt: skip


ZOOM_RATIO = WireField("ratio", "i", "zoom ratio, 0.1 steps", 10, 32768, 10, "x")
"""``ZoomTo.ratio``: sent as −(ratio × 10) in the S16 ZZ ZZ."""
ZOOM_FRACTION = WireField("fraction", "h", "1/10000 steps", 1, 10000, 10000, "of maximum ratio")
"""``ZoomTo.fraction``: sent as fraction × 10000 in the S16 ZZ ZZ."""


@dataclass(frozen=True)
class ZoomValue(ParamKind):
    """The S16 ZZ ZZ of zoom-to: a ``ratio`` (sent negative, ×10) or a ``fraction`` of the
    maximum ratio (×10000); exactly one is given."""

    scalar: ClassVar[bool] = False

    def __post_init__(self) -> None:
        low = -ZOOM_RATIO.raw_high
        self._set(("ratio", "fraction"), (WireField("raw_value", "h", "", low,
                                                    ZOOM_FRACTION.raw_high),))  # fmt: skip

    def encoder(self) -> Callable[[Any, Any], tuple[int]]:
        r, f = ZOOM_RATIO, ZOOM_FRACTION
        r_args = (r.name, r.scale, r.raw_low, r.raw_high, r.unit)
        f_args = (f.name, f.scale, f.raw_low, f.raw_high, f.unit)

        def encode(ratio: Any, fraction: Any) -> tuple[int]:
            if fraction is None and ratio is not None:
                name, scale, low, high, unit = r_args
                return (-quantize(name, ratio, scale, low, high, unit),)
            if ratio is None and fraction is not None:
                name, scale, low, high, unit = f_args
                return (quantize(name, fraction, scale, low, high, unit),)
            raise ValueError("ZoomTo: give exactly one of ratio= or fraction=")

        return encode

    def encode(self, ratio: Any, fraction: Any) -> tuple[int]:
        if (ratio is None) == (fraction is None):
            raise ValueError("ZoomTo: give exactly one of ratio= or fraction=")
        if ratio is not None:
            return (-ZOOM_RATIO.to_raw(ratio),)
        return (ZOOM_FRACTION.to_raw(fraction),)

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
        return {w.name: Parameter(w.name, Kind.REAL, w.doc, w.unit, w.raw_low / w.scale,
                                  w.raw_high / w.scale, default=defaults[w.name])
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


Encoder = Callable[..., Any]
