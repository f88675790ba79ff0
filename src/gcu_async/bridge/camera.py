"""The camera component (MAV_COMP_ID_CAMERA): Camera Protocol v2 over the GCU's camera.

Pure, like :mod:`gcu_async.bridge.gimbal` (docs/mavlink-bridge.md, "Camera"). Capabilities
follow the pod model's Appendix 8 row once the GCU reported it: tracking (``TRACK``), zoom
to a ratio (``ZOOM_TO``), focus (``FOCUS``) and picture-in-picture (``PICTURE_IN_PICTURE``)
are offered, and accepted, only where the model supports them; a request for what it lacks
is UNSUPPORTED.

Zoom "range" is MAVLink's 0–100 % of the full range; the GCU's own fraction form of
``ZOOM_TO`` is the same idea (a fraction of the maximum ratio: 50 % of a 30× camera is 15×, 0 % the
minimum 1×), so the bridge sends it unchanged and needs no knowledge of the maximum. The
reverse (CAMERA_SETTINGS zoomLevel) needs the maximum ratio, which V2.0.6 does not report:
it is NaN ("not known") unless :attr:`CameraConfig.max_zoom` is given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any
from urllib.parse import urlsplit

from gcu_async.bridge._mavlink import mavlink
from gcu_async.bridge.commands import (
    ACCEPTED,
    DENIED,
    UNSUPPORTED,
    CommandIn,
    GcuCall,
    Plan,
    refuse,
    run,
)
from gcu_async.bridge.geometry import ground_point, quaternion_from_euler
from gcu_async.bridge.gimbal import DEVICE_ID, encode_version, text
from gcu_async.bridge.view import GcuView
from gcu_async.protocol.commands import ZOOM_RATIO_MAX
from gcu_async.protocol.enums import Mode, Opcode, PodStatus
from gcu_async.protocol.pods import is_thermal, pod_name
from gcu_async.protocol.units import GeoPosition

COMPONENT = mavlink.MAV_COMP_ID_CAMERA
INT32_MAX = 2**31 - 1
"""MAVLink's "unknown" for CAMERA_FOV_STATUS positions."""
NAN_Q = (math.nan, math.nan, math.nan, math.nan)
TRACK_POINT_RADIUS = 0.05
"""Half the side of the box tracked for MAV_CMD_CAMERA_TRACK_POINT when the radius is 0
(the GCU tracks boxes only), as a fraction of the image."""
ZOOM_STEP = 1.0
"""Ratio change of one ZOOM_TYPE_STEP step (×)."""

RGB = mavlink.CAMERA_SOURCE_RGB
IR = mavlink.CAMERA_SOURCE_IR
DEFAULT_PIP_MODES: dict[tuple[int, int], int] = {
    (RGB, IR): 1,
    (IR, RGB): 2,
    (RGB, 0): 3,
    (IR, 0): 4,
}
"""(primary, secondary) CAMERA_SOURCE → GCU picture-in-picture mode. V2.0.6 numbers the
modes 1–4 without saying what each shows: this table is the bridge's **assumption**
(override it with :attr:`CameraConfig.pip_modes` for your pod)."""
STREAM_TYPES = {
    "rtsp": mavlink.VIDEO_STREAM_TYPE_RTSP,
    "udp": mavlink.VIDEO_STREAM_TYPE_RTPUDP,
    "rtp": mavlink.VIDEO_STREAM_TYPE_RTPUDP,
    "tcp": mavlink.VIDEO_STREAM_TYPE_TCP_MPEG,
}
"""URL scheme → VIDEO_STREAM_TYPE."""


