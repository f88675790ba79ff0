"""Whole packets in both directions: encode and decode.

Layout (both directions): 0–1 header, 2–3 total length S (LE), 4 version, 5–36 main frame,
37–68 sub frame, 69 opcode, 70..S-3 parameters (host) or execution status (GCU),
S-2..S-1 CRC-16/XMODEM of bytes 0..S-3, **high byte first**.

Receive is liberal, send is strict (docs/client.md, "Liberal receive, strict send"): only a
wrong header, length or CRC (or too few bytes) makes bytes undecodable
(:class:`RemoteProtocolError` with its :class:`ProtocolErrorReason`); any other unexpected
value is kept and listed in the packet's ``anomalies``.
"""

from __future__ import annotations

import struct
from binascii import crc_hqx
from collections.abc import Collection
from typing import Any, Literal, NamedTuple, NoReturn, TypedDict, TypeVar

from gcu_async._checks import check_int, type_error
from gcu_async.errors import ProtocolErrorReason, RemoteProtocolError
from gcu_async.protocol.anomalies import VERSION_DETAIL, Anomaly, AnomalyDict
from gcu_async.protocol.command_base import Command
from gcu_async.protocol.command_decode import (
    AnomalousCommand,
    UnknownCommand,
    decode_command,
)
from gcu_async.protocol.commands import NullCommand
from gcu_async.protocol.crc import crc16_xmodem
from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.fields import WIRE_RANGES
from gcu_async.protocol.frame_schema import FrameSchema
from gcu_async.protocol.gcu_frame_tables import GCU_MAIN_SCHEMA, GCU_SUB_SCHEMA
from gcu_async.protocol.gcu_frames import (
    GcuMainFrame,
    GcuMainFrameDict,
    GcuSubFrame,
    GcuSubFrameDict,
    UnknownSubFrame,
    UnknownSubFrameDict,
)
from gcu_async.protocol.host_frame_tables import HOST_MAIN_SCHEMA, HOST_SUB_SCHEMA
from gcu_async.protocol.host_frames import (
    HostMainFrame,
    HostMainFrameDict,
    HostSubFrame,
    HostSubFrameDict,
)
from gcu_async.protocol.layout import (
    CRC_SIZE,
    MAIN_START,
    OPCODE_OFFSET,
    SUB_FRAME_HEADER,
    SUB_HEADER_OFFSET,
    SUB_SIZE,
    SUB_START,
)

HOST_HEADER = b"\xa8\xe5"
GCU_HEADER = b"\x8a\x5e"
PREFIX = struct.Struct("<2sHB")
"""Bytes 0–4: header, length S, version."""
CRC_STRUCT = struct.Struct(">H")
BASE_LENGTH = OPCODE_OFFSET + 1 + CRC_SIZE
"""S of a packet with no parameters / no execution status (72)."""
MAX_LENGTH = 256
"""Longest packet ``Deframer(header)`` accepts by default (V2.0.6's longest is 84 bytes;
the streaming deframers of each direction accept less: see :mod:`~gcu_async.protocol.deframer`)."""
SUPPORTED_VERSIONS = frozenset({1, 2})
"""Versions V2.0.6 defines; others decode with its layout, flagged (:func:`version_anomalies`)."""
DEFAULT_VERSION = 2
_ZERO_SUB = bytes(1 + SUB_SIZE)
_PARAMS = OPCODE_OFFSET + 1


class _Body(NamedTuple):
    """Bytes 0–69 in one struct (prefix, main frame, sub frame header + standard sub frame,
    opcode), so a packet is packed and unpacked with one call; and where each part's values
    sit in the unpacked tuple, from the frame schemas."""

    struct: struct.Struct
    header: int
    """The packet header as the U16 the struct reads (ints compare without a bytes object)."""
    main: slice
    sub_header: int
    sub: slice
    opcode: int
    zero_sub: tuple[int, ...]
    """The standard sub frame's fields all zero: what bytes 38–68 hold under another header."""


def _body(header: bytes, main: FrameSchema, sub: FrameSchema) -> _Body:
    if (main.start, main.end, sub.start, sub.end) != (MAIN_START, SUB_HEADER_OFFSET,
                                                      SUB_START, OPCODE_OFFSET):  # fmt: skip
        raise ValueError(f"{main.title} / {sub.title} do not fill bytes {MAIN_START}-"
                         f"{OPCODE_OFFSET - 1}")  # fmt: skip
    layout = struct.Struct("<HHB" + main.format + "B" + sub.format + "B")
    if layout.size != _PARAMS:
        raise ValueError(f"packet body is {layout.size} bytes, not {_PARAMS}")
    m = len(PREFIX.unpack(bytes(PREFIX.size)))  # header, length, version
    s = m + len(main.fields) + 1
    return _Body(layout, int.from_bytes(header, "little"), slice(m, m + len(main.fields)),
                 s - 1, slice(s, s + len(sub.fields)), s + len(sub.fields),
                 (0,) * len(sub.fields))  # fmt: skip


