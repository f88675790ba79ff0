"""The GCU → host frame tables: main frame (bytes 5–36) and sub frame (bytes 37–68).

Each frame is one table, :data:`GCU_MAIN_SCHEMA` and :data:`GCU_SUB_SCHEMA`: its fields in
wire order and what the frame presents of them (:mod:`~gcu_async.protocol.frame_schema`).
The functions above the tables are the readings the tables cannot say. The frame classes
(:class:`~gcu_async.protocol.gcu_frames.GcuMainFrame`, ``GcuSubFrame``) are generated from
the tables into :mod:`~gcu_async.protocol.gcu_frames` by ``tools/gen_frames.py``.
"""

from __future__ import annotations

from dataclasses import replace

from gcu_async.protocol.enums import (
    PIP_MODE_MASK,
    CameraFlags,
    FaultFlags,
    Mode,
    PodModel,
    PodStatus,
    ThermalFlags,
)
from gcu_async.protocol.fields import (
    ANGLE_RANGE,
    CAMERA_ZOOM,
    CENTIDEGREE,
    LATITUDE_RANGE,
    LONGITUDE_RANGE,
    TILT_RANGE,
    WireField,
)
from gcu_async.protocol.frame_schema import Bit, Bits, Code, Flags, FrameSchema, Group, Value
from gcu_async.protocol.headings import HeadingRule, heading
from gcu_async.protocol.layout import MAIN_SIZE, MAIN_START, SUB_FRAME_HEADER, SUB_SIZE, SUB_START
from gcu_async.protocol.pods import pod_name
from gcu_async.protocol.units import Attitude, AxisAngles, GeoPosition, check_tuple, quantize

CAMERA_YAW = HeadingRule(heading("yaw_raw", "camera absolute yaw (a heading)"))
"""The camera's absolute yaw, and how any raw value reads as a heading
(:mod:`~gcu_async.protocol.headings`: the Z-1Pro sends a signed S16)."""


# -- the readings the tables cannot say ----------------------------------------------------
def camera_attitude(roll_raw: int, pitch_raw: int, yaw_raw: int) -> Attitude:
    """Camera absolute roll/pitch/yaw, degrees (needs valid aircraft INS data); the yaw a
    heading of its field's range whatever the pod sends (a signed S16 too:
    :data:`~gcu_async.protocol.gcu_frame_tables.CAMERA_YAW`, docs/protocol-notes.md "What real
    pods do"); ``yaw_raw`` keeps the wire value."""
    return Attitude(roll_raw / GCU_MAIN_SCHEMA["roll_raw"].scale,
                    pitch_raw / GCU_MAIN_SCHEMA["pitch_raw"].scale,
                    CAMERA_YAW.degrees(yaw_raw))  # fmt: skip


def tracked_miss(miss_x: int, miss_y: int, pod_status_raw: int) -> tuple[int, int] | None:
    """Horizontal (right +) and vertical (down +) miss distance, image centre = 0, or
    ``None`` unless a target is tracked (``PodStatus.TRACKING_OK``: only then are they valid);
    ``miss_x``/``miss_y`` keep the wire values."""
    return (miss_x, miss_y) if pod_status_raw & PodStatus.TRACKING_OK else None


def measured_distance(target_distance_raw: int) -> float | None:
    """Laser-ranged distance in metres, or ``None`` when there is no measurement (raw ≤ 0:
    the document's −1 or 0, docs/protocol-notes.md §7)."""
    raw = target_distance_raw
    return raw / GCU_SUB_SCHEMA["target_distance_raw"].scale if raw > 0 else None


def measured_position(target_latitude_raw: int, target_longitude_raw: int,
                      target_altitude_raw: int,
                      target_distance_raw: int) -> GeoPosition | None:  # fmt: skip
    """Ranged target position, or ``None`` when there is no measurement (as
    ``target_distance``); the ``target_*_raw`` fields keep the wire values."""
    if target_distance_raw <= 0:
        return None
    s = GCU_SUB_SCHEMA
    return GeoPosition(target_latitude_raw / s["target_latitude_raw"].scale,
                       target_longitude_raw / s["target_longitude_raw"].scale,
                       target_altitude_raw / s["target_altitude_raw"].scale)  # fmt: skip


