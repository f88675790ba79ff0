"""Hypothesis strategies for every frame, command and packet of the protocol core.

Values are drawn on the wire grid (raw integers in range, or units = raw / scale), so
decode(encode(x)) == x must hold exactly. ``COMMAND_STRATEGIES`` is made from the command
schema: one entry per class in ``COMMAND_TYPES``, with nothing to add for a new command.
"""

from __future__ import annotations

from typing import Any

import crcmod.predefined
from hypothesis import strategies as st

from gcu_async.protocol import (
    COMMAND_TYPES,
    AnomalousCommand,
    CameraMask,
    Command,
    Feedback,
    GcuMainFrame,
    GcuPacket,
    GcuSubFrame,
    HostMainFrame,
    HostPacket,
    HostSubFrame,
    ImageBox,
    ImagePoint,
    UnknownCommand,
    UnknownSubFrame,
    decode_command,
)

MS_PER_WEEK = 604_800_000
S16 = st.integers(-(2**15), 2**15 - 1)
S32 = st.integers(-(2**31), 2**31 - 1)
U8 = st.integers(0, 0xFF)
U16 = st.integers(0, 0xFFFF)
VERSIONS = st.sampled_from([1, 2])

_xmodem = crcmod.predefined.mkCrcFun("xmodem")
S16_RANGE, S32_RANGE = (-(2**15), 2**15 - 1), (-(2**31), 2**31 - 1)

# The wire range of every raw frame field, as validate() must enforce it.
RAW_RANGES: dict[type[Any], dict[str, tuple[int, int]]] = {
    HostMainFrame: {
        "control_roll_raw": (-18000, 18000),
        "control_pitch_raw": (-18000, 18000),
        "control_yaw_raw": (-18000, 18000),
        "flags_raw": (0, 0xFFFF),
        "aircraft_roll_raw": (-18000, 17999),
        "aircraft_pitch_raw": (-9000, 9000),
        "aircraft_yaw_raw": (0, 35999),
        "accel_north_raw": S16_RANGE,
        "accel_east_raw": S16_RANGE,
        "accel_up_raw": S16_RANGE,
        "vel_north_raw": S16_RANGE,
        "vel_east_raw": S16_RANGE,
        "vel_up_raw": S16_RANGE,
        "subframe_request": (0, 255),
    },
    HostSubFrame: {
        "longitude_raw": (-1_800_000_000, 1_800_000_000),
        "latitude_raw": (-900_000_000, 900_000_000),
        "altitude_raw": S32_RANGE,
        "satellites": (0, 255),
        "gnss_ms": (0, 604_799_999),
        "gnss_week": (0, 32767),
        "relative_altitude_raw": S32_RANGE,
    },
    GcuMainFrame: {
        "mode_raw": (0, 255),
        "pod_status_raw": (0, 0xFFFF),
        "miss_x": (-1000, 1000),
        "miss_y": (-1000, 1000),
        "relative_x_raw": (-18000, 17999),
        "relative_y_raw": (-18000, 17999),
        "relative_z_raw": (-18000, 17999),
        "roll_raw": (-9000, 9000),
        "pitch_raw": (-18000, 17999),
        "yaw_raw": (0, 35999),
        "rate_x_raw": S16_RANGE,
        "rate_y_raw": S16_RANGE,
        "rate_z_raw": S16_RANGE,
    },
    GcuSubFrame: {
        "hardware_version_raw": (0, 255),
        "firmware_version_raw": (0, 255),
        "pod_code": (0, 255),
        "fault_raw": (0, 0xFFFF),
        "target_distance_raw": S32_RANGE,
        "target_longitude_raw": S32_RANGE,
        "target_latitude_raw": S32_RANGE,
        "target_altitude_raw": S32_RANGE,
        "camera1_zoom_raw": (0, 0xFFFF),
        "camera2_zoom_raw": (0, 0xFFFF),
        "thermal_flags_raw": (0, 255),
        "camera_flags_raw": (0, 0xFFFF),
        "time_zone": (-128, 127),
    },
}
"""Every raw frame field's allowed range (inclusive): what ``validate()`` / ``encode()``
enforce (``flags_raw`` also has reserved bits)."""


def seal(header: bytes, body: bytes, version: int = 2) -> bytes:
    """A packet assembled by hand (independently of the library's encoder): header, LE
    length, version, ``body`` (bytes 5..S-3), CRC-16/XMODEM high byte first."""
    n = 5 + len(body) + 2
    head = header + n.to_bytes(2, "little") + bytes([version]) + body
    return head + _xmodem(head).to_bytes(2, "big")