_GCU = _body(GCU_HEADER, GCU_MAIN_SCHEMA, GCU_SUB_SCHEMA)
_HOST = _body(HOST_HEADER, HOST_MAIN_SCHEMA, HOST_SUB_SCHEMA)

HostSub = HostSubFrame | UnknownSubFrame | None
GcuSub = GcuSubFrame | UnknownSubFrame | None


def version_anomalies(version: int) -> tuple[Anomaly, ...]:
    """The version byte as an anomaly unless V2.0.6 defines it (1 or 2)."""
    if version in SUPPORTED_VERSIONS:
        return ()
    return (Anomaly("version", version, 1, 2, "", VERSION_DETAIL),)


def _encode(body: _Body, version: int, main: tuple[int, ...], sub: Any, standard: type[Any],
            opcode: int, tail: bytes) -> bytes:  # fmt: skip
    """The wire bytes of a packet whose parts are checked: bytes 0–69 in one call, ``tail``
    (parameters or execution status), the CRC-16/XMODEM (crc.py) high byte first."""
    if type(sub) is standard:
        head, fields = SUB_FRAME_HEADER, sub
    else:  # none: all zero; another header: its data replaces the zeros below
        head, fields = (0, body.zero_sub) if sub is None else (sub.header, body.zero_sub)
    data = body.struct.pack(body.header, BASE_LENGTH + len(tail), version, *main, head,
                            *fields, opcode) + tail  # fmt: skip
    if isinstance(sub, UnknownSubFrame):
        data = data[:SUB_START] + bytes(sub.data) + data[OPCODE_OFFSET:]
    return data + CRC_STRUCT.pack(crc_hqx(data, 0))


def _check_sub(sub: object, standard: type[Any], expected: str) -> None:
    if sub is not None:
        if type(sub) is not standard and not isinstance(sub, (standard, UnknownSubFrame)):
            raise type_error("sub", expected, sub)
        sub.validate()  # type: ignore[attr-defined]


class _Anomalies(TypedDict, total=False):
    anomalies: list[AnomalyDict]
    """Present when the packet has anomalies (:attr:`GcuPacket.anomalies`), in wire order."""


class HostPacketDict(_Anomalies):
    """What :meth:`HostPacket.as_dict` returns."""

    direction: Literal["host_to_gcu"]
    version: int
    main: HostMainFrameDict
    sub: HostSubFrameDict | UnknownSubFrameDict | None
    command: dict[str, Any]
    """:meth:`Command.as_dict`: ``command`` (its name), ``opcode``, ``params``."""


class GcuPacketDict(_Anomalies):
    """What :meth:`GcuPacket.as_dict` returns."""

    direction: Literal["gcu_to_host"]
    version: int
    main: GcuMainFrameDict
    sub: GcuSubFrameDict | UnknownSubFrameDict | None
    feedback: dict[str, Any]
    """:meth:`Feedback.as_dict`."""


class HostPacket(NamedTuple):
    """A host → GCU packet. Built raw; :meth:`encode` checks every part (types and ranges)
    and raises ``TypeError`` / :class:`FieldRangeError` naming the part and field."""

    main: HostMainFrame
    sub: HostSub = None
    """``None`` when bytes 37–68 are all zero (no sub frame)."""
    command: Command = NullCommand()
    version: int = DEFAULT_VERSION

    def encode(self) -> bytes:
        """Validate every field and return the wire bytes."""
        main, sub, command, version = self
        if not isinstance(main, HostMainFrame):
            raise type_error("main", "a HostMainFrame", main)
        main.validate()
        _check_sub(sub, HostSubFrame, "a HostSubFrame, an UnknownSubFrame or None")
        if not isinstance(command, Command):
            raise type_error("command", "a Command", command)
        if type(version) is not int or not 0 <= version <= 255:
            check_int("version", version, 0, 255)
        params = command.encode_params()  # an AnomalousCommand raises here: send is strict
        opcode = command.code if isinstance(command, UnknownCommand) else command.OPCODE
        return _encode(_HOST, version, main, sub, HostSubFrame, opcode, params)

    def as_dict(self) -> HostPacketDict:
        """The packet for JSON output (:class:`HostPacketDict`)."""
        shown: HostPacketDict = {
            "direction": "host_to_gcu",
            "version": self.version,
            "main": self.main.as_dict(),
            "sub": None if self.sub is None else self.sub.as_dict(),
            "command": self.command.as_dict(),
        }
        return _with_anomalies(shown, self.anomalies)

    @property
    def anomalies(self) -> tuple[Anomaly, ...]:
        """Everything V2.0.6 does not expect in this packet, in wire order: its version, its
        frames' fields (:attr:`HostMainFrame.anomalies`, :attr:`HostSubFrame.anomalies`),
        its command's parameters (an :class:`AnomalousCommand`); empty for an ordinary
        packet."""
        found = version_anomalies(self.version) + self.main.anomalies
        if isinstance(self.sub, HostSubFrame):
            found += self.sub.anomalies
        if isinstance(self.command, AnomalousCommand):
            found += self.command.anomalies
        return found


