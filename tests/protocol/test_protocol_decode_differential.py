"""The decoders against a copy of the code before the frame schemas (kept only here).

``decode_gcu_packet`` and ``decode_host_packet`` now take their struct, slices and offsets
from the frame schemas, compare the header as a U16 and share status-less feedbacks. For
any bytes — valid packets, packets with bytes changed and the CRC fixed, truncated or
extended ones, junk — they must return what the old code returned, or raise the same error
(type, reason and message).
"""

from __future__ import annotations

import struct
from binascii import crc_hqx
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from gcu_async.errors import RemoteProtocolError
from gcu_async.protocol import (
    Feedback,
    GcuMainFrame,
    GcuPacket,
    GcuSubFrame,
    HostMainFrame,
    HostPacket,
    HostSubFrame,
    UnknownSubFrame,
    decode_command,
    decode_gcu_packet,
    decode_host_packet,
)
from gcu_async.protocol.gcu_frame_tables import GCU_MAIN_SCHEMA, GCU_SUB_SCHEMA
from gcu_async.protocol.host_frame_tables import HOST_MAIN_SCHEMA, HOST_SUB_SCHEMA
from gcu_async.protocol.packets import GCU_HEADER, HOST_HEADER, _check_envelope
from helpers.protocol.strategies import gcu_packets, host_packets
from helpers.scale import scaled

# --- the old decoders, as they were -------------------------------------------------------
# Their logic is the old one; the frames' formats come from the schemas (so a field added
# later does not break this test: the layout itself is tests/test_protocol_frame_schema.py's).
_OLD_GCU_BODY = struct.Struct("<2sHB" + GCU_MAIN_SCHEMA.format + "B" + GCU_SUB_SCHEMA.format
                              + "B")  # fmt: skip
_M = 3 + len(GCU_MAIN_SCHEMA.fields)  # the sub frame header's index
_S = _M + 1 + len(GCU_SUB_SCHEMA.fields)  # the opcode's index
_OLD_HOST_MAIN = HOST_MAIN_SCHEMA.struct
_OLD_HOST_SUB = HOST_SUB_SCHEMA.struct
_new = tuple.__new__


def old_decode_gcu_packet(data: bytes) -> GcuPacket:
    n = len(data)
    if n < 72:
        _check_envelope(data, GCU_HEADER)
    fields = _OLD_GCU_BODY.unpack_from(data)
    if fields[0] != GCU_HEADER or fields[1] != n or crc_hqx(data, 0):
        _check_envelope(data, GCU_HEADER)
    main = _new(GcuMainFrame, fields[3:_M])
    sub_header = fields[_M]
    sub: Any
    if sub_header == 0x01:
        sub = _new(GcuSubFrame, fields[_M + 1 : _S])
    elif data[37:69] == bytes(32):
        sub = None
    else:
        sub = UnknownSubFrame(sub_header, bytes(data[38:69]))
    if n == 72:
        feedback = _new(Feedback, (fields[_S], None, b""))
    elif n == 73:
        feedback = _new(Feedback, (fields[_S], data[70], b""))
    else:
        feedback = _new(Feedback, (fields[_S], data[70], bytes(data[71:-2])))
    return _new(GcuPacket, (main, sub, feedback, fields[2]))


def old_decode_host_packet(data: bytes) -> HostPacket:
    _check_envelope(data, HOST_HEADER)
    version = data[4]
    main = _new(HostMainFrame, _OLD_HOST_MAIN.unpack_from(data, 5))
    sub_header = data[37]
    sub: Any
    if sub_header == 0x01:
        sub = _new(HostSubFrame, _OLD_HOST_SUB.unpack_from(data, 38))
    elif data[37:69] == bytes(32):
        sub = None
    else:
        sub = UnknownSubFrame(sub_header, bytes(data[38:69]))
    command = decode_command(data[69], bytes(data[70:-2]))
    return _new(HostPacket, (main, sub, command, version))


# --- the comparison -----------------------------------------------------------------------
def _outcome(decode: Any, data: bytes) -> Any:
    try:
        packet = decode(data)
    except RemoteProtocolError as exc:
        return ("error", exc.reason, str(exc))
    return ("ok", packet, packet.anomalies, packet.as_dict())


def _reseal(data: bytearray) -> bytes:
    if len(data) >= 2:
        data[-2:] = crc_hqx(bytes(data[:-2]), 0).to_bytes(2, "big")
    return bytes(data)


@st.composite
def _hostile(draw: st.DrawFn, packets: st.SearchStrategy[Any]) -> bytes:
    wire = bytearray(draw(packets).encode())
    how = draw(st.sampled_from(["as is", "changed", "changed, resealed", "cut", "extended",
                                "length", "junk"]))  # fmt: skip
    if how in ("changed", "changed, resealed"):
        for _ in range(draw(st.integers(1, 6))):
            wire[draw(st.integers(0, len(wire) - 1))] = draw(st.integers(0, 255))
        if how == "changed, resealed":
            wire = bytearray(_reseal(wire))
    elif how == "cut":
        wire = wire[: draw(st.integers(0, len(wire) - 1))]
    elif how == "extended":
        wire[-2:-2] = draw(st.binary(min_size=1, max_size=20))
        wire[2:4] = len(wire).to_bytes(2, "little")
        wire = bytearray(_reseal(wire))
    elif how == "length":
        wire[2:4] = draw(st.integers(0, 0xFFFF)).to_bytes(2, "little")
    elif how == "junk":
        wire = bytearray(draw(st.binary(max_size=100)))
    return bytes(wire)


@settings(max_examples=scaled(1500, 150), deadline=None)
@given(_hostile(gcu_packets))
def test_gcu_decode_is_the_old_decode(data: bytes) -> None:
    assert _outcome(decode_gcu_packet, data) == _outcome(old_decode_gcu_packet, data)


@settings(max_examples=scaled(1500, 150), deadline=None)
@given(_hostile(host_packets))
def test_host_decode_is_the_old_decode(data: bytes) -> None:
    assert _outcome(decode_host_packet, data) == _outcome(old_decode_host_packet, data)
