"""GCU → host frames: main frame (bytes 5–36) and sub frame (bytes 37–68).

Each frame is one table, :data:`GCU_MAIN_SCHEMA` and :data:`GCU_SUB_SCHEMA`: its fields in
wire order and what the frame presents of them (:mod:`~gcu_async.protocol.frame_schema`).
The classes below the marker line are generated from the tables by ``tools/gen_frames.py``:
immutable ``NamedTuple``\\ s of raw wire integers with engineering-unit properties,
``build()`` from units, ``validate()``, ``anomalies``, ``as_dict()`` and ``str()``. The
functions above the tables are the readings the tables cannot say.
"""

from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple, TypedDict

from gcu_async._checks import check_int, type_error
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
from gcu_async.protocol.fields import (
    ANGLE_RANGE,
    CAMERA_ZOOM,
    LATITUDE_RANGE,
    LONGITUDE_RANGE,
    TILT_RANGE,
    WireField,
)
from gcu_async.protocol.frame_schema import (
    Bit,
    Bits,
    Code,
    Flags,
    FrameSchema,
    Group,
    Value,
    check_parts,
    flag_names,
    flag_text,
    group_text,
    number_text,
)
from gcu_async.protocol.headings import HeadingRule, heading
from gcu_async.protocol.layout import MAIN_SIZE, MAIN_START, SUB_FRAME_HEADER, SUB_SIZE, SUB_START
from gcu_async.protocol.pods import pod_name
from gcu_async.protocol.units import Attitude, AxisAngles, GeoPosition, check_tuple, quantize

D001 = "0.01 deg"
CAMERA_YAW = HeadingRule(heading("yaw_raw", "camera absolute yaw (a heading)"))
"""The camera's absolute yaw, and how any raw value reads as a heading
(:mod:`~gcu_async.protocol.headings`: the Z-1Pro sends a signed S16)."""


