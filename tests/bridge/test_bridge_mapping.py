"""The bridge's pure MAVLink ⇄ GCU mapping, without sockets: frames, geometry, plans, acks."""

from __future__ import annotations

import math
from typing import Any

import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from gcu_async.bridge import camera, dispatch, gimbal
from gcu_async.bridge._mavlink import mavlink
from gcu_async.bridge.autopilot import AutopilotFeed, gimbal_device_state_changes
from gcu_async.bridge.camera import CameraConfig
from gcu_async.bridge.commands import (
    ACCEPTED,
    DENIED,
    FAILED,
    TEMPORARILY_REJECTED,
    UNSUPPORTED,
    CommandIn,
    GcuCall,
    Plan,
    result_for,
)
from gcu_async.bridge.geometry import euler_from_quaternion, ground_point, quaternion_from_euler
from gcu_async.bridge.view import Control, GcuView
from gcu_async.errors import (
    CommandFailed,
    CommandLinkLost,
    CommandTimeout,
    FieldRangeError,
    Outcome,
    UnsupportedCommandError,
)
from gcu_async.protocol.aircraft import AircraftState
from gcu_async.protocol.enums import FaultFlags, Mode, PodModel, PodStatus
from gcu_async.protocol.gcu_frames import GcuMainFrame, GcuSubFrame
from gcu_async.protocol.units import METRES_PER_DEGREE, GeoPosition

NAN = math.nan
GCS = (255, 190)
CONFIG = CameraConfig(max_zoom=30.0, video_url="rtsp://10.0.0.1:554/main")


def cmd(command: int, *params: float, source: tuple[int, int] = GCS, frame: int | None = None,
        target: tuple[int, int] = (1, gimbal.COMPONENT)) -> CommandIn:  # fmt: skip
    values = (*params, *([0.0] * (7 - len(params))))
    return CommandIn(command, values, source, *target, frame)  # type: ignore[arg-type]


def view(mode: Mode = Mode.POINTING_FOLLOW, *, pod: PodModel = PodModel.D_90PRO_TA,
         **changes: Any) -> GcuView:  # fmt: skip
    status = GcuMainFrame.build(mode=mode, attitude=(0.0, -10.0, 90.0),
                                relative_angles=(10.0, 0.0, 45.0))  # fmt: skip
    info = GcuSubFrame.build(pod_model=pod, firmware_version=5.2, hardware_version=3.1,
                             camera1_zoom=6.0)  # fmt: skip
    fields: dict[str, Any] = {"link_up": True, "status": status, "info": info}
    fields.update(changes)
    return GcuView(**fields)


# -- geometry -------------------------------------------------------------------------------
angle = st.floats(-179.9, 179.9)


@given(roll=st.floats(-89.0, 89.0), pitch=st.floats(-89.0, 89.0), yaw=angle)
def test_quaternion_round_trip(roll: float, pitch: float, yaw: float) -> None:
    q = quaternion_from_euler(roll, pitch, yaw)
    assert sum(c * c for c in q) == pytest.approx(1.0)
    back = euler_from_quaternion(q)
    assert back.roll == pytest.approx(roll, abs=1e-6)
    assert back.pitch == pytest.approx(pitch, abs=1e-6)
    assert math.isclose((back.yaw - yaw + 180) % 360 - 180, 0.0, abs_tol=1e-6)


