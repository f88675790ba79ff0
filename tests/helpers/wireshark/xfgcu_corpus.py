"""Packets of every kind, and captures of them over UDP, TCP and serial with junk and splits.

:func:`corpus` has a packet of every command (with parameters away from their defaults), GCU
replies of every sub frame and feedback kind, odd but valid values (unknown modes and pod
codes, negative distances and time zones, reserved bits, version 1), and anomalous packets
with a valid CRC that decode flags (version 3, wrong parameter lengths, parameters out of
range, extra status bytes, statuses a command never answers), and every command row at the
edges of each parameter's range (:func:`row_packets`). :func:`write_capture` writes
packets through :class:`PacketCapture` as UDP datagrams (some holding several packets,
junk, or a packet whose CRC fails), a TCP connection whose segments cut packets anywhere,
and a serial link read in random chunks.
"""

from __future__ import annotations

import random
import struct
from pathlib import Path

from gcu_async.capture import PacketCapture
from gcu_async.protocol import (
    COMMAND_TYPES,
    GCU_HEADER,
    HOST_HEADER,
    AngleControl,
    AreaTemperature,
    Calibration,
    CameraMask,
    Centre,
    ClickToPan,
    Command,
    DigitalZoom,
    EulerControl,
    Feedback,
    FillLight,
    Focus,
    Fpv,
    GazeAtCoordinates,
    GazeLock,
    GcuMainFrame,
    GcuPacket,
    GcuSubFrame,
    GeoPosition,
    HostMainFrame,
    HostPacket,
    HostSubFrame,
    ImageAutoFlip,
    ImageBox,
    ImagePoint,
    Isotherm,
    NightVision,
    NightVisionMode,
    NullCommand,
    Osd,
    OsdCoordinates,
    OsdCoordinateSource,
    Palette,
    PictureInPicture,
    PointingFollow,
    PointingLock,
    Ranging,
    Record,
    SpotTemperature,
    TakePhoto,
    TargetDetection,
    TemperatureAlarm,
    TimeZone,
    TopDown,
    Track,
    UnknownCommand,
    UnknownSubFrame,
    ZoomIn,
    ZoomOut,
    ZoomStop,
    ZoomTo,
)
from gcu_async.protocol.builder import build
from gcu_async.protocol.catalogue import CATALOGUE
from gcu_async.protocol.fields import WIRE_RANGES
from gcu_async.protocol.host_frame_tables import ControlValues
from gcu_async.wireshark.tables import WireParam, rows
from helpers.protocol.catalogue_samples import required_samples
from helpers.protocol.strategies import seal

HOST, GCU = ("127.0.0.1", 2338), ("127.0.0.1", 2337)
TCP_HOST, TCP_GCU = ("127.0.0.1", 45000), ("127.0.0.1", 2332)
SERIAL = "/dev/ttyGCU0"

COMMANDS: list[Command] = [
    NullCommand(), Calibration(), Centre(), AngleControl(), PointingLock(), PointingFollow(),
    TopDown(), EulerControl(), GazeLock(), Fpv(),
    GazeAtCoordinates(latitude=-33.8688197, longitude=151.2092955, altitude=-12.345),
    Track(True, ImageBox(0.1, 0.2, 0.3, 0.4), CameraMask.CAMERA_1 | CameraMask.CAMERA_3),
    Track(False, ImageBox(0.0, 0.0, 0.0, 0.0)),
    ClickToPan(ImagePoint(0.25, 0.7501), cameras=2),
    OsdCoordinates(OsdCoordinateSource.TARGET), ImageAutoFlip(False), ImageAutoFlip(True),
    TimeZone(-12), TimeZone(14), TakePhoto(), Record(3), ZoomIn(), ZoomOut(2), ZoomStop(),
    ZoomTo(ratio=10.0), ZoomTo(ratio=3276.8, cameras=255), ZoomTo(fraction=0.5, cameras=2),
    ZoomTo(fraction=1e-4), Focus(), Palette(10), Palette(0, cameras=1),
    NightVision(NightVisionMode.AUTO), NightVision(NightVisionMode.OFF, cameras=2),
    AreaTemperature(True, ImageBox(0.5, 0.5, 1.0, 1.0)), AreaTemperature(False),
    TemperatureAlarm(True, high=50.5, low=-10.2), Isotherm(False, high=30.0, low=30.0),
    SpotTemperature(True, ImagePoint(0.5, 0.5)), Osd(False), Osd(True), PictureInPicture(4),
    TargetDetection(True), DigitalZoom(False), FillLight(0), FillLight(255), Ranging(True),
    Ranging(False), UnknownCommand(0x42, b"\x01\x02\xff"), UnknownCommand(0xFE),
]  # fmt: skip
COMMANDS += [build(e, **required_samples(e)).command for e in CATALOGUE
             if e.command not in {type(c) for c in COMMANDS}]  # fmt: skip
