"""GCU → host frames: main frame (bytes 5–36) and sub frame (bytes 37–68).

Immutable ``NamedTuple``s of raw wire integers with engineering-unit properties.
"""

from __future__ import annotations

import struct
from typing import Any, NamedTuple

from gcu_async._checks import check_int, type_error
from gcu_async.errors import FieldRangeError
from gcu_async.protocol.anomalies import Anomaly, FieldRange, check_ranges, range_anomalies
from gcu_async.protocol.enums import (
    PIP_MODE_MASK,
    CameraFlags,
    FaultFlags,
    Mode,
    PodModel,
    PodStatus,
    ThermalFlags,
)
from gcu_async.protocol.layout import S16, S32, SUB_FRAME_HEADER
from gcu_async.protocol.pods import pod_name
from gcu_async.protocol.units import Attitude, AxisAngles, GeoPosition, check_tuple, quantize

GCU_MAIN = struct.Struct("<BHhhhhhhhHhhh7x")
"""Bytes 5–36 of a GCU packet."""
GCU_SUB = struct.Struct("<BBBHiiiiHHBHb2x")
"""Bytes 38–68 of a GCU packet when the sub frame header (byte 37) is 0x01."""

GCU_MAIN_RANGES = (
    FieldRange("mode_raw", 0, 255),
    FieldRange("pod_status_raw", 0, 0xFFFF),
    FieldRange("miss_x", -1000, 1000),
    FieldRange("miss_y", -1000, 1000),
    *(FieldRange(f"relative_{axis}_raw", -18000, 17999, "0.01 deg") for axis in "xyz"),
    FieldRange("roll_raw", -9000, 9000, "0.01 deg"),
    FieldRange("pitch_raw", -18000, 17999, "0.01 deg"),
    FieldRange("yaw_raw", 0, 35999, "0.01 deg"),
    *(FieldRange(f"rate_{axis}_raw", *S16, "0.1 deg/s") for axis in "xyz"),
)
"""Each main-frame field's raw range, in wire order (:class:`FieldRange`)."""
GCU_SUB_RANGES = (
    FieldRange("hardware_version_raw", 0, 255),
    FieldRange("firmware_version_raw", 0, 255),
    FieldRange("pod_code", 0, 255),
    FieldRange("fault_raw", 0, 0xFFFF),
    FieldRange("target_distance_raw", *S32, "0.1 m"),
    FieldRange("target_longitude_raw", *S32, "1e-7 deg"),
    FieldRange("target_latitude_raw", *S32, "1e-7 deg"),
    FieldRange("target_altitude_raw", *S32, "mm"),
    FieldRange("camera1_zoom_raw", 0, 0xFFFF, "0.1x"),
    FieldRange("camera2_zoom_raw", 0, 0xFFFF, "0.1x"),
    FieldRange("thermal_flags_raw", 0, 0xFF),
    FieldRange("camera_flags_raw", 0, 0xFFFF),
    FieldRange("time_zone", -128, 127, "h"),
)
"""Each sub-frame field's raw range, in wire order (:class:`FieldRange`): none narrower
than its wire type, so a decoded sub frame has no anomalies."""


def _flag_names(flags: Any) -> list[str]:
    return [m.name for m in type(flags) if m in flags and m.name is not None]


