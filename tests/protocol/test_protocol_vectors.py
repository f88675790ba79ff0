"""The corrected vendor examples (Appendix 1 host packet, Appendix 2 GCU packet; tests/data)
decode to the values docs/protocol-notes.md ("Errata") lists, re-encode byte for byte, and the
Appendix 1 packet can be built from the document's physical values."""

from __future__ import annotations

from datetime import datetime, timedelta, timezone

import pytest

from gcu_async.protocol import (
    ControlValues,
    ExecutionStatus,
    Feedback,
    GcuMainFrame,
    GcuPacket,
    GcuSubFrame,
    GeoPosition,
    HostFlags,
    HostMainFrame,
    HostPacket,
    HostSubFrame,
    Mode,
    NullCommand,
    Opcode,
    PodModel,
    PodStatus,
    decode_gcu_packet,
    decode_host_packet,
    decode_packet,
    pod_name,
)
from helpers.protocol.vectors import GCU_EXAMPLE, HOST_EXAMPLE


def test_vector_files_have_declared_lengths() -> None:
    assert len(HOST_EXAMPLE) == 72 == int.from_bytes(HOST_EXAMPLE[2:4], "little")
    assert len(GCU_EXAMPLE) == 73 == int.from_bytes(GCU_EXAMPLE[2:4], "little")


# --- Appendix 2: GCU → host ------------------------------------------------------------
def test_gcu_example_envelope_and_main_frame() -> None:
    p = decode_gcu_packet(GCU_EXAMPLE)
    assert p.version == 2
    m = p.main
    assert m.mode_raw == 0x12
    assert m.mode is Mode.POINTING_FOLLOW
    # bytes 6–7 "01 80" read little-endian: 0x8001 = TRACKING_OK + reserved bit 15
    assert m.pod_status_raw == 0x8001
    assert PodStatus.TRACKING_OK in m.pod_status
    assert m.tracking_ok
    assert m.pod_status_raw & 0x8000
    assert PodStatus.RANGING_ON not in m.pod_status
    assert PodStatus.RANGE_VALID not in m.pod_status
    assert (m.miss_x, m.miss_y) == (-500, 500)
    assert (m.relative_x_raw, m.relative_y_raw, m.relative_z_raw) == (-803, 32, 6218)
    assert m.relative_angles == (-8.03, 0.32, 62.18)
    assert (m.roll_raw, m.pitch_raw, m.yaw_raw) == (-1, 933, 6215)
    assert m.attitude == (-0.01, 9.33, 62.15)
    assert (m.rate_x_raw, m.rate_y_raw, m.rate_z_raw) == (-1, 1, -2)
    assert m.angular_rates == (-0.1, 0.1, -0.2)


def test_gcu_example_sub_frame() -> None:
    s = decode_gcu_packet(GCU_EXAMPLE).sub
    assert GCU_EXAMPLE[37] == 0x01
    assert isinstance(s, GcuSubFrame)
    assert (s.hardware_version_raw, s.hardware_version) == (0x1F, 3.1)
    assert (s.firmware_version_raw, s.firmware_version) == (0x32, 5.0)
    assert s.pod_code == 41
    assert s.pod_model is PodModel.D_90AI
    assert pod_name(s.pod_code) == "D-90AI"
    assert s.fault_raw == 0
    assert not s.faults
    assert (s.target_distance_raw, s.target_distance) == (5894, 589.4)
    assert (s.target_longitude_raw, s.target_latitude_raw) == (1709175332, 380300822)
    assert s.target_position == GeoPosition(38.0300822, 170.9175332, 41.123)
    assert s.target_altitude_raw == 41123
    assert (s.camera1_zoom_raw, s.camera1_zoom) == (299, 29.9)
    assert (s.camera2_zoom_raw, s.camera2_zoom) == (20, 2.0)
    assert s.thermal_flags_raw == 0
    assert s.camera_flags_raw == 0
    assert s.pip_mode == 0
    assert s.time_zone == 8


def test_gcu_example_feedback() -> None:
    fb = decode_gcu_packet(GCU_EXAMPLE).feedback
    assert fb == Feedback(0x20, 0x00)
    assert fb.opcode == Opcode.TAKE_PHOTO
    assert fb.command == "TAKE_PHOTO"
    assert fb.result is ExecutionStatus.SUCCESS
    assert fb.succeeded