@dataclass(frozen=True)
class CameraConfig:
    """What the bridge is told about the camera (V2.0.6 does not report it)."""

    video_url: str | None = None
    """The video stream's URL (``rtsp://…``); ``None``: no VIDEO_STREAM_INFORMATION."""
    max_zoom: float | None = None
    """Camera 1's maximum zoom ratio, for CAMERA_SETTINGS zoomLevel (``None``: NaN)."""
    pip_modes: dict[tuple[int, int], int] = field(
        default_factory=lambda: dict(DEFAULT_PIP_MODES))
    """(primary, secondary) CAMERA_SOURCE → picture-in-picture mode 1–4."""

    def __post_init__(self) -> None:
        if self.video_url is not None:
            scheme = urlsplit(self.video_url).scheme
            if scheme not in STREAM_TYPES:
                raise ValueError(f"video_url: {self.video_url!r} has scheme {scheme!r}, not "
                                 f"one of {', '.join(STREAM_TYPES)}")  # fmt: skip
        if self.max_zoom is not None and not (
            math.isfinite(self.max_zoom) and 1.0 <= self.max_zoom <= ZOOM_RATIO_MAX
        ):
            raise ValueError(f"max_zoom: {self.max_zoom!r} is outside the allowed range "
                             f"[1, {ZOOM_RATIO_MAX:g}] x")  # fmt: skip


def _char_array(value: str, size: int = 32) -> list[int]:
    return list(text(value, size).ljust(size, b"\0"))


def capabilities(view: GcuView, config: CameraConfig) -> int:
    """CAMERA_CAP_FLAGS for the pod model (everything while the model is unknown). The GCU
    has no photo/video modes: photos and recording work at any time, so both "in the other
    mode" flags are set (ground stations refuse otherwise)."""
    flags: int = (mavlink.CAMERA_CAP_FLAGS_CAPTURE_IMAGE | mavlink.CAMERA_CAP_FLAGS_CAPTURE_VIDEO
                  | mavlink.CAMERA_CAP_FLAGS_CAN_CAPTURE_IMAGE_IN_VIDEO_MODE
                  | mavlink.CAMERA_CAP_FLAGS_CAN_CAPTURE_VIDEO_IN_IMAGE_MODE
                  | mavlink.CAMERA_CAP_FLAGS_HAS_BASIC_ZOOM)  # fmt: skip
    if view.supports(Opcode.FOCUS):
        flags |= mavlink.CAMERA_CAP_FLAGS_HAS_BASIC_FOCUS
    if view.supports(Opcode.TRACK):
        flags |= (mavlink.CAMERA_CAP_FLAGS_HAS_TRACKING_POINT
                  | mavlink.CAMERA_CAP_FLAGS_HAS_TRACKING_RECTANGLE)  # fmt: skip
    if config.video_url is not None:
        flags |= mavlink.CAMERA_CAP_FLAGS_HAS_VIDEO_STREAM
    return flags


# -- messages out ---------------------------------------------------------------------------
def camera_information(view: GcuView, config: CameraConfig) -> Any:
    """CAMERA_INFORMATION: vendor, model, firmware, capability flags; optics unknown (NaN)."""
    info = view.info
    model = "unknown (no reply yet)" if info is None else pod_name(info.pod_code)
    firmware = 0 if info is None else encode_version(info.firmware_version_raw)
    return mavlink.MAVLink_camera_information_message(
        view.time_boot_ms, _char_array("XF Robot"), _char_array(model), firmware, math.nan,
        math.nan, math.nan, 0, 0, 0, capabilities(view, config), 0, b"", DEVICE_ID, 0)


def zoom_level(view: GcuView, config: CameraConfig) -> float:
    """Camera 1's zoom as % of the full range (the fraction of the maximum ratio, as the
    GCU's ``ZOOM_TO`` defines it); NaN while the maximum or the zoom is unknown."""
    if config.max_zoom is None or view.info is None:
        return math.nan
    return max(0.0, min(100.0, view.info.camera1_zoom / config.max_zoom * 100.0))


def camera_mode(view: GcuView) -> int:
    mode: int = mavlink.CAMERA_MODE_VIDEO if view.recording else view.camera_mode
    return mode


def camera_settings(view: GcuView, config: CameraConfig) -> Any:
    """CAMERA_SETTINGS: mode (video while recording), zoom level, focus level unknown."""
    return mavlink.MAVLink_camera_settings_message(
        view.time_boot_ms, camera_mode(view), zoom_level(view, config), math.nan, 0)


def capture_status(view: GcuView, config: CameraConfig) -> Any:
    """CAMERA_CAPTURE_STATUS: video from the GCU's record flag, the time since the bridge
    saw it start, photos taken through the bridge; capacity unknown (NaN)."""
    recording = bool(view.recording)
    since = view.recording_since_ms
    elapsed = view.time_boot_ms - since if recording and since is not None else 0
    return mavlink.MAVLink_camera_capture_status_message(
        view.time_boot_ms, 0, 1 if recording else 0, 0.0, max(0, elapsed), math.nan,
        view.images_captured, 0)