"""Above: chosen edge values per command; then one sample of any command added since."""


def host_packets() -> list[bytes]:
    assert {type(c) for c in COMMANDS} >= set(COMMAND_TYPES.values())
    main = HostMainFrame.build(
        control=ControlValues.angles(-12.34, 45.6, 179.99), attitude=(-11.32, 1.01, 240.0),
        acceleration=(1.12, -1.12, 0.01), velocity=(21.12, -21.12, -0.5),
    )  # fmt: skip
    sub = HostSubFrame.build(latitude=38.0300822, longitude=-170.9175332, altitude=-41.123,
                             satellites=19, gnss_week=2278, gnss_ms=352718123,
                             relative_altitude=12.12)  # fmt: skip
    subs: list[HostSubFrame | UnknownSubFrame | None] = [
        sub, None, UnknownSubFrame(0x07, bytes(range(31))), UnknownSubFrame(0x00, b"\x01" * 31)
    ]
    out = []
    for i, command in enumerate(COMMANDS):
        out.append(HostPacket(main, subs[i % len(subs)], command, version=1 + i % 2).encode())
    out.append(HostPacket(HostMainFrame(), HostSubFrame(0, 0, 0, 0, 0, 0, 0)).encode())
    return out


def gcu_packets() -> list[bytes]:
    mains = [
        GcuMainFrame.build(mode=0x12, pod_status=0x8001, miss_distance=(-500, 500),
                           relative_angles=(-8.03, 0.32, 62.18), attitude=(-0.01, 9.33, 62.15),
                           angular_rates=(-0.1, 0.1, -3276.8)),
        GcuMainFrame(0x42, 0xFFFF, 1000, -1000, -18000, 17999, 0, 9000, -18000, 35999, 32767,
                     -32768, 0),
        GcuMainFrame(),
    ]
    subs: list[GcuSubFrame | UnknownSubFrame | None] = [
        GcuSubFrame.build(hardware_version=3.1, firmware_version=5.0, pod_model=41,
                          target_distance=589.4,
                          target_position=GeoPosition(38.0300822, 170.9175332, 41.123),
                          camera1_zoom=29.9, camera2_zoom=2.0, time_zone=8),
        GcuSubFrame(255, 0, 99, 0xFFFF, -1, -1_800_000_000, 900_000_000, -(2**31), 65535, 0,
                    0xFF, 0xFFFF, -128),
        GcuSubFrame(10, 11, 45, 0x6080, 0, 1, -1, 2**31 - 1, 10, 10, 0x12, 0x2813, -5),
        None,
        UnknownSubFrame(0x02, b"\x00" * 30 + b"\x01"),
    ]
    feedbacks = [Feedback(0x20, 0), Feedback(0x00, None), Feedback(0x22, 0x03),
                 Feedback(0x25, 0x00), Feedback(0x01, 0x02), Feedback(0x01, 0x01),
                 Feedback(0x2A, 0x02), Feedback(0x99, 0x07), Feedback(0x81, None)]  # fmt: skip
    out = []
    for i, feedback in enumerate(feedbacks * 2):
        out.append(GcuPacket(mains[i % len(mains)], subs[i % len(subs)], feedback,
                             version=2 if i % 3 else 1).encode())  # fmt: skip
    return out


