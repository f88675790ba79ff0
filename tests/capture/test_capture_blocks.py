"""The pcap/pcapng block reader: each kind of structural damage is a CaptureError naming
the record or block, its offset and what is wrong, after the packets before it."""

from __future__ import annotations

import io
import struct

import pytest

from gcu_async.capture import CaptureError
from gcu_async.capture.blocks import MAX_BLOCK, MAX_PACKET, Packet, Source, packets
from gcu_async.capture.synth import udp_packet
from helpers.protocol.vectors import HOST_EXAMPLE

IP = udp_packet(("127.0.0.1", 1), ("127.0.0.2", 2), HOST_EXAMPLE)


def block(kind: int, body: bytes, *, length: int | None = None, end: int | None = None) -> bytes:
    body += b"\0" * (-len(body) % 4)
    size = len(body) + 12
    return (struct.pack("<II", kind, size if length is None else length) + body
            + struct.pack("<I", size if end is None else end))  # fmt: skip


SHB = block(0x0A0D0D0A, struct.pack("<IHHq", 0x1A2B3C4D, 1, 0, -1))
IDB = block(1, struct.pack("<HHI", 101, 0, 0) + struct.pack("<HHB3x", 9, 1, 3) + bytes(4))


def epb(data: bytes, *, iface: int = 0, options: bytes = b"") -> bytes:
    body = struct.pack("<IIIII", iface, 0, 1000, len(data), len(data)) + data
    return block(6, body + b"\0" * (-len(data) % 4) + options)


def read(data: bytes) -> tuple[list[Packet], CaptureError | None]:
    got: list[Packet] = []
    try:
        for packet in packets(Source(io.BytesIO(data))):
            got.append(packet)
    except CaptureError as exc:
        return got, exc
    return got, None


def test_a_sound_pcapng_with_options_and_a_skipped_block() -> None:
    flags = struct.pack("<HHI", 2, 4, 2) + bytes(4)  # epb_flags: outbound; end of options
    data = SHB + IDB + block(5, bytes(20)) + epb(IP, options=flags)
    got, error = read(data)
    assert error is None
    assert got == [Packet(1000 * 1e-3, 101, IP, 2, 0)]  # if_tsresol 3: milliseconds


@pytest.mark.parametrize(("tail", "number", "message"), [
    (block(6, bytes(20), length=13), 4, "block length 13 is not a multiple of 4 of at least 12"),
    (block(6, bytes(20), end=36), 4, "block length 32 at its start but 36 at its end"),
    (epb(IP, iface=3), 4, "refers to interface 3; the section describes 1"),
    (epb(IP, options=struct.pack("<HH", 2, 200)), 4, "option 2 of 200 bytes runs past"),
    (struct.pack("<II", 6, MAX_BLOCK + 4), 4, f"block length {MAX_BLOCK + 4} is more than"),
    (epb(IP)[:-10], 4, "truncated"),
    (struct.pack("<I", 6), 4, "header at offset"),
    (block(6, struct.pack("<IIIII", 0, 0, 0, 999, 999)), 4, "captured length 999 is more"),
    (block(0x0A0D0D0A, struct.pack("<IHHq", 0x11223344, 1, 0, -1)), 4, "byte-order magic"),
])  # fmt: skip
def test_pcapng_damage(tail: bytes, number: int, message: str) -> None:
    data = SHB + IDB + epb(IP) + tail
    got, error = read(data)
    assert len(got) == 1  # the packet before the damage
    assert error is not None and message in str(error), error
    assert error.block == number
    assert error.offset == len(SHB + IDB + epb(IP))
    assert f"block {number} " in str(error) and f"at offset {error.offset}" in str(error)


def pcap_header(major: int = 2) -> bytes:
    return struct.pack("<IHHiIII", 0xA1B2C3D4, major, 4, 0, 0, 65535, 101)


def record(caplen: int, origlen: int, data: bytes = b"") -> bytes:
    return struct.pack("<IIII", 1, 2, caplen, origlen) + data


@pytest.mark.parametrize(("tail", "message"), [
    (record(MAX_PACKET + 1, MAX_PACKET + 1), f"captured length {MAX_PACKET + 1} is more than"),
    (record(0, 0), "original length 0"),
    (record(10, 5, bytes(10)), "captured length 10 is more than the original length 5"),
    (record(10, 10, bytes(4)), "truncated: 26 bytes needed, 20 present"),
    (record(10, 10)[:9], "record 2 header at offset"),
])  # fmt: skip
def test_pcap_damage(tail: bytes, message: str) -> None:
    first = record(len(IP), len(IP), IP)
    got, error = read(pcap_header() + first + tail)
    assert [p.data for p in got] == [IP]
    assert error is not None and message in str(error), error
    assert error.block == 2 and error.offset == 24 + len(first)


def test_not_a_capture_and_a_wrong_version_name_offset_0() -> None:
    for data, message in ((bytes(64), "offset 0: 00 00 00 00"), (pcap_header(3), "version 3.4")):
        got, error = read(data)
        assert not got and error is not None and error.offset == 0 and message in str(error)


def test_a_damaged_capture_is_a_gcu_error_and_a_value_error() -> None:
    """Applications catch the library's errors at one root (docs: the error tree)."""
    from gcu_async.errors import GcuError

    assert issubclass(CaptureError, GcuError) and issubclass(CaptureError, ValueError)
