"""MAVLink → AircraftState mapping (gcu_async.mavlink) with real pymavlink messages.

Expected values are computed by hand in the comments; the wire tests pack with one pymavlink
MAVLink instance and parse with another, so fields go through MAVLink's real scaling (float32,
int16 cm/s, int32 1e-7 °), then through a host packet and back via the protocol core.
"""

from __future__ import annotations

import math
import subprocess
import sys
from typing import Any

import pytest
from pymavlink.dialects.v20 import common as mavlink2

from gcu_async import AircraftState, FieldRangeError
from gcu_async.mavlink import (
    MILLI_G,
    STANDARD_GRAVITY,
    MavlinkAircraftState,
    acceleration_from_imu,
    acceleration_from_specific_force,
    acceleration_from_velocity_change,
    convert_attitude,
    convert_local_velocity,
    convert_position,
    convert_relative_altitude,
    convert_satellites,
    convert_system_time,
    convert_velocity,
)
from gcu_async.protocol import HostPacket, HostSubFrame, decode_host_packet
from gcu_async.protocol.units import Attitude, NorthEastUp

G = STANDARD_GRAVITY
STILL = NorthEastUp(0.0, 0.0, 0.0)
LEVEL = Attitude(0.0, 0.0, 0.0)


def ins_frame(attitude: Attitude = LEVEL, acceleration: NorthEastUp = STILL,
              velocity: NorthEastUp = STILL) -> Any:  # fmt: skip
    """A main frame with all three INS parts (the only way they go on the wire)."""
    frame = AircraftState(attitude=attitude, acceleration=acceleration,
                          velocity=velocity).main_frame()  # fmt: skip
    assert frame.ins_valid
    return frame


# -- message factories (real pymavlink objects) -------------------------------------------
def attitude_msg(roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0) -> Any:
    return mavlink2.MAVLink_attitude_message(
        time_boot_ms=1000, roll=roll, pitch=pitch, yaw=yaw, rollspeed=0, pitchspeed=0, yawspeed=0
    )


def global_position_msg(
    lat: int = 473977418,
    lon: int = 85455939,
    alt: int = 488120,
    relative_alt: int = 15250,
    vx: int = 250,
    vy: int = -120,
    vz: int = 150,
) -> Any:
    return mavlink2.MAVLink_global_position_int_message(
        time_boot_ms=1000, lat=lat, lon=lon, alt=alt, relative_alt=relative_alt,
        vx=vx, vy=vy, vz=vz, hdg=9000,
    )  # fmt: skip


def local_position_msg(t_ms: int, vx: float, vy: float, vz: float) -> Any:
    return mavlink2.MAVLink_local_position_ned_message(
        time_boot_ms=t_ms, x=0.0, y=0.0, z=0.0, vx=vx, vy=vy, vz=vz
    )


def scaled_imu_msg(xacc: int, yacc: int, zacc: int) -> Any:
    return mavlink2.MAVLink_scaled_imu_message(
        time_boot_ms=1000, xacc=xacc, yacc=yacc, zacc=zacc,
        xgyro=0, ygyro=0, zgyro=0, xmag=0, ymag=0, zmag=0,
    )  # fmt: skip


def raw_imu_msg(xacc: int, yacc: int, zacc: int) -> Any:
    return mavlink2.MAVLink_raw_imu_message(
        time_usec=1_000_000, xacc=xacc, yacc=yacc, zacc=zacc,
        xgyro=0, ygyro=0, zgyro=0, xmag=0, ymag=0, zmag=0,
    )  # fmt: skip


def highres_imu_msg(xacc: float, yacc: float, zacc: float) -> Any:
    return mavlink2.MAVLink_highres_imu_message(
        time_usec=1_000_000, xacc=xacc, yacc=yacc, zacc=zacc,
        xgyro=0, ygyro=0, zgyro=0, xmag=0, ymag=0, zmag=0,
        abs_pressure=0, diff_pressure=0, pressure_alt=0, temperature=0, fields_updated=0b111,
    )  # fmt: skip


