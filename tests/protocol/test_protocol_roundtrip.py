"""decode(encode(x)) == x for every frame, every command and whole packets of both
directions (versions 1 and 2), with values on the wire grid; build() from units agrees with
the raw fields and the unit properties."""

from __future__ import annotations

import dataclasses
import sys

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcu_async.protocol import (
    COMMAND_TYPES,
    AnomalousCommand,
    Command,
    ControlValues,
    GcuMainFrame,
    GcuPacket,
    GcuSubFrame,
    GeoPosition,
    HostMainFrame,
    HostPacket,
    HostSubFrame,
    NullCommand,
    Opcode,
    PodStatus,
    UnknownCommand,
    UnknownSubFrame,
    command_code,
    decode_command,
    decode_gcu_packet,
    decode_host_packet,
    decode_packet,
)
from gcu_async.protocol.catalogue import CATALOGUE
from gcu_async.protocol.gcu_frame_tables import GCU_SUB_SCHEMA
from helpers.protocol.strategies import (
    COMMAND_STRATEGIES,
    VERSIONS,
    commands,
    feedbacks,
    gcu_main_frames,
    gcu_packets,
    gcu_sub_frames,
    gcu_subs,
    host_main_frames,
    host_packets,
    host_sub_frames,
    host_subs,
    unknown_sub_frames,
)

ALL_COMMAND_CLASSES = [*dict.fromkeys(e.command for e in CATALOGUE), NullCommand, UnknownCommand]
"""The command classes of the catalogue (a command a method sends: a new catalogue entry
without a strategy fails below), the null command (sent by the session) and unknown ones."""


def _subclasses(cls: type) -> set[type]:
    out = set()
    for sub in cls.__subclasses__():
        out.add(sub)
        out |= _subclasses(sub)
    return out


# --- completeness guards: a new command cannot be silently untested ----------------------
def test_every_command_class_has_a_strategy() -> None:
    missing = [cls.__name__ for cls in ALL_COMMAND_CLASSES if cls not in COMMAND_STRATEGIES]
    assert not missing, f"no Hypothesis strategy for {missing}"


def test_command_types_cover_every_opcode_and_every_public_command_class() -> None:
    assert set(COMMAND_TYPES) == {int(op) for op in Opcode}
    assert set(COMMAND_TYPES.values()) | {UnknownCommand} == set(ALL_COMMAND_CLASSES)
    for code, cls in COMMAND_TYPES.items():
        assert int(cls.OPCODE) == code
    # dataclass(slots=True) leaves the pre-slots class behind: keep the module-level ones
    concrete = {
        c
        for c in _subclasses(Command)
        if not c.__name__.startswith("_")
        and getattr(sys.modules[c.__module__], c.__name__, None) is c
    }
    # AnomalousCommand is decode-only (it never encodes): tests/protocol/test_protocol_liberal.py
    assert concrete == {*ALL_COMMAND_CLASSES, AnomalousCommand}


# --- commands ------------------------------------------------------------------------------
@pytest.mark.parametrize("cls", ALL_COMMAND_CLASSES, ids=lambda c: c.__name__)
@given(data=st.data())
def test_command_roundtrip_in_host_packet(cls: type[Command], data: st.DataObject) -> None:
    command = data.draw(COMMAND_STRATEGIES[cls])
    assert type(command) is cls
    params = command.encode_params()
    assert decode_command(command_code(command), params) == command
    packet = HostPacket(
        data.draw(host_main_frames), data.draw(host_subs), command, data.draw(VERSIONS)
    )
    wire = packet.encode()
    assert len(wire) == 72 + len(params)
    assert wire[69] == command_code(command)
    assert wire[70:-2] == params
    decoded = decode_host_packet(wire)
    assert type(decoded.command) is cls
    assert decoded == packet
    assert decoded.encode() == wire


