"""Frame schemas: each frame's fields and what it presents of them, as one table.

A :class:`FrameSchema` is the only place a frame field's byte position, wire type, raw range,
scale and units are written (its :class:`WireField`\\ s, in wire order), and the only place
the frame's class is described (its :class:`View`\\ s: the unit properties, ``build``'s
keywords, ``as_dict``'s entries and ``str()``'s words). The frame classes are generated from
it ahead of time by ``tools/gen_frames.py`` into the frame modules, between two marker lines
(``tests/protocol/test_protocol_frame_code.py`` regenerates them and compares). At run time
the schema gives the frame's ``struct`` (padding included), each field's offset, the
field-by-field checks that name the failing field (:meth:`FrameSchema.validate`,
:meth:`FrameSchema.anomalies`: the generated classes fall back to them) and the packet
layout's slices (:mod:`~gcu_async.protocol.packets`).

A view reads the frame's raw fields; a view whose reading is special names a hand-written
function of them (``read``), and one whose build keyword is special a function of the
keywords (``write``, its parameters the keywords). Everything else follows from the fields.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from enum import IntEnum, IntFlag
from typing import Any

from gcu_async._checks import check_int, type_error
from gcu_async.errors import FieldRangeError
from gcu_async.protocol.anomalies import Anomaly, check_raw, reserved_bits_detail
from gcu_async.protocol.fields import WireField, offsets
from gcu_async.protocol.units import check_flags

AUTO = "<auto>"
"""A view's ``as_dict`` key made by the rule: its name, with the unit (``_deg``, ``_m``, …)."""


def flag_bits(flags: type[IntFlag]) -> int:
    """Every bit some member of ``flags`` defines (the rest are reserved)."""
    bits = 0
    for member in flags:
        bits |= int(member)
    return bits


def flag_names(flags: IntFlag) -> list[str]:
    """The names of the members set in ``flags``, in definition order (``as_dict``)."""
    return [m.name for m in type(flags) if m in flags and m.name is not None]


def flag_text(flags: IntFlag) -> str:
    """The members set in ``flags`` for ``str()``: ``TRACKING_OK,RANGE_VALID`` or ``none``."""
    return ",".join(flag_names(flags)) or "none"


def number_text(value: float | None, unit: str = "") -> str:
    """A value for ``str()``: ``%g`` and its unit (``1x``, ``45 deg``), or ``none``."""
    if value is None:
        return "none"
    return f"{value:g}{unit}" if unit in ("", "x") else f"{value:g} {unit}"


def group_text(value: tuple[float, ...] | None, unit: str = "") -> str:
    """A NamedTuple of units for ``str()``: ``roll 0 pitch -30 yaw 45 deg``, or ``none``."""
    if value is None:
        return "none"
    names: tuple[str, ...] = value._fields  # type: ignore[attr-defined]
    words = " ".join(f"{n} {v:g}" for n, v in zip(names, value, strict=True))
    return f"{words} {unit}" if unit else words


def check_parts(field: str, value: object, n: int) -> tuple[Any, ...]:
    """``value`` as a plain tuple of ``n`` raw integers (each checked by the caller)."""
    if type(value) is tuple and len(value) == n:
        return value
    raise type_error(field, f"a tuple of {n} integers", value)


# -- views: what a frame presents of its raw fields ------------------------------------------
@dataclass(frozen=True, kw_only=True)
class View:
    """One thing a frame presents: ``name`` (its property, its ``build`` keyword and its
    ``as_dict`` key's stem) read from the raw ``fields``. ``doc`` is the property's
    docstring (a ``read`` function's own docstring when it has one). ``read`` is a
    hand-written function of the raw fields (in order) giving the value, for a reading the
    table cannot say; ``write`` a hand-written function of ``build`` keywords (its parameters,
    with their types and defaults) giving the raw value(s). ``keyword`` is the ``build``
    keyword (``None``: the view is not built, another view writes its fields) and ``key``
    the ``as_dict`` key of the value (``None``: none; the raw fields are listed anyway)."""

    name: str
    fields: tuple[str, ...]
    doc: str = ""
    read: Callable[..., Any] | None = None
    write: Callable[..., Any] | None = None
    keyword: str | None = AUTO
    key: str | None = AUTO
    optional: bool = False
    """The value may be ``None`` (not measured): a ``read`` function says when."""
    needs: tuple[str, ...] = ()
    """Raw fields ``read`` takes after the view's own (to tell when a value is measured)."""

    @property
    def build_keyword(self) -> str | None:
        return self.name if self.keyword == AUTO else self.keyword


