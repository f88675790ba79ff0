"""The GCU's answer frames built from the simulator state (raw wire integers)."""

from __future__ import annotations

from gcu_async.protocol.enums import Mode, PodStatus
from gcu_async.protocol.gcu_frames import GcuMainFrame, GcuSubFrame
from gcu_async.protocol.layout import S16, S32
from gcu_async.protocol.units import wrap_degrees_360
from gcu_async.sim.profiles import PodProfile
from gcu_async.sim.state import SimState


def _clamp(value: int, low: int, high: int) -> int:
    return min(max(value, low), high)


def _wrap_centi(degrees: float) -> int:
    """Degrees → 0.01° wrapped into [-18000, 18000)."""
    return (round(degrees * 100) + 18000) % 36000 - 18000


def pod_status(state: SimState) -> int:
    """Main frame bytes 6–7."""
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


def main_frame(state: SimState) -> GcuMainFrame:
    """GCU main frame, bytes 5–36."""
    g = state.gimbal
    rel = state.relative_axes
    att = state.attitude
    roll_rate, pitch_rate, yaw_rate = g.rates
    return GcuMainFrame(
        int(g.mode),
        pod_status(state),
        g.miss[0],
        g.miss[1],
        _wrap_centi(rel.x),
        _wrap_centi(rel.y),
        _wrap_centi(rel.z),
        _clamp(round(att.roll * 100), -9000, 9000),
        _wrap_centi(att.pitch),
        round(wrap_degrees_360(att.yaw) * 100) % 36000,
        _clamp(round(-pitch_rate * 10), *S16),
        _clamp(round(roll_rate * 10), *S16),
        _clamp(round(yaw_rate * 10), *S16),
    )


def sub_frame(state: SimState, profile: PodProfile) -> GcuSubFrame:
    """GCU sub frame 0x01, bytes 38–68."""
    cam, rf = state.camera, state.rangefinder
    distance = 0 if not rf.on else _clamp(round(rf.distance * 10), *S32)
    lat = lon = alt = 0
    if rf.valid and rf.position is not None:
        lat = round(rf.position.latitude * 1e7)
        lon = round(rf.position.longitude * 1e7)
        alt = _clamp(round(rf.position.altitude * 1000), *S32)
    zoom = state.zoom
    return GcuSubFrame(
        round(profile.hardware_version * 10),
        round(profile.firmware_version * 10),
        int(profile.model),
        state.faults & 0xFFFF,
        distance,
        lon,
        lat,
        alt,
        _clamp(round(zoom.get(1, 0.0) * 10), 0, 0xFFFF),
        _clamp(round(zoom.get(2, 0.0) * 10), 0, 0xFFFF),
        cam.thermal_flags(profile.radiometric),
        cam.camera_flags() | (cam.pip_mode & 0x07),
        _clamp(cam.time_zone, -128, 127),
    )