def test_quaternion_matches_mavlinks_frame_conventions() -> None:
    # pure yaw 90: rotation about down (z) by +90 (clockwise seen from above)
    w, x, y, z = quaternion_from_euler(0.0, 0.0, 90.0)
    assert (w, x, y, z) == pytest.approx((math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)))
    # pitch down 90: rotation about the right axis (y) by -90
    assert quaternion_from_euler(0.0, -90.0, 0.0) == pytest.approx(
        (math.sqrt(0.5), 0.0, -math.sqrt(0.5), 0.0))
    # the rotation matrix of the quaternion equals pymavlink's direction cosine matrix
    from pymavlink.rotmat import Matrix3

    dcm = Matrix3()
    dcm.from_euler(*(math.radians(a) for a in (10.0, -35.0, 120.0)))
    w, x, y, z = quaternion_from_euler(10.0, -35.0, 120.0)
    rows = [
        (1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
        (2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
        (2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)),
    ]
    expected = [(r.x, r.y, r.z) for r in (dcm.a, dcm.b, dcm.c)]
    for row, ref in zip(rows, expected, strict=True):
        assert row == pytest.approx(ref, abs=1e-9)


@pytest.mark.parametrize("q", [(NAN, 0, 0, 0), (0, 0, 0, 0), (1, 0, 0)])
def test_bad_quaternions_are_refused(q: tuple[float, ...]) -> None:
    with pytest.raises(ValueError, match="q:"):
        euler_from_quaternion(q)


@given(pitch=st.floats(-89.0, -5.0), yaw=st.floats(0.0, 359.9), height=st.floats(1.0, 500.0))
def test_ground_point_lies_on_the_ground_along_the_line_of_sight(
    pitch: float, yaw: float, height: float
) -> None:
    camera_pos = GeoPosition(22.5, 113.9, 40.0 + height)
    hit = ground_point(camera_pos, pitch, yaw, 40.0)
    distance = height / math.sin(math.radians(-pitch))
    assume(distance <= 10_000)
    assert hit is not None
    assert hit.altitude == pytest.approx(40.0)
    north = (hit.latitude - camera_pos.latitude) * METRES_PER_DEGREE
    east = ((hit.longitude - camera_pos.longitude) * METRES_PER_DEGREE
            * math.cos(math.radians(camera_pos.latitude)))  # fmt: skip
    horizontal = height / math.tan(math.radians(-pitch))
    assert math.hypot(north, east) == pytest.approx(horizontal, rel=1e-3, abs=1e-3)
    if horizontal > 1.0:
        bearing = math.degrees(math.atan2(east, north)) % 360
        assert math.isclose((bearing - yaw + 180) % 360 - 180, 0.0, abs_tol=0.1)


@pytest.mark.parametrize(("pitch", "alt"), [(0.0, 140.0), (10.0, 140.0), (-30.0, 40.0),
                                             (-30.0, 20.0), (-0.1, 140.0)])
def test_no_ground_point_looking_up_from_below_or_too_far(pitch: float, alt: float) -> None:
    assert ground_point(GeoPosition(22.5, 113.9, alt), pitch, 0.0, 40.0) is None


# -- acknowledgements ----------------------------------------------------------------------
@pytest.mark.parametrize(("error", "expected"), [
    (None, (ACCEPTED, 0)),
    (CommandFailed(0x14, 0x01), (FAILED, 1)),
    (CommandFailed(0x22, 0x02, 0x02), (FAILED, 2)),
    (CommandTimeout("t", outcome=Outcome.UNKNOWN), (FAILED, -1)),
    (CommandTimeout("t", outcome=Outcome.NOT_SENT), (TEMPORARILY_REJECTED, 0)),
    (CommandLinkLost("l", outcome=Outcome.NOT_SENT), (TEMPORARILY_REJECTED, 0)),
    (CommandLinkLost("l", outcome=Outcome.UNKNOWN), (FAILED, -1)),
    (UnsupportedCommandError("TRACK", "Z-6A"), (UNSUPPORTED, 0)),
    (FieldRangeError("pitch_rate", 500, -150, 150), (DENIED, 0)),
    (ValueError("set_angles: no mode takes angles"), (DENIED, 0)),
    (TypeError("box"), (DENIED, 0)),
])  # fmt: skip
def test_result_for_every_outcome(error: BaseException | None,
                                  expected: tuple[int, int]) -> None:  # fmt: skip
    assert result_for(error) == expected


def test_result_for_reraises_bugs() -> None:
    with pytest.raises(KeyError):
        result_for(KeyError("bug"))


def test_plan_needs_exactly_one_of_result_and_call() -> None:
    with pytest.raises(ValueError, match="exactly one"):
        Plan()
    with pytest.raises(ValueError, match="exactly one"):
        Plan(ACCEPTED, call=GcuCall("focus"))


# -- gimbal ---------------------------------------------------------------------------------
def test_attitude_requests_choose_the_mode_and_then_only_values() -> None:
    v = view(Mode.POINTING_FOLLOW)
    call = gimbal.attitude_call(v, pitch=-30.0, yaw=200.0, yaw_lock=True)
    assert call == GcuCall("enter_euler_control", {"roll": 0.0, "pitch": -30.0, "yaw": -160.0},
                           mode=Mode.EULER_CONTROL)  # fmt: skip
    confirmed = view(Mode.EULER_CONTROL, bridge_mode=Mode.EULER_CONTROL)
    assert gimbal.attitude_call(confirmed, pitch=-30.0, yaw=20.0, yaw_lock=True).method == (
        "set_angles")
    pending = view(Mode.POINTING_FOLLOW, pending_mode=Mode.EULER_CONTROL)
    assert gimbal.attitude_call(pending, pitch=-30.0, yaw_lock=True).method == "set_angles"
    # the pod changed mode by itself: a mode command again
    drifted = view(Mode.TRACK, bridge_mode=Mode.EULER_CONTROL)
    assert gimbal.attitude_call(drifted, pitch=-30.0, yaw_lock=True).method == "enter_euler_control"
    # a missing angle keeps the current one (absolute for yaw lock, relative otherwise)
    assert gimbal.attitude_call(v, pitch=-5.0, yaw_lock=True).kwargs["yaw"] == 90.0
    assert gimbal.attitude_call(v, pitch=-5.0, yaw_lock=False).kwargs["yaw"] == 45.0
    assert gimbal.attitude_call(v, yaw=5.0, yaw_lock=False).kwargs["pitch"] == -10.0
    rates = gimbal.attitude_call(v, pitch_rate=NAN, yaw_rate=12.0, yaw_lock=False)
    assert rates == GcuCall("enter_pointing_follow", {"pitch_rate": 0.0, "yaw_rate": 12.0},
                            mode=Mode.POINTING_FOLLOW)  # fmt: skip
    assert gimbal.attitude_call(v, yaw_rate=1.0, yaw_lock=True).method == "enter_pointing_lock"
    assert gimbal.attitude_call(v, yaw_lock=True) == GcuCall("release_control")


def test_neutral_and_retract_flags() -> None:
    plan = gimbal.pitchyaw_plan(cmd(1000, NAN, NAN, NAN, NAN, mavlink.GIMBAL_MANAGER_FLAGS_NEUTRAL),
                                view())
    assert plan.call == GcuCall("centre")
    plan = gimbal.pitchyaw_plan(cmd(1000, NAN, NAN, NAN, NAN, mavlink.GIMBAL_MANAGER_FLAGS_RETRACT),
                                view())
    assert plan.result == UNSUPPORTED


def test_configure_sets_and_releases_controllers() -> None:
    control = Control()
    taken = gimbal.configure(cmd(1001, -2, -2, -1, -1), control)
    assert taken == Control(GCS, (0, 0))
    assert taken is not None and not taken.allows((1, 1)) and taken.allows(GCS)
    other = gimbal.configure(cmd(1001, -3, -3, 7, 8, source=(9, 9)), taken)
    assert other == Control(GCS, (7, 8))  # only the holder releases
    assert gimbal.configure(cmd(1001, -3, -3, -1, -1), taken) == Control()
    assert gimbal.configure(cmd(1001, 300, 1, -1, -1), control) is None
    assert gimbal.configure(cmd(1001, NAN, 1, -1, -1), control) is None


def test_roi_altitude_frames() -> None:
    v = view(home_altitude=50.0)
    long_plan = gimbal.roi_location_plan(cmd(195, 0, 0, 0, 0, 22.5, 113.9, 30.0), v)
    assert long_plan.call == GcuCall("gaze_at", {"latitude": 22.5, "longitude": 113.9,
                                                 "altitude": 80.0}, mode=Mode.GAZE)
    msl = gimbal.roi_location_plan(cmd(195, 0, 0, 0, 0, 225_000_000, 1_139_000_000, 30.0,
                                       frame=mavlink.MAV_FRAME_GLOBAL_INT), v)
    assert msl.call is not None and msl.call.kwargs == {
        "latitude": 22.5, "longitude": 113.9, "altitude": 30.0}
    no_home = gimbal.roi_location_plan(cmd(195, 0, 0, 0, 0, 22.5, 113.9, 30.0), view())
    assert no_home.result == TEMPORARILY_REJECTED
    local = gimbal.roi_location_plan(cmd(195, 0, 0, 0, 0, 1, 1, 1,
                                         frame=mavlink.MAV_FRAME_LOCAL_NED), v)
    assert local.result == UNSUPPORTED
    assert gimbal.roi_location_plan(cmd(195, 0, 0, 0, 0, NAN, 1, 1), v).result == DENIED


def test_failure_flags_from_faults_and_link() -> None:
    info = GcuSubFrame.build(faults=FaultFlags.POD_HARDWARE | FaultFlags.GNSS_NO_FIX
                             | FaultFlags.MAVLINK_RATE)  # fmt: skip
    flags = gimbal.failure_flags(GcuView(link_up=True, info=info))
    assert flags == (mavlink.GIMBAL_DEVICE_ERROR_FLAGS_MOTOR_ERROR
                     | mavlink.GIMBAL_DEVICE_ERROR_FLAGS_COMMS_ERROR)  # fmt: skip
    assert gimbal.failure_flags(GcuView(link_up=True)) == 0
    assert gimbal.failure_flags(GcuView(link_up=False)) == (
        mavlink.GIMBAL_DEVICE_ERROR_FLAGS_COMMS_ERROR)
    assert gimbal.heartbeat(GcuView(link_up=False), 26).system_status == (
        mavlink.MAV_STATE_CRITICAL)


def test_attitude_status_frame_follows_ins_validity() -> None:
    earth = gimbal.device_attitude_status(view(ins_valid=True))
    assert earth.flags & gimbal.YAW_IN_EARTH_FRAME
    assert euler_from_quaternion(earth.q).yaw == pytest.approx(90.0)
    assert math.degrees(earth.delta_yaw) == pytest.approx(45.0)
    vehicle = gimbal.device_attitude_status(view(ins_valid=False))
    assert vehicle.flags & gimbal.YAW_IN_VEHICLE_FRAME
    assert euler_from_quaternion(vehicle.q).yaw == pytest.approx(45.0)
    assert math.isnan(vehicle.delta_yaw)
    assert gimbal.device_attitude_status(GcuView()) is None
    assert gimbal.encode_version(52) == 5 | 2 << 8


# -- camera ---------------------------------------------------------------------------------
def c(command: int, *params: float) -> CommandIn:
    return cmd(command, *params, target=(1, camera.COMPONENT))


def test_zoom_plans() -> None:
    v = view()
    zoom = mavlink.MAV_CMD_SET_CAMERA_ZOOM
    assert camera.zoom_plan(c(zoom, 1, 1), v, CONFIG).call == GcuCall("zoom_in")
    assert camera.zoom_plan(c(zoom, 1, -1), v, CONFIG).call == GcuCall("zoom_out")
    assert camera.zoom_plan(c(zoom, 1, 0), v, CONFIG).call == GcuCall("stop_zoom")
    assert camera.zoom_plan(c(zoom, 1, 0.5), v, CONFIG).result == DENIED
    assert camera.zoom_plan(c(zoom, 2, 50), v, CONFIG).call == GcuCall(
        "zoom_to_fraction", {"fraction": 0.5})
    assert camera.zoom_plan(c(zoom, 2, 0), v, CONFIG).call == GcuCall(
        "zoom_to_fraction", {"fraction": 1e-4})
    assert camera.zoom_plan(c(zoom, 2, 101), v, CONFIG).result == DENIED
    assert camera.zoom_plan(c(zoom, 0, 2), v, CONFIG).call == GcuCall("zoom_to", {"ratio": 8.0})
    assert camera.zoom_plan(c(zoom, 0, -9), v, CONFIG).call == GcuCall("zoom_to", {"ratio": 1.0})
    assert camera.zoom_plan(c(zoom, 0, 99), v, CONFIG).call == GcuCall("zoom_to", {"ratio": 30.0})
    assert camera.zoom_plan(c(zoom, 3, 20), v, CONFIG).result == UNSUPPORTED
    assert camera.zoom_plan(c(zoom, 2, NAN), v, CONFIG).result == DENIED
    # Z-6C: no zoom-to-ratio (Appendix 8): range and step are UNSUPPORTED, continuous works
    z6c = view(pod=PodModel.Z_6C)
    assert camera.zoom_plan(c(zoom, 2, 50), z6c, CONFIG).result == UNSUPPORTED
    assert camera.zoom_plan(c(zoom, 1, 1), z6c, CONFIG).call == GcuCall("zoom_in")


def test_zoom_level_is_percent_of_the_maximum_ratio_or_nan() -> None:
    assert camera.camera_settings(view(), CONFIG).zoomLevel == pytest.approx(20.0)
    assert math.isnan(camera.camera_settings(view(), CameraConfig()).zoomLevel)


def test_camera_capabilities_follow_appendix_8() -> None:
    full = camera.capabilities(view(), CONFIG)
    assert full & mavlink.CAMERA_CAP_FLAGS_HAS_TRACKING_RECTANGLE
    assert full & mavlink.CAMERA_CAP_FLAGS_HAS_BASIC_FOCUS
    assert full & mavlink.CAMERA_CAP_FLAGS_HAS_VIDEO_STREAM
    z6c = camera.capabilities(view(pod=PodModel.Z_6C), CameraConfig())
    assert not z6c & mavlink.CAMERA_CAP_FLAGS_HAS_TRACKING_POINT
    assert not z6c & mavlink.CAMERA_CAP_FLAGS_HAS_VIDEO_STREAM
    assert z6c & mavlink.CAMERA_CAP_FLAGS_CAPTURE_IMAGE


def test_track_plans() -> None:
    v = view()
    point = camera.track_plan(c(mavlink.MAV_CMD_CAMERA_TRACK_POINT, 0.02, 0.5, 0.0), v)
    assert point.call is not None
    assert point.call.kwargs["box"] == pytest.approx((0.0, 0.45, 0.07, 0.55))
    assert point.call.tracking_mode == mavlink.CAMERA_TRACKING_MODE_POINT
    rect = camera.track_plan(c(mavlink.MAV_CMD_CAMERA_TRACK_RECTANGLE, 0.1, 0.2, 0.3, 0.4), v)
    assert rect.call == GcuCall("track", {"box": (0.1, 0.2, 0.3, 0.4)}, mode=Mode.TRACK,
                                tracking_mode=mavlink.CAMERA_TRACKING_MODE_RECTANGLE)
    for bad in ((0.3, 0.2, 0.1, 0.4), (0.1, 0.2, 1.3, 0.4), (NAN, 0.2, 0.3, 0.4)):
        assert camera.track_plan(c(mavlink.MAV_CMD_CAMERA_TRACK_RECTANGLE, *bad), v).result == (
            DENIED)
    assert camera.track_plan(c(mavlink.MAV_CMD_CAMERA_TRACK_POINT, 0.5, 0.5),
                             view(pod=PodModel.Z_6C)).result == UNSUPPORTED


def test_source_plans() -> None:
    src = mavlink.MAV_CMD_SET_CAMERA_SOURCE
    assert camera.source_plan(c(src, 0, camera.IR, camera.RGB), view(), CONFIG).call == GcuCall(
        "set_picture_in_picture", {"mode": 2})
    assert camera.source_plan(c(src, 0, camera.IR, 0), view(pod=PodModel.D_80AI),
                              CONFIG).result == UNSUPPORTED  # no thermal camera
    assert camera.source_plan(c(src, 0, 3, 0), view(), CONFIG).result == DENIED  # NDVI


def test_tracking_status_point_from_miss_distances() -> None:
    status = GcuMainFrame.build(mode=Mode.TRACK, pod_status=PodStatus.TRACKING_OK,
                                miss_distance=(500, -1000))  # fmt: skip
    msg = camera.tracking_status(GcuView(status=status, tracking_mode=1))
    assert msg.tracking_status == mavlink.CAMERA_TRACKING_STATUS_FLAGS_ACTIVE
    assert (msg.point_x, msg.point_y) == pytest.approx((0.75, 0.0))
    lost = camera.tracking_status(GcuView(status=GcuMainFrame.build(mode=Mode.TRACK)))
    assert lost.tracking_status == mavlink.CAMERA_TRACKING_STATUS_FLAGS_ERROR
    idle = camera.tracking_status(GcuView(status=GcuMainFrame.build()))
    assert idle.tracking_status == mavlink.CAMERA_TRACKING_STATUS_FLAGS_IDLE


def test_fov_target_prefers_the_laser_then_the_ground() -> None:
    aircraft = AircraftState(position=GeoPosition(22.5, 113.9, 150.0))
    status = GcuMainFrame.build(attitude=(0.0, -45.0, 0.0))
    v = GcuView(status=status, aircraft=aircraft, position_current=True, ins_valid=True,
                home_altitude=50.0)  # fmt: skip
    target = camera.image_target(v)
    assert target is not None and target.altitude == pytest.approx(50.0)
    assert (target.latitude - 22.5) * METRES_PER_DEGREE == pytest.approx(100.0, rel=1e-6)
    ranged = GcuMainFrame.build(attitude=(0.0, -45.0, 0.0), pod_status=PodStatus.RANGE_VALID)
    info = GcuSubFrame.build(target_position=GeoPosition(1.0, 2.0, 3.0), target_distance=5.0)
    laser = camera.image_target(GcuView(status=ranged, info=info))
    assert laser == GeoPosition(1.0, 2.0, 3.0)
    assert camera.image_target(GcuView(status=status, aircraft=aircraft)) is None  # stale
    unknown = camera.fov_status(GcuView(status=status), CONFIG)
    assert unknown.lat_image == camera.INT32_MAX and unknown.lat_camera == camera.INT32_MAX


def test_camera_config_checks() -> None:
    with pytest.raises(ValueError, match="video_url"):
        CameraConfig(video_url="ftp://x")
    with pytest.raises(ValueError, match="max_zoom"):
        CameraConfig(max_zoom=0.5)


# -- dispatch -------------------------------------------------------------------------------
def test_routing() -> None:
    request = mavlink.MAV_CMD_REQUEST_MESSAGE
    gim = mavlink.MAVLINK_MSG_ID_GIMBAL_MANAGER_INFORMATION
    cam = mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION
    assert dispatch.components_for(cmd(request, gim, target=(0, 0)), 1, CONFIG) == (
        gimbal.COMPONENT,)
    assert dispatch.components_for(cmd(request, cam, target=(1, 0)), 1, CONFIG) == (
        camera.COMPONENT,)
    assert dispatch.components_for(cmd(request, 33, target=(1, 0)), 1, CONFIG) == ()
    assert dispatch.components_for(cmd(1000, target=(1, 0)), 1, CONFIG) == ()
    assert dispatch.components_for(cmd(1000, target=(2, 154)), 1, CONFIG) == ()
    assert dispatch.components_for(cmd(1000, target=(1, 1)), 1, CONFIG) == ()
    assert dispatch.components_for(cmd(1000, target=(1, 100)), 1, CONFIG) == (100,)


@pytest.mark.parametrize("param1", [NAN, -1.0, 1e30, 33.0])
def test_requests_for_unknown_messages_are_unsupported(param1: float) -> None:
    plan = dispatch.plan(cmd(mavlink.MAV_CMD_REQUEST_MESSAGE, param1), gimbal.COMPONENT, view(),
                         CONFIG)  # fmt: skip
    assert plan.result == UNSUPPORTED


@given(command=st.integers(0, 65535),
       params=st.lists(st.floats(allow_nan=True, allow_infinity=True, width=32), min_size=7,
                       max_size=7),
       component=st.sampled_from(dispatch.COMPONENTS),
       frame=st.none() | st.integers(0, 255))  # fmt: skip
def test_any_command_gets_a_plan_never_an_exception(command: int, params: list[float],
                                                    component: int, frame: int | None) -> None:
    """Hostile parameters: every command is planned (refused or called), nothing raises."""
    plan = dispatch.plan(cmd(command, *params, frame=frame, target=(1, component)), component,
                         view(home_altitude=10.0), CONFIG)  # fmt: skip
    assert (plan.result is None) != (plan.call is None)


# -- autopilot ------------------------------------------------------------------------------
def test_autopilot_state_for_gimbal_device_gives_attitude_and_velocity() -> None:
    q = quaternion_from_euler(5.0, -2.0, -90.0)
    msg = mavlink.MAVLink_autopilot_state_for_gimbal_device_message(
        1, 154, 0, q, 0, 1.0, 2.0, 3.0, 0, 0.0, 0, 0)
    changes = gimbal_device_state_changes(msg)
    assert changes["attitude"] == pytest.approx((5.0, -2.0, 270.0))
    assert changes["velocity"] == (1.0, 2.0, -3.0)
    unknown = mavlink.MAVLink_autopilot_state_for_gimbal_device_message(
        1, 154, 0, [NAN] * 4, 0, NAN, 0.0, 0.0, 0, 0.0, 0, 0)
    assert gimbal_device_state_changes(unknown) == {}


def test_autopilot_feed_home_altitude_and_utc() -> None:
    feed = AutopilotFeed(1)
    pos = mavlink.MAVLink_global_position_int_message(0, 225_000_000, 1_139_000_000, 150_000,
                                                      100_000, 0, 0, 0, 0)  # fmt: skip
    changes = feed.update(pos, now=10.0)
    assert changes is not None and changes["position"] == GeoPosition(22.5, 113.9, 150.0)
    assert feed.home_altitude == 50.0
    assert feed.position_current(10.5, 1.0) and not feed.position_current(11.5, 1.0)
    home = mavlink.MAVLink_home_position_message(0, 0, 42_000, 0, 0, 0, [1, 0, 0, 0], 0, 0, 0)
    feed.update(home, now=11.0)
    feed.update(pos, now=12.0)
    assert feed.home_altitude == 42.0  # HOME_POSITION wins
    assert feed.utc_usec(12.0) == 0
    feed.update(mavlink.MAVLink_system_time_message(1_700_000_000_000_000, 0), now=12.0)
    assert feed.utc_usec(12.5) == 1_700_000_000_500_000


# -- streams --------------------------------------------------------------------------------
def test_stream_schedule_defaults_intervals_and_stops() -> None:
    from gcu_async.bridge import streams

    served = set(dispatch.builders(gimbal.COMPONENT, CONFIG))
    schedule = streams.StreamSchedule(served, start=0.0)
    att, status = streams.ATTITUDE, mavlink.MAVLINK_MSG_ID_GIMBAL_MANAGER_STATUS
    sent = [mid for t in range(100) for mid in schedule.due(t / 100)]  # 1 s at 100 Hz
    assert sent.count(att) == 10 and sent.count(status) == 5
    schedule.set(att, 0.5, now=1.0)
    schedule.set(status, math.inf, now=1.0)
    sent = [mid for t in range(100, 200) for mid in schedule.due(t / 100)]
    assert sent.count(att) == 2 and sent.count(status) == 0
    assert schedule.next_time() == pytest.approx(2.0)
    schedule.set(status, None, now=2.0)  # back to the default
    assert schedule.interval(status) == pytest.approx(0.2)
    info = mavlink.MAVLINK_MSG_ID_GIMBAL_DEVICE_INFORMATION
    schedule.set(info, 1.0, now=2.0)  # any served message can be streamed
    assert schedule.explicit(info) and info in schedule.due(2.0)
    schedule.set(info, None, now=3.0)
    assert schedule.interval(info) == math.inf
    with pytest.raises(ValueError, match="not served"):
        schedule.set(mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION, 1.0, now=3.0)
    # a late loop sends once and plans from now: no burst
    assert schedule.due(10.0).count(att) == 1 and att not in schedule.due(10.01)


@pytest.mark.parametrize(("value", "expected"), [(-1, math.inf), (0, None), (500_000, 0.5),
                                                 (10_000, 0.01)])  # fmt: skip
def test_message_interval_requests(value: float, expected: float | None) -> None:
    from gcu_async.bridge import streams

    assert streams.interval_from_request(value) == expected


@pytest.mark.parametrize("value", [NAN, -2, 1, 9_999, 0.5, math.inf])
def test_bad_message_intervals_are_denied(value: float) -> None:
    plan = dispatch.plan(cmd(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL,
                             mavlink.MAVLINK_MSG_ID_GIMBAL_MANAGER_STATUS, value),
                         gimbal.COMPONENT, view(), CONFIG)  # fmt: skip
    assert plan.result == DENIED


def test_message_interval_for_another_components_message_is_unsupported() -> None:
    plan = dispatch.plan(cmd(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL,
                             mavlink.MAVLINK_MSG_ID_CAMERA_SETTINGS, 0),
                         gimbal.COMPONENT, view(), CONFIG)  # fmt: skip
    assert plan.result == UNSUPPORTED


def test_tracking_rectangle_is_reported_with_its_start_size() -> None:
    status = GcuMainFrame.build(mode=Mode.TRACK, pod_status=PodStatus.TRACKING_OK,
                                miss_distance=(0, 0))  # fmt: skip
    msg = camera.tracking_status(GcuView(status=status, tracking_mode=2,
                                         tracking_box=(0.1, 0.2, 0.3, 0.6)))  # fmt: skip
    assert (msg.rec_top_x, msg.rec_top_y, msg.rec_bottom_x, msg.rec_bottom_y) == (
        pytest.approx((0.4, 0.3, 0.6, 0.7)))
