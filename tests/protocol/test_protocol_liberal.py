"""Liberal receive, strict send (docs/client.md, "Liberal receive, strict send").

Receive: a CRC-valid packet of either direction always decodes; a value V2.0.6 does not expect
is kept raw and flagged (``anomalies``); only too few bytes, a bad header, length or CRC raise
:class:`RemoteProtocolError`, whose ``reason`` says which. The simulator answers every CRC-valid
host packet and still takes its aircraft data. Send: an out-of-range value raises
:class:`FieldRangeError` naming the field, and a decoded anomalous command never goes back on the
wire.
"""

from __future__ import annotations

import logging
from typing import Any

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from gcu_async.errors import FieldRangeError, ProtocolErrorReason, RemoteProtocolError
from gcu_async.protocol import (
    COMMAND_TYPES,
    GCU_HEADER,
    HOST_HEADER,
    AnomalousCommand,
    Anomaly,
    CameraMask,
    ClickToPan,
    Command,
    ExecutionStatus,
    Feedback,
    GcuPacket,
    HostMainFrame,
    HostPacket,
    ImageBox,
    NullCommand,
    Opcode,
    TakePhoto,
    TemperatureAlarm,
    TimeZone,
    Track,
    UnknownCommand,
    ZoomTo,
    decode_command,
    decode_gcu_packet,
    decode_host_packet,
)
from gcu_async.protocol.command_fields import Cameras, Integer
from gcu_async.protocol.deframer import GCU_MAX_LENGTH, HOST_MAX_LENGTH
from gcu_async.session.session import Session
from gcu_async.sim import ManualClock, SimulatorModel
from gcu_async.sim.aircraft import aircraft_yaw
from gcu_async.sim.tolerance import tolerated
from helpers.protocol.strategies import seal
from helpers.protocol.vectors import GCU_EXAMPLE, HOST_EXAMPLE

MAIN_AND_SUB = HOST_EXAMPLE[5:69]
"""Bytes 5–68 of the document's host example: INS valid, a sub frame."""


def host_packet(opcode: int, params: bytes, *, version: int = 2,
                body: bytes = MAIN_AND_SUB) -> bytes:  # fmt: skip
    return seal(HOST_HEADER, body + bytes([opcode]) + params, version)


def flagged(anomalies: tuple[Anomaly, ...]) -> list[tuple[str, int, int, int]]:
    return [(a.field, a.value, a.low, a.high) for a in anomalies]


# --- out-of-range parameters, each decoded, kept and flagged -------------------------------
OUT_OF_RANGE: list[tuple[str, int, bytes, list[tuple[str, int, int, int]]]] = [
    # issue 9's cases
    ("time zone +15", 0x08, b"\x0f", [("offset_hours", 15, -12, 14)]),
    ("temperature alarm off, low > high", 0x31,
     b"\x02\x00" + (100).to_bytes(2, "little") + (200).to_bytes(2, "little"),
     [("low", 200, -32768, 100)]),
    ("exit tracking with an inverted box", 0x17,
     b"\x01\x00" + b"".join(v.to_bytes(2, "little") for v in (6000, 7000, 2000, 3000)),
     [("box.right", 2000, 6000, 10000), ("box.bottom", 3000, 7000, 10000)]),
    ("camera mask 0", 0x20, b"\x00", [("cameras", 0, 1, 255)]),
    # every other kind of range: signed, flags, boxes, points, zoom, enums, coordinates
    ("time zone -13", 0x08, b"\xf3", [("offset_hours", -13, -12, 14)]),
    ("OSD coordinates 2", 0x06, b"\x02", [("coordinates", 2, 0, 1)]),
    ("image auto-flip 2", 0x07, b"\x02", [("enabled", 2, 0, 1)]),
    ("track enter 2", 0x17, b"\x01\x02" + bytes(8), [("enter", 2, 0, 1)]),
    ("enter tracking with an inverted box", 0x17,
     b"\x01\x01" + (5000).to_bytes(2, "little") * 2 + bytes(4),
     [("box.right", 0, 5000, 10000), ("box.bottom", 0, 5000, 10000)]),
    ("track box beyond 10000", 0x17, b"\x01\x01" + bytes(4) + (10001).to_bytes(2, "little") * 2,
     [("box.right", 10001, 0, 10000), ("box.bottom", 10001, 0, 10000)]),
    ("click-to-pan x 10001", 0x1A, b"\x01" + (10001).to_bytes(2, "little") + bytes(2),
     [("point.x", 10001, 0, 10000)]),
    ("zoom to 0", 0x25, b"\x01\x00\x00", [("raw_value", 0, -32768, 10000)]),
    ("zoom to ratio -9", 0x25, b"\x01" + (-9).to_bytes(2, "little", signed=True),
     [("raw_value", -9, -32768, 10000)]),
    ("zoom beyond 10000, no camera", 0x25, b"\x00" + (10001).to_bytes(2, "little"),
     [("cameras", 0, 1, 255), ("raw_value", 10001, -32768, 10000)]),
    ("palette 11", 0x2A, b"\x02\x0b", [("palette", 11, 0, 10)]),
    ("night vision 3", 0x2B, b"\x01\x03", [("mode", 3, 0, 2)]),
    ("temperature alarm on, low > high", 0x31,
     b"\x02\x01" + (10).to_bytes(2, "little") + (20).to_bytes(2, "little"),
     [("low", 20, -32768, 10)]),
    ("isotherm enabled 5", 0x32, b"\x02\x05" + bytes(4), [("enabled", 5, 0, 1)]),
    ("spot temperature x 20000", 0x33, b"\x02\x01" + (20000).to_bytes(2, "little") + bytes(2),
     [("point.x", 20000, 0, 10000)]),
    ("OSD 2", 0x73, b"\x02", [("enabled", 2, 0, 1)]),
    ("picture-in-picture 5", 0x74, b"\x05", [("mode", 5, 0, 4)]),
    ("ranging 1", 0x81, b"\x01", [("enabled", 1, 0, 2)]),  # only 0x00 or 0x02
    ("gaze beyond 180 E and 90 S", 0x15,
     (1_800_000_001).to_bytes(4, "little") + (-900_000_001).to_bytes(4, "little", signed=True)
     + bytes(4), [("longitude", 1_800_000_001, -1_800_000_000, 1_800_000_000),
                  ("latitude", -900_000_001, -900_000_000, 900_000_000)]),
]  # fmt: skip
"""A host command with parameters out of range, and every field it flags (all of them, not
only the first), raw value and raw range."""


