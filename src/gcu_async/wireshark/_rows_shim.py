"""The command rows of the dissector's tables, computed from today's command classes.

A stand-in for ``gcu_async.protocol.schema_tables.wire_rows`` (the protocol schema's own
rows), with the same interface: :mod:`gcu_async.wireshark.tables` imports ``wire_rows`` from
here in one place, to be replaced by the schema's. The facts come from the command classes
(``LAYOUT``, dataclass fields, the raw values their encoder gives) and the catalogue
(parameter ranges and units); the scales of the scaled fields are the one table the
classes keep inside their encoders.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

from gcu_async.protocol import commands as c
from gcu_async.protocol.catalogue import CATALOGUE, Kind, Parameter
from gcu_async.protocol.enums import Opcode
from gcu_async.protocol.fields import WIRE_RANGES


class WireParam(NamedTuple):
    """One parameter field on the wire."""

    name: str
    """``cameras``, ``box.left``, ``point.x``: the path of its value in ``as_dict()``."""
    fmt: str
    """One little-endian struct code: ``B b H h I i``."""
    scale: float
    """Engineering value = raw / scale (1 for plain integers)."""
    unit: str
    """The engineering unit, ``""`` if none."""
    low: int | None
    """Raw range, inclusive; ``None``: the wire type's own range."""
    high: int | None
    enum: str | None
    """The name of the enum (in :mod:`gcu_async.protocol`) of a choice field, else ``None``."""


class WireRow(NamedTuple):
    """One opcode and its parameters in wire order."""

    opcode: int
    command: str
    """The :class:`~gcu_async.protocol.Opcode` member's name (``ZOOM_TO``)."""
    params: tuple[WireParam, ...]


_SCALES = {"box": c.IMAGE_SCALE, "point": c.IMAGE_SCALE, "latitude": 1e7, "longitude": 1e7,
           "altitude": 1000, "high": 10, "low": 10}  # fmt: skip
_WIRE_FIRST = ("cameras", "longitude")  # KK leads; gaze-at sends longitude before latitude
_SWITCHES = {cls: {f.name for f in dataclasses.fields(cls) if f.type == "bool"}
             for cls in c.COMMAND_TYPES.values()}  # fmt: skip


def _names(cls: type[c.Command]) -> list[str]:
    if cls is c.ZoomTo:  # one S16 carries either field: the value its anomalies name
        return ["cameras", "raw_value"]
    names: list[str] = []
    for f in dataclasses.fields(cls):
        if f.name == "box":
            names += [f"box.{e}" for e in c.ImageBox._fields]
        elif f.name == "point":
            names += [f"point.{e}" for e in c.ImagePoint._fields]
        else:
            names.append(f.name)
    first = [n for n in _WIRE_FIRST if n in names]
    return first + [n for n in names if n not in first]


def _parameter(cls: type[c.Command], name: str) -> Parameter | None:
    key = name.rsplit(".", 1)[-1]
    for entry in CATALOGUE:
        if entry.command is cls:
            for p in entry.parameters:
                if p.name == key:
                    return p
    return None


def _param(cls: type[c.Command], name: str, fmt: str, index: int) -> WireParam:
    scale = _SCALES.get(name.split(".")[0], 1)
    p = _parameter(cls, name)
    unit = p.unit if p is not None else ""
    if name.startswith(("box.", "point.")):
        unit = "image fraction"
    low = high = None
    choice: str | None = None
    if name in _SWITCHES.get(cls, ()):  # the raw bytes "on" and "off" send
        on = cls(**{name: True}).raw_params()[index]
        off = cls(**{name: False}).raw_params()[index]
        low, high = min(on, off), max(on, off)
    elif p is not None and p.choices is not None:
        choice = p.choices.__name__
        low, high = int(min(p.choices)), int(max(p.choices))
    elif p is not None and p.kind is Kind.CAMERAS:
        low, high, choice = 1, 0xFF, "CameraMask"
    elif cls is c.ZoomTo:
        low, high = WIRE_RANGES[fmt][0], c.ZOOM_FRACTION_RAW_MAX
    elif p is not None and p.low is not None and p.high is not None:
        low, high = round(p.low * scale), round(p.high * scale)
    elif name.startswith(("box.", "point.")):
        low, high = 0, c.IMAGE_SCALE
    wire_low, wire_high = WIRE_RANGES[fmt]
    if (low, high) == (wire_low, wire_high):
        low = high = None
    return WireParam(name, fmt, scale, unit, low, high, choice)


def _row(opcode: int, cls: type[c.Command]) -> WireRow:
    fmts = cls.LAYOUT.format.lstrip("<")
    names = _names(cls)
    if len(names) != len(fmts):
        raise AssertionError(f"{cls.__name__}: {names} for layout {fmts!r}")
    params = tuple(_param(cls, n, f, i) for i, (n, f) in enumerate(zip(names, fmts, strict=True)))
    return WireRow(opcode, Opcode(opcode).name, params)


def wire_rows() -> tuple[WireRow, ...]:
    """Every opcode of V2.0.6 (the null command included), ascending, with its parameters."""
    return tuple(_row(op, cls) for op, cls in sorted(c.COMMAND_TYPES.items()))


__all__ = ["WireParam", "WireRow", "wire_rows"]
