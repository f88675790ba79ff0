"""CRC-16/XMODEM: equal to crcmod's ``xmodem`` and to the document's nibble-table C function
on arbitrary bytes, and sent high byte first."""

from __future__ import annotations

import crcmod.predefined
import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcu_async.protocol import GcuPacket, HostPacket, crc16_xmodem
from helpers.protocol.strategies import gcu_packets, host_packets
from helpers.protocol.vectors import GCU_EXAMPLE, HOST_EXAMPLE

xmodem = crcmod.predefined.mkCrcFun("xmodem")

_CRC_TA = (
    0x0000,
    0x1021,
    0x2042,
    0x3063,
    0x4084,
    0x50A5,
    0x60C6,
    0x70E7,
    0x8108,
    0x9129,
    0xA14A,
    0xB16B,
    0xC18C,
    0xD1AD,
    0xE1CE,
    0xF1EF,
)


def document_crc(data: bytes) -> int:
    """Line-by-line port of the document's ``CalculateCrc16`` (nibble table)."""
    crc = 0
    for byte in data:
        da = crc >> 12
        crc = (crc << 4) & 0xFFFF
        crc ^= _CRC_TA[da ^ (byte >> 4)]
        da = crc >> 12
        crc = (crc << 4) & 0xFFFF
        crc ^= _CRC_TA[da ^ (byte & 0x0F)]
    return crc


def test_check_value() -> None:
    # the catalogue check value of CRC-16/XMODEM
    assert crc16_xmodem(b"123456789") == 0x31C3
    assert crc16_xmodem(b"") == 0


@given(st.binary(max_size=512))
def test_crc_equals_crcmod_xmodem_and_document_function(data: bytes) -> None:
    assert crc16_xmodem(data) == xmodem(data) == document_crc(data)


@given(st.binary(max_size=128))
def test_crc_accepts_bytearray_and_memoryview(data: bytes) -> None:
    assert crc16_xmodem(bytearray(data)) == crc16_xmodem(memoryview(data)) == xmodem(data)


@pytest.mark.parametrize(
    ("vector", "crc"), [(HOST_EXAMPLE, 0x5D1B), (GCU_EXAMPLE, 0xEC85)], ids=["host", "gcu"]
)
def test_vector_crc_high_byte_first(vector: bytes, crc: int) -> None:
    assert crc16_xmodem(vector[:-2]) == crc
    assert vector[-2:] == crc.to_bytes(2, "big")


@given(st.one_of(host_packets, gcu_packets))
def test_encoded_crc_is_xmodem_high_byte_first(packet: HostPacket | GcuPacket) -> None:
    wire = packet.encode()
    assert wire[-2:] == xmodem(wire[:-2]).to_bytes(2, "big")