def storage_information(view: GcuView, config: CameraConfig) -> Any:
    """STORAGE_INFORMATION: the GCU reports no storage, so "not supported", sizes NaN."""
    nan = math.nan
    return mavlink.MAVLink_storage_information_message(
        view.time_boot_ms, 1, 1, mavlink.STORAGE_STATUS_NOT_SUPPORTED, nan, nan, nan, nan, nan,
        0, b"", 0)


def video_stream_information(view: GcuView, config: CameraConfig) -> Any | None:
    """VIDEO_STREAM_INFORMATION for the configured URL (``None`` without one). Resolution,
    frame rate and bit rate are not reported by the GCU: 0 ("unknown")."""
    url = config.video_url
    if url is None:
        return None
    kind = STREAM_TYPES[urlsplit(url).scheme]
    return mavlink.MAVLink_video_stream_information_message(
        1, 1, kind, mavlink.VIDEO_STREAM_STATUS_FLAGS_RUNNING, 0.0, 0, 0, 0, 0, 0,
        text("XF video"), text(url, 160), 0, 0)


def video_stream_status(view: GcuView, config: CameraConfig) -> Any | None:
    """VIDEO_STREAM_STATUS of the configured stream (``None`` without one): running, the
    rest unknown (0), as in VIDEO_STREAM_INFORMATION."""
    if config.video_url is None:
        return None
    return mavlink.MAVLink_video_stream_status_message(
        1, mavlink.VIDEO_STREAM_STATUS_FLAGS_RUNNING, 0.0, 0, 0, 0, 0, 0, 0)


def camera_q(view: GcuView) -> tuple[float, float, float, float]:
    """The camera's earth-frame attitude while the INS data are valid, else NaN."""
    status = view.status
    if status is None or not view.ins_valid:
        return NAN_Q
    att = status.attitude
    return quaternion_from_euler(att.roll, att.pitch, att.yaw)


def image_target(view: GcuView) -> GeoPosition | None:
    """The image centre's ground position: the laser's target while ranging gives one
    (pod status B7), else the line of sight's meeting with flat ground at the home
    altitude (needs a current aircraft position, valid INS data and the home altitude)."""
    status, info = view.status, view.info
    if status is None:
        return None
    if info is not None and status.pod_status_raw & PodStatus.RANGE_VALID:
        return info.target_position
    position = view.aircraft.position
    if (not view.position_current or position is None or not view.ins_valid
            or view.home_altitude is None):  # fmt: skip
        return None
    att = status.attitude
    return ground_point(position, att.pitch, att.yaw, view.home_altitude)


def fov_status(view: GcuView, config: CameraConfig) -> Any:
    """CAMERA_FOV_STATUS: aircraft position, image-centre target (INT32_MAX: unknown),
    camera attitude; the fields of view are unknown (NaN)."""
    position = view.aircraft.position if view.position_current else None
    cam = ((INT32_MAX,) * 3 if position is None else
           (round(position.latitude * 1e7), round(position.longitude * 1e7),
            round(position.altitude * 1000)))  # fmt: skip
    target = image_target(view)
    img = ((INT32_MAX,) * 3 if target is None else
           (round(target.latitude * 1e7), round(target.longitude * 1e7),
            round(target.altitude * 1000)))  # fmt: skip
    return mavlink.MAVLink_camera_fov_status_message(
        view.time_boot_ms, *cam, *img, camera_q(view), math.nan, math.nan, 0)