def send_target_distance(target_distance: float | None = None) -> int:
    """``None`` sends "no measurement" (0); a distance is never negative."""
    if target_distance is None:
        return 0
    f = GCU_SUB_SCHEMA["target_distance_raw"]
    return quantize("target_distance", target_distance, f.scale, 0, f.raw_high, f.unit)


def send_target_position(
    target_position: GeoPosition | tuple[float, float, float] | None = None,
    target_distance: float | None = None,
) -> tuple[int, int, int]:
    """A position only with a distance (a measurement has both); ``None``: zeros."""
    if target_position is None:
        return (0, 0, 0)
    lat, lon, alt = check_tuple("target_position", target_position, GeoPosition)
    if target_distance is None:
        raise ValueError("target_position: a ranged position needs its target_distance "
                         "(without one the frame says no measurement)")  # fmt: skip
    s = GCU_SUB_SCHEMA
    return (s["target_latitude_raw"].to_raw(lat, "target latitude"),
            s["target_longitude_raw"].to_raw(lon, "target longitude"),
            s["target_altitude_raw"].to_raw(alt, "target altitude"))  # fmt: skip


# -- the tables ------------------------------------------------------------------------------
_XYZ = ("x", "y", "z")
GCU_MAIN_SCHEMA = FrameSchema("GcuMainFrame", "GCU main frame", MAIN_START, MAIN_SIZE, (
    WireField("mode_raw", "B", "pod working mode (Mode)"),
    WireField("pod_status_raw", "H", "pod status flags (PodStatus)"),
    *(WireField(f"miss_{a}", "h", f"{doc} miss distance, image centre = 0", -1000, 1000)
      for a, doc in (("x", "horizontal (right +)"), ("y", "vertical (down +)"))),
    *(WireField(f"relative_{a}_raw", "h", f"camera {a.upper()} angle relative to the aircraft",
                *ANGLE_RANGE, 100, "deg", CENTIDEGREE, high_open=True) for a in _XYZ),
    WireField("roll_raw", "h", "camera absolute roll", *TILT_RANGE, 100, "deg", CENTIDEGREE),
    WireField("pitch_raw", "h", "camera absolute pitch", *ANGLE_RANGE, 100, "deg", CENTIDEGREE,
              high_open=True),
    CAMERA_YAW.field,
    *(WireField(f"rate_{a}_raw", "h", f"camera {a.upper()}-axis absolute angular rate",
                scale=10, unit="deg/s", raw_unit="0.1 deg/s") for a in _XYZ),
), (
    Code(name="mode", fields=("mode_raw",), enum=Mode, default=Mode.POINTING_LOCK,
         doc="Working mode; ``Mode.UNKNOWN`` for codes V2.0.6 does not define (see "
             "``mode_raw``)."),
    Flags(name="pod_status", fields=("pod_status_raw",), flags=PodStatus,
          doc="Pod status flags."),
    Bit(name="tracking_ok", fields=("pod_status_raw",), member=PodStatus.TRACKING_OK,
        key=None, doc="B0: target tracked, miss distances valid."),
    Group(name="miss_distance", fields=("miss_x", "miss_y"), cls=tuple, read=tracked_miss,
          needs=("pod_status_raw",), optional=True, default=(0, 0),
          labels=("miss distance x", "miss distance y")),
    Group(name="relative_angles", fields=tuple(f"relative_{a}_raw" for a in _XYZ),
          cls=AxisAngles, labels=("relative X angle", "relative Y angle", "relative Z angle"),
          default=(0.0, 0.0, 0.0),
          doc="Camera X/Y/Z angles relative to the aircraft, degrees (encoder based)."),
    Group(name="attitude", fields=("roll_raw", "pitch_raw", "yaw_raw"), cls=Attitude,
          read=camera_attitude, labels=("camera roll", "camera pitch", "camera yaw"),
          default=(0.0, 0.0, 0.0)),
    Group(name="angular_rates", fields=tuple(f"rate_{a}_raw" for a in _XYZ), cls=AxisAngles,
          labels=("X angular rate", "Y angular rate", "Z angular rate"),
          default=(0.0, 0.0, 0.0), doc="Camera X/Y/Z absolute angular rates, °/s."),
), details={"yaw_raw": CAMERA_YAW.detail})  # fmt: skip
"""Bytes 5–36 of a GCU packet: the one table of the main frame."""
GCU_SUB_SCHEMA = FrameSchema("GcuSubFrame", "GCU sub frame 0x01", SUB_START, SUB_SIZE, (
    WireField("hardware_version_raw", "B", "hardware version, 0.1 resolution (0x1F: 3.1)",
              scale=10),
    WireField("firmware_version_raw", "B", "firmware version, 0.1 resolution", scale=10),
    WireField("pod_code", "B", "pod model code (Appendix 7)"),
    WireField("fault_raw", "H", "fault flags (FaultFlags)"),
    WireField("target_distance_raw", "i", "laser-ranged distance; <= 0: no measurement",
              scale=10, unit="m", raw_unit="0.1 m"),
    WireField("target_longitude_raw", "i", "ranged target longitude", *LONGITUDE_RANGE, 1e7,
              "deg", "1e-7 deg"),
    WireField("target_latitude_raw", "i", "ranged target latitude", *LATITUDE_RANGE, 1e7,
              "deg", "1e-7 deg"),
    WireField("target_altitude_raw", "i", "ranged target altitude", scale=1000, unit="m",
              raw_unit="mm"),
    replace(CAMERA_ZOOM, name="camera1_zoom_raw", doc="camera 1 zoom (visible by default)"),
    replace(CAMERA_ZOOM, name="camera2_zoom_raw", doc="camera 2 zoom (thermal by default)"),
    WireField("thermal_flags_raw", "B", "thermal camera flags (ThermalFlags)"),
    WireField("camera_flags_raw", "H", "camera flags (CameraFlags); bits 2-0: pip mode"),
    WireField("time_zone", "b", "UTC offset in hours", raw_unit="h"),
), (
    Value(name="hardware_version", fields=("hardware_version_raw",), default=0.0,
          doc="Hardware version (0.1 resolution)."),
    Value(name="firmware_version", fields=("firmware_version_raw",), default=0.0,
          doc="Firmware version (0.1 resolution)."),
    Code(name="pod_model", fields=("pod_code",), enum=PodModel, spelling=pod_name,
         doc="Pod model; ``PodModel.UNKNOWN`` for codes Appendix 7 does not list (see "
             "``pod_code``)."),
    Flags(name="faults", fields=("fault_raw",), flags=FaultFlags, doc="Fault flags."),
    Value(name="target_distance", fields=("target_distance_raw",), read=measured_distance,
          write=send_target_distance, optional=True),
    Group(name="target_position", cls=GeoPosition, read=measured_position,
          fields=("target_latitude_raw", "target_longitude_raw", "target_altitude_raw"),
          needs=("target_distance_raw",), write=send_target_position, optional=True),
    Value(name="camera1_zoom", fields=("camera1_zoom_raw",), default=1.0,
          doc="Camera 1 zoom ratio (visible / zoom by default)."),
    Value(name="camera2_zoom", fields=("camera2_zoom_raw",), default=1.0,
          doc="Camera 2 zoom ratio (thermal by default)."),
    Flags(name="thermal_flags", fields=("thermal_flags_raw",), flags=ThermalFlags,
          doc="Thermal camera flags."),
    Flags(name="camera_flags", fields=("camera_flags_raw",), flags=CameraFlags,
          mask=PIP_MODE_MASK, doc="Camera flags (bits 2–0 are :attr:`pip_mode`)."),
    Bits(name="pip_mode", fields=("camera_flags_raw",), mask=PIP_MODE_MASK,
         doc="Picture-in-picture mode (bits 2–0 of the camera flags)."),
    Bit(name="recording", fields=("camera_flags_raw",), member=CameraFlags.RECORDING,
        key=None, doc="Camera 1 is recording."),
    Bit(name="auto_flip", fields=("camera_flags_raw",), member=CameraFlags.AUTO_FLIP_OFF,
        clear=True, key=None, doc="Image auto-flip on (B11 = 0 means on)."),
    Value(name="time_zone", fields=("time_zone",), doc="UTC offset in hours."),
), header=SUB_FRAME_HEADER)  # fmt: skip
"""Bytes 38–68 of a GCU packet when the sub frame header (byte 37) is 0x01: the one table
of the sub frame."""
