"""The gimbal component (MAV_COMP_ID_GIMBAL): gimbal manager and gimbal device in one.

Pure: messages out are built from a :class:`~gcu_async.bridge.view.GcuView`; messages and
commands in become a :class:`~gcu_async.bridge.commands.GcuCall` or a
:class:`~gcu_async.bridge.commands.Plan` (docs/mavlink-bridge.md, "Gimbal").

The XF gimbal is not a MAVLink device, so the manager speaks for it with gimbal device id
:data:`DEVICE_ID` (MAVLink's 1–6 "non-MAVLink gimbal" range); commands naming device 0
(all) or 1 are taken, any other id is denied.

Control requests map onto the GCU's modes:

=====================================  ===============================================
request                                client call (mode)
=====================================  ===============================================
angles, yaw lock (earth frame)         ``enter_euler_control`` (Euler control)
angles, yaw follow (vehicle frame)     ``enter_angle_control`` (angle control)
rates only, yaw lock                   ``enter_pointing_lock`` (pointing lock)
rates only, yaw follow                 ``enter_pointing_follow`` (pointing follow)
neither (all NaN)                      ``release_control`` (values invalid: hold)
NEUTRAL flag                           ``centre``
=====================================  ===============================================

Once the pod reports the mode the bridge set (or while that mode command is pending),
further requests of the same kind only change the control values (``set_angles`` /
``set_rates``): a ground station's joystick stream does not become a stream of mode
commands.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

from gcu_async.bridge._mavlink import mavlink
from gcu_async.bridge.commands import (
    ACCEPTED,
    DENIED,
    TEMPORARILY_REJECTED,
    UNSUPPORTED,
    CommandIn,
    GcuCall,
    Plan,
    refuse,
    run,
)
from gcu_async.bridge.geometry import euler_from_quaternion, quaternion_from_euler
from gcu_async.bridge.view import Control, GcuView
from gcu_async.protocol.enums import FaultFlags, Mode
from gcu_async.protocol.gcu_frame_tables import GCU_MAIN_SCHEMA
from gcu_async.protocol.pods import pod_name
from gcu_async.protocol.units import wrap_degrees_180

COMPONENT = mavlink.MAV_COMP_ID_GIMBAL
DEVICE_ID = 1
"""The gimbal device id the manager uses for the XF gimbal."""
VENDOR = "XF Robot"

ROLL_LOCK = mavlink.GIMBAL_DEVICE_FLAGS_ROLL_LOCK
PITCH_LOCK = mavlink.GIMBAL_DEVICE_FLAGS_PITCH_LOCK
YAW_LOCK = mavlink.GIMBAL_DEVICE_FLAGS_YAW_LOCK
YAW_IN_VEHICLE_FRAME = mavlink.GIMBAL_DEVICE_FLAGS_YAW_IN_VEHICLE_FRAME
YAW_IN_EARTH_FRAME = mavlink.GIMBAL_DEVICE_FLAGS_YAW_IN_EARTH_FRAME
NEUTRAL = mavlink.GIMBAL_MANAGER_FLAGS_NEUTRAL
RETRACT = mavlink.GIMBAL_MANAGER_FLAGS_RETRACT

CAP_FLAGS = (
    mavlink.GIMBAL_MANAGER_CAP_FLAGS_HAS_NEUTRAL
    | mavlink.GIMBAL_MANAGER_CAP_FLAGS_HAS_ROLL_AXIS
    | mavlink.GIMBAL_MANAGER_CAP_FLAGS_HAS_ROLL_LOCK
    | mavlink.GIMBAL_MANAGER_CAP_FLAGS_HAS_PITCH_AXIS
    | mavlink.GIMBAL_MANAGER_CAP_FLAGS_HAS_PITCH_LOCK
    | mavlink.GIMBAL_MANAGER_CAP_FLAGS_HAS_YAW_AXIS
    | mavlink.GIMBAL_MANAGER_CAP_FLAGS_HAS_YAW_FOLLOW
    | mavlink.GIMBAL_MANAGER_CAP_FLAGS_HAS_YAW_LOCK
    | mavlink.GIMBAL_MANAGER_CAP_FLAGS_SUPPORTS_YAW_IN_EARTH_FRAME
    | mavlink.GIMBAL_MANAGER_CAP_FLAGS_CAN_POINT_LOCATION_GLOBAL
)
"""What the manager offers: 3 axes (roll and pitch locked to the horizon, yaw lock or
follow), neutral (the GCU's centre command), pointing at a global location (gaze)."""
DEVICE_CAP_FLAGS = CAP_FLAGS & 0xFFFF
"""GIMBAL_DEVICE_INFORMATION's 16-bit cap_flags (the same bits)."""

_YAW_SPAN = GCU_MAIN_SCHEMA.by_name["yaw_raw"].limits[1]
ANGLE_LIMITS_DEG = (GCU_MAIN_SCHEMA.by_name["roll_raw"].limits,
                    GCU_MAIN_SCHEMA.by_name["pitch_raw"].limits,
                    (-_YAW_SPAN / 2, _YAW_SPAN / 2))  # fmt: skip
"""Roll, pitch, yaw limits reported: the ranges of the GCU's attitude fields (V2.0.6 gives
no mechanical limits per pod), yaw as MAVLink's signed equivalent of the full turn."""

YAW_LOCKED_MODES = frozenset({Mode.POINTING_LOCK, Mode.EULER_CONTROL, Mode.GAZE, Mode.TRACK})
"""Modes whose yaw holds an earth-fixed direction (the others follow the aircraft)."""

FAULT_FAILURES: tuple[tuple[int, int], ...] = (
    (FaultFlags.POD_HARDWARE, mavlink.GIMBAL_DEVICE_ERROR_FLAGS_MOTOR_ERROR),
    (FaultFlags.GCU_HARDWARE, mavlink.GIMBAL_DEVICE_ERROR_FLAGS_SOFTWARE_ERROR),
    (FaultFlags.MAVLINK_RATE, mavlink.GIMBAL_DEVICE_ERROR_FLAGS_COMMS_ERROR),
)
"""GCU fault bit (sub frame bytes 41–42) → GIMBAL_DEVICE_ERROR_FLAGS bit. GNSS_NO_FIX is
the aircraft's, not the gimbal's: it has no failure flag."""


def encode_version(raw: int) -> int:
    """A GCU version byte (0.1 resolution: 0x1F = 3.1) as MAVLink's uint32 version:
    major in bits 0–7, minor in bits 8–15."""
    return (raw // 10) & 0xFF | (raw % 10 & 0xFF) << 8


def text(value: str, size: int = 32) -> bytes:
    """``value`` as a MAVLink char[size] (UTF-8, cut to ``size`` bytes)."""
    return value.encode("utf-8")[:size]


# -- messages out ---------------------------------------------------------------------------
def heartbeat(view: GcuView, mav_type: int) -> Any:
    """HEARTBEAT of a bridge component: ACTIVE while the GCU answers, CRITICAL while not."""
    state = mavlink.MAV_STATE_ACTIVE if view.link_up else mavlink.MAV_STATE_CRITICAL
    return mavlink.MAVLink_heartbeat_message(mav_type, mavlink.MAV_AUTOPILOT_INVALID, 0, 0,
                                             state, 3)  # fmt: skip


def manager_information(view: GcuView) -> Any:
    """GIMBAL_MANAGER_INFORMATION: capabilities and angle limits (rad)."""
    (r0, r1), (p0, p1), (y0, y1) = ((math.radians(a), math.radians(b))
                                    for a, b in ANGLE_LIMITS_DEG)  # fmt: skip
    return mavlink.MAVLink_gimbal_manager_information_message(
        view.time_boot_ms, CAP_FLAGS, DEVICE_ID, r0, r1, p0, p1, y0, y1)


def device_information(view: GcuView) -> Any:
    """GIMBAL_DEVICE_INFORMATION: vendor, model (the pod code's name), versions, limits."""
    info = view.info
    model = "unknown (no reply yet)" if info is None else pod_name(info.pod_code)
    firmware = 0 if info is None else encode_version(info.firmware_version_raw)
    hardware = 0 if info is None else encode_version(info.hardware_version_raw)
    (r0, r1), (p0, p1), (y0, y1) = ((math.radians(a), math.radians(b))
                                    for a, b in ANGLE_LIMITS_DEG)  # fmt: skip
    return mavlink.MAVLink_gimbal_device_information_message(
        view.time_boot_ms, text(VENDOR), text(model), b"", firmware, hardware, 0,
        DEVICE_CAP_FLAGS, 0, r0, r1, p0, p1, y0, y1, DEVICE_ID)


def lock_flags(view: GcuView) -> int:
    """ROLL_LOCK | PITCH_LOCK (stabilised) except in FPV; YAW_LOCK in the yaw-locked modes."""
    mode = view.mode
    flags = 0 if mode is Mode.FPV else ROLL_LOCK | PITCH_LOCK
    if mode in YAW_LOCKED_MODES:
        flags |= YAW_LOCK
    return flags


def failure_flags(view: GcuView) -> int:
    """GIMBAL_DEVICE_ERROR_FLAGS: COMMS_ERROR while the GCU link is down, plus the GCU's
    fault bits (:data:`FAULT_FAILURES`)."""
    flags = 0 if view.link_up else mavlink.GIMBAL_DEVICE_ERROR_FLAGS_COMMS_ERROR
    if view.info is not None:
        for fault, failure in FAULT_FAILURES:
            if view.info.fault_raw & fault:
                flags |= failure
    return flags


def device_attitude_status(view: GcuView) -> Any | None:
    """GIMBAL_DEVICE_ATTITUDE_STATUS (``None`` before the first GCU reply).

    While the host packets mark the aircraft's INS data valid, the GCU's absolute attitude
    is earth-referenced: the quaternion is that attitude with YAW_IN_EARTH_FRAME, and
    delta_yaw the yaw relative to the aircraft. Otherwise the yaw is the relative one
    (YAW_IN_VEHICLE_FRAME) and delta_yaw NaN. Roll and pitch are always the GCU's absolute
    ones (horizon-referenced). Angular velocity: roll rate = Y-axis rate, pitch rate =
    −X-axis rate, yaw rate = Z-axis rate (Appendix 4's axes), rad/s."""
    status = view.status
    if status is None:
        return None
    att = status.attitude
    relative_yaw = wrap_degrees_180(status.relative_angles.z)
    flags = lock_flags(view)
    if view.ins_valid:
        q = quaternion_from_euler(att.roll, att.pitch, att.yaw)
        flags |= YAW_IN_EARTH_FRAME
        delta_yaw = math.radians(relative_yaw)
    else:
        q = quaternion_from_euler(att.roll, att.pitch, relative_yaw)
        flags |= YAW_IN_VEHICLE_FRAME
        delta_yaw = math.nan
    rates = status.angular_rates
    return mavlink.MAVLink_gimbal_device_attitude_status_message(
        0, 0, view.time_boot_ms, flags, q, math.radians(rates.y), math.radians(-rates.x),
        math.radians(rates.z), failure_flags(view), delta_yaw, math.nan, DEVICE_ID)


def manager_status(view: GcuView) -> Any:
    """GIMBAL_MANAGER_STATUS: the mode's lock flags and who is in control."""
    control = view.control
    return mavlink.MAVLink_gimbal_manager_status_message(
        view.time_boot_ms, lock_flags(view), DEVICE_ID, *control.primary, *control.secondary)


# -- control requests in --------------------------------------------------------------------
def attitude_call(
    view: GcuView,
    *,
    roll: float = 0.0,
    pitch: float = math.nan,
    yaw: float = math.nan,
    pitch_rate: float = math.nan,
    yaw_rate: float = math.nan,
    yaw_lock: bool,
) -> GcuCall:
    """The client call for an attitude request in degrees and °/s (NaN: not given). Angles
    win over rates when both are given (the GCU takes one or the other); a missing angle
    keeps the current one; yaw is wrapped signed
    (:func:`~gcu_async.protocol.units.wrap_degrees_180`, the same direction)."""
    if math.isfinite(pitch) or math.isfinite(yaw):
        status = view.status
        if yaw_lock:
            current_pitch = status.attitude.pitch if status else 0.0
            current_yaw = status.attitude.yaw if status else 0.0
        else:
            current_pitch = status.attitude.pitch if status else 0.0
            current_yaw = status.relative_angles.z if status else 0.0
        angles = {
            "roll": roll,
            "pitch": pitch if math.isfinite(pitch) else current_pitch,
            "yaw": wrap_degrees_180(yaw if math.isfinite(yaw) else current_yaw),
        }
        mode = Mode.EULER_CONTROL if yaw_lock else Mode.ANGLE_CONTROL
        if view.in_mode(mode):
            return GcuCall("set_angles", angles)
        method = "enter_euler_control" if yaw_lock else "enter_angle_control"
        return GcuCall(method, angles, mode=mode)
    if math.isfinite(pitch_rate) or math.isfinite(yaw_rate):
        rates = (pitch_rate if math.isfinite(pitch_rate) else 0.0,
                 yaw_rate if math.isfinite(yaw_rate) else 0.0)  # fmt: skip
        mode = Mode.POINTING_LOCK if yaw_lock else Mode.POINTING_FOLLOW
        if view.in_mode(mode):
            return GcuCall("set_rates", {"pitch": rates[0], "yaw": rates[1]})
        method = "enter_pointing_lock" if yaw_lock else "enter_pointing_follow"
        return GcuCall(method, {"pitch_rate": rates[0], "yaw_rate": rates[1]}, mode=mode)
    return GcuCall("release_control")


def flag_call(flags: int) -> GcuCall | None:
    """NEUTRAL → centre; RETRACT has no GCU command (``ValueError``); else ``None``."""
    if flags & RETRACT:
        raise ValueError("flags: RETRACT has no XF gimbal command")
    if flags & NEUTRAL:
        return GcuCall("centre", mode=None)
    return None


CONTROL_MESSAGES = frozenset({"GIMBAL_MANAGER_SET_ATTITUDE", "GIMBAL_MANAGER_SET_PITCHYAW",
                              "GIMBAL_DEVICE_SET_ATTITUDE"})  # fmt: skip
"""The gimbal control messages :func:`message_call` takes."""


def message_call(msg: Any, view: GcuView) -> GcuCall | None:
    """The client call for a gimbal control message addressed to this component
    (GIMBAL_MANAGER_SET_ATTITUDE, GIMBAL_MANAGER_SET_PITCHYAW, GIMBAL_DEVICE_SET_ATTITUDE);
    ``None`` when the message is not one of them, names another gimbal device, or comes
    from a component not in control. Raises ``ValueError`` for a malformed request (logged
    by the bridge: messages get no acknowledgement)."""
    kind = msg.get_type()
    if kind not in CONTROL_MESSAGES:
        return None
    if not view.control.allows((msg.get_srcSystem(), msg.get_srcComponent())):
        return None
    if getattr(msg, "gimbal_device_id", 0) not in (0, DEVICE_ID):
        return None
    flags = int(msg.flags)
    special = flag_call(flags)
    if special is not None:
        return special
    yaw_lock = bool(flags & (YAW_LOCK | YAW_IN_EARTH_FRAME))
    if kind == "GIMBAL_MANAGER_SET_PITCHYAW":
        return attitude_call(
            view, pitch=math.degrees(msg.pitch), yaw=math.degrees(msg.yaw),
            pitch_rate=math.degrees(msg.pitch_rate), yaw_rate=math.degrees(msg.yaw_rate),
            yaw_lock=yaw_lock)  # fmt: skip
    q = list(msg.q)
    rates = (msg.angular_velocity_y, msg.angular_velocity_z)
    if all(math.isfinite(c) for c in q):
        att = euler_from_quaternion(q)
        return attitude_call(view, roll=att.roll, pitch=att.pitch, yaw=att.yaw,
                             yaw_lock=yaw_lock)  # fmt: skip
    return attitude_call(view, pitch_rate=math.degrees(rates[0]),
                         yaw_rate=math.degrees(rates[1]), yaw_lock=yaw_lock)  # fmt: skip


def _device_ok(value: float) -> bool:
    return not math.isfinite(value) or int(value) in (0, DEVICE_ID)


def pitchyaw_plan(cmd: CommandIn, view: GcuView) -> Plan:
    """MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW: param1/2 pitch/yaw (deg), param3/4 rates
    (deg/s), param5 flags, param7 device id."""
    if not view.control.allows(cmd.source):
        return refuse(DENIED, "another component controls the gimbal")
    if not _device_ok(cmd.param(7)):
        return refuse(DENIED, f"gimbal device {cmd.param(7):g} is not this gimbal ({DEVICE_ID})")
    flags = int(cmd.param(5)) if math.isfinite(cmd.param(5)) else 0
    try:
        special = flag_call(flags)
    except ValueError as exc:
        return refuse(UNSUPPORTED, str(exc))
    if special is not None:
        return run(special)
    return run(attitude_call(view, pitch=cmd.param(1), yaw=cmd.param(2),
                             pitch_rate=cmd.param(3), yaw_rate=cmd.param(4),
                             yaw_lock=bool(flags & (YAW_LOCK | YAW_IN_EARTH_FRAME))))  # fmt: skip


def configure(cmd: CommandIn, control: Control) -> Control | None:
    """MAV_CMD_DO_GIMBAL_MANAGER_CONFIGURE: the new controllers, or ``None`` for invalid
    parameters. Per controller (param1/2 primary, param3/4 secondary): −1 leaves it, −2
    makes the sender the controller, −3 releases it if the sender holds it, ≥ 0 sets the
    given system/component id."""
    def one(sysid: float, compid: float, current: tuple[int, int]) -> tuple[int, int] | None:
        if not (math.isfinite(sysid) and math.isfinite(compid)):
            return None
        s, c = int(sysid), int(compid)
        if s == -1:
            return current
        if s == -2:
            return cmd.source
        if s == -3:
            return (0, 0) if current == cmd.source else current
        if 0 <= s <= 255 and 0 <= c <= 255:
            return (s, c)
        return None

    if not _device_ok(cmd.param(7)):
        return None
    primary = one(cmd.param(1), cmd.param(2), control.primary)
    secondary = one(cmd.param(3), cmd.param(4), control.secondary)
    if primary is None or secondary is None:
        return None
    return Control(primary, secondary)


def roi_location_plan(cmd: CommandIn, view: GcuView) -> Plan:
    """MAV_CMD_DO_SET_ROI_LOCATION → ``gaze_at``: param1 device id, param5/6 latitude and
    longitude, param7 altitude. COMMAND_INT in MAV_FRAME_GLOBAL(_INT) takes the altitude as
    MSL; in MAV_FRAME_GLOBAL_RELATIVE_ALT(_INT), and in a COMMAND_LONG (which carries no
    frame; MAVSDK and QGroundControl send heights above home there), as metres above the
    home point the autopilot reported (TEMPORARILY_REJECTED until it did)."""
    if not view.control.allows(cmd.source):
        return refuse(DENIED, "another component controls the gimbal")
    if not _device_ok(cmd.param(1)):
        return refuse(DENIED, f"gimbal device {cmd.param(1):g} is not this gimbal")
    lat, lon = cmd.latitude_longitude()
    alt = cmd.param(7)
    if not all(math.isfinite(v) for v in (lat, lon, alt)):
        return refuse(DENIED, "latitude, longitude and altitude must be finite")
    if cmd.frame in (mavlink.MAV_FRAME_GLOBAL, mavlink.MAV_FRAME_GLOBAL_INT):
        msl = alt
    elif cmd.frame in (None, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                       mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT):  # fmt: skip
        if view.home_altitude is None:
            return refuse(TEMPORARILY_REJECTED, "no home altitude from the autopilot yet")
        msl = view.home_altitude + alt
    else:
        return refuse(UNSUPPORTED, f"frame {cmd.frame}: only global frames are supported")
    return run(GcuCall("gaze_at", {"latitude": lat, "longitude": lon, "altitude": msl},
                       mode=Mode.GAZE))  # fmt: skip


def roi_none_plan(cmd: CommandIn, view: GcuView) -> Plan:
    """MAV_CMD_DO_SET_ROI_NONE: stop gazing; the camera follows the aircraft again
    (``enter_pointing_follow`` with zero rates)."""
    if not view.control.allows(cmd.source):
        return refuse(DENIED, "another component controls the gimbal")
    if not _device_ok(cmd.param(1)):
        return refuse(DENIED, f"gimbal device {cmd.param(1):g} is not this gimbal")
    return run(GcuCall("enter_pointing_follow", {"pitch_rate": 0.0, "yaw_rate": 0.0},
                       mode=Mode.POINTING_FOLLOW))  # fmt: skip


MESSAGES = {
    mavlink.MAVLINK_MSG_ID_GIMBAL_MANAGER_INFORMATION: manager_information,
    mavlink.MAVLINK_MSG_ID_GIMBAL_MANAGER_STATUS: manager_status,
    mavlink.MAVLINK_MSG_ID_GIMBAL_DEVICE_INFORMATION: device_information,
    mavlink.MAVLINK_MSG_ID_GIMBAL_DEVICE_ATTITUDE_STATUS: device_attitude_status,
}
"""Message id → builder, for MAV_CMD_REQUEST_MESSAGE."""


def command_plan(cmd: CommandIn, view: GcuView) -> Plan | None:
    """The plan for a gimbal command (``None``: not a gimbal command)."""
    if cmd.command == mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW:
        return pitchyaw_plan(cmd, view)
    if cmd.command == mavlink.MAV_CMD_DO_SET_ROI_LOCATION:
        return roi_location_plan(cmd, view)
    if cmd.command == mavlink.MAV_CMD_DO_SET_ROI_NONE:
        return roi_none_plan(cmd, view)
    if cmd.command == mavlink.MAV_CMD_DO_GIMBAL_MANAGER_CONFIGURE:
        control = configure(cmd, view.control)
        if control is None:
            return refuse(DENIED, "invalid controller ids")
        # the new controllers at once, not at the next streamed status
        return Plan(ACCEPTED, control=control,
                    replies=(manager_status(replace(view, control=control)),))
    return None