class GcuPacket(NamedTuple):
    """A GCU → host packet. Built raw; :meth:`encode` checks every part (types and ranges)
    and raises ``TypeError`` / :class:`FieldRangeError` naming the part and field."""

    main: GcuMainFrame
    sub: GcuSub = None
    """``None`` when bytes 37–68 are all zero (no sub frame requested, or an unknown one)."""
    feedback: Feedback = Feedback(0)
    version: int = DEFAULT_VERSION

    def encode(self, *, deviations: Collection[str] = ()) -> bytes:
        """Validate every field and return the wire bytes. The version (0–255) and the
        feedback's ``extra_status`` bytes are written as they are, so a decoded reply
        re-encodes to its own bytes (the simulator can act as other firmware).
        ``deviations`` names main-frame fields to send outside their V2.0.6 range (a firmware
        that does, e.g. a signed ``yaw_raw``): each is still an ``int`` of its wire type."""
        main, sub, feedback, version = self
        if not isinstance(main, GcuMainFrame):
            raise type_error("main", "a GcuMainFrame", main)
        if deviations:
            _check_deviations(main, deviations)
        else:
            main.validate()
        _check_sub(sub, GcuSubFrame, "a GcuSubFrame, an UnknownSubFrame or None")
        check_int("version", version, 0, 255)
        if not isinstance(feedback, Feedback):
            raise type_error("feedback", "a Feedback", feedback)
        check_int("feedback opcode", feedback.opcode, 0, 255)
        status, extra = feedback.status, feedback.extra_status
        if not isinstance(extra, (bytes, bytearray)):
            raise type_error("feedback extra_status", "bytes", extra)
        if status is None:
            if extra:
                raise ValueError("feedback: extra_status needs a status byte before it")
            tail = b""
        else:
            tail = bytes((check_int("feedback status", status, 0, 255),)) + extra
        return _encode(_GCU, version, main, sub, GcuSubFrame, feedback.opcode, tail)

    def as_dict(self) -> GcuPacketDict:
        """The reply for JSON output (:class:`GcuPacketDict`)."""
        shown: GcuPacketDict = {
            "direction": "gcu_to_host",
            "version": self.version,
            "main": self.main.as_dict(),
            "sub": None if self.sub is None else self.sub.as_dict(),
            "feedback": self.feedback.as_dict(),
        }
        return _with_anomalies(shown, self.anomalies)

    @property
    def anomalies(self) -> tuple[Anomaly, ...]:
        """Everything V2.0.6 does not expect in this reply, in wire order: its version, its
        frames' fields (:attr:`GcuMainFrame.anomalies`, :attr:`GcuSubFrame.anomalies`), its
        feedback (:attr:`Feedback.anomalies`); empty for an ordinary reply."""
        found = version_anomalies(self.version) + self.main.anomalies
        if isinstance(self.sub, GcuSubFrame):
            found += self.sub.anomalies
        return found + self.feedback.anomalies


_P = TypeVar("_P", HostPacketDict, GcuPacketDict)


def _with_anomalies(shown: _P, anomalies: tuple[Anomaly, ...]) -> _P:
    if anomalies:
        shown["anomalies"] = [a.as_dict() for a in anomalies]
    return shown


def _check_deviations(main: GcuMainFrame, deviations: Collection[str]) -> None:
    """``main`` valid but for the fields ``deviations`` names, which need only fit their wire
    type."""
    fields = GCU_MAIN_SCHEMA.by_name
    unknown = set(deviations) - set(fields)
    if unknown:
        raise ValueError(f"deviations: {sorted(unknown)} name no main-frame field")
    for name in deviations:
        low, high = WIRE_RANGES[fields[name].fmt]
        check_int(name, getattr(main, name), low, high, fields[name].raw_unit)
    main._replace(**{name: fields[name].raw_low for name in deviations}).validate()


def _envelope_error(data: bytes, header: bytes) -> NoReturn:
    """Raise the error :func:`_check_envelope` finds in ``data``."""
    _check_envelope(data, header)
    raise AssertionError("unreachable: _check_envelope raised")  # pragma: no cover


