"""The command table of the web example: URL name → typed parameters → client method.

The table is made from the command catalogue (:mod:`gcu_async.protocol.catalogue`): one
entry per client command method, named as the method, with the catalogue's parameters and
defaults; each names the JSON parameters it accepts (type, default or required) and the
:class:`~gcu_async.GcuClient` method it calls. :func:`parse_params` checks a request body
against an entry and raises ``ValueError`` naming the parameter for anything wrong (unknown
names, wrong types, missing required values, non-finite numbers) and
:class:`~gcu_async.FieldRangeError` (also a ``ValueError``) naming the parameter, its
catalogue range and the value for a number outside it, before any conversion: a
400-digit integer is refused as out of range, never converted to a float. The protocol
core checks again when the command is built (rules that tie parameters together, such as
a box's left < right).
"""

from __future__ import annotations

import math
from collections.abc import Awaitable, Callable, Mapping
from dataclasses import dataclass, field
from enum import IntEnum
from typing import Any

from gcu_async import FieldRangeError, GcuClient
from gcu_async.protocol import Feedback
from gcu_async.protocol.catalogue import CATALOGUE, CatalogueEntry, Kind, Parameter
from gcu_async.protocol.catalogue import REQUIRED as CATALOGUE_REQUIRED

REQUIRED: Any = object()
"""Marker default: the parameter must be given."""

Call = Callable[..., Awaitable[Feedback | None]]


@dataclass(frozen=True)
class Param:
    """One JSON parameter: ``kind`` is ``"float"``, ``"int"``, ``"bool"`` or ``"box"``
    (``[left, top, right, bottom]`` image fractions)."""

    kind: str
    default: Any = REQUIRED
    rule: Parameter | None = None
    """The catalogue's parameter: its range (``low``, ``high``), unit and choices."""

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    def describe(self) -> dict[str, Any]:
        if self.required:
            return {"type": self.kind, "required": True}
        return {"type": self.kind, "default": self.default}


@dataclass(frozen=True)
class CommandSpec:
    """A command the web API exposes."""

    name: str
    method: str
    """Name of the :class:`GcuClient` method called with the parsed parameters."""
    doc: str
    params: Mapping[str, Param] = field(default_factory=dict)

    def describe(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "doc": self.doc,
            "params": {name: p.describe() for name, p in self.params.items()},
        }

    async def run(self, gcu: GcuClient, values: Mapping[str, Any]) -> Feedback | None:
        """Call the client method with already parsed ``values``."""
        method: Call = getattr(gcu, self.method)
        return await method(**values)


KINDS = {Kind.REAL: "float", Kind.INTEGER: "int", Kind.CAMERAS: "int", Kind.CHOICE: "int",
         Kind.SWITCH: "bool", Kind.BOX: "box"}  # fmt: skip
"""The JSON kind of each catalogue parameter kind (a choice is its integer value)."""


def _param(p: Parameter) -> Param:
    default = p.default
    if default is CATALOGUE_REQUIRED:
        default = REQUIRED
    elif isinstance(default, IntEnum):
        default = int(default)  # JSON has no enums: the value
    return Param(KINDS[p.kind], default, p)


def _spec(entry: CatalogueEntry) -> CommandSpec:
    return CommandSpec(entry.method, entry.method, f"{entry.doc} (0x{entry.opcode:02X})",
                       {p.name: _param(p) for p in entry.parameters})  # fmt: skip


COMMANDS: dict[str, CommandSpec] = {entry.method: _spec(entry) for entry in CATALOGUE}
"""Every command the web API exposes, by URL name: one per entry of the command catalogue
(:mod:`gcu_async.protocol.catalogue`), named as its client method."""


def parse_params(spec: CommandSpec, body: object) -> dict[str, Any]:
    """The parameters of ``spec`` from a decoded JSON body (an object; an empty body reads
    as ``{}``), with defaults filled in. Raises ``ValueError`` naming the offending
    parameter."""
    if not isinstance(body, dict):
        raise ValueError(f"{spec.name}: the body must be a JSON object, got {_json_type(body)}")
    unknown = sorted(set(body) - set(spec.params))
    if unknown:
        allowed = ", ".join(spec.params) or "none"
        raise ValueError(f"{spec.name}: unknown parameter(s) {', '.join(unknown)} "
                         f"(allowed: {allowed})")  # fmt: skip
    values: dict[str, Any] = {}
    missing = []
    for name, param in spec.params.items():  # the values given first: their errors name them
        if name in body:
            values[name] = _convert(name, param, body[name])
        elif param.required:
            missing.append(name)
        else:
            values[name] = param.default
    if missing:
        raise ValueError(f"{missing[0]}: required parameter of {spec.name} is missing")
    return values


def _convert(name: str, param: Param, value: object) -> Any:
    kind = param.kind
    if kind == "float":
        return _float(name, _in_range(name, param.rule, _number(name, value)))
    if kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError(f"{name}: expected an integer, got {_json_type(value)} {value!r}")
        return _in_range(name, param.rule, value)
    if kind == "bool":
        if not isinstance(value, bool):
            raise ValueError(f"{name}: expected true or false, got {_json_type(value)} {value!r}")
        return value
    if kind == "box":
        if not isinstance(value, list) or len(value) != 4:
            raise ValueError(
                f"{name}: expected [left, top, right, bottom] (4 numbers), got {value!r}"
            )
        sides = [(f"{name}[{i}]", v) for i, v in enumerate(value)]
        return tuple(_float(n, _in_range(n, BOX_SIDE, _number(n, v))) for n, v in sides)
    raise AssertionError(f"unknown parameter kind {kind!r}")  # pragma: no cover


BOX_SIDE = Parameter("side", Kind.REAL, "image fraction", "image fraction", 0.0, 1.0)
"""The range of each side of a box (the catalogue's box is one parameter, kind BOX)."""


def _in_range(name: str, rule: Parameter | None, value: int | float) -> int | float:
    """``value`` if inside the catalogue range of ``rule``, else ``FieldRangeError``.
    Python compares ``int`` and ``float`` exactly: a huge integer is out of range, not an
    ``OverflowError``."""
    if rule is None:
        return value
    if rule.choices is not None:
        allowed = sorted(int(member) for member in rule.choices)
        if value not in allowed:
            raise FieldRangeError(name, value, allowed[0], allowed[-1], rule.unit,
                                  detail=f"one of {', '.join(map(str, allowed))}: "
                                         f"{rule.range_text()}")  # fmt: skip
        return value
    if rule.low is None or rule.high is None:
        return value
    below = value <= rule.low if rule.low_open else value < rule.low
    above = value >= rule.high if rule.high_open else value > rule.high
    if below or above:
        raise FieldRangeError(name, value, rule.low, rule.high, rule.unit,
                              high_open=rule.high_open,
                              detail="low end excluded" if rule.low_open else "")  # fmt: skip
    return value


def _number(name: str, value: object) -> int | float:
    """A JSON number as given (an ``int`` stays one until its range is checked)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{name}: expected a number, got {_json_type(value)} {value!r}")
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"{name}: {value!r} is not a finite number")
    return value


def _float(name: str, value: int | float) -> float:
    """``value`` as a float; an integer too large for one (only where the range has no
    upper end) is a ``ValueError`` naming it, not an ``OverflowError``."""
    try:
        return float(value)
    except OverflowError:
        raise ValueError(f"{name}: an integer of {len(str(abs(value)))} digits is too large "
                         "for a number (the largest is about 1.8e308)") from None


def _json_type(value: object) -> str:
    names = {dict: "object", list: "array", str: "string", bool: "boolean", type(None): "null"}
    return names.get(type(value), "number")