def anomalous_packets() -> list[bytes]:
    """CRC-valid packets with values V2.0.6 does not expect (each decodes, flagged)."""
    body = bytes(64)
    return [
        seal(HOST_HEADER, body + b"\x00", version=3),
        seal(GCU_HEADER, body + b"\x20\x00", version=0),
        seal(HOST_HEADER, body + b"\x20"),  # TAKE_PHOTO without its camera mask
        seal(HOST_HEADER, body + b"\x20\x01\x02"),  # ... with one byte too many
        seal(HOST_HEADER, body + b"\x20\x00"),  # camera mask 0
        seal(HOST_HEADER, body + b"\x17\x01\x05" + bytes(8)),  # track: enter byte 5
        seal(HOST_HEADER, body + b"\x17\x01\x01" + (5000).to_bytes(2, "little") * 2 + bytes(4)),
        seal(HOST_HEADER, body + b"\x25\x01\x00\x00"),  # zoom-to value 0
        seal(HOST_HEADER, body + b"\x25\x01" + (10001).to_bytes(2, "little")),
        seal(HOST_HEADER, body + b"\x08\x0f"),  # time zone +15
        seal(HOST_HEADER, body + b"\x06\x02"),  # OSD coordinates 2
        seal(HOST_HEADER, body + b"\x2b\x01\x03"),  # night vision mode 3
        seal(HOST_HEADER, body + b"\x2a\x02\x0b"),  # palette 11
        seal(HOST_HEADER, body + b"\x74\x05"),  # picture-in-picture 5
        seal(HOST_HEADER, body + b"\x81\x01"),  # ranging on is 0x02
        seal(HOST_HEADER, body + b"\x31\x02\x01" + (10).to_bytes(2, "little", signed=True)
             + (20).to_bytes(2, "little", signed=True)),  # alarm: low > high
        seal(HOST_HEADER, body + b"\x1a\x01" + (10001).to_bytes(2, "little") + bytes(2)),
        seal(HOST_HEADER, body + b"\x15" + (1_800_000_001).to_bytes(4, "little") + bytes(8)),
        seal(HOST_HEADER, body + b"\x15" + bytes(4) + (-900_000_001).to_bytes(4, "little",
                                                                          signed=True) + bytes(4)),
        seal(GCU_HEADER, body + b"\x20\x00\x00"),  # two execution-status bytes
        seal(GCU_HEADER, body + b"\x20\x05\x01\x7f", version=9),  # three, a status 5, version 9
        seal(GCU_HEADER, body + b"\x2a\x01"),  # palette fails with 0x02, not 0x01
        seal(GCU_HEADER, body + b"\x01\x03"),  # calibration: 0x00, 0x01, 0x02
        seal(HOST_HEADER, body + b"\x2b\x00\x07"),  # night vision: mask 0 and mode 7
        seal(HOST_HEADER, body + b"\x07\x02"),  # image auto-flip byte 2
        seal(HOST_HEADER, body + b"\x30\x00\x03" + (10001).to_bytes(2, "little") * 2
             + bytes(4)),  # area temperature: every box check
        seal(GCU_HEADER, _frame_fields(body, {3: (2000, 2, True), 17: (36000, 2, False)})
             + b"\x00"),  # miss distance x 2000, camera yaw 360.00°
        seal(HOST_HEADER, _frame_fields(body, {6: (0x07, 1, False), 9: (9500, 2, True),
                                               32: (1, 1, False), 46: (604_800_000, 4, False)})
             + b"\x00"),  # reserved flag bit, aircraft pitch 95°, a GNSS ms past the week
    ]  # fmt: skip


def _frame_fields(body: bytes, fields: dict[int, tuple[int, int, bool]]) -> bytes:
    """``body`` (bytes 5–68) with little-endian values written at body offsets (wire offset
    less 5): {offset: (value, size, signed)}."""
    out = bytearray(body)
    for offset, (value, size, signed) in fields.items():
        out[offset : offset + size] = value.to_bytes(size, "little", signed=signed)
    return bytes(out)


def corrupt(packet: bytes, rng: random.Random) -> bytes:
    """``packet`` with one bit flipped after the length (so its CRC fails)."""
    data = bytearray(packet)
    data[rng.randrange(5, len(data))] ^= 1 << rng.randrange(8)
    return bytes(data)


def junk(rng: random.Random) -> bytes:
    """Bytes that are no packet: random, and sometimes a false header with a length."""
    size = rng.randrange(1, 40)
    data = bytearray(rng.randbytes(size))
    if rng.random() < 0.5 and size >= 4:
        data[0:2] = rng.choice((HOST_HEADER, GCU_HEADER))
        data[2:4] = rng.randrange(60, 300).to_bytes(2, "little")
    return bytes(data)