@dataclass(frozen=True, kw_only=True)
class Value(View):
    """One field: in units (``raw / scale``, a ``float``) when scaled, else the raw ``int``
    itself (no property: the field is the value). ``label`` names it in ``build``'s errors
    (default: the name with spaces); ``default`` is ``build``'s (``required``: none)."""

    label: str = ""
    default: Any = 0
    required: bool = False


@dataclass(frozen=True, kw_only=True)
class Group(View):
    """Several fields as one NamedTuple ``cls`` of their units (``Attitude``), each
    ``raw / scale``; ``labels`` name each element in ``build``'s errors. ``optional``: the
    ``build`` keyword may be ``None`` (sent as zeros)."""

    cls: type[tuple[Any, ...]]
    labels: tuple[str, ...] = ()
    default: Any = None


@dataclass(frozen=True, kw_only=True)
class Code(View):
    """One field read as the ``IntEnum`` ``enum`` (unknown codes: its ``UNKNOWN``);
    ``build`` takes a member or any code. ``spelling``: a function code → the vendor's name
    of it, shown in ``as_dict`` beside the member's name (``pod_model_member``)."""

    enum: type[IntEnum]
    label: str = ""
    default: Any = 0
    spelling: Callable[[int], str] | None = None


@dataclass(frozen=True, kw_only=True)
class Flags(View):
    """One field read as the ``IntFlag`` ``flags``; ``mask`` holds bits another view
    (:class:`Bits`) presents, left out of the flags and refused in ``build``'s."""

    flags: type[IntFlag]
    label: str = ""
    mask: int = 0


@dataclass(frozen=True, kw_only=True)
class Bits(View):
    """The bits ``mask`` of one field as an ``int`` (sent with the field's :class:`Flags`)."""

    mask: int
    label: str = ""


@dataclass(frozen=True, kw_only=True)
class Bit(View):
    """One flag ``member`` of one field as a ``bool`` (``clear``: true when the bit is clear);
    ``key=None`` unless ``as_dict`` shows it."""

    member: IntFlag
    clear: bool = False


@dataclass(frozen=True, kw_only=True)
class Entry(View):
    """An ``as_dict`` entry only: ``read`` (required) of the raw fields, under ``name``."""


@dataclass(frozen=True, kw_only=True)
class Method(View):
    """A method ``name(self, *, options)``: ``read`` of the raw fields with its keyword-only
    options (``HostSubFrame.gnss_time(apply_leap_seconds=…)``)."""