def gps_raw_msg(satellites: int) -> Any:
    return mavlink2.MAVLink_gps_raw_int_message(
        time_usec=0, fix_type=3, lat=473977418, lon=85455939, alt=488120,
        eph=100, epv=100, vel=0, cog=0, satellites_visible=satellites,
    )  # fmt: skip


def system_time_msg(time_unix_usec: int) -> Any:
    return mavlink2.MAVLink_system_time_message(time_unix_usec=time_unix_usec, time_boot_ms=5)


def over_the_wire(*msgs: Any) -> list[Any]:
    """Pack with one MAVLink 2 instance, parse the bytes with another."""
    sender = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    receiver = mavlink2.MAVLink(None)
    data = b"".join(m.pack(sender) for m in msgs)
    assert data[0] == 0xFD  # MAVLink 2 framing
    parsed = receiver.parse_buffer(data)
    assert parsed is not None
    assert [m.get_type() for m in parsed] == [m.get_type() for m in msgs]
    return list(parsed)


def approx_neu(n: float, e: float, u: float, tol: float = 1e-9) -> Any:
    return pytest.approx((n, e, u), abs=tol)


# -- ATTITUDE ------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("rad", "expected_deg"),
    [
        ((0.0, 0.0, -math.pi / 2), (0.0, 0.0, 270.0)),  # yaw −90° → 270°
        ((0.0, 0.0, math.pi / 2), (0.0, 0.0, 90.0)),
        ((0.0, 0.0, math.pi), (0.0, 0.0, 180.0)),
        ((math.pi, 0.0, 0.0), (-180.0, 0.0, 0.0)),  # roll +180° → −180° ([-180, 180))
        ((-math.pi / 6, math.pi / 6, 0.0), (-30.0, 30.0, 0.0)),
        ((0.0, 0.0, -1e-6), (0.0, 0.0, 0.0)),  # −0.00006° → 0.00°, not 360.00°
        ((1e-6 - math.pi, 0.0, 0.0), (-180.0, 0.0, 0.0)),  # 179.99994° → -180.00°
    ],
)
def test_attitude_radians_to_wrapped_degrees(
    rad: tuple[float, float, float], expected_deg: tuple[float, float, float]
) -> None:
    att = convert_attitude(attitude_msg(*rad))
    assert att == pytest.approx(expected_deg, abs=1e-9)
    frame = ins_frame(att)  # every result fits the wire field
    assert frame.aircraft_attitude == pytest.approx(expected_deg, abs=1e-9)


def test_attitude_over_the_wire_float32() -> None:
    # float32(−π/2) = −1.5707963705 rad = −90.0000025°: still 270.00° on the wire
    (msg,) = over_the_wire(attitude_msg(math.radians(-11.32), math.radians(9.33), -math.pi / 2))
    assert msg.yaw != -math.pi / 2  # really went through float32
    att = convert_attitude(msg)
    main = ins_frame(att)
    assert (main.aircraft_roll_raw, main.aircraft_pitch_raw, main.aircraft_yaw_raw) == (
        -1132, 933, 27000,
    )  # fmt: skip


# -- GLOBAL_POSITION_INT ---------------------------------------------------------------------
def test_global_position_int_conversions() -> None:
    msg = global_position_msg()
    assert convert_position(msg) == pytest.approx((47.3977418, 8.5455939, 488.12), abs=1e-12)
    assert convert_relative_altitude(msg) == pytest.approx(15.25)  # 15250 mm
    # vx 250 cm/s N, vy −120 cm/s E, vz +150 cm/s DOWN → up −1.5 m/s
    assert convert_velocity(msg) == approx_neu(2.5, -1.2, -1.5)


def test_velocity_climbing_is_positive_up() -> None:
    assert convert_velocity(global_position_msg(vx=0, vy=0, vz=-320)).up == pytest.approx(3.2)


