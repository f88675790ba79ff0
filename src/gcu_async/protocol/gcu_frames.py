"""GCU → host frames: main frame (bytes 5–36) and sub frame (bytes 37–68).

Immutable ``NamedTuple``s of raw wire integers with engineering-unit properties.
"""

from __future__ import annotations

from typing import Any, NamedTuple

from gcu_async._checks import check_int, type_error
from gcu_async.errors import FieldRangeError
from gcu_async.protocol.anomalies import Anomaly
from gcu_async.protocol.enums import (
    PIP_MODE_MASK,
    CameraFlags,
    FaultFlags,
    Mode,
    PodModel,
    PodStatus,
    ThermalFlags,
)
from gcu_async.protocol.fields import WireField
from gcu_async.protocol.frame_schema import FrameSchema
from gcu_async.protocol.headings import HeadingRule
from gcu_async.protocol.host_frames import HOST_SUB_SCHEMA
from gcu_async.protocol.layout import MAIN_SIZE, MAIN_START, SUB_FRAME_HEADER, SUB_SIZE, SUB_START
from gcu_async.protocol.pods import pod_name
from gcu_async.protocol.units import Attitude, AxisAngles, GeoPosition, check_tuple, quantize

D001 = "0.01 deg"
CAMERA_YAW = HeadingRule(WireField("yaw_raw", "H", "camera absolute yaw (a heading)", 0, 36000,
                                   100, "deg", D001, high_open=True))  # fmt: skip
"""Bytes 22–23, the camera's absolute yaw, and how any raw value reads as a heading in
[0°, 360°) (:mod:`~gcu_async.protocol.headings`: the Z-1Pro sends a signed S16)."""

GCU_MAIN_SCHEMA = FrameSchema("GCU main frame", MAIN_START, MAIN_SIZE, (
    WireField("mode_raw", "B", "pod working mode (see Mode)"),
    WireField("pod_status_raw", "H", "pod status flags (PodStatus)"),
    WireField("miss_x", "h", "horizontal miss distance, image centre = 0, right +", -1000, 1000),
    WireField("miss_y", "h", "vertical miss distance, down +", -1000, 1000),
    *(WireField(f"relative_{axis}_raw", "h", f"camera {axis.upper()} angle relative to the "
                "aircraft", -18000, 18000, 100, "deg", D001, high_open=True) for axis in "xyz"),
    WireField("roll_raw", "h", "camera absolute roll", -9000, 9000, 100, "deg", D001),
    WireField("pitch_raw", "h", "camera absolute pitch", -18000, 18000, 100, "deg", D001,
              high_open=True),
    CAMERA_YAW.field,
    *(WireField(f"rate_{axis}_raw", "h", f"camera {axis.upper()}-axis absolute angular rate",
                scale=10, unit="deg/s", raw_unit="0.1 deg/s") for axis in "xyz"),
), details={"yaw_raw": CAMERA_YAW.detail})  # fmt: skip
"""Bytes 5–36 of a GCU packet: the one table of the main frame's fields."""
GCU_SUB_SCHEMA = FrameSchema("GCU sub frame", SUB_START, SUB_SIZE, (
    WireField("hardware_version_raw", "B", "hardware version, 0.1 resolution (0x1F: 3.1)",
              scale=10),
    WireField("firmware_version_raw", "B", "firmware version, 0.1 resolution", scale=10),
    WireField("pod_code", "B", "pod model code (Appendix 7)"),
    WireField("fault_raw", "H", "fault flags (FaultFlags)"),
    WireField("target_distance_raw", "i", "laser-ranged distance; <= 0: no measurement",
              scale=10, unit="m", raw_unit="0.1 m"),
    WireField("target_longitude_raw", "i", "ranged target longitude", scale=1e7, unit="deg",
              raw_unit="1e-7 deg"),
    WireField("target_latitude_raw", "i", "ranged target latitude", scale=1e7, unit="deg",
              raw_unit="1e-7 deg"),
    WireField("target_altitude_raw", "i", "ranged target altitude", scale=1000, unit="m",
              raw_unit="mm"),
    WireField("camera1_zoom_raw", "H", "camera 1 zoom (visible / zoom by default)", scale=10,
              unit="x", raw_unit="0.1x"),
    WireField("camera2_zoom_raw", "H", "camera 2 zoom (thermal by default)", scale=10,
              unit="x", raw_unit="0.1x"),
    WireField("thermal_flags_raw", "B", "thermal camera flags (ThermalFlags)"),
    WireField("camera_flags_raw", "H", "camera flags (CameraFlags); bits 2-0: pip mode"),
    WireField("time_zone", "b", "UTC offset in hours", raw_unit="h"),
))  # fmt: skip
"""Bytes 38–68 of a GCU packet when the sub frame header (byte 37) is 0x01: no range
narrower than its wire type, so a decoded sub frame has no anomalies."""