@pytest.mark.parametrize(("case", "opcode", "params", "expected"), OUT_OF_RANGE,
                         ids=[c[0] for c in OUT_OF_RANGE])  # fmt: skip
def test_out_of_range_parameters_decode_raw_kept_and_flagged(
    case: str, opcode: int, params: bytes, expected: list[tuple[str, int, int, int]]
) -> None:
    wire = host_packet(opcode, params)
    packet = decode_host_packet(wire)
    command = decode_command(opcode, params)
    assert packet.command == command
    assert isinstance(command, AnomalousCommand)
    assert (command.code, command.opcode, command.params) == (opcode, Opcode(opcode), params)
    assert command.command_type is COMMAND_TYPES[opcode]
    assert command.raw == COMMAND_TYPES[opcode].LAYOUT.unpack(params)
    assert flagged(command.anomalies) == expected
    assert packet.anomalies == command.anomalies
    assert packet.main == decode_host_packet(HOST_EXAMPLE).main  # the rest decodes as usual
    as_dict = packet.as_dict()
    assert as_dict["command"]["params_hex"] == params.hex(" ")
    assert [a["field"] for a in as_dict["anomalies"]] == [e[0] for e in expected]


def test_two_status_bytes_decode_kept_and_flagged() -> None:
    wire = seal(GCU_HEADER, GCU_EXAMPLE[5:70] + b"\x00\x05")  # TAKE_PHOTO, status 00 then 05
    packet = decode_gcu_packet(wire)
    assert packet.feedback == Feedback(0x20, 0x00, b"\x05")
    assert packet.feedback.result is ExecutionStatus.SUCCESS  # byte 70 is the status
    assert flagged(packet.anomalies) == [("status length", 2, 1, 1)]
    assert packet.as_dict()["feedback"]["extra_status_hex"] == "05"
    assert packet.encode() == wire


def test_extra_status_bytes_are_checked_when_encoding() -> None:
    main = decode_gcu_packet(GCU_EXAMPLE).main
    with pytest.raises(TypeError, match="extra_status"):
        GcuPacket(main, None, Feedback(0x20, 0, "05")).encode()  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="needs a status byte"):
        GcuPacket(main, None, Feedback(0x20, None, b"\x05")).encode()