# -- GPS_RAW_INT / SYSTEM_TIME ----------------------------------------------------------------
@pytest.mark.parametrize(("visible", "expected"), [(12, 12), (0, 0), (254, 254), (255, 0)])
def test_satellites_255_means_unknown(visible: int, expected: int) -> None:
    assert convert_satellites(gps_raw_msg(visible)) == expected


def test_system_time_to_gnss_week_ms_with_leap_seconds() -> None:
    # 2024-01-01T00:00:00.123456Z (Unix 1704067200): GPS week 2295 began Sunday 2023-12-31
    # (week 2048 began 2019-04-07; +1729 days = 247 weeks). Monday 00:00 UTC = 86 400 s into
    # the week, + 18 leap seconds, + 123 ms (µs truncated) → 86 418 123 ms.
    assert convert_system_time(system_time_msg(1_704_067_200_123_456)) == (2295, 86_418_123)
    # Saturday 2024-01-06T23:59:50Z = 604 790 s into week 2295; +18 s crosses into week 2296
    assert convert_system_time(system_time_msg(1_704_585_590_000_000)) == (2296, 8_000)


def test_system_time_zero_is_no_time() -> None:
    mapper = MavlinkAircraftState()
    assert convert_system_time(system_time_msg(0)) is None
    assert mapper.update(system_time_msg(0)) is False
    assert (mapper.state.gnss_week, mapper.state.gnss_ms) == (0, 0)


# -- acceleration from IMU specific force ----------------------------------------------------
def test_imu_at_rest_level_is_zero() -> None:
    # level at rest, an FRD accelerometer reads (0, 0, −1 g) = −1000 mG
    accel = acceleration_from_imu(scaled_imu_msg(0, 0, -1000), Attitude(0, 0, 0), scale=MILLI_G)
    assert accel == approx_neu(0, 0, 0)


def test_imu_at_rest_pitched_30_is_zero() -> None:
    # nose up 30°: f_body = Rᵀ(0, 0, −g) = (g·sin30, 0, −g·cos30) = (+500, 0, −866) mG
    accel = acceleration_from_imu(scaled_imu_msg(500, 0, -866), Attitude(0, 30, 0), scale=MILLI_G)
    assert accel == approx_neu(0, 0, 0, tol=1e-3)  # int16 mG rounding: |error| < 0.0003
    assert ins_frame(acceleration=accel).acceleration == (0, 0, 0)


def test_imu_at_rest_any_attitude_is_zero() -> None:
    roll, pitch, yaw = 20.0, -35.0, 237.0
    r, p = math.radians(roll), math.radians(pitch)
    # f_body = Rᵀ(0, 0, −g) = (g·sinθ, −g·sinφ·cosθ, −g·cosφ·cosθ)
    f = (G * math.sin(p), -G * math.sin(r) * math.cos(p), -G * math.cos(r) * math.cos(p))
    accel = acceleration_from_imu(highres_imu_msg(*f), Attitude(roll, pitch, yaw), scale=1.0)
    assert accel == approx_neu(0, 0, 0)


def test_imu_raw_output_would_not_be_zero() -> None:
    # the bug of docs/protocol-notes.md §10 "Aircraft acceleration excludes gravity":
    # without the +g a level aircraft at rest "accelerates" 1 g upwards
    wrong = acceleration_from_specific_force((0, 0, -G), Attitude(0, 0, 0), gravity=0.0)
    assert wrong == approx_neu(0, 0, G)
    right = acceleration_from_specific_force((0, 0, -G), Attitude(0, 0, 0))
    assert right == approx_neu(0, 0, 0)


def test_imu_pure_north_acceleration() -> None:
    # level, heading north, accelerating 2 m/s² north: f = a − g = (2, 0, −g)
    level = acceleration_from_imu(highres_imu_msg(2.0, 0.0, -G), Attitude(0, 0, 0), scale=1.0)
    assert level == approx_neu(2, 0, 0)
    # heading east (yaw 90°): north is to the left, i.e. body −y
    east = acceleration_from_imu(highres_imu_msg(0.0, -2.0, -G), Attitude(0, 0, 90), scale=1.0)
    assert east == approx_neu(2, 0, 0)