GCU_MAIN = GCU_MAIN_SCHEMA.struct
"""Bytes 5–36 of a GCU packet."""
GCU_SUB = GCU_SUB_SCHEMA.struct
"""Bytes 38–68 of a GCU packet when the sub frame header (byte 37) is 0x01."""
GCU_MAIN_RANGES = GCU_MAIN_SCHEMA.ranges
"""Each main-frame field's raw range, in wire order (:class:`FieldRange`)."""
GCU_SUB_RANGES = GCU_SUB_SCHEMA.ranges
"""Each sub-frame field's raw range, in wire order (:class:`FieldRange`)."""

_M = GCU_MAIN_SCHEMA.by_name
_S = GCU_SUB_SCHEMA.by_name
_relative = GCU_MAIN_SCHEMA.view(AxisAngles, "relative_x_raw", "relative_y_raw", "relative_z_raw")
_ROLL, _PITCH = _M["roll_raw"].scale, _M["pitch_raw"].scale
_heading = CAMERA_YAW.degrees
_rates = GCU_MAIN_SCHEMA.view(AxisAngles, "rate_x_raw", "rate_y_raw", "rate_z_raw")
_target = GCU_SUB_SCHEMA.view(GeoPosition, "target_latitude_raw", "target_longitude_raw",
                              "target_altitude_raw")  # fmt: skip
_MAIN_SHOWN = ("mode_raw", "pod_status_raw", "miss_x", "miss_y", "relative_x_raw",
               "relative_y_raw", "relative_z_raw", "roll_raw", "pitch_raw", "yaw_raw",
               "rate_x_raw", "rate_y_raw", "rate_z_raw")  # fmt: skip
"""Main-frame fields ``as_dict`` presents its own way (the rest: ``FrameSchema.plain_dict``)."""
_SUB_SHOWN = ("hardware_version_raw", "firmware_version_raw", "pod_code", "fault_raw",
              "target_distance_raw", "target_longitude_raw", "target_latitude_raw",
              "target_altitude_raw", "camera1_zoom_raw", "camera2_zoom_raw", "thermal_flags_raw",
              "camera_flags_raw", "time_zone")  # fmt: skip


def _flag_names(flags: Any) -> list[str]:
    return [m.name for m in type(flags) if m in flags and m.name is not None]