@pytest.mark.parametrize(
    ("opcode", "status", "expected"),
    [
        (0x20, 0x05, [("status", 5, 0, 1)]),  # photo: 0x00 / 0x01 only
        (0x2A, 0x01, [("status", 1, 0, 2)]),  # palette fails with 0x02
        (0x01, 0x03, [("status", 3, 0, 2)]),  # calibration: 0x00, 0x01, 0x02
        (0x01, 0x02, []),
        (0x25, 0x80, []),  # zoom: any camera mask
        (0x2A, 0x02, []),
        (0x20, 0x01, []),
        (0x99, 0x07, []),  # an opcode V2.0.6 does not define: nothing to compare with
    ],
)
def test_status_a_command_never_answers_is_flagged(
    opcode: int, status: int, expected: list[tuple[str, int, int, int]]
) -> None:
    packet = decode_gcu_packet(seal(GCU_HEADER, GCU_EXAMPLE[5:69] + bytes([opcode, status])))
    assert packet.feedback.status == status
    assert flagged(packet.anomalies) == expected


def test_ordinary_packets_have_no_anomalies() -> None:
    assert decode_host_packet(HOST_EXAMPLE).anomalies == ()
    assert decode_gcu_packet(GCU_EXAMPLE).anomalies == ()
    assert "anomalies" not in decode_gcu_packet(GCU_EXAMPLE).as_dict()


# --- send stays strict ---------------------------------------------------------------------
def test_issue_cases_cannot_be_built() -> None:
    """Building each issue-9 value raises FieldRangeError naming the field."""
    cases: list[tuple[Any, str]] = [
        (lambda: TimeZone(15), "offset_hours"),
        (lambda: TemperatureAlarm(enabled=False, high=10.0, low=20.0), "low"),
        (lambda: Track(enter=False, box=ImageBox(0.6, 0.7, 0.2, 0.3)), "box.right"),
        (lambda: TakePhoto(cameras=0), "cameras"),
    ]
    for build, field in cases:
        with pytest.raises(FieldRangeError) as info:
            build()
        assert info.value.field == field


@pytest.mark.parametrize(("opcode", "params", "expected"), [c[1:] for c in OUT_OF_RANGE],
                         ids=[c[0] for c in OUT_OF_RANGE])  # fmt: skip
def test_decoded_anomalous_command_is_never_re_encoded(
    opcode: int, params: bytes, expected: list[tuple[str, int, int, int]]
) -> None:
    """Re-encoding raises the FieldRangeError of the first anomaly — the packet, the command,
    and the client's session all refuse it."""
    packet = decode_host_packet(host_packet(opcode, params))
    field, value, low, high = expected[0]
    for attempt in (packet.encode, packet.command.encode_params, packet.command.raw_params):
        with pytest.raises(FieldRangeError) as info:
            attempt()
        assert (info.value.field, info.value.value, info.value.low, info.value.high) == (
            field, value, low, high)  # fmt: skip
    session = Session()
    with pytest.raises(FieldRangeError) as info:
        session.submit(packet.command, 0.0)
    assert info.value.field == field


def test_anomalous_command_checks_what_it_is_given() -> None:
    anomaly = Anomaly("offset_hours", 15, -12, 14, "h")
    with pytest.raises(ValueError, match="UnknownCommand"):
        AnomalousCommand(0x42, b"\x0f", (anomaly,))
    with pytest.raises(ValueError, match="at least one"):
        AnomalousCommand(0x08, b"\x0f", ())
    with pytest.raises(TypeError):
        AnomalousCommand(0x08, "0f", (anomaly,))  # type: ignore[arg-type]
    assert str(anomaly) == "offset_hours: 15 is outside the allowed range [-12, 14] h"


REQUIRED_SAMPLES: dict[type[Command], dict[str, Any]] = {ClickToPan: {"point": (0.5, 0.5)},
                                                 ZoomTo: {"ratio": 2.0}}  # fmt: skip
INTEGER_FIELDS = [
    (cls, w.name, w.raw_low, w.raw_high)
    for cls in COMMAND_TYPES.values()
    for kind in cls.SCHEMA.params if isinstance(kind, (Cameras, Integer))
    for w in kind.wire
]  # fmt: skip
"""Every integer parameter of every command, with its range (from the command schema)."""


def test_the_integer_fields_include_the_known_ones() -> None:
    found = {(cls.__name__, name): (low, high) for cls, name, low, high in INTEGER_FIELDS}
    assert found[("TimeZone", "offset_hours")] == (-12, 14)
    assert found[("Palette", "palette")] == (0, 10)
    assert found[("PictureInPicture", "mode")] == (0, 4)
    assert found[("TakePhoto", "cameras")] == (1, 255)


