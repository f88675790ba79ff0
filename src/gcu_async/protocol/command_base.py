"""The base of every command class, and its codec: plain loops over the class's schema.

A command class (:mod:`gcu_async.protocol.commands`) is a frozen dataclass in engineering
units whose ``SCHEMA`` lists its parameters in wire order as kinds
(:mod:`gcu_async.protocol.command_fields`). :func:`codec` checks the class against its schema
and derives its ``LAYOUT`` (the parameters' ``struct``, little-endian); every method here
walks the kinds, each doing its own part:

- building a command checks and encodes each parameter (its kind's ``normalize`` and
  ``encode``) in the order of the class's fields, so a bad argument raises before anything is
  sent, naming it; the raw values are kept, in wire order (:meth:`Command.raw_params`);
- :meth:`Command.encode_params` packs them with ``LAYOUT``;
- :meth:`Command.from_raw_params` builds the command from what the kinds decode, and
  :meth:`Command.raw_anomalies` lists what they find outside V2.0.6's ranges (decoding a
  packet, :func:`gcu_async.protocol.command_decode.decode_command`, keeps such bytes as an
  ``AnomalousCommand``).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field, fields
from itertools import chain
from typing import TYPE_CHECKING, Any, ClassVar, TypeVar

from gcu_async.protocol.anomalies import Anomaly
from gcu_async.protocol.command_schema import CommandSchema, ParamKind
from gcu_async.protocol.fields import struct_of
from gcu_async.protocol.opcodes import Opcode

_C = TypeVar("_C", bound="Command")


@dataclass(frozen=True)
class Command:
    """Base of all commands. ``OPCODE`` is the protocol opcode, ``SCHEMA`` the rest of its
    description; ``LAYOUT`` the parameter layout (little-endian), derived from the schema."""

    __slots__ = ("_raw",)  # the raw parameters, encoded once when the command is built
    if TYPE_CHECKING:  # a slot, not a field: fields() and the constructor do not list it
        _raw: tuple[int, ...] = field(init=False)

    OPCODE: ClassVar[Opcode]
    SCHEMA: ClassVar[CommandSchema] = CommandSchema()
    LAYOUT: ClassVar[struct.Struct] = struct.Struct("<")
    CHECKED: ClassVar[tuple[tuple[int, ParamKind], ...]] = ()
    """The schema's kinds, each with its place in wire order, in the order of the class's
    fields: the order of the checks."""

    def __post_init__(self) -> None:
        if not hasattr(self, "OPCODE"):
            raise TypeError(f"{type(self).__name__} is abstract: build one of its subclasses")
        encoded: list[tuple[int, ...]] = [()] * len(self.CHECKED)
        for at, kind in self.CHECKED:
            attrs = kind.attrs
            if len(attrs) > 1:  # thresholds, zoom value
                encoded[at] = kind.encode(*[getattr(self, name) for name in attrs])
                continue
            value = getattr(self, attrs[0])
            if kind.normalizes:  # stored as its class (a NamedTuple, an enum member)
                value = kind.normalize(value)
                object.__setattr__(self, attrs[0], value)
            encoded[at] = kind.encode(value)
        raw = encoded[0] if len(encoded) == 1 else tuple(chain.from_iterable(encoded))
        object.__setattr__(self, "_raw", raw)

    def __reduce__(self) -> tuple[Any, ...]:
        """Copies and pickles are built again from the fields (and so checked)."""
        return type(self), tuple(getattr(self, f.name) for f in fields(self))

    @property
    def opcode(self) -> Opcode:
        return self.OPCODE

    def raw_params(self) -> tuple[int, ...]:
        """The parameter values as the raw integers that go on the wire."""
        return self._raw

    def encode_params(self) -> bytes:
        """Parameter bytes (70..S-3 of the host packet)."""
        return self.LAYOUT.pack(*self._raw)

    @classmethod
    def from_raw_params(cls: type[_C], raw: tuple[int, ...]) -> _C:
        """The command of raw parameters (as unpacked by ``LAYOUT``); ``ValueError`` for
        values V2.0.6 does not allow."""
        values: dict[str, Any] = {}
        at = 0
        for kind in cls.SCHEMA.params:
            n = len(kind.wire)
            values.update(zip(kind.attrs, kind.decode(*raw[at : at + n]), strict=True))
            at += n
        return cls(**values)

    @classmethod
    def raw_anomalies(cls, raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
        """Every value of the raw parameters (as unpacked by ``LAYOUT``) outside its range:
        empty exactly when :meth:`from_raw_params` accepts them."""
        found: tuple[Anomaly, ...] = ()
        at = 0
        for kind in cls.SCHEMA.params:
            n = len(kind.wire)
            found += kind.anomalies(*raw[at : at + n])
            at += n
        return found

    def as_dict(self) -> dict[str, Any]:
        """Name, opcode, parameters in units and raw, for JSON output."""
        params: dict[str, Any] = {}
        for kind in self.SCHEMA.params:
            for name in kind.attrs:
                value = getattr(self, name)
                params[name] = value if value is None else kind.json(value)
        return {
            "command": self.OPCODE.name,
            "opcode": int(self.OPCODE),
            "params": {f.name: params[f.name] for f in fields(self)},
            "params_raw": list(self.raw_params()),
            "params_hex": self.encode_params().hex(" "),
        }


def codec(cls: type[_C]) -> type[_C]:
    """Check a command class against its schema (each attribute is one kind's) and derive
    its ``LAYOUT`` and ``CHECKED``."""
    names = [f.name for f in fields(cls)]
    kinds = cls.SCHEMA.params
    owned = [name for kind in kinds for name in kind.attrs]
    if sorted(owned) != sorted(names):
        raise TypeError(f"{cls.__name__}: attributes {names} but schema parameters {owned}")
    cls.LAYOUT = struct_of(cls.SCHEMA.wire)
    cls.CHECKED = tuple(sorted(enumerate(kinds), key=lambda k: names.index(k[1].attrs[0])))
    return cls