def test_imu_climbing_acceleration_is_positive_up() -> None:
    # accelerating upward 1 m/s²: a_NED = (0, 0, −1), f = a − (0, 0, g) = (0, 0, −g − 1)
    accel = acceleration_from_imu(highres_imu_msg(0.0, 0.0, -G - 1.0), Attitude(0, 0, 0), scale=1)
    assert accel == approx_neu(0, 0, 1)


# -- acceleration from LOCAL_POSITION_NED velocity change --------------------------------------
def test_velocity_change_over_100ms() -> None:
    # Δv = (0.3, −0.2, −0.2) m/s NED over 0.1 s → (3, −2, −2) NED → up = +2
    a = acceleration_from_velocity_change(
        local_position_msg(1000, 1.0, 0.0, 0.5), local_position_msg(1100, 1.3, -0.2, 0.3)
    )
    assert a == approx_neu(3, -2, 2)


def test_velocity_change_over_the_wire() -> None:
    first, second = over_the_wire(
        local_position_msg(1000, 1.0, 0.0, 0.5), local_position_msg(1100, 1.3, -0.2, 0.3)
    )
    assert acceleration_from_velocity_change(first, second) == approx_neu(3, -2, 2, tol=1e-4)


def test_velocity_change_without_usable_interval() -> None:
    v0 = local_position_msg(1000, 0.0, 0.0, 0.0)
    assert acceleration_from_velocity_change(v0, local_position_msg(1000, 1, 0, 0)) is None
    assert acceleration_from_velocity_change(v0, local_position_msg(2001, 1, 0, 0)) is None
    assert acceleration_from_velocity_change(v0, local_position_msg(900, 1, 0, 0)) is None  # reboot
    wrapped = acceleration_from_velocity_change(
        local_position_msg(2**32 - 50, 0, 0, 0), local_position_msg(50, 1.0, 0, 0)
    )  # time_boot_ms wrapped after 49.7 days: 100 ms apart
    assert wrapped == approx_neu(10, 0, 0)


# -- the stateful mapper ---------------------------------------------------------------------
def test_mapper_fields_stay_none_until_their_message() -> None:
    mapper = MavlinkAircraftState()
    assert mapper.state == AircraftState()
    assert mapper.update(mavlink2.MAVLink_heartbeat_message(2, 3, 0, 0, 4, 3)) is False
    assert mapper.update(attitude_msg(yaw=-math.pi / 2)) is True
    s = mapper.state
    assert s.attitude == pytest.approx((0, 0, 270))
    assert (s.acceleration, s.velocity, s.position) == (None, None, None)
    assert mapper.used_types == {"ATTITUDE"}
    assert not s.main_frame().ins_valid  # an attitude alone is not INS data


def test_local_position_velocity_conversion() -> None:
    # vz +0.5 m/s DOWN → up −0.5 m/s
    assert convert_local_velocity(local_position_msg(1000, 1.0, -2.0, 0.5)) == approx_neu(
        1.0, -2.0, -0.5)  # fmt: skip


def test_mapper_gives_all_three_ins_parts_without_a_global_position() -> None:
    # no GNSS (indoor, PX4 without a global origin): LOCAL_POSITION_NED gives the velocity
    # it differentiates, so attitude + two samples make the INS data complete
    mapper = MavlinkAircraftState()
    mapper.update(attitude_msg(yaw=math.pi / 2))
    assert mapper.update(local_position_msg(1000, 1.0, 0.0, 0.5)) is True
    assert mapper.changes == {"velocity": approx_neu(1.0, 0.0, -0.5)}
    assert not mapper.state.main_frame().ins_valid  # no acceleration from one sample
    assert mapper.update(local_position_msg(1100, 1.3, -0.2, 0.3)) is True
    assert set(mapper.changes) == {"velocity", "acceleration"}
    state = mapper.state
    assert state.position is None
    main = decode_host_packet(HostPacket(state.main_frame()).encode()).main
    assert main.ins_valid
    assert (main.vel_north_raw, main.vel_east_raw, main.vel_up_raw) == (130, -20, -30)
    assert (main.accel_north_raw, main.accel_east_raw, main.accel_up_raw) == (300, -200, 200)
    assert main.aircraft_yaw_raw == 9000


