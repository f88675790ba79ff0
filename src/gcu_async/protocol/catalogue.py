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
classes' own validation are checked against it by tests (tests/test_catalogue.py), so the
copies cannot drift. Sans-I/O and immutable: tuples of frozen dataclasses.

One opcode may have several entries (``track`` / ``stop_tracking`` both send 0x17); the
null command (0x00) has none: the client sends it by itself (docs/protocol-notes.md §4 "The
same-opcode rule").
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields
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
    """The method's parameters: each named command attribute's kind gives its range, unit
    and doc, the class its default (``method.required`` overrides it)."""
    defaults: dict[str, object] = {}
    for f in fields(command):  # type: ignore[arg-type]
        default = f.default
        defaults[f.name] = REQUIRED if default is f.default_factory else default  # MISSING
    derived: dict[str, Parameter] = {}
    owner: dict[str, str] = {}
    for kind in command.SCHEMA.params:
        given = {a: defaults[a] for a in kind.attrs}
        for name, p in kind.parameters(given).items():
            derived[name] = p
            owner.setdefault(kind.attrs[0] if len(kind.attrs) == 1 else name, name)
    names = method.params if method.params is not None else tuple(defaults)
    found: list[Parameter] = []
    for item in names:
        if isinstance(item, Parameter):
            found.append(item)
            continue
        kind_params = [p for n, p in derived.items() if n == item or _attr_of(command, n) == item]
        for p in kind_params:
            if p.name in method.required:
                p = Parameter(p.name, p.kind, p.doc, p.unit, p.low, p.high, p.low_open,
                              p.high_open, REQUIRED, p.choices)  # fmt: skip
            found.append(p)
    return tuple(found)


def _attr_of(command: type[c.Command], parameter: str) -> str | None:
    """The attribute a derived parameter comes from (``x`` → ``point``)."""
    for kind in command.SCHEMA.params:
        if len(kind.attrs) == 1 and parameter in kind.parameters({kind.attrs[0]: REQUIRED}):
            return kind.attrs[0]
    return None


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