def tracking_status(view: GcuView) -> Any:
    """CAMERA_TRACKING_IMAGE_STATUS: ACTIVE while the pod tracks and reports the target
    (pod status B0), ERROR while in tracking mode without it, IDLE otherwise; the target
    point from the miss distances (centre 0, the ends of their fields' range at the edges;
    right and down positive). The GCU reports only the centre: a rectangle track is reported
    with the size it was started with around that centre; the radius is unknown (NaN)."""
    status = view.status
    nan = math.nan
    if status is None or status.mode is not Mode.TRACK:
        return mavlink.MAVLink_camera_tracking_image_status_message(
            mavlink.CAMERA_TRACKING_STATUS_FLAGS_IDLE, mavlink.CAMERA_TRACKING_MODE_NONE,
            0, nan, nan, nan, nan, nan, nan, nan, 0)
    mode = view.tracking_mode or mavlink.CAMERA_TRACKING_MODE_RECTANGLE
    if not status.tracking_ok:
        return mavlink.MAVLink_camera_tracking_image_status_message(
            mavlink.CAMERA_TRACKING_STATUS_FLAGS_ERROR, mode, 0, nan, nan, nan, nan, nan, nan,
            nan, 0)
    x = 0.5 + status.miss_x / 2000
    y = 0.5 + status.miss_y / 2000
    box = view.tracking_box
    if mode == mavlink.CAMERA_TRACKING_MODE_RECTANGLE and box is not None:
        half_w, half_h = (box[2] - box[0]) / 2, (box[3] - box[1]) / 2
        rect = (max(0.0, x - half_w), max(0.0, y - half_h), min(1.0, x + half_w),
                min(1.0, y + half_h))  # fmt: skip
    else:
        rect = (nan, nan, nan, nan)
    return mavlink.MAVLink_camera_tracking_image_status_message(
        mavlink.CAMERA_TRACKING_STATUS_FLAGS_ACTIVE, mode,
        mavlink.CAMERA_TRACKING_TARGET_DATA_IN_STATUS, x, y, nan, *rect, 0)


def image_captured(view: GcuView, index: int) -> Any:
    """CAMERA_IMAGE_CAPTURED for a photo the GCU confirmed: geotagged with the aircraft
    position while it is current (else zeros), the camera's earth-frame attitude while the
    INS data are valid (else NaN), UTC from the autopilot's SYSTEM_TIME (else 0)."""
    position = view.aircraft.position if view.position_current else None
    if position is None:
        lat = lon = alt = rel = 0
    else:
        lat, lon = round(position.latitude * 1e7), round(position.longitude * 1e7)
        alt = round(position.altitude * 1000)
        rel = round((view.aircraft.relative_altitude or 0.0) * 1000)
    return mavlink.MAVLink_camera_image_captured_message(
        view.time_boot_ms, view.utc_usec, 0, lat, lon, alt, rel, camera_q(view), index, 1,
        b"")


MESSAGES = {
    mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION: camera_information,
    mavlink.MAVLINK_MSG_ID_CAMERA_SETTINGS: camera_settings,
    mavlink.MAVLINK_MSG_ID_CAMERA_CAPTURE_STATUS: capture_status,
    mavlink.MAVLINK_MSG_ID_STORAGE_INFORMATION: storage_information,
    mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_INFORMATION: video_stream_information,
    mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_STATUS: video_stream_status,
    mavlink.MAVLINK_MSG_ID_CAMERA_FOV_STATUS: fov_status,
    mavlink.MAVLINK_MSG_ID_CAMERA_TRACKING_IMAGE_STATUS: (
        lambda view, config: tracking_status(view)),
}
"""Message id → builder, for MAV_CMD_REQUEST_MESSAGE."""

LEGACY_REQUESTS = {
    mavlink.MAV_CMD_REQUEST_CAMERA_INFORMATION: mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION,
    mavlink.MAV_CMD_REQUEST_CAMERA_SETTINGS: mavlink.MAVLINK_MSG_ID_CAMERA_SETTINGS,
    mavlink.MAV_CMD_REQUEST_STORAGE_INFORMATION: mavlink.MAVLINK_MSG_ID_STORAGE_INFORMATION,
    mavlink.MAV_CMD_REQUEST_CAMERA_CAPTURE_STATUS: mavlink.MAVLINK_MSG_ID_CAMERA_CAPTURE_STATUS,
    mavlink.MAV_CMD_REQUEST_VIDEO_STREAM_INFORMATION:
        mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_INFORMATION,
    mavlink.MAV_CMD_REQUEST_VIDEO_STREAM_STATUS: mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_STATUS,
}
"""The deprecated request commands some ground stations still send → the message id."""


# -- commands in ----------------------------------------------------------------------------
def _unsupported(view: GcuView, opcode: Opcode) -> Plan | None:
    if view.supports(opcode):
        return None
    model = view.pod_model
    name = pod_name(model) if model is not None else "the pod"
    return refuse(UNSUPPORTED, f"{name} does not support {opcode.name} (Appendix 8)")


