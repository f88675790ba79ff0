"""Malformed packets (too short, bad header, length or CRC) raise RemoteProtocolError naming
the problem, with its reason as data; anything else decodes (liberal receive: unexpected
versions, status bytes and parameter lengths are flagged here, out-of-range parameter values in
tests/protocol/test_protocol_liberal.py's one table); unknown opcodes and sub frames are kept
byte for byte; an all-zero sub frame is "none"."""

from __future__ import annotations

import crcmod.predefined
import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcu_async.errors import GcuError, ProtocolErrorReason, RemoteProtocolError
from gcu_async.protocol import (
    COMMAND_TYPES,
    GCU_HEADER,
    HOST_HEADER,
    AnomalousCommand,
    Feedback,
    GcuMainFrame,
    GcuPacket,
    GcuSubFrame,
    HostMainFrame,
    HostPacket,
    HostSubFrame,
    TakePhoto,
    UnknownCommand,
    UnknownSubFrame,
    decode_command,
    decode_gcu_packet,
    decode_host_packet,
    decode_packet,
)
from helpers.protocol.strategies import seal
from helpers.protocol.vectors import GCU_EXAMPLE, HOST_EXAMPLE

xmodem = crcmod.predefined.mkCrcFun("xmodem")

DECODERS = {
    "host": (decode_host_packet, HOST_HEADER, HOST_EXAMPLE),
    "gcu": (decode_gcu_packet, GCU_HEADER, GCU_EXAMPLE),
}


def _crc(head: bytes) -> bytes:
    """``head`` (bytes 0..S-3) followed by its CRC-16/XMODEM, high byte first."""
    return head + xmodem(head).to_bytes(2, "big")


@pytest.mark.parametrize("direction", DECODERS)
def test_bad_header(direction: str) -> None:
    decode, header, vec = DECODERS[direction]
    for bad in (b"\x00\x00", header[::-1], HOST_HEADER if header == GCU_HEADER else GCU_HEADER):
        packet = _crc(bad + vec[2:-2])
        with pytest.raises(RemoteProtocolError, match=r"^header .* is not") as info:
            decode(packet)
        assert info.value.reason is ProtocolErrorReason.HEADER


@pytest.mark.parametrize("direction", DECODERS)
@pytest.mark.parametrize("length", [0, 71, 74, 0xFFFF])
def test_wrong_length_field(direction: str, length: int) -> None:
    decode, _, vec = DECODERS[direction]
    packet = _crc(vec[:2] + length.to_bytes(2, "little") + vec[4:-2])
    with pytest.raises(
        RemoteProtocolError, match=f"length field says {length} bytes, packet has {len(vec)}"
    ) as info:
        decode(packet)
    assert info.value.reason is ProtocolErrorReason.LENGTH


@pytest.mark.parametrize("direction", DECODERS)
def test_truncated_packet(direction: str) -> None:
    decode, _, vec = DECODERS[direction]
    for n in (0, 1, 4, 71):
        with pytest.raises(RemoteProtocolError, match="shorter than the minimum 72") as info:
            decode(vec[:n])
        assert info.value.reason is ProtocolErrorReason.SHORT


@pytest.mark.parametrize("direction", DECODERS)
def test_crc_mismatch(direction: str) -> None:
    decode, _, vec = DECODERS[direction]
    for i in (4, 20, 60, len(vec) - 2, len(vec) - 1):
        bad = bytearray(vec)
        bad[i] ^= 0x40
        with pytest.raises(RemoteProtocolError, match="CRC mismatch") as info:
            decode(bytes(bad))
        assert info.value.reason is ProtocolErrorReason.CRC


@pytest.mark.parametrize("direction", DECODERS)
@pytest.mark.parametrize("version", [0, 3, 0x20, 255])
def test_other_version_decodes_flagged(direction: str, version: int) -> None:
    decode, _, vec = DECODERS[direction]
    packet = _crc(vec[:4] + bytes([version]) + vec[5:-2])
    decoded = decode(packet)
    assert decoded.version == version
    assert decoded == decode(vec)._replace(version=version)  # the V2.0.6 layout
    [anomaly] = decoded.anomalies
    assert (anomaly.field, anomaly.value, anomaly.low, anomaly.high) == ("version", version, 1, 2)
    # the encoder writes any version 0-255 (a test can act as other firmware)
    assert decoded.encode() == packet


@pytest.mark.parametrize("version", [1, 2])
def test_versions_1_and_2_accepted(version: int) -> None:
    for decode, _, vec in DECODERS.values():
        decoded = decode(_crc(vec[:4] + bytes([version]) + vec[5:-2]))
        assert decoded.version == version
        assert decoded.anomalies == ()


def test_gcu_feedback_longer_than_one_status_byte() -> None:
    packet = seal(GCU_HEADER, GCU_EXAMPLE[5:-2] + b"\x01\x7f")
    assert len(packet) == 75
    decoded = decode_gcu_packet(packet)
    assert decoded.feedback == Feedback(GCU_EXAMPLE[69], GCU_EXAMPLE[70], b"\x01\x7f")
    [anomaly] = decoded.anomalies
    assert (anomaly.field, anomaly.value, anomaly.low, anomaly.high) == ("status length", 3, 1, 1)
    assert "01 7f" in anomaly.detail
    assert decoded.encode() == packet  # kept byte for byte


