"""Every autopilot message the bridge reads, with any value its wire type can carry
(NaN, infinities, the integer extremes such as SYSTEM_TIME 2**64-1): the feed never raises
out of the bridge's handler — a value no host field can carry is skipped and logged once
per message type (docs/mavlink-bridge.md, "The autopilot side"). On main 03f36e5 an
OverflowError escaped as a traceback per message."""

from __future__ import annotations

import logging
import math
import struct
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gcu_async.bridge import MavlinkBridge
from gcu_async.bridge._mavlink import mavlink
from gcu_async.client.connect import connect
from helpers.scale import scaled

KINDS = ["ATTITUDE", "GLOBAL_POSITION_INT", "LOCAL_POSITION_NED", "GPS_RAW_INT",
         "SYSTEM_TIME", "HOME_POSITION", "AUTOPILOT_STATE_FOR_GIMBAL_DEVICE"]  # fmt: skip
INTS = {"int8_t": 8, "int16_t": 16, "int32_t": 32, "int64_t": 64}
UINTS = {"uint8_t": 8, "uint16_t": 16, "uint32_t": 32, "uint64_t": 64}


def value(kind: str) -> st.SearchStrategy[Any]:
    if kind in INTS:
        bits = INTS[kind]
        return st.sampled_from([-(2 ** (bits - 1)), 2 ** (bits - 1) - 1, 0, -1, 1]) | st.integers(
            -(2 ** (bits - 1)), 2 ** (bits - 1) - 1)
    if kind in UINTS:
        bits = UINTS[kind]
        return st.sampled_from([0, 2**bits - 1]) | st.integers(0, 2**bits - 1)
    if kind == "float":
        f32 = st.floats(width=32, allow_nan=True, allow_infinity=True)
        return st.sampled_from([math.nan, math.inf, -math.inf, 3.4e38, -3.4e38, 0.0]) | f32
    if kind == "char":
        return st.just(b"")
    raise AssertionError(kind)


@st.composite
def message(draw: st.DrawFn) -> Any:
    name = draw(st.sampled_from(KINDS))
    cls = mavlink.mavlink_map[getattr(mavlink, f"MAVLINK_MSG_ID_{name}")]
    args = []
    lengths = dict(zip(cls.ordered_fieldnames, cls.array_lengths, strict=True))
    for field, ftype in zip(cls.fieldnames, cls.fieldtypes, strict=True):
        length = lengths[field]
        if length:
            args.append([draw(value(ftype)) for _ in range(length)])
        else:
            args.append(draw(value(ftype)))
    msg = cls(*args)
    packer = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    try:
        data = msg.pack(packer)
    except (struct.error, OverflowError):  # not representable on the wire
        return None
    return packer.decode(bytearray(data))  # the values as a link delivers them


@pytest.fixture(scope="module")
def bridge() -> MavlinkBridge:
    client = connect("udp://127.0.0.1:9", local_port=0)
    return MavlinkBridge(client, ["udpout:127.0.0.1:9"], system_id=1)


@settings(max_examples=scaled(200, 25), suppress_health_check=[HealthCheck.function_scoped_fixture],
          deadline=None)  # fmt: skip
@given(msgs=st.lists(message(), min_size=1, max_size=8))
def test_no_autopilot_value_escapes_the_feed(bridge: MavlinkBridge, msgs: list[Any],
                                             caplog: pytest.LogCaptureFixture) -> None:  # fmt: skip
    caplog.set_level(logging.WARNING, logger="gcu_async.bridge")
    for i, msg in enumerate(msgs):
        if msg is not None:
            bridge._aircraft(msg, 100.0 + i)  # raises nothing
    assert not [r for r in caplog.records if r.exc_info]
