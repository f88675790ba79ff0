"""The command catalogue: one entry per client command method, the one place its names live.

Each :class:`CatalogueEntry` gives a command's client method name (a verb phrase), its
command class (the protocol's noun: the :class:`~gcu_async.protocol.Opcode` member's name in
CamelCase), its opcode, its ``gcu-async send`` name (the method name with dashes), its
parameters (:class:`Parameter`: name, kind, unit, range, default), a one-line doc and how
its feedback's execution status reads (:class:`StatusRule`, docs/protocol-notes.md §2
"Execution status per command"). Every entry is derived from the command schema
(:mod:`gcu_async.protocol.commands`, each class's ``SCHEMA``): nothing is written here. The
command line's ``send`` subcommands, the web example's table and the docs' command table are
made from it; the client's methods and the command
classes' own validation are checked against it by tests (tests/protocol/test_catalogue.py), so the
copies cannot drift. Sans-I/O and immutable: tuples of frozen dataclasses.

One opcode may have several entries (``track`` / ``stop_tracking`` both send 0x17); the
null command (0x00) has none: the client sends it by itself (docs/protocol-notes.md §4 "The
same-opcode rule").
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import MISSING, dataclass, fields, replace
from types import MappingProxyType

from gcu_async.protocol import commands as c
from gcu_async.protocol.command_fields import REQUIRED as REQUIRED
from gcu_async.protocol.command_fields import Kind as Kind
from gcu_async.protocol.command_fields import Method
from gcu_async.protocol.command_fields import Parameter as Parameter
from gcu_async.protocol.command_fields import Required as Required
from gcu_async.protocol.command_fields import StatusRule as StatusRule
from gcu_async.protocol.commands import RATE_LIMIT as RATE_LIMIT
from gcu_async.protocol.commands import TEMPERATURE_RAW
from gcu_async.protocol.commands import YAW_INPUT_RANGE as YAW_INPUT_RANGE
from gcu_async.protocol.enums import Opcode
from gcu_async.protocol.layout import S32


@dataclass(frozen=True, slots=True)
class CatalogueEntry:
    """One command method: its names, its command, its parameters."""

    method: str
    """The :class:`~gcu_async.client.GcuClient` method (a verb phrase)."""
    command: type[c.Command]
    """The command class it sends (the protocol's noun)."""
    doc: str
    """One line."""
    parameters: tuple[Parameter, ...] = ()
    needs_ins: bool = False
    """The GCU executes it only while the host packets carry valid INS data: the aircraft's
    attitude, acceleration and velocity with the INS-valid bit set (host byte 11 B0); without
    them it answers a failure status. The one place this is written: the CLI's ``send
    --aircraft`` help and :attr:`~gcu_async.errors.CommandFailed.likely_cause` derive from it."""

    @property
    def opcode(self) -> Opcode:
        return self.command.OPCODE

    @property
    def cli_name(self) -> str:
        """The ``gcu-async send`` subcommand: the method name with dashes."""
        return self.method.replace("_", "-")

    @property
    def status(self) -> StatusRule:
        return self.command.SCHEMA.status

    def parameter(self, name: str) -> Parameter:
        """The parameter ``name`` (``KeyError`` if it has none)."""
        for p in self.parameters:
            if p.name == name:
                return p
        raise KeyError(f"{self.method} has no parameter {name!r}")


ALTITUDE_RANGE = (S32[0] / 1000, S32[1] / 1000)
"""Metres: what the gaze-at altitude field (S32, 1 mm) carries."""
TEMPERATURE_RANGE = (TEMPERATURE_RAW[0] / 10, TEMPERATURE_RAW[1] / 10)
"""°C: what a threshold field (S16, 0.1 °C) carries."""


def _parameters(command: type[c.Command], method: Method) -> tuple[Parameter, ...]:
    """The method's parameters: each named command attribute's kind gives its name(s), range,
    unit and doc, the class its default (``method.required`` drops it)."""
    defaults = {f.name: REQUIRED if f.default is MISSING else f.default for f in fields(command)}
    by_attr: dict[str, tuple[Parameter, ...]] = {}
    for kind in command.SCHEMA.params:
        derived = kind.parameters({a: defaults[a] for a in kind.attrs})
        if len(kind.attrs) == 1:  # a point gives x and y
            by_attr[kind.attrs[0]] = tuple(derived.values())
        else:  # thresholds, zoom value: one parameter per attribute
            by_attr.update((a, (derived[a],)) for a in kind.attrs)
    found: list[Parameter] = []
    for item in method.params if method.params is not None else tuple(defaults):
        if isinstance(item, Parameter):
            found.append(item)
            continue
        for p in by_attr[item]:
            if p.name in method.required:
                p = replace(p, default=REQUIRED)
            found.append(p)
    return tuple(found)


CATALOGUE: tuple[CatalogueEntry, ...] = tuple(
    CatalogueEntry(m.name, cls, m.doc, _parameters(cls, m), cls.SCHEMA.needs_ins)
    for cls in c.COMMAND_TYPES.values()
    for m in cls.SCHEMA.methods
)
"""Every command method of the client, in the order of the docs' command table (the order
of the schema)."""

BY_METHOD: Mapping[str, CatalogueEntry] = MappingProxyType({e.method: e for e in CATALOGUE})
"""The catalogue by method name."""
NEEDS_INS: frozenset[Opcode] = frozenset(e.opcode for e in CATALOGUE if e.needs_ins)
"""The opcodes the GCU executes only with valid INS data (:attr:`CatalogueEntry.needs_ins`)."""
