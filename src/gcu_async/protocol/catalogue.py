"""The command catalogue: one entry per client command method, the one place its names live.

Each :class:`CatalogueEntry` gives a command's client method name (a verb phrase), its
command class (the protocol's noun: the :class:`~gcu_async.protocol.Opcode` member's name in
CamelCase), its opcode, its ``gcu-async send`` name (the method name with dashes), its
parameters (:class:`Parameter`: name, kind, unit, range, default), a one-line doc and how
its feedback's execution status reads (:class:`StatusRule`, docs/protocol-notes.md §2
"Execution status per command"). Every entry is derived from the command table
(:mod:`gcu_async.protocol.commands`, each class's ``SCHEMA``): nothing is written here. The
command line's ``send`` subcommands, the web example's table and the docs' command table are
made from it; the client's methods and the command
classes' own validation are checked against it by tests (tests/protocol/test_catalogue.py), so the
copies cannot drift. Sans-I/O and immutable: tuples of frozen dataclasses.

One opcode may have several entries (``track`` and ``stop_tracking`` both send TRACK); the
null command has none: the client sends it by itself (docs/protocol-notes.md §4 "The
same-opcode rule").
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import MISSING, dataclass, fields, replace
from types import MappingProxyType

from gcu_async.protocol.command_base import Command
from gcu_async.protocol.command_schema import REQUIRED as REQUIRED
from gcu_async.protocol.command_schema import Kind as Kind
from gcu_async.protocol.command_schema import Method
from gcu_async.protocol.command_schema import Parameter as Parameter
from gcu_async.protocol.command_schema import Required as Required
from gcu_async.protocol.command_schema import StatusRule as StatusRule
from gcu_async.protocol.commands import COMMAND_TYPES
from gcu_async.protocol.commands import RATE_LIMIT as RATE_LIMIT
from gcu_async.protocol.opcodes import Opcode
from gcu_async.protocol.units import YAW_INPUT_RANGE as YAW_INPUT_RANGE


@dataclass(frozen=True, slots=True)
class CatalogueEntry:
    """One command method: its names, its command, its parameters."""

    method: str
    """The :class:`~gcu_async.client.GcuClient` method (a verb phrase)."""
    command: type[Command]
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


def _parameters(command: type[Command], method: Method) -> tuple[Parameter, ...]:
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
    for cls in COMMAND_TYPES.values()
    for m in cls.SCHEMA.methods
)
"""Every command method of the client, in the order of the docs' command table (the order
of the schema)."""

BY_METHOD: Mapping[str, CatalogueEntry] = MappingProxyType({e.method: e for e in CATALOGUE})
"""The catalogue by method name."""
NEEDS_INS: frozenset[Opcode] = frozenset(e.opcode for e in CATALOGUE if e.needs_ins)
"""The opcodes the GCU executes only with valid INS data (:attr:`CatalogueEntry.needs_ins`)."""
