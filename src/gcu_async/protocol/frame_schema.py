"""Frame schemas: each frame's fields as one table of :class:`WireField`\\ s, and all that is
derived from it.

A :class:`FrameSchema` is the only place a frame field's byte position, wire type, raw range,
scale and units are written. From it come the frame's ``struct`` (padding included), each
field's offset, the send side's ``validate`` (a type-and-range check generated as one Python
expression at import, with a field-by-field fallback that raises the error naming the field),
the receive side's ``anomalies`` (likewise generated), the engineering-unit views
(:meth:`FrameSchema.view`), the plain ``as_dict`` entries (:meth:`FrameSchema.plain_dict`),
the range tables (:attr:`FrameSchema.ranges`) and the packet layout's slices
(:mod:`~gcu_async.protocol.packets`).
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Iterable, Mapping
from enum import IntFlag
from typing import Any, TypeVar

from gcu_async._checks import check_int
from gcu_async.errors import FieldRangeError
from gcu_async.protocol.anomalies import Anomaly, FieldRange, check_raw, reserved_bits_detail
from gcu_async.protocol.fields import WireField, offsets
from gcu_async.protocol.units import check_flags, quantize

_T = TypeVar("_T")


def flag_bits(flags: type[IntFlag]) -> int:
    """Every bit some member of ``flags`` defines (the rest are reserved)."""
    bits = 0
    for member in flags:
        bits |= int(member)
    return bits


class FrameSchema:
    """One frame: its ``fields`` in wire order from byte ``start``, ``size`` bytes in all
    (bytes after the last field are reserved: zeros on send, ignored on receive).
    ``flags`` names the fields that hold flags of an ``IntFlag`` (reserved bits must be zero:
    a :class:`FieldRangeError` on send, an :class:`Anomaly` on receive). ``details`` gives
    fields whose out-of-range values have a known reading a function ``raw -> detail``, the
    words both sides add to the error or anomaly (e.g. a signed heading,
    :mod:`~gcu_async.protocol.headings`)."""

    __slots__ = (
        "_anomalies",
        "_validate",
        "by_name",
        "details",
        "fields",
        "flags",
        "name",
        "names",
        "offsets",
        "ranges",
        "size",
        "start",
        "struct",
    )  # fmt: skip

    def __init__(self, name: str, start: int, size: int, fields: Iterable[WireField],
                 flags: Mapping[str, type[IntFlag]] | None = None,
                 details: Mapping[str, Callable[[int], str]] | None = None) -> None:  # fmt: skip
        self.name = name
        self.start = start
        self.size = size
        self.fields: tuple[WireField, ...] = tuple(fields)
        self.flags: dict[str, type[IntFlag]] = dict(flags or {})
        self.by_name = {f.name: f for f in self.fields}
        self.names = tuple(self.by_name)
        if len(self.names) != len(self.fields):
            raise ValueError(f"{name}: duplicate field names")
        if set(self.flags) - set(self.names):
            raise ValueError(f"{name}: flags name no field: {set(self.flags) - set(self.names)}")
        self.details: dict[str, Callable[[int], str]] = dict(details or {})
        if set(self.details) - set(self.names) or set(self.details) & set(self.flags):
            raise ValueError(f"{name}: details name no field, or a flags field: "
                             f"{sorted(self.details)}")  # fmt: skip
        used = sum(f.size for f in self.fields)
        if used > size:
            raise ValueError(f"{name}: fields take {used} bytes, more than the frame's {size}")
        pad = f"{size - used}x" if size > used else ""
        self.struct = struct.Struct("<" + "".join(f.fmt for f in self.fields) + pad)
        self.offsets = offsets(self.fields, start)
        self.ranges = tuple(FieldRange(f.name, f.raw_low, f.raw_high, f.raw_unit)
                            for f in self.fields if f.name not in self.flags)  # fmt: skip
        self._validate = self._generate("validate", typed=True, ok="return",
                                        slow=self._validate_slow)  # fmt: skip
        self._anomalies = self._generate("anomalies", typed=False, ok="return ()",
                                         slow=self._anomalies_slow)  # fmt: skip

    @property
    def format(self) -> str:
        """The struct format without its byte-order prefix (to splice into a packet's)."""
        return self.struct.format[1:]

    @property
    def end(self) -> int:
        """The byte after the frame."""
        return self.start + self.size

    def check_fields(self, cls: type[tuple[Any, ...]]) -> None:
        """Raise unless the NamedTuple ``cls`` has exactly this schema's fields, in order."""
        declared = tuple(getattr(cls, "_fields", ()))
        if declared != self.names:
            raise TypeError(f"{cls.__name__} fields {declared} are not the {self.name} "
                            f"schema's {self.names}")  # fmt: skip

    def install(self, cls: type[tuple[Any, ...]]) -> None:
        """Check that the NamedTuple ``cls`` declares this schema's fields, then replace its
        ``validate`` method and ``anomalies`` property (where it defines them; docstrings
        kept) with the fast paths generated from the table: one function call each."""
        self.check_fields(cls)
        old = cls.__dict__.get("validate")
        if old is not None:
            fast = self._generate("validate", typed=True, ok="return", slow=self._validate_slow)
            fast.__doc__, fast.__module__ = old.__doc__, cls.__module__
            fast.__qualname__ = f"{cls.__qualname__}.validate"
            setattr(cls, "validate", fast)  # noqa: B010 - mypy: no assignment to a method
        prop = cls.__dict__.get("anomalies")
        if isinstance(prop, property):
            fast = self._generate("anomalies", typed=False, ok="return ()",
                                  slow=self._anomalies_slow)  # fmt: skip
            fast.__module__, fast.__qualname__ = cls.__module__, f"{cls.__qualname__}.anomalies"
            setattr(cls, "anomalies", property(fast, doc=prop.__doc__))  # noqa: B010

    # -- generated fast paths -------------------------------------------------------------
    def _generate(self, name: str, *, typed: bool, ok: str,
                  slow: Callable[[tuple[Any, ...]], Any]) -> Callable[..., Any]:  # fmt: skip
        """``def name(frame)``: ``ok`` when every field is in range (and, ``typed``, a plain
        ``int``; a flags field may also be its ``IntFlag``), tested as one expression; else
        ``slow(frame)``, which names the field."""
        args = [f"v{i}" for i in range(len(self.fields))]
        env: dict[str, Any] = {"slow": slow}
        lines = [f"def {name}(self):", f"    {', '.join(args)}, = self"]
        conds: list[str] = []
        if typed:
            conds.append(" is ".join(["int", *(f"type({a})" for a in args)]))
        for a, f in zip(args, self.fields, strict=True):
            flags = self.flags.get(f.name)
            if flags is not None:
                env[f"F{a}"] = flags
                if typed:
                    lines.append(f"    if type({a}) is F{a}: {a} = int({a})")
                conds.append(f"{a} >= 0 and not {a} & {~flag_bits(flags)}")
            else:
                conds.append(f"{f.raw_low} <= {a} <= {f.raw_high}")
        lines += [f"    if {' and '.join(conds)}:", f"        {ok}", "    return slow(self)"]
        exec("\n".join(lines), env)  # the source is built above from the field table
        function: Callable[..., Any] = env[name]
        return function

    # -- send side --------------------------------------------------------------------------
    def validate(self, frame: tuple[Any, ...]) -> None:
        """Raise ``TypeError`` / :class:`FieldRangeError` for the first field of ``frame``
        (wire order) that is not an ``int`` in its range (flags: with no reserved bit)."""
        self._validate(frame)

    def _validate_slow(self, frame: tuple[Any, ...]) -> None:
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

    def quantizer(self, name: str, label: str | None = None) -> Callable[[object], int]:
        """Send side: a function ``value -> raw`` for field ``name`` — what
        ``WireField.to_raw(value, label)`` does (rounded, range-checked, a
        :class:`FieldRangeError` naming ``label``), its arguments bound once and an in-range
        ``float``/``int`` taking a short path (frames are built from units at the packet rate)."""
        f = self.by_name[name]
        field, scale, low, high, unit, open_ = (label or name, f.scale, f.raw_low,
                                                f.raw_high + f.high_open, f.unit, f.high_open)
        top = f.raw_high

        def to_raw(value: object) -> int:
            if type(value) is float or type(value) is int:
                try:
                    raw = round(value * scale)
                except (OverflowError, ValueError):  # inf, nan: quantize raises the error
                    raw = low - 1
                if low <= raw <= top:
                    return raw
            return quantize(field, value, scale, low, high, unit, high_open=open_)  # type: ignore[arg-type]

        return to_raw

    def check(self, name: str, value: object, label: str | None = None) -> int:
        """``value`` checked as field ``name``'s raw integer, errors naming ``label``."""
        f = self.by_name[name]
        return check_int(label or name, value, f.raw_low, f.raw_high, f.raw_unit)

    # -- receive side -----------------------------------------------------------------------
    def anomalies(self, frame: tuple[Any, ...]) -> tuple[Anomaly, ...]:
        """One :class:`Anomaly` per field of a decoded ``frame`` outside its range (flags:
        with reserved bits set), in wire order; ``()`` for an ordinary frame."""
        found: tuple[Anomaly, ...] = self._anomalies(frame)
        return found

    def _anomalies_slow(self, frame: tuple[Any, ...]) -> tuple[Anomaly, ...]:
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

    # -- units ------------------------------------------------------------------------------
    def view(self, cls: Callable[..., _T], *names: str) -> Callable[[tuple[Any, ...]], _T]:
        """A function ``frame -> cls(value, ...)``: the named fields in engineering units
        (``raw / scale``), e.g. ``view(Attitude, "roll_raw", "pitch_raw", "yaw_raw")``."""
        index = {n: i for i, n in enumerate(self.names)}
        parts = []
        for n in names:
            scale = self.by_name[n].scale
            parts.append(f"frame[{index[n]}]" if scale == 1 else f"frame[{index[n]}] / {scale!r}")
        env: dict[str, Any] = {"cls": cls}
        exec(f"def view(frame):\n    return cls({', '.join(parts)})", env)
        view: Callable[[tuple[Any, ...]], _T] = env["view"]
        return view

    def plain_dict(self, frame: tuple[Any, ...], done: Iterable[str]) -> dict[str, Any]:
        """``as_dict`` entries of the fields not in ``done`` (those a frame presents its own
        way): ``name`` raw, and for a scaled ``x_raw`` also ``x`` in units."""
        skip = set(done)
        out: dict[str, Any] = {}
        for f, value in zip(self.fields, frame, strict=True):
            if f.name in skip:
                continue
            if f.scale != 1:
                out[f.name.removesuffix("_raw")] = value / f.scale
            out[f.name] = value
        return out