class GcuMainFrame(NamedTuple):
    """GCU main frame, bytes 5–36 (raw integers)."""

    mode_raw: int = 0x11
    """Byte 5: pod working mode (see :class:`Mode`)."""
    pod_status_raw: int = 0
    """Bytes 6–7, little-endian: pod status flags."""
    miss_x: int = 0
    """Bytes 8–9, S16: horizontal miss distance, image centre = 0, right +."""
    miss_y: int = 0
    """Bytes 10–11, S16: vertical miss distance, down +."""
    relative_x_raw: int = 0
    """Bytes 12–13, S16 0.01°: camera X angle relative to the aircraft."""
    relative_y_raw: int = 0
    """Bytes 14–15."""
    relative_z_raw: int = 0
    """Bytes 16–17."""
    roll_raw: int = 0
    """Bytes 18–19, S16 0.01°: camera absolute roll."""
    pitch_raw: int = 0
    """Bytes 20–21, S16 0.01°: camera absolute pitch."""
    yaw_raw: int = 0
    """Bytes 22–23, U16 0.01°: camera absolute yaw, [0, 36000) (a pod may send a signed
    S16: :attr:`attitude` reads it, :data:`CAMERA_YAW`)."""
    rate_x_raw: int = 0
    """Bytes 24–25, S16 0.1 °/s: camera X-axis absolute angular rate."""
    rate_y_raw: int = 0
    """Bytes 26–27."""
    rate_z_raw: int = 0
    """Bytes 28–29."""

    @classmethod
    def build(
        cls,
        *,
        mode: int = Mode.POINTING_LOCK,
        pod_status: int = 0,
        miss_distance: tuple[int, int] = (0, 0),
        relative_angles: tuple[float, float, float] = (0.0, 0.0, 0.0),
        attitude: tuple[float, float, float] = (0.0, 0.0, 0.0),
        angular_rates: tuple[float, float, float] = (0.0, 0.0, 0.0),
    ) -> GcuMainFrame:
        """Build from engineering units (degrees, °/s). ``mode`` is a :class:`Mode` member or
        any code 0–255 (a simulator may play a firmware with modes V2.0.6 does not define);
        ``pod_status`` an ``int`` 0–0xFFFF (:class:`PodStatus` flags); the tuples are checked
        element by element (``relative X angle``, ``camera roll``, ``miss distance x``, …)."""
        relative = check_tuple("relative_angles", relative_angles, AxisAngles)
        rx, ry, rz = (
            _M[f"relative_{axis.lower()}_raw"].to_raw(v, f"relative {axis} angle")
            for axis, v in zip("XYZ", relative, strict=True)
        )
        roll, pitch, yaw = check_tuple("attitude", attitude, Attitude)
        rates = check_tuple("angular_rates", angular_rates, AxisAngles)
        wx, wy, wz = (
            _M[f"rate_{axis.lower()}_raw"].to_raw(v, f"{axis} angular rate")
            for axis, v in zip("XYZ", rates, strict=True)
        )
        if not isinstance(miss_distance, tuple) or len(miss_distance) != 2:
            raise type_error("miss_distance", "a tuple (x, y) of ints", miss_distance)
        check = GCU_MAIN_SCHEMA.check
        return cls(
            check("mode_raw", mode, "mode"),
            check("pod_status_raw", pod_status, "pod_status"),
            check("miss_x", miss_distance[0], "miss distance x"),
            check("miss_y", miss_distance[1], "miss distance y"),
            rx,
            ry,
            rz,
            _M["roll_raw"].to_raw(roll, "camera roll"),
            _M["pitch_raw"].to_raw(pitch, "camera pitch"),
            _M["yaw_raw"].to_raw(yaw, "camera yaw"),
            wx,
            wy,
            wz,
        )

    @property
    def mode(self) -> Mode:
        """Working mode; ``Mode.UNKNOWN`` for codes V2.0.6 does not define (see ``mode_raw``)."""
        return Mode(self.mode_raw)

    @property
    def pod_status(self) -> PodStatus:
        return PodStatus(self.pod_status_raw)

    @property
    def tracking_ok(self) -> bool:
        """B0: target tracked, miss distances valid."""
        return bool(self.pod_status_raw & PodStatus.TRACKING_OK)

    @property
    def relative_angles(self) -> AxisAngles:
        """Camera X/Y/Z angles relative to the aircraft, degrees (encoder based)."""
        return _relative(self)

    @property
    def attitude(self) -> Attitude:
        """Camera absolute roll/pitch/yaw, degrees (needs valid aircraft INS data); the yaw
        a heading in [0°, 360°) whatever the pod sends (a signed S16 too: :data:`CAMERA_YAW`,
        docs/protocol-notes.md "What real pods do"); ``yaw_raw`` keeps the wire value."""
        return Attitude(self.roll_raw / _ROLL, self.pitch_raw / _PITCH, _heading(self.yaw_raw))

    @property
    def angular_rates(self) -> AxisAngles:
        """Camera X/Y/Z absolute angular rates, °/s."""
        return _rates(self)

    def validate(self) -> None:
        """Raise :class:`FieldRangeError` for any raw field outside its range (the
        schema's)."""
        GCU_MAIN_SCHEMA.validate(self)

    @property
    def anomalies(self) -> tuple[Anomaly, ...]:
        """Fields of a decoded frame outside the ranges V2.0.6 gives them (miss distances,
        angles), kept raw and flagged (docs/client.md, "Liberal receive, strict send"); a yaw
        of 36000 or more says how it was read (:data:`CAMERA_YAW`)."""
        return GCU_MAIN_SCHEMA.anomalies(self)

    def __str__(self) -> str:
        """Engineering units (``print(gcu.status)``); ``repr()`` keeps the raw fields."""
        a, r, w = self.attitude, self.relative_angles, self.angular_rates
        flags = ",".join(_flag_names(self.pod_status)) or "none"
        return (f"GcuMainFrame(mode {self.mode.name} (0x{self.mode_raw:02X}), attitude roll "
                f"{a.roll:g} pitch {a.pitch:g} yaw {a.yaw:g} deg, relative axes x {r.x:g} "
                f"y {r.y:g} z {r.z:g} deg, rates x {w.x:g} y {w.y:g} z {w.z:g} deg/s, miss "
                f"{self.miss_x} {self.miss_y}, pod status {flags})")  # fmt: skip

    def as_dict(self) -> dict[str, Any]:
        return {
            "mode": self.mode.name,
            "mode_raw": self.mode_raw,
            "pod_status": _flag_names(self.pod_status),
            "pod_status_raw": self.pod_status_raw,
            "miss_distance": [self.miss_x, self.miss_y],
            "relative_angles_deg": self.relative_angles._asdict(),
            "relative_angles_raw": [self.relative_x_raw, self.relative_y_raw, self.relative_z_raw],
            "attitude_deg": self.attitude._asdict(),
            "attitude_raw": [self.roll_raw, self.pitch_raw, self.yaw_raw],
            "angular_rates_deg_s": self.angular_rates._asdict(),
            "angular_rates_raw": [self.rate_x_raw, self.rate_y_raw, self.rate_z_raw],
            **GCU_MAIN_SCHEMA.plain_dict(self, _MAIN_SHOWN),
        }