def row_packets() -> list[bytes]:
    """Every command row (:func:`gcu_async.wireshark.tables.rows`) with each parameter in
    turn at the ends of its range and one step past them (where its wire type has room),
    the others at the bottom of theirs, and with one parameter byte too few: so that a
    command added to the protocol is in the corpus without an entry here."""
    body = bytes(64)
    out = []
    for row in rows():
        layout = struct.Struct("<" + "".join(p.fmt for p in row.params))
        ranges = [_raw_range(p) for p in row.params]
        base = [low for low, _ in ranges]
        for i, p in enumerate(row.params):
            wire_low, wire_high = WIRE_RANGES[p.fmt]
            low, high = ranges[i]
            for raw in sorted({low - 1, low, high, high + 1}):
                if wire_low <= raw <= wire_high:
                    raws = list(base)
                    raws[i] = raw
                    out.append(seal(HOST_HEADER, body + bytes([row.opcode]) + layout.pack(*raws)))
        if row.params:
            out.append(seal(HOST_HEADER, body + bytes([row.opcode])
                            + layout.pack(*base)[:-1]))  # fmt: skip
    return out


def _raw_range(p: WireParam) -> tuple[int, int]:
    wire_low, wire_high = WIRE_RANGES[p.fmt]
    return (wire_low if p.low is None else p.low, wire_high if p.high is None else p.high)


def corpus() -> list[bytes]:
    return host_packets() + gcu_packets() + anomalous_packets() + row_packets()


def _chunks(data: bytes, rng: random.Random) -> list[bytes]:
    out, pos = [], 0
    while pos < len(data):
        n = rng.choice((1, 2, 5, 30, 71, 72, 73, 100, 200, 500))
        out.append(data[pos : pos + n])
        pos += n
    return out


# Every stream ends with more than 256 bytes of packets and no junk: a false header near the
# end of a TCP or serial stream waits for bytes that never come (the dissector cannot know
# the stream ended, decode can), a documented limit of any stream dissector.


def stream_of(packets: list[bytes], rng: random.Random, junk_rate: float) -> bytes:
    if junk_rate < 1.0:  # a stream: junk only before a clean tail of more than 256 bytes
        tail = 0
        while tail < len(packets) and sum(map(len, packets[len(packets) - tail :])) <= 256:
            tail += 1
        if sum(map(len, packets[len(packets) - tail :])) <= 256:
            return b"".join(packets)  # too short for junk
        head = packets[: len(packets) - tail]
        return _mixed(head, rng, junk_rate) + b"".join(packets[len(head) :])
    return _mixed(packets, rng, junk_rate)


def _mixed(packets: list[bytes], rng: random.Random, junk_rate: float) -> bytes:
    parts: list[bytes] = []
    for packet in packets:
        if rng.random() < junk_rate:
            parts.append(junk(rng))
        if rng.random() < junk_rate / 2:
            parts.append(corrupt(packet, rng))
        parts.append(packet)
    return b"".join(parts)


def write_capture(path: Path, packets: list[bytes], *, seed: int = 1, junk_rate: float = 0.2,
                  links: tuple[str, ...] = ("udp", "tcp", "serial")) -> None:  # fmt: skip
    """``packets`` over each of ``links``, host packets from the host's side, GCU packets
    from the GCU's; junk, CRC-failed copies and cuts at random (seeded)."""
    rng = random.Random(seed)
    capture = PacketCapture(path)
    capture.acquire()
    try:
        host = [p for p in packets if p[:2] == HOST_HEADER]
        gcu = [p for p in packets if p[:2] == GCU_HEADER]
        if "udp" in links:
            for packet in packets:
                src, dst = (HOST, GCU) if packet[:2] == HOST_HEADER else (GCU, HOST)
                roll = rng.random()
                if roll < junk_rate:
                    datagram = _mixed([packet, packet], rng, 1.0)
                elif roll < 2 * junk_rate:
                    datagram = packet + packet[: rng.randrange(1, len(packet))]  # a cut copy
                else:
                    datagram = packet
                capture.udp(src, dst, datagram)
        if "tcp" in links:
            capture.tcp_open(TCP_HOST, TCP_GCU)
            up = _chunks(stream_of(host, rng, junk_rate), rng)
            down = _chunks(stream_of(gcu, rng, junk_rate), rng)
            while up or down:
                if up and (not down or rng.random() < 0.5):
                    capture.tcp(TCP_HOST, TCP_GCU, up.pop(0))
                else:
                    capture.tcp(TCP_GCU, TCP_HOST, down.pop(0))
            capture.tcp_close(TCP_HOST, TCP_GCU)
        if "serial" in links:
            for chunk in _chunks(stream_of(host, rng, junk_rate), rng):
                capture.serial(SERIAL, chunk, outbound=True)
            for chunk in _chunks(stream_of(gcu, rng, junk_rate), rng):
                capture.serial(SERIAL, chunk, outbound=False)
    finally:
        capture.release()