@given(build=st.sampled_from(INTEGER_FIELDS), value=st.integers(), data=st.data())
def test_send_side_any_out_of_range_value_raises_naming_the_field(
    build: tuple[type[Command], str, int, int], value: int, data: st.DataObject
) -> None:
    cls, field, low, high = build
    assume(not low <= value <= high)
    kwargs: dict[str, Any] = {**REQUIRED_SAMPLES.get(cls, {}), field: value}
    with pytest.raises(FieldRangeError) as info:
        cls(**kwargs)
    assert (info.value.field, info.value.value, info.value.low, info.value.high) == (
        field, value, low, high)  # fmt: skip


# --- decode: strict acceptance and the anomalies agree, for every command ----------------------
PARAM_TYPES = [cls for cls in COMMAND_TYPES.values() if cls.LAYOUT.size]


@pytest.mark.parametrize("cls", PARAM_TYPES, ids=lambda c: c.__name__)
@given(data=st.data())
def test_a_command_decodes_typed_exactly_when_nothing_is_flagged(
    cls: type[Command], data: st.DataObject
) -> None:
    """Random parameter bytes: typed (and re-encoding to the very bytes) when no field is out
    of range, an AnomalousCommand listing the fields otherwise, never an exception."""
    params = data.draw(st.binary(min_size=cls.LAYOUT.size, max_size=cls.LAYOUT.size))
    anomalies = cls.raw_anomalies(cls.LAYOUT.unpack(params))
    command = decode_command(int(cls.OPCODE), params)
    if anomalies:
        assert command == AnomalousCommand(int(cls.OPCODE), params, anomalies)
    else:
        assert type(command) is cls
        assert command.encode_params() == params


# --- any CRC-valid packet decodes and is answered; anything else has its reason ----------------
host_bodies = st.binary(min_size=64, max_size=64)
versions = st.integers(0, 255)


@st.composite
def any_host_packet(draw: st.DrawFn) -> bytes:
    opcode = draw(st.one_of(st.sampled_from(sorted(COMMAND_TYPES)), st.integers(0, 255)))
    size = COMMAND_TYPES[opcode].LAYOUT.size if opcode in COMMAND_TYPES else 0
    params = draw(st.one_of(st.binary(min_size=size, max_size=size),
                            st.binary(max_size=HOST_MAX_LENGTH - 72)))  # fmt: skip
    body = draw(st.one_of(host_bodies, st.just(MAIN_AND_SUB)))
    return host_packet(opcode, params, version=draw(versions), body=body)


@st.composite
def any_gcu_packet(draw: st.DrawFn) -> bytes:
    body = draw(st.one_of(host_bodies, st.just(GCU_EXAMPLE[5:69])))
    status = draw(st.binary(max_size=GCU_MAX_LENGTH - 72))
    return seal(GCU_HEADER, body + bytes([draw(st.integers(0, 255))]) + status, draw(versions))


@settings(suppress_health_check=[HealthCheck.too_slow])
@given(wire=any_host_packet())
def test_any_crc_valid_host_packet_decodes_and_the_simulator_answers(wire: bytes) -> None:
    packet = decode_host_packet(wire)
    assert packet.version == wire[4]
    assert packet.as_dict()["direction"] == "host_to_gcu"
    model = SimulatorModel(clock=ManualClock())
    [reply] = model.receive(wire)
    feedback = decode_gcu_packet(reply).feedback
    assert feedback.opcode == wire[69]
    assert model.stats.answered == 1
    if isinstance(packet.command, AnomalousCommand):
        assert model.stats.anomalous == 1
        if tolerated(packet.command) is not None:  # run anyway: docs/protocol-notes.md §14
            assert model.stats.tolerated == 1
            assert model.executions[wire[69]] == 1
        else:
            # not executed: its failure status; a null command with parameter bytes is
            # still the separator, answered without a status
            want = ExecutionStatus.NONE if wire[69] == 0 else ExecutionStatus.FAILED
            assert feedback.result is want
    aircraft = model.state.aircraft
    assert aircraft.packets == 1  # the aircraft data were taken
    if packet.main.ins_valid:  # yaw as the simulator reads it (protocol-notes §15)
        main = packet.main
        assert aircraft.attitude == (main.aircraft_roll_raw / 100, main.aircraft_pitch_raw / 100,
                                     aircraft_yaw(main.aircraft_yaw_raw))
    assert model.stats.other_versions == (wire[4] not in (1, 2))