class GcuSubFrame(NamedTuple):
    """GCU sub frame 0x01, bytes 38–68 (raw integers): pod information."""

    hardware_version_raw: int = 0
    """Byte 38, U8, 0.1 resolution (0x1F → 3.1)."""
    firmware_version_raw: int = 0
    """Byte 39, U8, 0.1 resolution."""
    pod_code: int = 0
    """Byte 40: pod model code (Appendix 7)."""
    fault_raw: int = 0
    """Bytes 41–42: fault flags."""
    target_distance_raw: int = 0
    """Bytes 43–46, S32, 0.1 m; ≤ 0 means no measurement."""
    target_longitude_raw: int = 0
    """Bytes 47–50, S32, 1e-7°."""
    target_latitude_raw: int = 0
    """Bytes 51–54, S32, 1e-7°."""
    target_altitude_raw: int = 0
    """Bytes 55–58, S32, mm."""
    camera1_zoom_raw: int = 0
    """Bytes 59–60, U16, 0.1×: camera 1 (visible / zoom by default)."""
    camera2_zoom_raw: int = 0
    """Bytes 61–62, U16, 0.1×: camera 2 (thermal by default)."""
    thermal_flags_raw: int = 0
    """Byte 63: thermal camera flags."""
    camera_flags_raw: int = 0
    """Bytes 64–65: camera flags; bits 2–0 are the picture-in-picture mode."""
    time_zone: int = 0
    """Byte 66, S8: UTC offset in hours."""


    @classmethod
    def build(
        cls,
        *,
        hardware_version: float = 0.0,
        firmware_version: float = 0.0,
        pod_model: int = 0,
        faults: int = 0,
        target_distance: float | None = None,
        target_position: GeoPosition | None = None,
        camera1_zoom: float = 1.0,
        camera2_zoom: float = 1.0,
        thermal_flags: int = 0,
        camera_flags: int = 0,
        pip_mode: int = 0,
        time_zone: int = 0,
    ) -> GcuSubFrame:
        """Build from engineering units (metres, degrees, zoom ratio). ``camera_flags`` must
        leave bits 2–0 clear (they carry ``pip_mode``). ``pod_model`` is a
        :class:`PodModel` member or any code 0–255; the flag arguments are ``int``s (their
        IntFlag members welcome); ``target_position`` a :class:`GeoPosition` (or tuple) or
        ``None`` (zeros); ``target_distance=None`` sends "no measurement" (0)."""
        pos = (
            GeoPosition(0.0, 0.0, 0.0)
            if target_position is None
            else check_tuple("target_position", target_position, GeoPosition)
        )
        check = GCU_SUB_SCHEMA.check
        distance = _S["target_distance_raw"]
        return cls(
            _S["hardware_version_raw"].to_raw(hardware_version, "hardware version"),
            _S["firmware_version_raw"].to_raw(firmware_version, "firmware version"),
            check("pod_code", pod_model, "pod model"),
            check("fault_raw", faults, "faults"),
            0 if target_distance is None else quantize(  # a distance is never negative
                "target distance", target_distance, distance.scale, 0, distance.raw_high,
                distance.unit),
            # the target's position takes the ranges of a position the host sends
            HOST_SUB_SCHEMA.by_name["longitude_raw"].to_raw(pos.longitude, "target longitude"),
            HOST_SUB_SCHEMA.by_name["latitude_raw"].to_raw(pos.latitude, "target latitude"),
            _S["target_altitude_raw"].to_raw(pos.altitude, "target altitude"),
            _S["camera1_zoom_raw"].to_raw(camera1_zoom, "camera 1 zoom"),
            _S["camera2_zoom_raw"].to_raw(camera2_zoom, "camera 2 zoom"),
            check("thermal_flags_raw", thermal_flags, "thermal flags"),
            _camera_flags(camera_flags) | check_int("pip mode", pip_mode, 0, PIP_MODE_MASK),
            check("time_zone", time_zone, "time zone"),
        )  # fmt: skip

    @property
    def hardware_version(self) -> float:
        return self.hardware_version_raw / _S["hardware_version_raw"].scale

    @property
    def firmware_version(self) -> float:
        return self.firmware_version_raw / _S["firmware_version_raw"].scale

    @property
    def pod_model(self) -> PodModel:
        """Pod model; ``PodModel.UNKNOWN`` for codes Appendix 7 does not list (see ``pod_code``)."""
        return PodModel(self.pod_code)

    @property
    def faults(self) -> FaultFlags:
        return FaultFlags(self.fault_raw)

    @property
    def target_distance(self) -> float | None:
        """Laser-ranged distance in metres, or ``None`` when there is no measurement (raw ≤ 0)."""
        raw = self.target_distance_raw
        return raw / _S["target_distance_raw"].scale if raw > 0 else None

    @property
    def target_position(self) -> GeoPosition:
        """Ranged target position (valid when ``PodStatus.RANGE_VALID`` is set)."""
        return _target(self)

    @property
    def camera1_zoom(self) -> float:
        return self.camera1_zoom_raw / _S["camera1_zoom_raw"].scale

    @property
    def camera2_zoom(self) -> float:
        return self.camera2_zoom_raw / _S["camera2_zoom_raw"].scale

    @property
    def thermal_flags(self) -> ThermalFlags:
        return ThermalFlags(self.thermal_flags_raw)

    @property
    def camera_flags(self) -> CameraFlags:
        return CameraFlags(self.camera_flags_raw & ~PIP_MODE_MASK)

    @property
    def pip_mode(self) -> int:
        """Picture-in-picture mode (bits 2–0 of bytes 64–65)."""
        return self.camera_flags_raw & PIP_MODE_MASK

    @property
    def recording(self) -> bool:
        return bool(self.camera_flags_raw & CameraFlags.RECORDING)

    @property
    def auto_flip(self) -> bool:
        """Image auto-flip on (B11 = 0 means on)."""
        return not self.camera_flags_raw & CameraFlags.AUTO_FLIP_OFF

    def validate(self) -> None:
        """Raise :class:`FieldRangeError` for any raw field outside its wire range."""
        GCU_SUB_SCHEMA.validate(self)

    @property
    def anomalies(self) -> tuple[Anomaly, ...]:
        """Fields of a decoded sub frame outside the ranges V2.0.6 gives them, kept raw and
        flagged (V2.0.6 gives none narrower than its wire type: empty)."""
        return GCU_SUB_SCHEMA.anomalies(self)

    def __str__(self) -> str:
        """Engineering units (``print(gcu.info)``); ``repr()`` keeps the raw fields."""
        dist = "none" if self.target_distance is None else f"{self.target_distance:g} m"
        flags = ",".join(_flag_names(self.camera_flags)) or "none"
        return (f"GcuSubFrame({pod_name(self.pod_code)}, hardware {self.hardware_version:g}, "
                f"firmware {self.firmware_version:g}, zoom {self.camera1_zoom:g}x / "
                f"{self.camera2_zoom:g}x, target distance {dist}, camera flags {flags}, "
                f"UTC{self.time_zone:+d})")  # fmt: skip

    def as_dict(self) -> dict[str, Any]:
        return {
            "header": SUB_FRAME_HEADER,
            "hardware_version": self.hardware_version,
            "hardware_version_raw": self.hardware_version_raw,
            "firmware_version": self.firmware_version,
            "firmware_version_raw": self.firmware_version_raw,
            "pod_model": pod_name(self.pod_code),  # the vendor's spelling, e.g. "D-90AI"
            "pod_model_member": self.pod_model.name,  # PodModel's member, e.g. "D_90AI"
            "pod_code": self.pod_code,
            "faults": _flag_names(self.faults),
            "fault_raw": self.fault_raw,
            "target_distance_m": self.target_distance,
            "target_distance_raw": self.target_distance_raw,
            "target_position": self.target_position._asdict(),
            "target_position_raw": [
                self.target_latitude_raw, self.target_longitude_raw, self.target_altitude_raw
            ],
            "camera1_zoom": self.camera1_zoom,
            "camera1_zoom_raw": self.camera1_zoom_raw,
            "camera2_zoom": self.camera2_zoom,
            "camera2_zoom_raw": self.camera2_zoom_raw,
            "thermal_flags": _flag_names(self.thermal_flags),
            "thermal_flags_raw": self.thermal_flags_raw,
            "camera_flags": _flag_names(self.camera_flags),
            "pip_mode": self.pip_mode,
            "camera_flags_raw": self.camera_flags_raw,
            "time_zone": self.time_zone,
            **GCU_SUB_SCHEMA.plain_dict(self, _SUB_SHOWN),
        }  # fmt: skip