def test_mapper_velocity_from_the_latest_of_both_messages() -> None:
    mapper = MavlinkAircraftState(acceleration_source="HIGHRES_IMU")
    mapper.update(global_position_msg(vx=250, vy=-120, vz=150))
    assert mapper.state.velocity == approx_neu(2.5, -1.2, -1.5)
    assert mapper.update(local_position_msg(1000, 2.6, -1.1, 1.4)) is True  # velocity only
    assert mapper.changes == {"velocity": approx_neu(2.6, -1.1, -1.4)}
    assert mapper.state.acceleration is None  # not the acceleration source
    mapper.update(global_position_msg(vx=240, vy=-130, vz=160))
    assert mapper.state.velocity == approx_neu(2.4, -1.3, -1.6)


def test_mapper_changes_name_what_the_last_message_gave() -> None:
    mapper = MavlinkAircraftState()
    assert mapper.changes == {}
    mapper.update(attitude_msg())
    assert set(mapper.changes) == {"attitude"}
    mapper.update(global_position_msg())
    assert set(mapper.changes) == {"position", "relative_altitude", "velocity"}
    changes = mapper.changes
    changes.clear()  # a copy: the mapper keeps its own
    assert set(mapper.changes) == {"position", "relative_altitude", "velocity"}
    assert mapper.update(mavlink2.MAVLink_heartbeat_message(2, 3, 0, 0, 4, 3)) is False
    assert set(mapper.changes) == {"position", "relative_altitude", "velocity"}  # unused


def test_mapper_velocity_source_needs_two_samples() -> None:
    mapper = MavlinkAircraftState()  # default: LOCAL_POSITION_NED
    assert mapper.update(scaled_imu_msg(0, 0, -1000)) is False  # not the chosen source
    assert mapper.update(local_position_msg(1000, 1.0, 0.0, 0.5)) is True
    assert mapper.state.acceleration is None  # one sample: no estimate invented
    assert mapper.update(local_position_msg(1100, 1.3, -0.2, 0.3)) is True
    assert mapper.state.acceleration == approx_neu(3, -2, 2)


def test_mapper_imu_source_needs_attitude_first() -> None:
    mapper = MavlinkAircraftState(acceleration_source="SCALED_IMU")
    assert mapper.update(scaled_imu_msg(500, 0, -866)) is False  # cannot rotate yet
    assert mapper.state.acceleration is None
    assert mapper.update(local_position_msg(1000, 1.0, 0.0, 0.5)) is True  # velocity only
    assert mapper.state.acceleration is None
    mapper.update(attitude_msg(pitch=math.radians(30)))
    assert mapper.update(scaled_imu_msg(500, 0, -866)) is True
    assert mapper.state.acceleration == approx_neu(0, 0, 0, tol=1e-3)


def test_mapper_raw_imu_needs_explicit_scale() -> None:
    with pytest.raises(ValueError, match="raw_imu_scale"):
        MavlinkAircraftState(acceleration_source="RAW_IMU")
    with pytest.raises(ValueError, match="raw_imu_scale"):
        MavlinkAircraftState(acceleration_source="SCALED_IMU", raw_imu_scale=MILLI_G)
    with pytest.raises(ValueError, match="acceleration_source: 'IMU'"):
        MavlinkAircraftState(acceleration_source="IMU")
    mapper = MavlinkAircraftState(acceleration_source="RAW_IMU", raw_imu_scale=MILLI_G)
    mapper.update(attitude_msg())
    assert mapper.update(raw_imu_msg(204, 0, -1000)) is True  # ArduPilot: mG
    assert mapper.state.acceleration == approx_neu(204 * MILLI_G, 0, 0)


