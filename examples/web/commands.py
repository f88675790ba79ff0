"""The command table of the web example: URL name → typed parameters → client method.

The table is made from the command catalogue (:mod:`gcu_async.protocol.catalogue`): one
entry per client command method, named as the method, with the catalogue's parameters and
defaults; each names the JSON parameters it accepts (type, default or required) and the
:class:`~gcu_async.GcuClient` method it calls. :func:`parse_params` checks a request body
against an entry and raises ``ValueError`` naming the parameter for anything wrong (unknown
names, wrong types, missing required values, non-finite numbers); ranges are checked by the
protocol core when the command is built (``FieldRangeError``, also a ``ValueError``).
"""

from __future__ import annotations

import math
from collections.abc import Awaitable, Callable, Mapping
from dataclasses import dataclass, field
from enum import IntEnum
from typing import Any

from gcu_async import GcuClient
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
    return Param(KINDS[p.kind], default)


def _spec(entry: CatalogueEntry) -> CommandSpec:
    return CommandSpec(entry.method, entry.method, f"{entry.doc} (0x{entry.opcode:02X})",
                       {p.name: _param(p) for p in entry.parameters})  # fmt: skip


COMMANDS: dict[str, CommandSpec] = {entry.method: _spec(entry) for entry in CATALOGUE}
"""Every command the web API exposes, by URL name: one per entry of the command catalogue
(:mod:`gcu_async.protocol.catalogue`), named as its client method."""


def parse_params(spec: CommandSpec, body: object) -> dict[str, Any]:
    """The parameters of ``spec`` from a decoded JSON body (an object, or ``None`` for no
    body), with defaults filled in. Raises ``ValueError`` naming the offending parameter."""
    if body is None:
        body = {}
    if not isinstance(body, dict):
        raise ValueError(f"{spec.name}: the body must be a JSON object, got {_json_type(body)}")
    unknown = sorted(set(body) - set(spec.params))
    if unknown:
        allowed = ", ".join(spec.params) or "none"
        raise ValueError(f"{spec.name}: unknown parameter(s) {', '.join(unknown)} "
                         f"(allowed: {allowed})")  # fmt: skip
    values: dict[str, Any] = {}
    for name, param in spec.params.items():
        if name in body:
            values[name] = _convert(name, param.kind, body[name])
        elif param.required:
            raise ValueError(f"{name}: required parameter of {spec.name} is missing")
        else:
            values[name] = param.default
    return values


def _convert(name: str, kind: str, value: object) -> Any:
    if kind == "float":
        return _number(name, value)
    if kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError(f"{name}: expected an integer, got {_json_type(value)} {value!r}")
        return value
    if kind == "bool":
        if not isinstance(value, bool):
            raise ValueError(f"{name}: expected true or false, got {_json_type(value)} {value!r}")
        return value
    if kind == "box":
        if not isinstance(value, list) or len(value) != 4:
            raise ValueError(
                f"{name}: expected [left, top, right, bottom] (4 numbers), got {value!r}"
            )
        return tuple(_number(f"{name}[{i}]", v) for i, v in enumerate(value))
    raise AssertionError(f"unknown parameter kind {kind!r}")  # pragma: no cover


def _number(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{name}: expected a number, got {_json_type(value)} {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"{name}: {value!r} is not a finite number")
    return float(value)


def _json_type(value: object) -> str:
    names = {dict: "object", list: "array", str: "string", bool: "boolean", type(None): "null"}
    return names.get(type(value), "number")
