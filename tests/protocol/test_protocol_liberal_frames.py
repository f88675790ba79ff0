"""Liberal receive of frame fields (docs/client.md, "Liberal receive, strict send").

A CRC-valid packet whose main or sub frame holds a value outside the range V2.0.6 gives it
(a miss distance of 2000, a camera yaw of 360°, an aircraft pitch of 95°, a reserved flag bit,
a GNSS millisecond past the week) decodes with the raw value kept and one anomaly per field,
in wire order; the strict side (``validate()``, ``encode()``) raises the same error for the
same value. The oracle is the independent range table of ``helpers.protocol.strategies``.
"""

from __future__ import annotations

import subprocess
import sys
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcu_async.errors import FieldRangeError
from gcu_async.protocol import (
    GCU_HEADER,
    HOST_HEADER,
    GcuMainFrame,
    GcuPacket,
    GcuSubFrame,
    HostSubFrame,
    decode_gcu_packet,
    decode_host_packet,
    decode_packet,
)
from gcu_async.protocol.headings import PAST_TURN_DETAIL
from helpers.protocol.strategies import RAW_RANGES, seal

HOST_FLAG_BITS = 0x05
"""Byte 11's defined bits (control valid, INS valid): the rest are reserved."""


def expected(frame: tuple[Any, ...]) -> list[tuple[str, int]]:
    """(field, value) of each field of ``frame`` the oracle's table does not allow."""
    ranges = RAW_RANGES[type(frame)]
    found = []
    for field, value in zip(type(frame)._fields, frame, strict=True):  # type: ignore[attr-defined]
        low, high = ranges[field]
        if not low <= value <= high or (field == "flags_raw" and value & ~HOST_FLAG_BITS):
            found.append((field, value))
    return found


def strict_error(frame: Any) -> str | None:
    try:
        frame.validate()
    except FieldRangeError as exc:
        return str(exc)
    return None


bodies = st.binary(min_size=64, max_size=64).map(lambda b: b[:32] + b"\x01" + b[33:])
"""Bytes 5–68 of any packet with a standard sub frame: every field any wire value."""


@pytest.mark.parametrize("header", [HOST_HEADER, GCU_HEADER], ids=["host", "gcu"])
@given(body=bodies, opcode=st.sampled_from([0x00, 0x20]))
def test_any_frame_value_decodes_kept_and_flagged_as_the_send_side_refuses_it(
    header: bytes, body: bytes, opcode: int
) -> None:
    """Either direction, a null command or "take photo" (a parameter, or a status byte)."""
    tail = bytes([opcode]) + (b"\x01" if opcode else b"")
    packet = decode_packet(seal(header, body + tail))
    frames = (packet.main, packet.sub)
    assert isinstance(packet.sub, (HostSubFrame, GcuSubFrame))
    flagged = [found for frame in frames for found in expected(frame)]
    assert [(a.field, a.value) for a in packet.anomalies] == flagged
    for frame in frames:  # the GCU sub frame has no range narrower than its wire types
        anomalies = getattr(frame, "anomalies", ())
        assert strict_error(frame) == (str(anomalies[0]) if anomalies else None)


def test_the_issue_style_examples_keep_their_values() -> None:
    gcu = GcuPacket(GcuMainFrame()).encode()
    raw = bytearray(gcu)
    raw[8:10] = (2000).to_bytes(2, "little", signed=True)  # miss distance x
    raw[22:24] = (36000).to_bytes(2, "little")  # camera yaw 360.00°
    packet = decode_gcu_packet(seal(GCU_HEADER, bytes(raw[5:-2])))
    # the raw value stays; the heading wraps (neither U16 nor S16 explains it)
    assert packet.main.miss_x == 2000 and packet.main.yaw_raw == 36000
    assert packet.main.attitude.yaw == 0.0
    assert [str(a) for a in packet.anomalies] == [
        "miss_x: 2000 is outside the allowed range [-1000, 1000]",
        f"yaw_raw: 36000 is outside the allowed range [0, 35999] 0.01 deg ({PAST_TURN_DETAIL})",
    ]
    host = bytearray(64 + 1)
    host[14 - 5 : 16 - 5] = (9500).to_bytes(2, "little", signed=True)  # aircraft pitch 95°
    host[11 - 5] = 0x07  # control valid, INS valid and reserved bit 1
    packet2 = decode_host_packet(seal(HOST_HEADER, bytes(host)))
    assert packet2.main.aircraft_attitude.pitch == 95.0
    assert [str(a) for a in packet2.anomalies] == [
        "flags_raw: 7 is outside the allowed range [0, 5] (reserved bits 0x2 must be zero)",
        "aircraft_pitch_raw: 9500 is outside the allowed range [-9000, 9000] 0.01 deg",
    ]


@pytest.mark.subprocess  # a fresh interpreter (tests/helpers/tiers.py)
def test_decode_shows_frame_anomalies_and_exits_0() -> None:
    raw = bytearray(GcuPacket(GcuMainFrame()).encode())
    raw[10:12] = (-1001).to_bytes(2, "little", signed=True)  # miss distance y
    wire = seal(GCU_HEADER, bytes(raw[5:-2]))
    proc = subprocess.run(
        [sys.executable, "-c", "import sys; from gcu_async.cli import main; sys.exit(main())",
         "decode", wire.hex()],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.splitlines() == [
        "gcu-async decode: packet 1 (gcu_to_host): flagged: miss_y: -1001 is outside the "
        "allowed range [-1000, 1000]"
    ]