@given(command=commands)
def test_command_as_dict_names_opcode_and_raw_params(command: Command) -> None:
    d = command.as_dict()
    assert d["opcode"] == command_code(command)
    if isinstance(command, UnknownCommand):
        assert d["command"] == f"UNKNOWN_0x{command.code:02X}"
        assert bytes.fromhex(d["params_hex"]) == command.params
    else:
        assert d["command"] == command.OPCODE.name
        assert bytes.fromhex(d["params_hex"]) == command.encode_params()
        assert tuple(d["params_raw"]) == command.raw_params()
        assert set(d["params"]) == {f.name for f in dataclasses.fields(command)}


# --- frames in whole packets -----------------------------------------------------------------
@given(main=host_main_frames, sub=host_subs, version=VERSIONS)
def test_host_frames_roundtrip(main: HostMainFrame, sub: object, version: int) -> None:
    packet = HostPacket(main, sub, version=version)  # type: ignore[arg-type]
    wire = packet.encode()
    assert wire[:2] == b"\xa8\xe5"
    assert wire[4] == version
    assert decode_host_packet(wire) == packet
    assert decode_packet(wire) == packet


@given(main=gcu_main_frames, sub=gcu_subs, feedback=feedbacks, version=VERSIONS)
def test_gcu_frames_roundtrip(
    main: GcuMainFrame, sub: object, feedback: object, version: int
) -> None:
    packet = GcuPacket(main, sub, feedback, version)  # type: ignore[arg-type]
    wire = packet.encode()
    assert wire[:2] == b"\x8a\x5e"
    status = packet.feedback.status
    assert len(wire) == (72 if status is None else 73 + len(packet.feedback.extra_status))
    assert decode_gcu_packet(wire) == packet
    assert decode_packet(wire) == packet


@pytest.mark.parametrize("direction", ["host", "gcu"])
@given(sub=unknown_sub_frames)
def test_unknown_sub_frame_roundtrip_both_directions(direction: str, sub: UnknownSubFrame) -> None:
    packet: HostPacket | GcuPacket
    packet = (
        HostPacket(HostMainFrame(), sub) if direction == "host" else GcuPacket(GcuMainFrame(), sub)
    )
    wire = packet.encode()
    assert wire[37] == sub.header
    assert wire[38:69] == sub.data
    assert decode_packet(wire).sub == sub


@pytest.mark.parametrize(
    "packet", [HostPacket(HostMainFrame()), GcuPacket(GcuMainFrame())], ids=["host", "gcu"]
)
def test_none_sub_frame_is_all_zero(packet: HostPacket | GcuPacket) -> None:
    wire = packet.encode()
    assert wire[37:69] == bytes(32)
    assert decode_packet(wire).sub is None


@given(packet=st.one_of(host_packets, gcu_packets))
def test_whole_packets_roundtrip(packet: HostPacket | GcuPacket) -> None:
    wire = packet.encode()
    assert int.from_bytes(wire[2:4], "little") == len(wire)
    decoded = decode_packet(wire)
    assert decoded == packet
    assert decoded.encode() == wire
    assert decoded.as_dict()["version"] == packet.version


# --- build() from units agrees with the raw fields ---------------------------------------------
@given(frame=host_main_frames.map(lambda f: f._replace(flags_raw=5)))
def test_host_main_build_from_units(frame: HostMainFrame) -> None:
    built = HostMainFrame.build(
        control=ControlValues.angles(*frame.control.as_angles()),
        attitude=frame.aircraft_attitude,
        acceleration=frame.acceleration,
        velocity=frame.velocity,
        subframe_request=frame.subframe_request,
    )
    assert built == frame


def test_host_main_build_invalid_parts_clear_flags() -> None:
    frame = HostMainFrame.build()
    assert frame.flags_raw == 0
    assert not frame.control_valid
    assert not frame.ins_valid
    assert frame.subframe_request == 1
    assert frame == HostMainFrame(subframe_request=1)
    rates = HostMainFrame.build(control=ControlValues.rates(1.0, -2.5, 150.0, zoom=1.0))
    assert rates.flags_raw == 4
    assert rates.control == ControlValues(10, -25, 1500)
    assert ControlValues.rates(0, 1.0, 0, zoom=10.0) == ControlValues(0, 100, 0)
    assert ControlValues(0, 100, 0).as_rates(zoom=10.0) == (0.0, 1.0, 0.0)


