"""The camera yaw (GCU bytes 22–23) as a heading: every raw value, the Z-1Pro's signed
encoding, the reading each out-of-range value gets (docs/protocol-notes.md, "What real pods
do")."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcu_async.errors import FieldRangeError
from gcu_async.protocol import GcuMainFrame, GcuPacket, decode_gcu_packet
from gcu_async.protocol.gcu_frame_tables import CAMERA_YAW
from gcu_async.protocol.headings import PAST_TURN_DETAIL, SIGNED_DETAIL, HeadingRule, Reading
from gcu_async.protocol.host_frame_tables import AIRCRAFT_YAW
from gcu_async.protocol.packets import GCU_HEADER
from gcu_async.protocol.units import wrap_degrees_180
from helpers.protocol.strategies import seal
from helpers.protocol.z1pro import MOVE_AGREEMENT_DEG, MOVES, YAW_BANDS, main_frame, reply
from helpers.scale import FULL


def expected_heading(raw: int) -> float:
    """The rule, written out by range (the module derives it from the field)."""
    if raw < 36000:
        return raw / 100
    if raw >= 47536:
        return ((raw - 65536) % 36000) / 100
    return (raw - 36000) / 100


EDGES = {0, 17999, 18000, 35999, 36000, 47535, 47536, 0xFFFF}
RAWS = range(0x10000) if FULL else sorted({*range(0, 0x10000, 13), *EDGES})
"""Every raw value at full size; a thirteenth of them and every band's edges at reduced size."""


def test_every_raw_yaw_reads_as_a_heading_in_0_360_and_keeps_its_raw_value() -> None:
    for raw in RAWS:
        frame = GcuMainFrame(yaw_raw=raw)
        yaw = frame.attitude.yaw
        assert 0.0 <= yaw < 360.0, raw
        assert yaw == expected_heading(raw), raw
        assert frame.yaw_raw == raw
        assert frame.as_dict()["attitude_deg"]["yaw"] == yaw
        assert frame.as_dict()["attitude_raw"][2] == raw
        details = [a.detail for a in frame.anomalies]
        if raw < 36000:
            assert details == [], raw
        else:
            assert details == [SIGNED_DETAIL if raw >= 47536 else PAST_TURN_DETAIL], raw


@pytest.mark.parametrize(("raw", "reading"), [
    (0, Reading.U16), (17999, Reading.U16), (18000, Reading.U16), (35999, Reading.U16),
    (36000, Reading.PAST_TURN), (47535, Reading.PAST_TURN),
    (47536, Reading.SIGNED), (65535, Reading.SIGNED),
])  # fmt: skip
def test_the_reading_of_each_band(raw: int, reading: Reading) -> None:
    assert CAMERA_YAW.reading(raw) is reading
    assert AIRCRAFT_YAW.reading(raw) is reading  # one rule for both headings


def test_a_heading_field_is_a_u16_from_zero() -> None:
    from gcu_async.protocol.fields import WireField

    with pytest.raises(ValueError, match="a heading is a U16 field from 0"):
        HeadingRule(WireField("yaw", "h", "", -18000, 18000))


@given(st.floats(-1e6, 1e6, allow_nan=False))
def test_a_signed_pod_sends_every_heading_signed(degrees: float) -> None:
    """What the simulator's z1pro-6.7 firmware sends: never in 18000 … 47535, and read back
    as the same heading (to the field's 0.01°)."""
    raw = CAMERA_YAW.signed_raw(degrees)
    assert 0 <= raw < 18000 or 47536 <= raw <= 65535
    back = CAMERA_YAW.degrees(raw)
    assert abs(wrap_degrees_180(back - degrees)) <= 0.005 + 1e-9 * abs(degrees)


def test_the_z1pro_heading_follows_its_relative_yaw() -> None:
    """Every logged move: the heading changes as the relative yaw does (the U16 reading
    is 53–72° off for 10 of them: the pod sends a signed S16)."""
    off_as_u16 = 0
    for rel0, yaw0, rel1, yaw1 in MOVES:
        before, after = main_frame(rel0, yaw0), main_frame(rel1, yaw1)
        turned = wrap_degrees_180(after.relative_angles.z - before.relative_angles.z)
        heading = wrap_degrees_180(after.attitude.yaw - before.attitude.yaw)
        assert abs(wrap_degrees_180(heading - turned)) <= MOVE_AGREEMENT_DEG
        assert 0.0 <= after.attitude.yaw < 360.0
        as_u16 = wrap_degrees_180(yaw1 / 100 - yaw0 / 100)
        off_as_u16 += abs(wrap_degrees_180(as_u16 - turned)) > 50
    assert off_as_u16 == 10


def test_z1pro_replies_decode_with_their_raw_yaw_and_a_flag() -> None:
    for low, high in YAW_BANDS:
        for raw in (low, high):
            packet = decode_gcu_packet(reply(0, raw))
            assert packet.main.yaw_raw == raw
            assert packet.main.attitude.yaw == expected_heading(raw)
            assert [a.field for a in packet.anomalies] == (["yaw_raw"] if raw >= 36000 else [])


def test_the_send_side_stays_strict() -> None:
    frame = GcuMainFrame(yaw_raw=51552)
    with pytest.raises(FieldRangeError, match=r"yaw_raw: 51552 .*\(read as a signed S16"):
        GcuPacket(frame).encode()
    with pytest.raises(FieldRangeError, match="camera yaw"):
        GcuMainFrame.build(attitude=(0.0, 0.0, 360.0))
    # a firmware that sends the signed yaw: only that field, only inside its wire type
    wire = GcuPacket(frame).encode(deviations={"yaw_raw"})
    body = wire[5:-2]
    assert wire == seal(GCU_HEADER, body)
    with pytest.raises(FieldRangeError, match="miss_x"):
        GcuPacket(frame._replace(miss_x=5000)).encode(deviations={"yaw_raw"})
    with pytest.raises(FieldRangeError, match=r"yaw_raw: 70000 .*\[0, 65535\]"):
        GcuPacket(frame._replace(yaw_raw=70000)).encode(deviations={"yaw_raw"})
    with pytest.raises(ValueError, match="name no main-frame field"):
        GcuPacket(frame).encode(deviations={"heading"})