def test_mapper_no_acceleration_source() -> None:
    mapper = MavlinkAircraftState(acceleration_source=None)
    mapper.update(attitude_msg())
    assert mapper.update(local_position_msg(1000, 0, 0, 0)) is True  # velocity only
    assert mapper.update(local_position_msg(1100, 1, 0, 0)) is True
    assert mapper.update(highres_imu_msg(0, 0, -G)) is False
    assert mapper.state.acceleration is None
    assert not mapper.state.main_frame().ins_valid  # without acceleration: never INS valid


def test_mapper_raises_out_of_range_and_keeps_state() -> None:
    mapper = MavlinkAircraftState()
    mapper.update(local_position_msg(1000, 0.0, 0.0, 0.0))
    mapper.update(local_position_msg(1100, 0.1, 0.0, 0.0))
    before = mapper.state
    assert before.acceleration == approx_neu(1, 0, 0)
    # estimator reset: +40 m/s in 100 ms = 400 m/s², beyond the S16 field's ±327.67
    with pytest.raises(FieldRangeError, match="aircraft acceleration north") as info:
        mapper.update(local_position_msg(1200, 40.1, 0.0, 0.0))
    assert info.value.high == pytest.approx(327.67)
    assert mapper.state is before
    # the next sample differs from the reset one, so the stream recovers
    assert mapper.update(local_position_msg(1300, 40.1, 0.0, 0.0)) is True
    assert mapper.state.acceleration == approx_neu(0, 0, 0)


def test_full_stream_over_the_wire_into_a_host_packet() -> None:
    msgs = over_the_wire(
        attitude_msg(math.radians(-11.32), math.radians(9.33), -math.pi / 2),
        global_position_msg(),
        gps_raw_msg(14),
        system_time_msg(1_704_067_200_123_456),
        local_position_msg(1000, 1.0, 0.0, 0.5),
        local_position_msg(1100, 1.3, -0.2, 0.3),
    )
    mapper = MavlinkAircraftState()
    assert [mapper.update(m) for m in msgs] == [True] * 6
    state = mapper.state
    packet = decode_host_packet(HostPacket(state.main_frame(), state.sub_frame()).encode())
    main, sub = packet.main, packet.sub
    assert main.ins_valid
    assert main.aircraft_attitude == pytest.approx((-11.32, 9.33, 270.0))
    assert (main.accel_north_raw, main.accel_east_raw, main.accel_up_raw) == (300, -200, 200)
    # velocity from the last of GLOBAL_POSITION_INT and LOCAL_POSITION_NED
    assert (main.vel_north_raw, main.vel_east_raw, main.vel_up_raw) == (130, -20, -30)
    assert isinstance(sub, HostSubFrame)
    assert (sub.latitude_raw, sub.longitude_raw, sub.altitude_raw) == (473977418, 85455939, 488120)
    assert sub.relative_altitude_raw == 15250
    assert (sub.satellites, sub.gnss_week, sub.gnss_ms) == (14, 2295, 86_418_123)
    assert mapper.used_types == {
        "ATTITUDE", "GLOBAL_POSITION_INT", "GPS_RAW_INT", "SYSTEM_TIME", "LOCAL_POSITION_NED",
    }  # fmt: skip


# -- optional dependency ---------------------------------------------------------------------
@pytest.mark.subprocess  # a fresh interpreter (tests/helpers/tiers.py)
def test_gcu_async_imports_without_pymavlink() -> None:
    code = (
        "import sys\n"
        "sys.modules['pymavlink'] = None\n"  # makes `import pymavlink` fail
        "import gcu_async, gcu_async.protocol\n"
        "assert 'gcu_async.mavlink' not in sys.modules\n"
        "try:\n"
        "    import gcu_async.mavlink\n"
        "except ImportError as exc:\n"
        "    print(exc)\n"
        "else:\n"
        "    raise SystemExit('gcu_async.mavlink imported without pymavlink')\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=30, check=False
    )
    assert done.returncode == 0, done.stderr
    assert "pip install 'gcu-async[mavlink]'" in done.stdout
