"""Sans-I/O SimulatorModel: modes and angles on a ManualClock (docs/protocol-notes.md §5 "Control
values change meaning with the mode")."""

from __future__ import annotations

import math

import pytest

from gcu_async.protocol import (
    AngleControl,
    Centre,
    ClickToPan,
    ControlValues,
    EulerControl,
    Fpv,
    GazeAtCoordinates,
    GazeLock,
    HostSubFrame,
    ImageBox,
    ImagePoint,
    Mode,
    PodStatus,
    PointingFollow,
    PointingLock,
    TopDown,
    Track,
    ZoomTo,
)
from gcu_async.protocol.units import wrap_degrees_180
from helpers.sim.support import Rig

A = pytest.approx


def yaw_diff(a: float, b: float) -> float:
    return abs(wrap_degrees_180(a - b))


def test_rates_integrate_into_angles() -> None:
    rig = Rig()
    rig.command(PointingLock())
    rig.control = ControlValues.rates(pitch=10.0, yaw=-20.0)
    reply = rig.run(1.0)
    assert reply.main.mode == Mode.POINTING_LOCK
    assert reply.main.attitude.pitch == A(10.0, abs=0.05)
    assert reply.main.attitude.yaw == A(340.0, abs=0.05)
    assert reply.main.angular_rates.z == A(-20.0, abs=0.2)  # Z = yaw rate
    assert reply.main.angular_rates.x == A(-10.0, abs=0.2)  # X = −pitch rate
    rig.control = None  # invalid control values: rate 0, angles held
    held = rig.run(1.0)
    assert held.main.attitude.pitch == A(10.0, abs=0.05)
    assert held.main.angular_rates.z == A(0.0, abs=0.05)


def test_rate_resolution_scales_with_zoom() -> None:
    rig = Rig()
    rig.command(PointingLock())
    rig.command(ZoomTo(ratio=4.0))
    rig.run(1.0)
    assert rig.model.state.zoom[1] == A(4.0)
    rig.control = ControlValues(0, 100, 0)  # raw 100 = 10 °/s at 1×, 2.5 °/s at 4×
    start = rig.attitude_now.pitch
    rig.run(2.0)
    assert rig.attitude_now.pitch - start == A(5.0, abs=0.05)
    rig.control = ControlValues.rates(pitch=-5.0, zoom=4.0)  # the host scales for the zoom
    start = rig.attitude_now.pitch
    rig.run(1.0)
    assert rig.attitude_now.pitch - start == A(-5.0, abs=0.05)


def test_euler_targets_are_reached_at_a_bounded_slew_rate() -> None:
    rig = Rig(max_slew_rate=60.0)
    rig.command(EulerControl())
    rig.control = ControlValues.angles(pitch=-45.0, yaw=90.0)
    rig.null()
    previous = rig.attitude_now
    steps = []
    for _ in range(50):  # 1 s at 50 Hz
        rig.clock.advance(0.02)
        rig.null()
        now = rig.attitude_now
        steps.append((abs(now.pitch - previous.pitch), yaw_diff(now.yaw, previous.yaw)))
        previous = now
    assert max(max(s) for s in steps) <= 60.0 * 0.02 + 1e-9
    after_1s = rig.attitude_now
    assert after_1s.pitch == A(-45.0, abs=0.01)  # 45° at 60 °/s: 0.75 s
    assert after_1s.yaw == A(60.0, abs=0.01)  # 90° at 60 °/s: 1.5 s
    assert rig.run(1.0).main.attitude.yaw == A(90.0, abs=0.01)
    # half-way there after 0.5 s: the bound really limits
    rig2 = Rig(max_slew_rate=60.0)
    rig2.command(EulerControl())
    rig2.control = ControlValues.angles(pitch=-45.0, yaw=90.0)
    reply = rig2.run(0.5)
    assert reply.main.attitude.pitch == A(-30.0, abs=0.01)
    assert reply.main.angular_rates.z == A(60.0, abs=0.5)


def test_euler_control_is_absolute_and_fpv_is_relative() -> None:
    rig = Rig()
    rig.attitude = (0.0, 5.0, 100.0)
    rig.command(EulerControl())
    rig.control = ControlValues.angles(pitch=-20.0, yaw=30.0)
    reply = rig.run(2.0)
    assert reply.main.attitude.pitch == A(-20.0, abs=0.01)
    assert reply.main.attitude.yaw == A(30.0, abs=0.01)
    assert reply.main.relative_angles.z == A(-70.0, abs=0.01)
    assert reply.main.relative_angles.x == A(25.0, abs=0.01)  # X = −relative pitch
    rig.control = None
    rig.command(Fpv())
    rig.control = ControlValues.angles(roll=3.0, pitch=-10.0, yaw=15.0)
    reply = rig.run(2.0)
    assert reply.main.mode == Mode.FPV
    assert reply.main.relative_angles == A((10.0, 3.0, 15.0), abs=0.01)
    assert reply.main.attitude.pitch == A(-5.0, abs=0.01)
    assert reply.main.attitude.yaw == A(115.0, abs=0.01)