def test_remote_protocol_error_carries_its_reason() -> None:
    err = RemoteProtocolError(ProtocolErrorReason.CRC, "CRC mismatch")
    assert (err.reason, str(err)) == (ProtocolErrorReason.CRC, "CRC mismatch")
    import pickle

    copy = pickle.loads(pickle.dumps(err))
    assert (copy.reason, str(copy)) == (ProtocolErrorReason.CRC, "CRC mismatch")
    with pytest.raises(TypeError, match="reason"):
        RemoteProtocolError("crc", "CRC mismatch")  # type: ignore[arg-type]


def test_remote_protocol_error_is_a_gcu_value_error() -> None:
    assert issubclass(RemoteProtocolError, GcuError)
    assert issubclass(RemoteProtocolError, ValueError)


# --- command parameters on the wire ------------------------------------------------------------
def _host_with(opcode: int, params: bytes) -> bytes:
    return seal(HOST_HEADER, HOST_EXAMPLE[5:69] + bytes([opcode]) + params)


@pytest.mark.parametrize("cls", COMMAND_TYPES.values(), ids=lambda c: c.__name__)
def test_wrong_parameter_length_for_known_opcode(cls: type) -> None:
    size = cls.LAYOUT.size
    for n in {size + 1, size + 7, max(size - 1, 0)} - {size}:
        params = bytes([1]) * n
        packet = _host_with(int(cls.OPCODE), params)
        decoded = decode_host_packet(packet)
        assert decoded.command == AnomalousCommand(int(cls.OPCODE), params, decoded.anomalies)
        [anomaly] = decoded.anomalies
        assert (anomaly.field, anomaly.value, anomaly.low, anomaly.high) == ("params", n, size,
                                                                             size)  # fmt: skip
        assert decoded.command.raw is None  # type: ignore[attr-defined]


def test_known_parameter_bytes_decode() -> None:
    assert decode_command(0x20, b"\x03") == TakePhoto(cameras=3)
    assert decode_command(0x81, b"\x02").enabled is True  # type: ignore[attr-defined]
    assert decode_command(0x07, b"\x00").enabled is True  # type: ignore[attr-defined]
    assert decode_command(0x08, b"\x08").offset_hours == 8  # type: ignore[attr-defined]
    assert decode_command(0x25, b"\x01\x9c\xff").ratio == 10.0  # type: ignore[attr-defined]
    assert decode_command(0x25, b"\x01\x88\x13").fraction == 0.5  # type: ignore[attr-defined]


# --- kept byte for byte ------------------------------------------------------------------------
UNKNOWN_OPCODES = [c for c in range(256) if c not in COMMAND_TYPES]


@given(opcode=st.sampled_from(UNKNOWN_OPCODES), params=st.binary(max_size=40))
def test_unknown_opcode_kept_byte_for_byte(opcode: int, params: bytes) -> None:
    packet = _host_with(opcode, params)
    decoded = decode_host_packet(packet)
    assert decoded.command == UnknownCommand(code=opcode, params=params)
    assert decoded.encode() == packet
    assert decoded.as_dict()["command"]["command"] == f"UNKNOWN_0x{opcode:02X}"


@pytest.mark.parametrize("direction", DECODERS)
@given(header=st.integers(2, 255), data=st.binary(min_size=31, max_size=31))
def test_unknown_sub_frame_kept(direction: str, header: int, data: bytes) -> None:
    decode, _, vec = DECODERS[direction]
    packet = _crc(vec[:37] + bytes([header]) + data + vec[69:-2])
    decoded = decode(packet)
    assert decoded.sub == UnknownSubFrame(header, data)
    assert decoded.encode() == packet
    assert decoded.as_dict()["sub"] == {"header": header, "data_hex": data.hex(" ")}


@pytest.mark.parametrize("direction", DECODERS)
def test_zero_header_with_data_is_kept_and_all_zero_is_none(direction: str) -> None:
    decode, _, vec = DECODERS[direction]
    data = bytes(30) + b"\x01"
    packet = _crc(vec[:37] + b"\x00" + data + vec[69:-2])
    assert decode(packet).sub == UnknownSubFrame(0, data)
    assert decode(packet).encode() == packet
    zero = _crc(vec[:37] + bytes(32) + vec[69:-2])
    assert decode(zero).sub is None
    assert decode(zero).encode() == zero


def test_standard_sub_frame_header_selects_typed_frame() -> None:
    assert isinstance(decode_host_packet(HOST_EXAMPLE).sub, HostSubFrame)
    assert isinstance(decode_gcu_packet(GCU_EXAMPLE).sub, GcuSubFrame)
    # header 0x01 with all-zero data is a (zero) standard sub frame, not "none"
    host = HostPacket(HostMainFrame(), HostSubFrame())
    assert decode_host_packet(host.encode()).sub == HostSubFrame()
    gcu = GcuPacket(GcuMainFrame(), GcuSubFrame(), Feedback(0))
    assert decode_gcu_packet(gcu.encode()).sub == GcuSubFrame()


def test_decode_packet_dispatches_on_header() -> None:
    assert isinstance(decode_packet(HOST_EXAMPLE), HostPacket)
    assert isinstance(decode_packet(GCU_EXAMPLE), GcuPacket)
    with pytest.raises(RemoteProtocolError, match="header"):
        decode_packet(_crc(b"\x12\x34" + HOST_EXAMPLE[2:-2]))