class GcuMainFrame(NamedTuple):
    """GCU main frame, bytes 5–36 (raw integers)."""

    mode_raw: int = 0x11
    """Byte 5: pod working mode (see :class:`Mode`)."""
    pod_status_raw: int = 0
    """Bytes 6–7, little-endian: pod status flags."""
    miss_x: int = 0
    """Bytes 8–9, S16 [-1000, 1000]: horizontal miss distance, image centre = 0, right +."""
    miss_y: int = 0
    """Bytes 10–11, S16 [-1000, 1000]: vertical miss distance, down +."""
    relative_x_raw: int = 0
    """Bytes 12–13, S16 0.01°, [-18000, 18000): camera X angle relative to the aircraft."""
    relative_y_raw: int = 0
    """Bytes 14–15."""
    relative_z_raw: int = 0
    """Bytes 16–17."""
    roll_raw: int = 0
    """Bytes 18–19, S16 0.01°, [-9000, 9000]: camera absolute roll."""
    pitch_raw: int = 0
    """Bytes 20–21, S16 0.01°, [-18000, 18000): camera absolute pitch."""
    yaw_raw: int = 0
    """Bytes 22–23, U16 0.01°, [0, 36000): camera absolute yaw."""
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
            quantize(f"relative {axis} angle", v, 100, -18000, 18000, "deg", high_open=True)
            for axis, v in zip("XYZ", relative, strict=True)
        )
        roll, pitch, yaw = check_tuple("attitude", attitude, Attitude)
        rates = check_tuple("angular_rates", angular_rates, AxisAngles)
        wx, wy, wz = (
            quantize(f"{axis} angular rate", v, 10, *S16, "deg/s")
            for axis, v in zip("XYZ", rates, strict=True)
        )
        if not isinstance(miss_distance, tuple) or len(miss_distance) != 2:
            raise type_error("miss_distance", "a tuple (x, y) of ints", miss_distance)
        frame = cls(
            check_int("mode", mode, 0, 255),
            check_int("pod_status", pod_status, 0, 0xFFFF),
            check_int("miss distance x", miss_distance[0], -1000, 1000),
            check_int("miss distance y", miss_distance[1], -1000, 1000),
            rx,
            ry,
            rz,
            quantize("camera roll", roll, 100, -9000, 9000, "deg"),
            quantize("camera pitch", pitch, 100, -18000, 18000, "deg", high_open=True),
            quantize("camera yaw", yaw, 100, 0, 36000, "deg", high_open=True),
            wx,
            wy,
            wz,
        )
        return frame

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
        return AxisAngles(
            self.relative_x_raw / 100, self.relative_y_raw / 100, self.relative_z_raw / 100
        )

    @property
    def attitude(self) -> Attitude:
        """Camera absolute roll/pitch/yaw, degrees (needs valid aircraft INS data)."""
        return Attitude(self.roll_raw / 100, self.pitch_raw / 100, self.yaw_raw / 100)

    @property
    def angular_rates(self) -> AxisAngles:
        """Camera X/Y/Z absolute angular rates, °/s."""
        return AxisAngles(self.rate_x_raw / 10, self.rate_y_raw / 10, self.rate_z_raw / 10)

    def validate(self) -> None:
        """Raise :class:`FieldRangeError` for any raw field outside its wire range."""
        # Fast path: plain ints inside the very ranges checked below (see HostMainFrame).
        mo, ps, mx, my, rx, ry, rz, ro, pi, ya, wx, wy, wz = self
        if (
            int is type(mo) is type(ps) is type(mx) is type(my) is type(rx) is type(ry)
            is type(rz) is type(ro) is type(pi) is type(ya) is type(wx) is type(wy)
            is type(wz)
            and 0 <= mo <= 255 and 0 <= ps <= 0xFFFF
            and -1000 <= mx <= 1000 and -1000 <= my <= 1000
            and -18000 <= rx <= 17999 and -18000 <= ry <= 17999 and -18000 <= rz <= 17999
            and -18000 <= pi <= 17999 and -9000 <= ro <= 9000 and 0 <= ya <= 35999
            and -32768 <= wx <= 32767 and -32768 <= wy <= 32767 and -32768 <= wz <= 32767
        ):  # fmt: skip
            return
        check_ranges(self, GCU_MAIN_RANGES)

    @property
    def anomalies(self) -> tuple[Anomaly, ...]:
        """Fields of a decoded frame outside the ranges V2.0.6 gives them (miss distances,
        angles), kept raw and flagged (docs/client.md, "Liberal receive, strict send")."""
        return range_anomalies(self, GCU_MAIN_RANGES)

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
        return cls(
            quantize("hardware version", hardware_version, 10, 0, 255),
            quantize("firmware version", firmware_version, 10, 0, 255),
            check_int("pod model", pod_model, 0, 255),
            check_int("faults", faults, 0, 0xFFFF),
            0 if target_distance is None else quantize(
                "target distance", target_distance, 10, 0, S32[1], "m"
            ),
            quantize("target longitude", pos.longitude, 1e7, -1_800_000_000, 1_800_000_000, "deg"),
            quantize("target latitude", pos.latitude, 1e7, -900_000_000, 900_000_000, "deg"),
            quantize("target altitude", pos.altitude, 1000, *S32, "m"),
            quantize("camera 1 zoom", camera1_zoom, 10, 0, 0xFFFF, "x"),
            quantize("camera 2 zoom", camera2_zoom, 10, 0, 0xFFFF, "x"),
            check_int("thermal flags", thermal_flags, 0, 0xFF),
            _camera_flags(camera_flags) | check_int("pip mode", pip_mode, 0, PIP_MODE_MASK),
            check_int("time zone", time_zone, -128, 127, "h"),
        )  # fmt: skip

    @property
    def hardware_version(self) -> float:
        return self.hardware_version_raw / 10

    @property
    def firmware_version(self) -> float:
        return self.firmware_version_raw / 10

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
        return self.target_distance_raw / 10 if self.target_distance_raw > 0 else None

    @property
    def target_position(self) -> GeoPosition:
        """Ranged target position (valid when ``PodStatus.RANGE_VALID`` is set)."""
        return GeoPosition(
            self.target_latitude_raw / 1e7,
            self.target_longitude_raw / 1e7,
            self.target_altitude_raw / 1000,
        )

    @property
    def camera1_zoom(self) -> float:
        return self.camera1_zoom_raw / 10

    @property
    def camera2_zoom(self) -> float:
        return self.camera2_zoom_raw / 10

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
        # Fast path: plain ints inside the very ranges checked below (see HostMainFrame).
        hw, fw, pod, fault, dist, lon, lat, alt, z1, z2, th, cam, tz = self
        lo, hi = S32
        if (
            int is type(hw) is type(fw) is type(pod) is type(fault) is type(dist)
            is type(lon) is type(lat) is type(alt) is type(z1) is type(z2) is type(th)
            is type(cam) is type(tz)
            and 0 <= hw <= 255 and 0 <= fw <= 255 and 0 <= pod <= 255 and 0 <= fault <= 0xFFFF
            and lo <= dist <= hi and lo <= lon <= hi and lo <= lat <= hi and lo <= alt <= hi
            and 0 <= z1 <= 0xFFFF and 0 <= z2 <= 0xFFFF and 0 <= th <= 0xFF
            and 0 <= cam <= 0xFFFF and -128 <= tz <= 127
        ):  # fmt: skip
            return
        check_ranges(self, GCU_SUB_RANGES)

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
        }  # fmt: skip


def _camera_flags(value: object) -> int:
    flags = check_int("camera flags", value, 0, 0xFFFF)
    if flags & PIP_MODE_MASK:
        raise FieldRangeError("camera flags", value, 0, 0xFFFF,
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
            raise type_error("sub frame data", "31 bytes", self.data)
        if len(self.data) != 31:
            raise ValueError(f"sub frame data: expected 31 bytes, got {len(self.data)}")

    def as_dict(self) -> dict[str, Any]:
        return {"header": self.header, "data_hex": self.data.hex(" ")}