def test_angle_control_yaw_is_relative_pitch_is_euler() -> None:
    rig = Rig()
    rig.attitude = (0.0, 4.0, 250.0)
    rig.command(AngleControl())
    rig.control = ControlValues.angles(pitch=-30.0, yaw=-40.0)
    reply = rig.run(2.0)
    assert reply.main.mode == Mode.ANGLE_CONTROL
    assert reply.main.attitude.pitch == A(-30.0, abs=0.01)
    assert reply.main.relative_angles.z == A(-40.0, abs=0.01)
    assert reply.main.attitude.yaw == A(210.0, abs=0.01)
    rig.attitude = (0.0, 4.0, 280.0)  # the aircraft turns: the relative yaw stays
    reply = rig.run(1.0)
    assert reply.main.attitude.yaw == A(240.0, abs=0.01)


def test_follow_mode_follows_the_aircraft_yaw() -> None:
    rig = Rig()
    rig.command(PointingFollow())
    rig.control = ControlValues.rates(yaw=10.0)
    rig.run(1.0)  # turn 10° against the aircraft
    rig.control = ControlValues.rates()  # yaw rate 0: follow the aircraft
    for heading in (30.0, 90.0, 200.0):
        rig.attitude = (0.0, 0.0, heading)
        reply = rig.run(1.0)
        assert reply.main.attitude.yaw == A(heading + 10.0, abs=0.05)
        assert reply.main.relative_angles.z == A(10.0, abs=0.05)


def test_lock_mode_holds_its_heading_when_the_aircraft_turns() -> None:
    rig = Rig()
    rig.command(PointingLock())
    rig.attitude = (2.0, -3.0, 90.0)
    reply = rig.run(1.0)
    assert reply.main.attitude.yaw == A(0.0, abs=0.05)
    assert reply.main.relative_angles.z == A(-90.0, abs=0.05)
    assert reply.main.attitude.roll == A(0.0, abs=0.05)  # stabilised level
    assert reply.main.relative_angles.y == A(-2.0, abs=0.05)


def test_absolute_angles_are_relative_plus_aircraft() -> None:
    rig = Rig()
    rig.command(Fpv())
    rig.control = ControlValues.angles(roll=2.0, pitch=-15.0, yaw=40.0)
    rig.attitude = (-3.0, 6.0, 350.0)
    main = rig.run(2.0).main
    rel, att = main.relative_angles, main.attitude
    assert att.roll == A(-3.0 + rel.y, abs=0.011)
    assert att.pitch == A(6.0 - rel.x, abs=0.011)
    assert att.yaw == A((350.0 + rel.z) % 360.0, abs=0.011)
    assert att.yaw == A(30.0, abs=0.02)


@pytest.mark.parametrize("entered_from", ["follow", "lock"])
def test_top_down_holds_minus_90(entered_from: str) -> None:
    rig = Rig()
    rig.command(PointingFollow() if entered_from == "follow" else PointingLock())
    rig.command(TopDown())
    rig.control = ControlValues.rates(pitch=20.0)  # pitch control is ignored in top-down
    rig.attitude = (0.0, 8.0, 0.0)
    reply = rig.run(2.0)
    assert reply.main.mode == Mode.TOP_DOWN
    assert reply.main.attitude.pitch == A(-90.0, abs=0.01)
    rig.control = None
    rig.attitude = (0.0, 8.0, 60.0)
    reply = rig.run(1.0)
    expected_yaw = 60.0 if entered_from == "follow" else 0.0
    assert reply.main.attitude.yaw == A(expected_yaw, abs=0.05)
    assert reply.main.attitude.pitch == A(-90.0, abs=0.01)