def _fraction(value: float) -> bool:
    return math.isfinite(value) and 0.0 <= value <= 1.0


def zoom_plan(cmd: CommandIn, view: GcuView, config: CameraConfig) -> Plan:
    """MAV_CMD_SET_CAMERA_ZOOM: param1 ZOOM_TYPE, param2 value. CONTINUOUS −1/0/1 → zoom
    out/stop/in; RANGE 0–100 % → ``ZOOM_TO`` fraction (0 % → the minimum); STEP ±n → the current
    ratio ± n × :data:`ZOOM_STEP` (kept ≥ 1×, and ≤ max_zoom when known); focal length
    and field of view: UNSUPPORTED (the GCU takes neither)."""
    kind, value = cmd.param(1), cmd.param(2)
    if not math.isfinite(value):
        return refuse(DENIED, f"zoom value {value!r} is not finite")
    if kind == mavlink.ZOOM_TYPE_CONTINUOUS:
        if value not in (-1.0, 0.0, 1.0):
            return refuse(DENIED, f"continuous zoom {value:g}: expected -1, 0 or 1")
        method = {-1.0: "zoom_out", 0.0: "stop_zoom", 1.0: "zoom_in"}[value]
        return run(GcuCall(method))
    if kind == mavlink.ZOOM_TYPE_RANGE:
        if not 0.0 <= value <= 100.0:
            return refuse(DENIED, f"zoom range {value:g}: outside [0, 100] %")
        refused = _unsupported(view, Opcode.ZOOM_TO)
        if refused is not None:
            return refused
        return run(GcuCall("zoom_to_fraction", {"fraction": max(value / 100.0, 1e-4)}))
    if kind == mavlink.ZOOM_TYPE_STEP:
        if value != int(value) or value == 0:
            return refuse(DENIED, f"zoom step {value:g}: expected a non-zero whole number")
        refused = _unsupported(view, Opcode.ZOOM_TO)
        if refused is not None:
            return refused
        current = view.info.camera1_zoom if view.info is not None else 1.0
        ratio = max(1.0, current + value * ZOOM_STEP)
        if config.max_zoom is not None:
            ratio = min(ratio, config.max_zoom)
        return run(GcuCall("zoom_to", {"ratio": ratio}))
    return refuse(UNSUPPORTED, f"zoom type {kind:g}: the GCU takes ratios and fractions only")


def focus_plan(cmd: CommandIn, view: GcuView) -> Plan:
    """MAV_CMD_SET_CAMERA_FOCUS: AUTO and AUTO_SINGLE → one ``FOCUS``; the other types
    (manual, continuous auto) have no GCU command: UNSUPPORTED."""
    kind = cmd.param(1)
    if kind not in (mavlink.FOCUS_TYPE_AUTO, mavlink.FOCUS_TYPE_AUTO_SINGLE):
        return refuse(UNSUPPORTED, f"focus type {kind:g}: the GCU only triggers autofocus")
    return _unsupported(view, Opcode.FOCUS) or run(GcuCall("focus"))


def source_plan(cmd: CommandIn, view: GcuView, config: CameraConfig) -> Plan:
    """MAV_CMD_SET_CAMERA_SOURCE: param2/param3 primary/secondary CAMERA_SOURCE → the
    picture-in-picture mode of :attr:`CameraConfig.pip_modes`; an infrared source on a pod
    without a thermal camera is UNSUPPORTED, a pair not in the table DENIED."""
    primary, secondary = cmd.param(2), cmd.param(3)
    if not (math.isfinite(primary) and math.isfinite(secondary)):
        return refuse(DENIED, "camera sources must be finite")
    pair = (int(primary), int(secondary))
    model = view.pod_model
    if IR in pair and model is not None and not is_thermal(model):
        return refuse(UNSUPPORTED, f"{pod_name(model)} has no thermal camera")
    mode = config.pip_modes.get(pair)
    if mode is None:
        return refuse(DENIED, f"sources {pair}: no picture-in-picture mode shows them")
    return _unsupported(view, Opcode.PICTURE_IN_PICTURE) or run(
        GcuCall("set_picture_in_picture", {"mode": mode}))