@given(frame=host_sub_frames)
def test_host_sub_build_from_units(frame: HostSubFrame) -> None:
    built = HostSubFrame.build(
        latitude=frame.latitude,
        longitude=frame.longitude,
        altitude=frame.altitude,
        satellites=frame.satellites,
        gnss_week=frame.gnss_week,
        gnss_ms=frame.gnss_ms,
        relative_altitude=frame.relative_altitude,
    )
    assert built == frame


@given(frame=gcu_main_frames)
def test_gcu_main_build_from_units(frame: GcuMainFrame) -> None:
    built = GcuMainFrame.build(
        mode=frame.mode_raw,
        pod_status=frame.pod_status_raw,
        miss_distance=(frame.miss_x, frame.miss_y),
        relative_angles=frame.relative_angles,
        attitude=frame.attitude,
        angular_rates=frame.angular_rates,
    )
    assert built == frame


@given(
    frame=gcu_sub_frames.map(
        lambda f: f._replace(target_distance_raw=max(f.target_distance_raw, 0)) if
        f.target_distance_raw > 0 else f._replace(target_distance_raw=0, target_latitude_raw=0,
                                                  target_longitude_raw=0, target_altitude_raw=0)
    )
)
def test_gcu_sub_build_from_units(frame: GcuSubFrame) -> None:
    special = {
        "pod_model": frame.pod_code,
        "faults": frame.fault_raw,
        "target_distance": frame.target_distance,
        "target_position": frame.target_position,
        "camera_flags": frame.camera_flags_raw & ~0x07,
        "pip_mode": frame.pip_mode,
    }
    done = {"pod_code", "fault_raw", "camera_flags_raw"}
    # every other field is the build keyword x of x_raw, in units (raw / scale)
    plain = {f.name.removesuffix("_raw"): getattr(frame, f.name) / f.scale if f.scale != 1
             else getattr(frame, f.name) for f in GCU_SUB_SCHEMA.fields
             if f.name not in done and not f.name.startswith("target_")}  # fmt: skip
    built = GcuSubFrame.build(**special, **plain)
    assert built == frame
    assert frame.camera_flags | frame.pip_mode == frame.camera_flags_raw


def test_gcu_sub_target_distance_not_positive_means_no_measurement() -> None:
    for raw in (0, -10, -(2**31)):
        no_measurement = GcuSubFrame(target_distance_raw=raw, target_latitude_raw=5)
        assert no_measurement.target_distance is None
        assert no_measurement.target_position is None
        shown = no_measurement.as_dict()
        assert shown["target_position"] is None and shown["target_distance_m"] is None
        assert shown["target_position_raw"] == [5, 0, 0]
    assert GcuSubFrame(target_distance_raw=1).target_distance == 0.1
    assert GcuSubFrame(target_distance_raw=1).target_position == (0.0, 0.0, 0.0)
    assert GcuSubFrame.build(target_distance=None).target_distance_raw == 0
    ranged = GcuSubFrame.build(target_distance=5.0, target_position=GeoPosition(1.5, -2.5, 3.0))
    assert ranged.target_position == (1.5, -2.5, 3.0)
    with pytest.raises(ValueError, match="target_position: a ranged position needs"):
        GcuSubFrame.build(target_position=GeoPosition(1.5, -2.5, 3.0))


def test_gcu_main_miss_distance_only_while_tracking() -> None:
    """The miss distances are valid only while a target is tracked (pod status B0)."""
    lost = GcuMainFrame(miss_x=-5, miss_y=7)
    assert lost.miss_distance is None and lost.as_dict()["miss_distance"] is None
    assert lost.as_dict()["miss_distance_raw"] == [-5, 7]
    tracked = lost._replace(pod_status_raw=PodStatus.TRACKING_OK)
    assert tracked.miss_distance == (-5, 7) and tracked.as_dict()["miss_distance"] == [-5, 7]