# -- the schema ----------------------------------------------------------------------------
class FrameSchema:
    """One frame: the class ``cls_name`` (``title`` in its docstring and errors), its
    ``fields`` in wire order from byte ``start``, ``size`` bytes in all (bytes after the last
    field are reserved: zeros on send, ignored on receive), and its ``views``. ``flags``
    names the fields that hold flags of an ``IntFlag`` whose reserved bits must be zero (a
    :class:`FieldRangeError` on send, an :class:`Anomaly` on receive). ``details`` gives
    fields whose out-of-range values have a known reading a function ``raw -> detail``, the
    words both sides add to the error or anomaly (a signed heading,
    :mod:`~gcu_async.protocol.headings`). ``header`` is a sub frame's header byte, which its
    ``as_dict`` shows."""

    __slots__ = ("by_name", "cls_name", "details", "fields", "flags", "header", "names",
                 "offsets", "size", "start", "struct", "title", "views")  # fmt: skip

    def __init__(self, cls_name: str, title: str, start: int, size: int,
                 fields: Iterable[WireField], views: Iterable[View] = (), *,
                 flags: Mapping[str, type[IntFlag]] | None = None,
                 details: Mapping[str, Callable[[int], str]] | None = None,
                 header: int | None = None) -> None:  # fmt: skip
        self.cls_name, self.title, self.start, self.size = cls_name, title, start, size
        self.header = header
        self.fields: tuple[WireField, ...] = tuple(fields)
        self.views: tuple[View, ...] = tuple(views)
        self.flags: dict[str, type[IntFlag]] = dict(flags or {})
        self.details: dict[str, Callable[[int], str]] = dict(details or {})
        self.by_name = {f.name: f for f in self.fields}
        self.names = tuple(self.by_name)
        if len(self.names) != len(self.fields):
            raise ValueError(f"{title}: duplicate field names")
        named = set(self.flags) | set(self.details) | {n for v in self.views for n in v.fields}
        if named - set(self.names) or set(self.details) & set(self.flags):
            raise ValueError(f"{title}: flags, details or views name no field (or a "
                             f"detail a flags field): {sorted(named - set(self.names))}")
        used = sum(f.size for f in self.fields)
        if used > size:
            raise ValueError(f"{title}: fields take {used} bytes, more than the frame's {size}")
        pad = f"{size - used}x" if size > used else ""
        self.struct = struct.Struct("<" + "".join(f.fmt for f in self.fields) + pad)
        self.offsets = offsets(self.fields, start)

    def __getitem__(self, name: str) -> WireField:
        """The field ``name`` (``GCU_SUB_SCHEMA["camera1_zoom_raw"].scale``)."""
        return self.by_name[name]

    @property
    def format(self) -> str:
        """The struct format without its byte-order prefix (to splice into a packet's)."""
        return self.struct.format[1:]

    @property
    def end(self) -> int:
        """The byte after the frame."""
        return self.start + self.size

    def check(self, name: str, value: object, label: str | None = None) -> int:
        """``value`` checked as field ``name``'s raw integer, errors naming ``label``."""
        f = self.by_name[name]
        return check_int(label or name, value, f.raw_low, f.raw_high, f.raw_unit)

    # -- send side: what a generated ``validate`` falls back to ------------------------------
    def validate(self, frame: tuple[Any, ...]) -> None:
        """Raise ``TypeError`` / :class:`FieldRangeError` for the first field of ``frame``
        (wire order) that is not an ``int`` in its range (flags: with no reserved bit)."""
        for f, value in zip(self.fields, frame, strict=True):
            flags = self.flags.get(f.name)
            if flags is not None:
                check_flags(f.name, value, flags)
                continue
            try:
                check_int(f.name, value, f.raw_low, f.raw_high, f.raw_unit)
            except FieldRangeError:
                explain = self.details.get(f.name)
                if explain is None:
                    raise
                raise FieldRangeError(f.name, value, f.raw_low, f.raw_high, f.raw_unit,
                                      detail=explain(value)) from None  # fmt: skip

    # -- receive side: what a generated ``anomalies`` falls back to --------------------------
    def anomalies(self, frame: tuple[Any, ...]) -> tuple[Anomaly, ...]:
        """One :class:`Anomaly` per field of a decoded ``frame`` outside its range (flags:
        with reserved bits set), in wire order; ``()`` for an ordinary frame."""
        found: tuple[Anomaly, ...] = ()
        for f, value in zip(self.fields, frame, strict=True):
            flags = self.flags.get(f.name)
            if flags is None:
                explain = self.details.get(f.name)
                detail = "" if explain is None else explain(value)
                found += check_raw(f.name, value, f.raw_low, f.raw_high, f.raw_unit, detail)
                continue
            bits = flag_bits(flags)
            if value & ~bits:
                found += (Anomaly(f.name, value, 0, bits, "",
                                  reserved_bits_detail(value & ~bits)),)  # fmt: skip
        return found

    # -- build: the parts ``build`` shares between frames -------------------------------------
    def masked(self, name: str, value: object, label: str, mask: int, holder: str) -> int:
        """Send side of a :class:`Flags` view with a ``mask``: ``value`` checked as field
        ``name``'s raw integer with the ``mask`` bits clear (they are ``holder``'s)."""
        raw = self.check(name, value, label)
        if raw & mask:
            f = self.by_name[name]
            raise FieldRangeError(label, value, f.raw_low, f.raw_high,
                                  detail=f"bits 0x{mask:X} hold the {holder.replace('_', ' ')}: "
                                         f"pass {holder}=")  # fmt: skip
        return raw