GCU_MAIN_SCHEMA.install(GcuMainFrame)
GCU_SUB_SCHEMA.install(GcuSubFrame)


def _camera_flags(value: object) -> int:
    f = _S["camera_flags_raw"]
    flags = check_int("camera flags", value, f.raw_low, f.raw_high)
    if flags & PIP_MODE_MASK:
        raise FieldRangeError("camera flags", value, f.raw_low, f.raw_high,
                              detail="bits 2-0 hold the pip mode: pass pip_mode=")  # fmt: skip
    return flags


class UnknownSubFrame(NamedTuple):
    """A sub frame whose header V2.0.6 does not define, kept byte for byte (bytes 37–68)."""

    header: int
    data: bytes
    """Bytes 38–68 (31 bytes)."""

    def validate(self) -> None:
        """Raise unless ``header`` is an ``int`` 0–255 other than 0x01 (that is the standard
        sub frame: build :class:`GcuSubFrame` / ``HostSubFrame``) and ``data`` 31 bytes."""
        check_int("sub frame header", self.header, 0, 255)
        if self.header == SUB_FRAME_HEADER:
            raise ValueError("sub frame header: 0x01 is the standard sub frame; build a "
                             "GcuSubFrame or HostSubFrame, not an UnknownSubFrame")  # fmt: skip
        if not isinstance(self.data, (bytes, bytearray)):
            raise type_error("sub frame data", f"{SUB_SIZE} bytes", self.data)
        if len(self.data) != SUB_SIZE:
            raise ValueError(f"sub frame data: expected {SUB_SIZE} bytes, got {len(self.data)}")

    def as_dict(self) -> dict[str, Any]:
        return {"header": self.header, "data_hex": self.data.hex(" ")}