# -- the readings the tables cannot say ----------------------------------------------------
def camera_attitude(roll_raw: int, pitch_raw: int, yaw_raw: int) -> Attitude:
    """Camera absolute roll/pitch/yaw, degrees (needs valid aircraft INS data); the yaw a
    heading of its field's range whatever the pod sends (a signed S16 too: :data:`CAMERA_YAW`,
    docs/protocol-notes.md "What real pods do"); ``yaw_raw`` keeps the wire value."""
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
                *ANGLE_RANGE, 100, "deg", D001, high_open=True) for a in _XYZ),
    WireField("roll_raw", "h", "camera absolute roll", *TILT_RANGE, 100, "deg", D001),
    WireField("pitch_raw", "h", "camera absolute pitch", *ANGLE_RANGE, 100, "deg", D001,
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

# --- generated by tools/gen_frames.py from the tables above: edit them, then run it ---


class GcuMainFrameDict(TypedDict):
    """What :meth:`GcuMainFrame.as_dict` returns."""

    mode: str
    mode_raw: int
    pod_status: list[str]
    pod_status_raw: int
    miss_distance: list[int] | None
    miss_distance_raw: list[int]
    relative_angles_deg: dict[str, float]
    relative_angles_raw: list[int]
    attitude_deg: dict[str, float]
    attitude_raw: list[int]
    angular_rates_deg_s: dict[str, float]
    angular_rates_raw: list[int]


class GcuMainFrame(NamedTuple):
    """GCU main frame, bytes 5–36 (raw integers): the fields of ``GCU_MAIN_SCHEMA``."""

    mode_raw: int = 0x11
    """Byte 5, U8: pod working mode (Mode)."""
    pod_status_raw: int = 0
    """Bytes 6–7, U16: pod status flags (PodStatus)."""
    miss_x: int = 0
    """Bytes 8–9, S16, [-1000, 1000]: horizontal (right +) miss distance, image centre = 0."""
    miss_y: int = 0
    """Bytes 10–11, S16, [-1000, 1000]: vertical (down +) miss distance, image centre = 0."""
    relative_x_raw: int = 0
    """Bytes 12–13, S16, 0.01 deg, [-18000, 18000): camera X angle relative to the aircraft."""
    relative_y_raw: int = 0
    """Bytes 14–15, S16, 0.01 deg, [-18000, 18000): camera Y angle relative to the aircraft."""
    relative_z_raw: int = 0
    """Bytes 16–17, S16, 0.01 deg, [-18000, 18000): camera Z angle relative to the aircraft."""
    roll_raw: int = 0
    """Bytes 18–19, S16, 0.01 deg, [-9000, 9000]: camera absolute roll."""
    pitch_raw: int = 0
    """Bytes 20–21, S16, 0.01 deg, [-18000, 18000): camera absolute pitch."""
    yaw_raw: int = 0
    """Bytes 22–23, U16, 0.01 deg, [0, 36000): camera absolute yaw (a heading)."""
    rate_x_raw: int = 0
    """Bytes 24–25, S16, 0.1 deg/s: camera X-axis absolute angular rate."""
    rate_y_raw: int = 0
    """Bytes 26–27, S16, 0.1 deg/s: camera Y-axis absolute angular rate."""
    rate_z_raw: int = 0
    """Bytes 28–29, S16, 0.1 deg/s: camera Z-axis absolute angular rate."""

    @property
    def mode(self) -> Mode:
        """Working mode; ``Mode.UNKNOWN`` for codes V2.0.6 does not define (see ``mode_raw``)."""
        return Mode(self.mode_raw)

    @property
    def pod_status(self) -> PodStatus:
        """Pod status flags."""
        return PodStatus(self.pod_status_raw)

    @property
    def tracking_ok(self) -> bool:
        """B0: target tracked, miss distances valid."""
        return bool(self.pod_status_raw & PodStatus.TRACKING_OK)

    @property
    def miss_distance(self) -> tuple[int, int] | None:
        """Horizontal (right +) and vertical (down +) miss distance, image centre = 0, or
        ``None`` unless a target is tracked (``PodStatus.TRACKING_OK``: only then are they
        valid); ``miss_x``/``miss_y`` keep the wire values."""
        return tracked_miss(self.miss_x, self.miss_y, self.pod_status_raw)

    @property
    def relative_angles(self) -> AxisAngles:
        """Camera X/Y/Z angles relative to the aircraft, degrees (encoder based)."""
        return AxisAngles(
            self.relative_x_raw / 100, self.relative_y_raw / 100, self.relative_z_raw / 100)

    @property
    def attitude(self) -> Attitude:
        """Camera absolute roll/pitch/yaw, degrees (needs valid aircraft INS data); the yaw a
        heading of its field's range whatever the pod sends (a signed S16 too:
        :data:`CAMERA_YAW`, docs/protocol-notes.md "What real pods do"); ``yaw_raw`` keeps the
        wire value."""
        return camera_attitude(self.roll_raw, self.pitch_raw, self.yaw_raw)

    @property
    def angular_rates(self) -> AxisAngles:
        """Camera X/Y/Z absolute angular rates, °/s."""
        return AxisAngles(self.rate_x_raw / 10, self.rate_y_raw / 10, self.rate_z_raw / 10)

    @classmethod
    def build(
        cls,
        *,
        mode: int = Mode.POINTING_LOCK,
        pod_status: int = 0,
        miss_distance: tuple[int, int] = (0, 0),
        relative_angles: AxisAngles | tuple[float, float, float] = (0.0, 0.0, 0.0),
        attitude: Attitude | tuple[float, float, float] = (0.0, 0.0, 0.0),
        angular_rates: AxisAngles | tuple[float, float, float] = (0.0, 0.0, 0.0),
    ) -> GcuMainFrame:
        """Build from engineering units: each value checked and converted to its raw field
        (rounded to the wire's step), a ``TypeError`` or :class:`FieldRangeError` naming it;
        integer codes and flags take their enum members or any value of the field."""
        mode_raw = GCU_MAIN_SCHEMA.check("mode_raw", mode, "mode")
        pod_status_raw = GCU_MAIN_SCHEMA.check("pod_status_raw", pod_status, "pod_status")
        miss_distance = check_parts("miss_distance", miss_distance, 2)
        miss_x = GCU_MAIN_SCHEMA.check("miss_x", miss_distance[0], "miss distance x")
        miss_y = GCU_MAIN_SCHEMA.check("miss_y", miss_distance[1], "miss distance y")
        relative_angles = check_tuple("relative_angles", relative_angles, AxisAngles)
        relative_x_raw = GCU_MAIN_SCHEMA["relative_x_raw"].to_raw(
            relative_angles[0], "relative X angle")
        relative_y_raw = GCU_MAIN_SCHEMA["relative_y_raw"].to_raw(
            relative_angles[1], "relative Y angle")
        relative_z_raw = GCU_MAIN_SCHEMA["relative_z_raw"].to_raw(
            relative_angles[2], "relative Z angle")
        attitude = check_tuple("attitude", attitude, Attitude)
        roll_raw = GCU_MAIN_SCHEMA["roll_raw"].to_raw(attitude[0], "camera roll")
        pitch_raw = GCU_MAIN_SCHEMA["pitch_raw"].to_raw(attitude[1], "camera pitch")
        yaw_raw = GCU_MAIN_SCHEMA["yaw_raw"].to_raw(attitude[2], "camera yaw")
        angular_rates = check_tuple("angular_rates", angular_rates, AxisAngles)
        rate_x_raw = GCU_MAIN_SCHEMA["rate_x_raw"].to_raw(angular_rates[0], "X angular rate")
        rate_y_raw = GCU_MAIN_SCHEMA["rate_y_raw"].to_raw(angular_rates[1], "Y angular rate")
        rate_z_raw = GCU_MAIN_SCHEMA["rate_z_raw"].to_raw(angular_rates[2], "Z angular rate")
        return cls(
            mode_raw, pod_status_raw, miss_x, miss_y, relative_x_raw, relative_y_raw,
            relative_z_raw, roll_raw, pitch_raw, yaw_raw, rate_x_raw, rate_y_raw, rate_z_raw)

    def validate(self) -> None:
        """Raise ``TypeError`` / :class:`FieldRangeError` for the first field (wire order) that
        is not an ``int`` in its range (``GCU_MAIN_SCHEMA``; flags: no reserved bit set)."""
        (mode_raw, pod_status_raw, miss_x, miss_y, relative_x_raw, relative_y_raw, relative_z_raw,
            roll_raw, pitch_raw, yaw_raw, rate_x_raw, rate_y_raw, rate_z_raw) = self
        if (int is type(mode_raw) is type(pod_status_raw) is type(miss_x) is type(miss_y) is
            type(relative_x_raw) is type(relative_y_raw) is type(relative_z_raw) is
            type(roll_raw) is type(pitch_raw) is type(yaw_raw) is type(rate_x_raw) is
            type(rate_y_raw) is type(rate_z_raw) and
            0 <= mode_raw <= 255 and 0 <= pod_status_raw <= 65535 and -1000 <= miss_x <= 1000 and
            -1000 <= miss_y <= 1000 and -18000 <= relative_x_raw <= 17999 and
            -18000 <= relative_y_raw <= 17999 and -18000 <= relative_z_raw <= 17999 and
            -9000 <= roll_raw <= 9000 and -18000 <= pitch_raw <= 17999 and 0 <= yaw_raw <= 35999 and
            -32768 <= rate_x_raw <= 32767 and -32768 <= rate_y_raw <= 32767 and
            -32768 <= rate_z_raw <= 32767):
            return
        GCU_MAIN_SCHEMA.validate(self)

    @property
    def anomalies(self) -> tuple[Anomaly, ...]:
        """Fields of a decoded frame outside the ranges V2.0.6 gives them (or with reserved bits
        set), kept raw and flagged (docs/client.md, "Liberal receive, strict send"); empty for
        an ordinary frame."""
        (mode_raw, pod_status_raw, miss_x, miss_y, relative_x_raw, relative_y_raw, relative_z_raw,
            roll_raw, pitch_raw, yaw_raw, rate_x_raw, rate_y_raw, rate_z_raw) = self
        if (0 <= mode_raw <= 255 and 0 <= pod_status_raw <= 65535 and -1000 <= miss_x <= 1000 and
            -1000 <= miss_y <= 1000 and -18000 <= relative_x_raw <= 17999 and
            -18000 <= relative_y_raw <= 17999 and -18000 <= relative_z_raw <= 17999 and
            -9000 <= roll_raw <= 9000 and -18000 <= pitch_raw <= 17999 and 0 <= yaw_raw <= 35999 and
            -32768 <= rate_x_raw <= 32767 and -32768 <= rate_y_raw <= 32767 and
            -32768 <= rate_z_raw <= 32767):
            return ()
        return GCU_MAIN_SCHEMA.anomalies(self)

    def __str__(self) -> str:
        """Engineering units (``print(frame)``); ``repr()`` keeps the raw fields."""
        return (f"GcuMainFrame(mode {self.mode.name} (0x{self.mode_raw:02X}), "
                f"pod status {flag_text(self.pod_status)}, "
                f"miss distance {group_text(self.miss_distance, '')}, "
                f"relative angles {group_text(self.relative_angles, 'deg')}, "
                f"attitude {group_text(self.attitude, 'deg')}, "
                f"angular rates {group_text(self.angular_rates, 'deg/s')})"
        )

    def as_dict(self) -> GcuMainFrameDict:
        """Every field, in engineering units and raw, for JSON output
        (:class:`GcuMainFrameDict`)."""
        miss_distance = self.miss_distance
        return {
            "mode": self.mode.name,
            "mode_raw": self.mode_raw,
            "pod_status": flag_names(self.pod_status),
            "pod_status_raw": self.pod_status_raw,
            "miss_distance": None if miss_distance is None else list(miss_distance),
            "miss_distance_raw": [self.miss_x, self.miss_y],
            "relative_angles_deg": self.relative_angles._asdict(),
            "relative_angles_raw": [self.relative_x_raw, self.relative_y_raw, self.relative_z_raw],
            "attitude_deg": self.attitude._asdict(),
            "attitude_raw": [self.roll_raw, self.pitch_raw, self.yaw_raw],
            "angular_rates_deg_s": self.angular_rates._asdict(),
            "angular_rates_raw": [self.rate_x_raw, self.rate_y_raw, self.rate_z_raw],
        }



class GcuSubFrameDict(TypedDict):
    """What :meth:`GcuSubFrame.as_dict` returns."""

    header: int
    """Byte 37, the sub frame header: 0x01, the standard sub frame (an :class:`UnknownSubFrame`'s
    dict gives its own header)."""
    hardware_version: float
    hardware_version_raw: int
    firmware_version: float
    firmware_version_raw: int
    pod_model: str
    pod_model_member: str
    pod_code: int
    faults: list[str]
    fault_raw: int
    target_distance_m: float | None
    target_distance_raw: int
    target_position: dict[str, float] | None
    target_position_raw: list[int]
    camera1_zoom: float
    camera1_zoom_raw: int
    camera2_zoom: float
    camera2_zoom_raw: int
    thermal_flags: list[str]
    thermal_flags_raw: int
    camera_flags: list[str]
    camera_flags_raw: int
    pip_mode: int
    time_zone: int


class GcuSubFrame(NamedTuple):
    """GCU sub frame 0x01, bytes 38–68 (raw integers): the fields of ``GCU_SUB_SCHEMA``."""

    hardware_version_raw: int = 0
    """Byte 38, U8: hardware version, 0.1 resolution (0x1F: 3.1)."""
    firmware_version_raw: int = 0
    """Byte 39, U8: firmware version, 0.1 resolution."""
    pod_code: int = 0
    """Byte 40, U8: pod model code (Appendix 7)."""
    fault_raw: int = 0
    """Bytes 41–42, U16: fault flags (FaultFlags)."""
    target_distance_raw: int = 0
    """Bytes 43–46, S32, 0.1 m: laser-ranged distance; <= 0: no measurement."""
    target_longitude_raw: int = 0
    """Bytes 47–50, S32, 1e-7 deg, [-1800000000, 1800000000]: ranged target longitude."""
    target_latitude_raw: int = 0
    """Bytes 51–54, S32, 1e-7 deg, [-900000000, 900000000]: ranged target latitude."""
    target_altitude_raw: int = 0
    """Bytes 55–58, S32, mm: ranged target altitude."""
    camera1_zoom_raw: int = 0
    """Bytes 59–60, U16, 0.1x: camera 1 zoom (visible by default)."""
    camera2_zoom_raw: int = 0
    """Bytes 61–62, U16, 0.1x: camera 2 zoom (thermal by default)."""
    thermal_flags_raw: int = 0
    """Byte 63, U8: thermal camera flags (ThermalFlags)."""
    camera_flags_raw: int = 0
    """Bytes 64–65, U16: camera flags (CameraFlags); bits 2-0: pip mode."""
    time_zone: int = 0
    """Byte 66, S8, h: UTC offset in hours."""

    @property
    def hardware_version(self) -> float:
        """Hardware version (0.1 resolution)."""
        return self.hardware_version_raw / 10

    @property
    def firmware_version(self) -> float:
        """Firmware version (0.1 resolution)."""
        return self.firmware_version_raw / 10

    @property
    def pod_model(self) -> PodModel:
        """Pod model; ``PodModel.UNKNOWN`` for codes Appendix 7 does not list (see
        ``pod_code``)."""
        return PodModel(self.pod_code)

    @property
    def faults(self) -> FaultFlags:
        """Fault flags."""
        return FaultFlags(self.fault_raw)

    @property
    def target_distance(self) -> float | None:
        """Laser-ranged distance in metres, or ``None`` when there is no measurement (raw ≤ 0:
        the document's −1 or 0, docs/protocol-notes.md §7)."""
        return measured_distance(self.target_distance_raw)

    @property
    def target_position(self) -> GeoPosition | None:
        """Ranged target position, or ``None`` when there is no measurement (as
        ``target_distance``); the ``target_*_raw`` fields keep the wire values."""
        return measured_position(
            self.target_latitude_raw, self.target_longitude_raw, self.target_altitude_raw,
            self.target_distance_raw)

    @property
    def camera1_zoom(self) -> float:
        """Camera 1 zoom ratio (visible / zoom by default)."""
        return self.camera1_zoom_raw / 10

    @property
    def camera2_zoom(self) -> float:
        """Camera 2 zoom ratio (thermal by default)."""
        return self.camera2_zoom_raw / 10

    @property
    def thermal_flags(self) -> ThermalFlags:
        """Thermal camera flags."""
        return ThermalFlags(self.thermal_flags_raw)

    @property
    def camera_flags(self) -> CameraFlags:
        """Camera flags (bits 2–0 are :attr:`pip_mode`)."""
        return CameraFlags(self.camera_flags_raw & ~0x07)

    @property
    def pip_mode(self) -> int:
        """Picture-in-picture mode (bits 2–0 of the camera flags)."""
        return self.camera_flags_raw & 0x07

    @property
    def recording(self) -> bool:
        """Camera 1 is recording."""
        return bool(self.camera_flags_raw & CameraFlags.RECORDING)

    @property
    def auto_flip(self) -> bool:
        """Image auto-flip on (B11 = 0 means on)."""
        return not self.camera_flags_raw & CameraFlags.AUTO_FLIP_OFF

    @classmethod
    def build(
        cls,
        *,
        hardware_version: float = 0.0,
        firmware_version: float = 0.0,
        pod_model: int = 0,
        faults: int = 0,
        target_distance: float | None = None,
        target_position: GeoPosition | tuple[float, float, float] | None = None,
        camera1_zoom: float = 1.0,
        camera2_zoom: float = 1.0,
        thermal_flags: int = 0,
        camera_flags: int = 0,
        pip_mode: int = 0,
        time_zone: int = 0,
    ) -> GcuSubFrame:
        """Build from engineering units: each value checked and converted to its raw field
        (rounded to the wire's step), a ``TypeError`` or :class:`FieldRangeError` naming it;
        integer codes and flags take their enum members or any value of the field."""
        hardware_version_raw = GCU_SUB_SCHEMA["hardware_version_raw"].to_raw(
            hardware_version, "hardware_version")
        firmware_version_raw = GCU_SUB_SCHEMA["firmware_version_raw"].to_raw(
            firmware_version, "firmware_version")
        pod_code = GCU_SUB_SCHEMA.check("pod_code", pod_model, "pod_model")
        fault_raw = GCU_SUB_SCHEMA.check("fault_raw", faults, "faults")
        target_distance_raw = send_target_distance(target_distance=target_distance)
        target_latitude_raw, target_longitude_raw, target_altitude_raw = send_target_position(
            target_position=target_position, target_distance=target_distance)
        camera1_zoom_raw = GCU_SUB_SCHEMA["camera1_zoom_raw"].to_raw(camera1_zoom, "camera1_zoom")
        camera2_zoom_raw = GCU_SUB_SCHEMA["camera2_zoom_raw"].to_raw(camera2_zoom, "camera2_zoom")
        thermal_flags_raw = GCU_SUB_SCHEMA.check(
            "thermal_flags_raw", thermal_flags, "thermal_flags")
        camera_flags_raw = GCU_SUB_SCHEMA.masked(
            "camera_flags_raw", camera_flags, "camera_flags", 0x07, "pip_mode")
        camera_flags_raw |= check_int("pip_mode", pip_mode, 0, 0x07)
        time_zone = GCU_SUB_SCHEMA.check("time_zone", time_zone, "time_zone")
        return cls(
            hardware_version_raw, firmware_version_raw, pod_code, fault_raw, target_distance_raw,
            target_longitude_raw, target_latitude_raw, target_altitude_raw, camera1_zoom_raw,
            camera2_zoom_raw, thermal_flags_raw, camera_flags_raw, time_zone)

    def validate(self) -> None:
        """Raise ``TypeError`` / :class:`FieldRangeError` for the first field (wire order) that
        is not an ``int`` in its range (``GCU_SUB_SCHEMA``; flags: no reserved bit set)."""
        (hardware_version_raw, firmware_version_raw, pod_code, fault_raw, target_distance_raw,
            target_longitude_raw, target_latitude_raw, target_altitude_raw, camera1_zoom_raw,
            camera2_zoom_raw, thermal_flags_raw, camera_flags_raw, time_zone) = self
        if (int is type(hardware_version_raw) is type(firmware_version_raw) is type(pod_code) is
            type(fault_raw) is type(target_distance_raw) is type(target_longitude_raw) is
            type(target_latitude_raw) is type(target_altitude_raw) is type(camera1_zoom_raw) is
            type(camera2_zoom_raw) is type(thermal_flags_raw) is type(camera_flags_raw) is
            type(time_zone) and
            0 <= hardware_version_raw <= 255 and 0 <= firmware_version_raw <= 255 and
            0 <= pod_code <= 255 and 0 <= fault_raw <= 65535 and
            -2147483648 <= target_distance_raw <= 2147483647 and
            -1800000000 <= target_longitude_raw <= 1800000000 and
            -900000000 <= target_latitude_raw <= 900000000 and
            -2147483648 <= target_altitude_raw <= 2147483647 and 0 <= camera1_zoom_raw <= 65535 and
            0 <= camera2_zoom_raw <= 65535 and 0 <= thermal_flags_raw <= 255 and
            0 <= camera_flags_raw <= 65535 and -128 <= time_zone <= 127):
            return
        GCU_SUB_SCHEMA.validate(self)

    @property
    def anomalies(self) -> tuple[Anomaly, ...]:
        """Fields of a decoded frame outside the ranges V2.0.6 gives them (or with reserved bits
        set), kept raw and flagged (docs/client.md, "Liberal receive, strict send"); empty for
        an ordinary frame."""
        (hardware_version_raw, firmware_version_raw, pod_code, fault_raw, target_distance_raw,
            target_longitude_raw, target_latitude_raw, target_altitude_raw, camera1_zoom_raw,
            camera2_zoom_raw, thermal_flags_raw, camera_flags_raw, time_zone) = self
        if (0 <= hardware_version_raw <= 255 and 0 <= firmware_version_raw <= 255 and
            0 <= pod_code <= 255 and 0 <= fault_raw <= 65535 and
            -2147483648 <= target_distance_raw <= 2147483647 and
            -1800000000 <= target_longitude_raw <= 1800000000 and
            -900000000 <= target_latitude_raw <= 900000000 and
            -2147483648 <= target_altitude_raw <= 2147483647 and 0 <= camera1_zoom_raw <= 65535 and
            0 <= camera2_zoom_raw <= 65535 and 0 <= thermal_flags_raw <= 255 and
            0 <= camera_flags_raw <= 65535 and -128 <= time_zone <= 127):
            return ()
        return GCU_SUB_SCHEMA.anomalies(self)

    def __str__(self) -> str:
        """Engineering units (``print(frame)``); ``repr()`` keeps the raw fields."""
        return (f"GcuSubFrame(hardware version {number_text(self.hardware_version, '')}, "
                f"firmware version {number_text(self.firmware_version, '')}, "
                f"pod model {self.pod_model.name} (0x{self.pod_code:02X}), "
                f"faults {flag_text(self.faults)}, "
                f"target distance {number_text(self.target_distance, 'm')}, "
                f"target position {group_text(self.target_position, '')}, "
                f"camera1 zoom {number_text(self.camera1_zoom, 'x')}, "
                f"camera2 zoom {number_text(self.camera2_zoom, 'x')}, "
                f"thermal flags {flag_text(self.thermal_flags)}, "
                f"camera flags {flag_text(self.camera_flags)}, pip mode {self.pip_mode}, "
                f"time zone {number_text(self.time_zone, 'h')})"
        )

    def as_dict(self) -> GcuSubFrameDict:
        """Every field, in engineering units and raw, for JSON output
        (:class:`GcuSubFrameDict`)."""
        target_position = self.target_position
        return {
            "header": 0x01,
            "hardware_version": self.hardware_version,
            "hardware_version_raw": self.hardware_version_raw,
            "firmware_version": self.firmware_version,
            "firmware_version_raw": self.firmware_version_raw,
            "pod_model": pod_name(self.pod_code),
            "pod_model_member": self.pod_model.name,
            "pod_code": self.pod_code,
            "faults": flag_names(self.faults),
            "fault_raw": self.fault_raw,
            "target_distance_m": self.target_distance,
            "target_distance_raw": self.target_distance_raw,
            "target_position": None if target_position is None else target_position._asdict(),
            "target_position_raw": [
                self.target_latitude_raw, self.target_longitude_raw, self.target_altitude_raw
            ],
            "camera1_zoom": self.camera1_zoom,
            "camera1_zoom_raw": self.camera1_zoom_raw,
            "camera2_zoom": self.camera2_zoom,
            "camera2_zoom_raw": self.camera2_zoom_raw,
            "thermal_flags": flag_names(self.thermal_flags),
            "thermal_flags_raw": self.thermal_flags_raw,
            "camera_flags": flag_names(self.camera_flags),
            "camera_flags_raw": self.camera_flags_raw,
            "pip_mode": self.pip_mode,
            "time_zone": self.time_zone,
        }


# --- end of generated code ---


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

    def as_dict(self) -> UnknownSubFrameDict:
        """``header`` (byte 37) and the 31 data bytes in hex."""
        return {"header": self.header, "data_hex": self.data.hex(" ")}


class UnknownSubFrameDict(TypedDict):
    """What :meth:`UnknownSubFrame.as_dict` returns."""

    header: int
    """Byte 37: the sub frame header (not 0x01)."""
    data_hex: str
    """Bytes 38–68 in hex, a space between bytes."""