def _check_envelope(data: bytes, header: bytes) -> None:
    """Check size, header, length and CRC: the only checks that make bytes no packet."""
    n = len(data)
    if n < BASE_LENGTH:
        raise RemoteProtocolError(
            ProtocolErrorReason.SHORT,
            f"packet of {n} bytes is shorter than the minimum {BASE_LENGTH}",
        )
    hdr, length, _ = PREFIX.unpack_from(data)
    if hdr != header:
        raise RemoteProtocolError(ProtocolErrorReason.HEADER,
                                  f"header {hdr.hex(' ')} is not {header.hex(' ')}")  # fmt: skip
    if length != n:
        raise RemoteProtocolError(ProtocolErrorReason.LENGTH,
                                  f"length field says {length} bytes, packet has {n}")  # fmt: skip
    crc = crc16_xmodem(memoryview(data)[:-CRC_SIZE])
    sent = CRC_STRUCT.unpack_from(data, n - CRC_SIZE)[0]
    if crc != sent:
        raise RemoteProtocolError(
            ProtocolErrorReason.CRC, f"CRC mismatch: computed 0x{crc:04X}, packet has 0x{sent:04X}"
        )


_new = tuple.__new__
_GCU_UNPACK = _GCU.struct.unpack_from
_GCU_HEADER_U16, _GCU_MAIN, _GCU_SUB_HEADER = _GCU.header, _GCU.main, _GCU.sub_header
_GCU_SUB, _GCU_OPCODE = _GCU.sub, _GCU.opcode
_NO_STATUS = tuple(Feedback(opcode) for opcode in range(256))
"""The feedback of each opcode with no execution status (S = 72), shared: immutable."""


def decode_gcu_packet(data: bytes) -> GcuPacket:
    """Decode one complete GCU → host packet (as produced by a :class:`Deframer`).

    Raises :class:`RemoteProtocolError` (with its ``reason``) only for too few bytes, a bad
    header, length or CRC; an unexpected version or status is kept and flagged
    (:attr:`GcuPacket.anomalies`).
    """
    # Fast path of _check_envelope (same checks, one struct call); on any failure,
    # _check_envelope names the first problem. A CRC-16/XMODEM over a whole packet, its
    # CRC included high byte first, is 0 exactly when that CRC matches (crc.py).
    n = len(data)
    if n < BASE_LENGTH:
        _envelope_error(data, GCU_HEADER)
    fields = _GCU_UNPACK(data)
    if fields[0] != _GCU_HEADER_U16 or fields[1] != n or crc_hqx(data, 0):
        _envelope_error(data, GCU_HEADER)
    main = _new(GcuMainFrame, fields[_GCU_MAIN])
    sub_header = fields[_GCU_SUB_HEADER]
    sub: GcuSub
    if sub_header == SUB_FRAME_HEADER:
        sub = _new(GcuSubFrame, fields[_GCU_SUB])
    elif data[SUB_HEADER_OFFSET:OPCODE_OFFSET] == _ZERO_SUB:
        sub = None
    else:
        sub = UnknownSubFrame(sub_header, bytes(data[SUB_START:OPCODE_OFFSET]))
    opcode = fields[_GCU_OPCODE]
    if n == BASE_LENGTH:
        feedback = _NO_STATUS[opcode]
    elif n == BASE_LENGTH + 1:
        feedback = _new(Feedback, (opcode, data[_PARAMS], b""))
    else:  # more status bytes than V2.0.6 defines: kept, flagged
        feedback = _new(Feedback, (opcode, data[_PARAMS], bytes(data[_PARAMS + 1 : -CRC_SIZE])))
    return _new(GcuPacket, (main, sub, feedback, fields[2]))


def decode_host_packet(data: bytes) -> HostPacket:
    """Decode one complete host → GCU packet, including the typed command.

    Raises :class:`RemoteProtocolError` (with its ``reason``) only for too few bytes, a bad
    header, length or CRC; an unexpected version or parameter is kept and flagged
    (:attr:`HostPacket.anomalies`, :class:`AnomalousCommand`).
    """
    _check_envelope(data, HOST_HEADER)
    fields = _HOST.struct.unpack_from(data)
    main = _new(HostMainFrame, fields[_HOST.main])
    sub_header = fields[_HOST.sub_header]
    sub: HostSub
    if sub_header == SUB_FRAME_HEADER:
        sub = _new(HostSubFrame, fields[_HOST.sub])
    elif data[SUB_HEADER_OFFSET:OPCODE_OFFSET] == _ZERO_SUB:
        sub = None
    else:
        sub = UnknownSubFrame(sub_header, bytes(data[SUB_START:OPCODE_OFFSET]))
    command = decode_command(fields[_HOST.opcode], bytes(data[_PARAMS:-CRC_SIZE]))
    return _new(HostPacket, (main, sub, command, fields[2]))


def decode_packet(data: bytes) -> HostPacket | GcuPacket:
    """Decode a packet of either direction, chosen by its header."""
    if data[:2] == GCU_HEADER:
        return decode_gcu_packet(data)
    return decode_host_packet(data)
