"""What a received opcode and its parameter bytes decode to, whatever they hold.

:func:`decode_command` turns opcode + parameter bytes into the typed command of the command
table (:mod:`gcu_async.protocol.commands`) — or, for an opcode V2.0.6 does not define, into
an :class:`UnknownCommand` that keeps the bytes, and for parameters that hold a value outside
its range or have the wrong length, into an :class:`AnomalousCommand` that keeps the bytes and
lists the :class:`~gcu_async.protocol.Anomaly` of each field. Receive is liberal, send is
strict (docs/client.md, "Liberal receive, strict send"): neither is ever re-encoded as if it
were a valid command.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from gcu_async._checks import check_int, type_error
from gcu_async.errors import FieldRangeError
from gcu_async.protocol.anomalies import Anomaly
from gcu_async.protocol.command_base import Command
from gcu_async.protocol.commands import COMMAND_TYPES
from gcu_async.protocol.opcodes import Opcode, opcode_name

MAX_PARAMS = 0xFFFF - 72
"""Most parameter bytes a packet can carry (S, a U16, counts 72 bytes besides them)."""


def _checked_bytes(params: object) -> bytes:
    if not isinstance(params, (bytes, bytearray)):
        raise type_error("params", "bytes", params)
    return bytes(params)  # an immutable copy


@dataclass(frozen=True, slots=True)
class UnknownCommand(Command):
    """An opcode V2.0.6 does not define, kept byte for byte."""

    OPCODE = Opcode.NULL  # placeholder; the real opcode is ``code``
    code: int = 0
    params: bytes = b""

    def __post_init__(self) -> None:
        check_int("opcode", self.code, 0, 255)
        if self.code in COMMAND_TYPES:
            name = COMMAND_TYPES[self.code].__name__
            raise ValueError(f"opcode: 0x{self.code:02X} is a known command; use {name}")
        params = _checked_bytes(self.params)
        if len(params) > MAX_PARAMS:
            raise FieldRangeError("params", len(params), 0, MAX_PARAMS, "bytes",
                                  detail="its length: the packet length S is a U16")  # fmt: skip
        object.__setattr__(self, "params", params)
        object.__setattr__(self, "_raw", ())  # no layout: the bytes are all there is

    @property
    def opcode(self) -> Opcode:  # pragma: no cover - unknown opcodes have no Opcode member
        raise AttributeError("UnknownCommand has no Opcode member; use .code")

    def encode_params(self) -> bytes:
        return bytes(self.params)

    def as_dict(self) -> dict[str, Any]:
        return {"command": f"UNKNOWN_0x{self.code:02X}", "opcode": self.code,
                "params_hex": bytes(self.params).hex(" ")}  # fmt: skip


@dataclass(frozen=True, slots=True)
class AnomalousCommand(Command):
    """A known opcode whose parameter bytes V2.0.6 does not allow (a value outside its
    range, or the wrong number of bytes), as decoded from a CRC-valid packet: the bytes are
    kept (``params``), every offending field is listed (``anomalies``, raw values and raw
    ranges). Receive is liberal, send is strict (docs/client.md, "Liberal receive, strict
    send"): it is never re-encoded — :meth:`encode_params`, and so ``HostPacket.encode`` and
    the client, raise the :class:`FieldRangeError` of its first anomaly."""

    OPCODE = Opcode.NULL  # placeholder; the real opcode is ``code``
    code: int = 0
    params: bytes = b""
    anomalies: tuple[Anomaly, ...] = ()

    def __post_init__(self) -> None:
        if check_int("opcode", self.code, 0, 255) not in COMMAND_TYPES:
            raise ValueError(f"opcode: 0x{self.code:02X} is not a V2.0.6 command; use "
                             "UnknownCommand")  # fmt: skip
        object.__setattr__(self, "params", _checked_bytes(self.params))
        anomalies = tuple(self.anomalies)
        if not anomalies or not all(isinstance(a, Anomaly) for a in anomalies):
            raise ValueError("anomalies: give at least one, each an Anomaly")
        object.__setattr__(self, "anomalies", anomalies)

    @property
    def opcode(self) -> Opcode:
        return Opcode(self.code)

    @property
    def command_type(self) -> type[Command]:
        """The command class its opcode names."""
        return COMMAND_TYPES[self.code]

    @property
    def raw(self) -> tuple[int, ...] | None:
        """The parameters unpacked with the command's layout (``None`` for a wrong length)."""
        layout = self.command_type.LAYOUT
        return layout.unpack(self.params) if len(self.params) == layout.size else None

    def error(self) -> FieldRangeError:
        """The error sending it raises: that of its first anomaly."""
        return self.anomalies[0].error()

    def raw_params(self) -> tuple[int, ...]:
        raise self.error()

    def encode_params(self) -> bytes:
        raise self.error()

    def as_dict(self) -> dict[str, Any]:
        """Name, opcode, raw parameters (``None`` for a wrong length) and their bytes; the
        anomalies are listed by the packet's ``as_dict``."""
        raw = self.raw
        return {"command": opcode_name(self.code), "opcode": self.code,
                "params_raw": None if raw is None else list(raw),
                "params_hex": self.params.hex(" ")}  # fmt: skip


def decode_command(opcode: int, params: bytes) -> Command:
    """Typed command for ``opcode`` + parameter bytes; unknown opcodes give
    :class:`UnknownCommand`, parameters V2.0.6 does not allow an :class:`AnomalousCommand`.
    Never raises for bytes: receive is liberal (docs/client.md, "Liberal receive, strict
    send")."""
    cls = COMMAND_TYPES.get(opcode)
    if cls is None:
        return UnknownCommand(code=opcode, params=bytes(params))
    layout = cls.LAYOUT
    if len(params) != layout.size:
        found = Anomaly("params", len(params), layout.size, layout.size, "bytes",
                        f"{cls.OPCODE.name} has {layout.size} parameter bytes")  # fmt: skip
        return AnomalousCommand(int(cls.OPCODE), bytes(params), (found,))
    raw = layout.unpack(params)
    try:
        return cls.from_raw_params(raw)
    except ValueError:  # the slow path: out of range
        return AnomalousCommand(int(cls.OPCODE), bytes(params), cls.raw_anomalies(raw))


def command_code(command: Command) -> int:
    """The opcode byte of ``command`` (works for :class:`UnknownCommand` and
    :class:`AnomalousCommand` too)."""
    if isinstance(command, (UnknownCommand, AnomalousCommand)):
        return command.code
    if not isinstance(command, Command):
        raise type_error("command", "a Command", command)
    return int(command.OPCODE)
