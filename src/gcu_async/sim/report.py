"""The GCU's answer frames built from the simulator state (raw wire integers)."""

from __future__ import annotations

from gcu_async.protocol.enums import PIP_MODE_MASK, FaultFlags, Mode, PodStatus
from gcu_async.protocol.fields import WireField
from gcu_async.protocol.gcu_frame_tables import CAMERA_YAW, GCU_MAIN_SCHEMA, GCU_SUB_SCHEMA
from gcu_async.protocol.gcu_frames import GcuMainFrame, GcuSubFrame
from gcu_async.sim.firmware import Firmware
from gcu_async.sim.profiles import PodProfile
from gcu_async.sim.state import SimState

_M, _S = GCU_MAIN_SCHEMA.by_name, GCU_SUB_SCHEMA.by_name
_YAW = _M["yaw_raw"]


def _clamped(field: WireField, value: float) -> int:
    """``value`` in the field's units → its raw integer, held inside the field's range (the
    simulated pod reports the nearest value the field can carry)."""
    return min(max(round(value * field.scale), field.raw_low), field.raw_high)


def _wrapped(field: WireField, degrees: float) -> int:
    """Degrees → the raw angle of a full-turn field, wrapped into its range (half a turn
    either way for the signed fields, one turn from 0 for the yaw)."""
    turn = field.raw_high + 1 - field.raw_low
    return (round(degrees * field.scale) - field.raw_low) % turn + field.raw_low


def pod_status(state: SimState) -> int:
    """The main frame's pod status flags."""
    flags = PodStatus(0)
    g, cam, rf = state.gimbal, state.camera, state.rangefinder
    if g.mode == Mode.TRACK and g.track is not None:
        flags |= PodStatus.TRACKING_OK
    if rf.valid:
        flags |= PodStatus.RANGE_VALID
    if rf.on:
        flags |= PodStatus.RANGING_ON
    if cam.night_vision_on:
        flags |= PodStatus.NIGHT_VISION_ON
    if cam.fill_light > 0:
        flags |= PodStatus.FILL_LIGHT_ON
    if state.inverted:
        flags |= PodStatus.INVERTED
    return int(flags)


def main_frame(state: SimState, firmware: Firmware) -> GcuMainFrame:
    """GCU main frame, bytes 5–36 (the camera yaw as ``firmware`` sends it)."""
    g = state.gimbal
    rel = state.relative_axes
    att = state.attitude
    yaw = CAMERA_YAW.signed_raw(att.yaw) if firmware.signed_yaw else _wrapped(_YAW, att.yaw)
    roll_rate, pitch_rate, yaw_rate = g.rates
    return GcuMainFrame(
        int(g.mode),
        pod_status(state),
        g.miss[0],
        g.miss[1],
        _wrapped(_M["relative_x_raw"], rel.x),
        _wrapped(_M["relative_y_raw"], rel.y),
        _wrapped(_M["relative_z_raw"], rel.z),
        _clamped(_M["roll_raw"], att.roll),
        _wrapped(_M["pitch_raw"], att.pitch),
        yaw,
        _clamped(_M["rate_x_raw"], -pitch_rate),
        _clamped(_M["rate_y_raw"], roll_rate),
        _clamped(_M["rate_z_raw"], yaw_rate),
    )


def sub_frame(state: SimState, profile: PodProfile, firmware: Firmware) -> GcuSubFrame:
    """GCU sub frame 0x01, bytes 38–68 (versions and faults as ``firmware`` reports them)."""
    cam, rf = state.camera, state.rangefinder
    distance = 0 if not rf.on else _clamped(_S["target_distance_raw"], rf.distance)
    lat = lon = alt = 0
    if rf.valid and rf.position is not None:
        lat = _clamped(_S["target_latitude_raw"], rf.position.latitude)
        lon = _clamped(_S["target_longitude_raw"], rf.position.longitude)
        alt = _clamped(_S["target_altitude_raw"], rf.position.altitude)
    zoom = state.zoom
    hardware, version = firmware.versions or (profile.hardware_version, profile.firmware_version)
    faults = state.faults
    if firmware.gnss_fault and not state.aircraft.satellites:
        faults |= FaultFlags.GNSS_NO_FIX
    return GcuSubFrame(
        _clamped(_S["hardware_version_raw"], hardware),
        _clamped(_S["firmware_version_raw"], version),
        int(profile.model),
        faults & 0xFFFF,
        distance,
        lon,
        lat,
        alt,
        _clamped(_S["camera1_zoom_raw"], zoom.get(1, 0.0)),
        _clamped(_S["camera2_zoom_raw"], zoom.get(2, firmware.missing_camera_zoom)),
        cam.thermal_flags(profile.radiometric),
        cam.camera_flags() | (cam.pip_mode & PIP_MODE_MASK),
        _clamped(_S["time_zone"], cam.time_zone),
    )