@given(wire=any_gcu_packet())
def test_any_crc_valid_gcu_packet_decodes_and_the_session_takes_it(wire: bytes) -> None:
    packet = decode_gcu_packet(wire)
    assert packet.version == wire[4]
    assert packet.feedback.opcode == wire[69]
    assert packet.feedback.status == (wire[70] if len(wire) > 72 else None)
    assert packet.feedback.extra_status == wire[71:-2]
    packet.as_dict()
    session = Session()
    session.open(0.0)
    session.receive(wire, 0.01, datagram=True)
    health = session.link_health(0.01)
    assert (health.up, health.packets_received) == (True, 1)
    assert health.other_versions == (wire[4] not in (1, 2))


@given(wire=st.one_of(any_host_packet(), any_gcu_packet()), data=st.data())
def test_a_broken_envelope_is_rejected_with_its_reason(wire: bytes, data: st.DataObject) -> None:
    decode = decode_gcu_packet if wire[:2] == GCU_HEADER else decode_host_packet
    damage = data.draw(st.sampled_from(list(ProtocolErrorReason)))
    bad = bytearray(wire)
    if damage is ProtocolErrorReason.SHORT:
        bad = bad[: data.draw(st.integers(0, 71))]
    elif damage is ProtocolErrorReason.HEADER:
        bad[data.draw(st.integers(0, 1))] ^= data.draw(st.integers(1, 255))
    elif damage is ProtocolErrorReason.LENGTH:
        length = data.draw(st.integers(0, 0xFFFF).filter(lambda n: n != len(wire)))
        bad[2:4] = length.to_bytes(2, "little")
    else:
        i = data.draw(st.integers(0, len(wire) - 1).filter(lambda i: i not in (2, 3)))
        bad[i] ^= data.draw(st.integers(1, 255))
        assume(bytes(bad[:2]) == wire[:2])
    with pytest.raises(RemoteProtocolError) as info:
        decode(bytes(bad))
    assert info.value.reason is damage


def test_simulator_warns_once_about_other_versions(caplog: pytest.LogCaptureFixture) -> None:
    model = SimulatorModel(clock=ManualClock())
    with caplog.at_level(logging.WARNING, logger="gcu_async.sim"):
        for version in (3, 3, 7):
            assert len(model.receive(host_packet(0x00, b"", version=version))) == 1
    assert model.stats.other_versions == 3
    warnings = [r for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 1
    assert "version 3" in warnings[0].getMessage()


def test_session_counts_and_warns_once_about_other_versions(
    caplog: pytest.LogCaptureFixture,
) -> None:
    session = Session(name="pod")
    session.open(0.0)
    reply = GcuPacket(decode_gcu_packet(GCU_EXAMPLE).main, None, Feedback(0), 9).encode()
    with caplog.at_level(logging.WARNING, logger="gcu_async.session"):
        session.receive(reply, 0.01, datagram=True)  # the one-datagram fast path
        session.receive(reply[:30], 0.02)  # the deframer's path
        session.receive(reply[30:], 0.02)
    health = session.link_health(0.02)
    assert (health.packets_received, health.other_versions) == (2, 2)
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 1
    assert warnings[0].startswith("pod: reply of protocol version 9")


def test_the_simulator_answers_anomalous_commands_with_failure_status() -> None:
    """Each family's failure status (docs/protocol-notes.md §2 "Execution status per
    command"): 0x01, 0x02 for thermal, the named cameras for zoom (camera 1 for none)."""
    model = SimulatorModel(clock=ManualClock())
    cases = [
        (host_packet(0x08, b"\x0f"), 0x01),  # time zone +15
        (host_packet(0x2A, b"\x02\x0b"), 0x02),  # palette 11
        (host_packet(0x25, b"\x03\x00\x00"), 0x03),  # zoom to 0 with cameras 1 and 2
        (host_packet(0x22, b"\x00"), 0x01),  # zoom in with no camera: camera 1 failed
        (host_packet(0x20, b"\x01\x01"), 0x01),  # photo with two parameter bytes
    ]
    for wire, status in cases:
        assert len(model.receive(host_packet(0x00, b""))) == 1  # a null between commands
        [reply] = model.receive(wire)
        assert decode_gcu_packet(reply).feedback == Feedback(wire[69], status)
    assert model.stats.anomalous == len(cases)
    assert model.executions[0x08] == 1  # acted upon (by failing), like any command


def test_unknown_and_null_commands_are_not_anomalous() -> None:
    assert decode_command(0x42, b"\x01\x02") == UnknownCommand(0x42, b"\x01\x02")
    assert decode_command(0x00, b"") == NullCommand()
    assert CameraMask(decode_command(0x20, b"\x03").cameras) == 3  # type: ignore[attr-defined]
    main = HostMainFrame()
    assert HostPacket(main, None, decode_command(0x20, b"\x03")).anomalies == ()