def track_plan(cmd: CommandIn, view: GcuView) -> Plan:
    """MAV_CMD_CAMERA_TRACK_POINT (param1/2 x/y, param3 radius; a square box of that
    half-side, :data:`TRACK_POINT_RADIUS` for 0, cut at the image edges) and
    MAV_CMD_CAMERA_TRACK_RECTANGLE (param1–4 left, top, right, bottom) → ``track``;
    image fractions 0–1, anything else DENIED."""
    refused = _unsupported(view, Opcode.TRACK)
    if refused is not None:
        return refused
    if cmd.command == mavlink.MAV_CMD_CAMERA_TRACK_POINT:
        x, y, radius = cmd.param(1), cmd.param(2), cmd.param(3)
        if not (_fraction(x) and _fraction(y) and _fraction(radius)):
            return refuse(DENIED, f"track point ({x}, {y}, radius {radius}): fractions 0-1")
        r = radius or TRACK_POINT_RADIUS
        box = (max(0.0, x - r), max(0.0, y - r), min(1.0, x + r), min(1.0, y + r))
        mode = mavlink.CAMERA_TRACKING_MODE_POINT
    else:
        box = (cmd.param(1), cmd.param(2), cmd.param(3), cmd.param(4))
        if not all(_fraction(v) for v in box) or box[0] >= box[2] or box[1] >= box[3]:
            return refuse(DENIED, f"track rectangle {box}: fractions 0-1, left < right, "
                          "top < bottom")  # fmt: skip
        mode = mavlink.CAMERA_TRACKING_MODE_RECTANGLE
    return run(GcuCall("track", {"box": box}, mode=Mode.TRACK, tracking_mode=mode))


def command_plan(cmd: CommandIn, view: GcuView, config: CameraConfig) -> Plan | None:
    """The plan for a camera command (``None``: not a camera command)."""
    c = cmd.command
    if c == mavlink.MAV_CMD_IMAGE_START_CAPTURE:
        count = cmd.param(3)
        if count != 1:
            return refuse(UNSUPPORTED, f"{count:g} images: only single captures (count 1)")
        return run(GcuCall("take_photo", then="image_captured"))
    if c == mavlink.MAV_CMD_IMAGE_STOP_CAPTURE:
        return Plan(ACCEPTED)  # single captures only: nothing runs to stop
    if c == mavlink.MAV_CMD_VIDEO_START_CAPTURE:
        return run(GcuCall("start_recording"))
    if c == mavlink.MAV_CMD_VIDEO_STOP_CAPTURE:
        return run(GcuCall("stop_recording"))
    if c == mavlink.MAV_CMD_SET_CAMERA_ZOOM:
        return zoom_plan(cmd, view, config)
    if c == mavlink.MAV_CMD_SET_CAMERA_FOCUS:
        return focus_plan(cmd, view)
    if c == mavlink.MAV_CMD_SET_CAMERA_SOURCE:
        return source_plan(cmd, view, config)
    if c in (mavlink.MAV_CMD_CAMERA_TRACK_POINT, mavlink.MAV_CMD_CAMERA_TRACK_RECTANGLE):
        return track_plan(cmd, view)
    if c == mavlink.MAV_CMD_CAMERA_STOP_TRACKING:
        return _unsupported(view, Opcode.TRACK) or run(GcuCall("stop_tracking"))
    if c == mavlink.MAV_CMD_VIDEO_START_STREAMING:
        if config.video_url is None:
            return refuse(UNSUPPORTED, "no video stream configured")
        return Plan(ACCEPTED)  # the GCU's stream runs all the time
    if c == mavlink.MAV_CMD_VIDEO_STOP_STREAMING:
        return refuse(UNSUPPORTED, "the GCU's video stream cannot be stopped")
    if c == mavlink.MAV_CMD_SET_CAMERA_MODE:
        mode = cmd.param(2)
        if mode not in (mavlink.CAMERA_MODE_IMAGE, mavlink.CAMERA_MODE_VIDEO):
            return refuse(DENIED, f"camera mode {mode:g}: image (0) or video (1)")
        return Plan(ACCEPTED, camera_mode=int(mode))  # the GCU has no modes: both work
    return None