# --- frames ---------------------------------------------------------------------------
host_main_frames = st.builds(
    HostMainFrame,
    control_roll_raw=st.integers(-18000, 18000),
    control_pitch_raw=st.integers(-18000, 18000),
    control_yaw_raw=st.integers(-18000, 18000),
    flags_raw=st.sampled_from([0, 1, 4, 5]),
    aircraft_roll_raw=st.integers(-18000, 17999),
    aircraft_pitch_raw=st.integers(-9000, 9000),
    aircraft_yaw_raw=st.integers(0, 35999),
    accel_north_raw=S16,
    accel_east_raw=S16,
    accel_up_raw=S16,
    vel_north_raw=S16,
    vel_east_raw=S16,
    vel_up_raw=S16,
    subframe_request=U8,
)
host_sub_frames = st.builds(
    HostSubFrame,
    longitude_raw=st.integers(-1_800_000_000, 1_800_000_000),
    latitude_raw=st.integers(-900_000_000, 900_000_000),
    altitude_raw=S32,
    satellites=U8,
    gnss_ms=st.integers(0, MS_PER_WEEK - 1),
    gnss_week=st.integers(0, 32767),
    relative_altitude_raw=S32,
)
gcu_main_frames = st.builds(
    GcuMainFrame,
    mode_raw=U8,
    pod_status_raw=U16,
    miss_x=st.integers(-1000, 1000),
    miss_y=st.integers(-1000, 1000),
    relative_x_raw=st.integers(-18000, 17999),
    relative_y_raw=st.integers(-18000, 17999),
    relative_z_raw=st.integers(-18000, 17999),
    roll_raw=st.integers(-9000, 9000),
    pitch_raw=st.integers(-18000, 17999),
    yaw_raw=st.integers(0, 35999),
    rate_x_raw=S16,
    rate_y_raw=S16,
    rate_z_raw=S16,
)
gcu_sub_frames = st.builds(
    GcuSubFrame,
    hardware_version_raw=U8,
    firmware_version_raw=U8,
    pod_code=U8,
    fault_raw=U16,
    target_distance_raw=S32,
    target_longitude_raw=S32,
    target_latitude_raw=S32,
    target_altitude_raw=S32,
    camera1_zoom_raw=U16,
    camera2_zoom_raw=U16,
    thermal_flags_raw=U8,
    camera_flags_raw=U16,
    time_zone=st.integers(-128, 127),
)
unknown_sub_frames = st.builds(
    UnknownSubFrame,
    header=U8.filter(lambda h: h != 0x01),
    data=st.binary(min_size=31, max_size=31),
).filter(lambda s: s.header != 0 or any(s.data))
"""Sub frames V2.0.6 does not define: header ≠ 0x01, and not all zero (that is "none")."""

host_subs = st.one_of(st.none(), host_sub_frames, unknown_sub_frames)
gcu_subs = st.one_of(st.none(), gcu_sub_frames, unknown_sub_frames)

# --- commands ---------------------------------------------------------------------------
masks = st.integers(1, 0xFF).map(CameraMask)
fractions = st.integers(0, 10000).map(lambda raw: raw / 10000)
points = st.builds(ImagePoint, fractions, fractions)


@st.composite
def boxes(draw: st.DrawFn) -> ImageBox:
    x0, x1 = sorted((draw(st.integers(0, 10000)), draw(st.integers(0, 10000))))
    y0, y1 = sorted((draw(st.integers(0, 10000)), draw(st.integers(0, 10000))))
    return ImageBox(x0 / 10000, y0 / 10000, x1 / 10000, y1 / 10000)


def _from_schema(cls: type[Command]) -> st.SearchStrategy[Command]:
    """Every command the schema allows: each wire field drawn in its raw range, decoded, kept
    unless a rule across fields (box edges, thresholds, the zoom value's gap, a switch's
    unused byte) rejects it."""
    fields = st.tuples(*(st.integers(w.raw_low, w.raw_high) for w in cls.SCHEMA.wire))
    return (fields.map(lambda raw: decode_command(int(cls.OPCODE), cls.LAYOUT.pack(*raw)))
            .filter(lambda c: not isinstance(c, AnomalousCommand)))  # fmt: skip


COMMAND_STRATEGIES: dict[type[Command], st.SearchStrategy[Command]] = {
    **{cls: _from_schema(cls) for cls in COMMAND_TYPES.values()},
    UnknownCommand: st.builds(
        UnknownCommand,
        code=U8.filter(lambda c: c not in COMMAND_TYPES),
        # up to 184 parameter bytes keeps S within Deframer(header)'s default 256
        params=st.binary(max_size=184),
    ),
}
"""One strategy per command class, made from the command schema."""

commands = st.one_of(*COMMAND_STRATEGIES.values())
feedbacks = st.one_of(
    st.builds(Feedback, opcode=U8, status=st.one_of(st.none(), U8), extra_status=st.just(b"")),
    # more status bytes than V2.0.6 defines (kept, flagged): GCU_MAX_LENGTH allows 15 more
    st.builds(Feedback, opcode=U8, status=U8, extra_status=st.binary(min_size=1, max_size=15)),
)

host_packets = st.builds(
    HostPacket, main=host_main_frames, sub=host_subs, command=commands, version=VERSIONS
)
gcu_packets = st.builds(
    GcuPacket, main=gcu_main_frames, sub=gcu_subs, feedback=feedbacks, version=VERSIONS
)