# --- Appendix 1: host → GCU ------------------------------------------------------------
def test_host_example_main_frame() -> None:
    p = decode_host_packet(HOST_EXAMPLE)
    assert p.version == 2
    m = p.main
    assert m.control == ControlValues(0, 100, -100)
    assert m.flags_raw == 0x05
    assert m.flags == HostFlags.CONTROL_VALID | HostFlags.INS_VALID
    assert m.control_valid
    assert m.ins_valid
    assert (m.aircraft_roll_raw, m.aircraft_pitch_raw, m.aircraft_yaw_raw) == (-1132, 101, 24000)
    assert m.aircraft_attitude == (-11.32, 1.01, 240.0)
    assert (m.accel_north_raw, m.accel_east_raw, m.accel_up_raw) == (112, -112, 112)
    assert m.acceleration == (1.12, -1.12, 1.12)
    assert (m.vel_north_raw, m.vel_east_raw, m.vel_up_raw) == (2112, -2112, 2112)
    assert m.velocity == (21.12, -21.12, 21.12)
    assert m.subframe_request == 1


def test_host_example_sub_frame_and_command() -> None:
    p = decode_host_packet(HOST_EXAMPLE)
    s = p.sub
    assert isinstance(s, HostSubFrame)
    assert s.longitude_raw == 1709175332
    assert s.latitude_raw == 380300822
    assert s.altitude_raw == 41123
    assert s.position == GeoPosition(38.0300822, 170.9175332, 41.123)
    assert s.satellites == 19
    assert s.gnss_ms == 352718000
    assert s.gnss_week == 2278
    assert s.relative_altitude_raw == 12120
    assert s.relative_altitude == 12.12
    # the document pairs this week + ms with UTC by its own rule (no leap seconds)
    example_utc = datetime(2023, 9, 7, 1, 58, 38, tzinfo=timezone.utc)
    assert s.gnss_time(apply_leap_seconds=False) == example_utc
    assert s.gnss_time() == example_utc - timedelta(seconds=18)  # GPS time: 18 s in 2023
    assert p.command == NullCommand()
    assert HOST_EXAMPLE[69] == 0x00


@pytest.mark.parametrize("vector", [HOST_EXAMPLE, GCU_EXAMPLE], ids=["host", "gcu"])
def test_vectors_reencode_byte_for_byte(vector: bytes) -> None:
    assert decode_packet(vector).encode() == vector


def test_host_example_built_from_document_physical_values() -> None:
    main = HostMainFrame.build(
        control=ControlValues.angles(0.0, 1.0, -1.0),
        attitude=(-11.3213, 1.01, 240.0),
        acceleration=(1.123, -1.123, 1.123),
        velocity=(21.123, -21.123, 21.123),
        subframe_request=0x01,
    )
    sub = HostSubFrame.build(
        latitude=38.030082231,
        longitude=170.917533212,
        altitude=41.1231,
        satellites=19,
        gnss_week=2278,
        gnss_ms=352718000,
        relative_altitude=12.12,
    )
    assert HostPacket(main, sub, NullCommand()).encode() == HOST_EXAMPLE


def test_host_example_sub_frame_built_from_gnss_datetime() -> None:
    sub = HostSubFrame.build(
        latitude=38.030082231,
        longitude=170.917533212,
        altitude=41.1231,
        satellites=19,
        gnss_time=datetime(2023, 9, 7, 1, 58, 38, tzinfo=timezone.utc),
        relative_altitude=12.12,
        apply_leap_seconds=False,  # the document's rule, as its example
    )
    assert sub == decode_host_packet(HOST_EXAMPLE).sub


def test_gcu_example_built_from_physical_values() -> None:
    main = GcuMainFrame.build(
        mode=Mode.POINTING_FOLLOW,
        pod_status=0x8001,
        miss_distance=(-500, 500),
        relative_angles=(-8.03, 0.32, 62.18),
        attitude=(-0.01, 9.33, 62.15),
        angular_rates=(-0.1, 0.1, -0.2),
    )
    sub = GcuSubFrame.build(
        hardware_version=3.1,
        firmware_version=5.0,
        pod_model=PodModel.D_90AI,
        target_distance=589.4,
        target_position=GeoPosition(38.0300822, 170.9175332, 41.123),
        camera1_zoom=29.9,
        camera2_zoom=2.0,
        time_zone=8,
    )
    packet = GcuPacket(main, sub, Feedback(Opcode.TAKE_PHOTO, 0x00))
    assert packet.encode() == GCU_EXAMPLE