def test_centre_recentres_and_is_ignored_in_euler_mode() -> None:
    rig = Rig()
    rig.command(PointingLock())
    rig.attitude = (0.0, 0.0, 45.0)
    rig.control = ControlValues.rates(pitch=-20.0, yaw=30.0)
    rig.run(1.0)
    assert rig.attitude_now.pitch == A(-20.0, abs=0.05)
    rig.control = None  # the spec: control values invalid while centring
    assert rig.command(Centre()).feedback.status == 0
    reply = rig.run(1.0)
    assert reply.main.mode == Mode.POINTING_LOCK
    assert reply.main.attitude.pitch == A(0.0, abs=0.05)
    assert reply.main.attitude.yaw == A(45.0, abs=0.05)
    rig.command(EulerControl())
    assert rig.command(Centre()).feedback.status == 0x01


def test_click_to_pan_turns_then_ends_in_pointing_lock() -> None:
    rig = Rig()
    reply = rig.command(ClickToPan(ImagePoint(0.75, 0.25)))
    assert reply.feedback.status == 0
    assert reply.main.mode == Mode.POINTING_FOLLOW  # still on the way
    reply = rig.run(1.0)
    assert reply.main.mode == Mode.POINTING_LOCK
    # 60° horizontal field of view at 1×, 16:9: a quarter of the image is 15° / 8.44°
    assert reply.main.attitude.yaw == A(15.0, abs=0.06)
    assert reply.main.attitude.pitch == A(60.0 / (16 / 9) / 4, abs=0.06)


def test_track_centres_the_target_and_exits_to_the_previous_mode() -> None:
    rig = Rig()
    rig.command(PointingLock())
    reply = rig.command(Track(True, ImageBox(0.7, 0.45, 0.8, 0.55)))
    assert reply.feedback.status == 0
    assert reply.main.mode == Mode.TRACK
    assert reply.main.pod_status & PodStatus.TRACKING_OK
    assert reply.main.miss_x == A(500, abs=2)
    assert reply.main.miss_y == A(0, abs=2)
    reply = rig.run(1.0)
    assert (reply.main.miss_x, reply.main.miss_y) == (0, 0)
    assert reply.main.attitude.yaw == A(15.0, abs=0.05)
    reply = rig.command(Track(False))
    assert reply.main.mode == Mode.POINTING_LOCK
    assert not reply.main.pod_status & PodStatus.TRACKING_OK
    assert rig.command(Track(True, ImageBox(0.5, 0.5, 0.5, 0.6))).feedback.status == 0x01


def _position(north_m: float = 0.0, east_m: float = 0.0) -> HostSubFrame:
    lat0, lon0 = 38.0, 117.0
    lat = lat0 + north_m / 111_320.0
    lon = lon0 + east_m / (111_320.0 * math.cos(math.radians(lat0)))
    return HostSubFrame.build(latitude=lat, longitude=lon, altitude=150.0, satellites=12,
                              relative_altitude=100.0)  # fmt: skip


def test_gaze_keeps_pointing_at_the_coordinates() -> None:
    rig = Rig()
    rig.sub = _position()
    target = _position(north_m=1000.0)
    reply = rig.command(GazeAtCoordinates(target.latitude, target.longitude, 50.0))
    assert reply.feedback.status == 0
    reply = rig.run(1.0)
    assert reply.main.mode == Mode.GAZE
    assert reply.main.attitude.pitch == A(-math.degrees(math.atan2(100, 1000)), abs=0.05)
    assert yaw_diff(reply.main.attitude.yaw, 0.0) < 0.05
    rig.sub = _position(east_m=1000.0)  # the aircraft flies east: look back north-west
    reply = rig.run(1.0)
    assert reply.main.attitude.yaw == A(315.0, abs=0.1)
    assert reply.main.attitude.pitch == A(-math.degrees(math.atan2(100, 1414.2)), abs=0.05)


def test_gaze_needs_valid_ins_data() -> None:
    rig = Rig()
    rig.attitude = None  # INS invalid (byte 11 B0 = 0)
    assert rig.command(GazeLock()).feedback.status == 0x01
    assert rig.command(GazeAtCoordinates(38.0, 117.0, 0.0)).feedback.status == 0x01
    assert rig.model.state.mode == Mode.POINTING_FOLLOW


def test_gaze_lock_holds_the_ground_point_under_the_centre() -> None:
    rig = Rig()
    rig.sub = _position()
    rig.command(PointingLock())
    rig.control = ControlValues.rates(pitch=-45.0)
    rig.run(1.0)
    rig.control = None
    rig.command(GazeLock())
    rig.sub = _position(north_m=-100.0)  # flies 100 m south: the ground point is 200 m north
    reply = rig.run(1.0)
    assert reply.main.attitude.pitch == A(-math.degrees(math.atan2(100, 200)), abs=0.1)
    assert yaw_diff(reply.main.attitude.yaw, 0.0) < 0.1
