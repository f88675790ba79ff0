"""Host → GCU frames: main frame (bytes 5–36) and sub frame (bytes 37–68).

Frames are immutable ``NamedTuple``s of the raw wire integers (cheap to build from
``struct.unpack``) with engineering-unit properties; ``build()`` constructs one from units.
"""

from __future__ import annotations

from datetime import datetime
from typing import Any, NamedTuple

from gcu_async._checks import check_bool, check_instance, check_int, check_real
from gcu_async.protocol.anomalies import Anomaly
from gcu_async.protocol.enums import HostFlags, SubFrameRequest
from gcu_async.protocol.fields import WireField
from gcu_async.protocol.frame_schema import FrameSchema, flag_bits
from gcu_async.protocol.headings import HeadingRule
from gcu_async.protocol.layout import MAIN_SIZE, MAIN_START, SUB_SIZE, SUB_START
from gcu_async.protocol.layout import SUB_FRAME_HEADER as SUB_FRAME_HEADER  # re-exported
from gcu_async.protocol.units import (
    Attitude,
    GeoPosition,
    NorthEastUp,
    check_tuple,
    quantize,
)

MS_PER_WEEK = 604_800_000
D001 = "0.01 deg"

HOST_MAIN_SCHEMA = FrameSchema("host main frame", MAIN_START, MAIN_SIZE, (
    *(WireField(f"control_{axis}_raw", "h", "control value (rate or angle, per mode)",
                -18000, 18000) for axis in ("roll", "pitch", "yaw")),
    WireField("flags_raw", "B", "B2 control values valid, B0 aircraft INS valid"),
    WireField("aircraft_roll_raw", "h", "aircraft roll", -18000, 18000, 100, "deg", D001,
              high_open=True),
    WireField("aircraft_pitch_raw", "h", "aircraft pitch", -9000, 9000, 100, "deg", D001),
    WireField("aircraft_yaw_raw", "H", "aircraft yaw", 0, 36000, 100, "deg", D001,
              high_open=True),
    *(WireField(f"accel_{axis}_raw", "h", f"aircraft acceleration {axis}, gravity excluded "
                "(0.01 m/s^2)", scale=100, unit="m/s^2") for axis in ("north", "east", "up")),
    *(WireField(f"vel_{axis}_raw", "h", f"aircraft velocity {axis} (0.01 m/s)", scale=100,
                unit="m/s") for axis in ("north", "east", "up")),
    WireField("subframe_request", "B", "GCU sub-frame request code (0x01 standard, 0x00 none)"),
), flags={"flags_raw": HostFlags})  # fmt: skip
"""Bytes 5–36 of a host packet: the one table of the main frame's fields."""
AIRCRAFT_YAW = HeadingRule(HOST_MAIN_SCHEMA.by_name["aircraft_yaw_raw"])
"""Bytes 16–17 read as a heading whatever the host sends (docs/protocol-notes.md §15
"Aircraft yaw outside [0, 36000)"): what the simulator uses; decoding keeps the raw value."""
HOST_SUB_SCHEMA = FrameSchema("host sub frame", SUB_START, SUB_SIZE, (
    WireField("longitude_raw", "i", "aircraft longitude", -1_800_000_000, 1_800_000_000, 1e7,
              "deg", "1e-7 deg"),
    WireField("latitude_raw", "i", "aircraft latitude", -900_000_000, 900_000_000, 1e7, "deg",
              "1e-7 deg"),
    WireField("altitude_raw", "i", "altitude above mean sea level", scale=1000, unit="m",
              raw_unit="mm"),
    WireField("satellites", "B", "satellites used"),
    WireField("gnss_ms", "I", "milliseconds of the GNSS week", 0, MS_PER_WEEK, unit="ms",
              raw_unit="ms", high_open=True),
    WireField("gnss_week", "h", "GNSS week number", 0),
    WireField("relative_altitude_raw", "i", "altitude relative to take-off (0 if not needed)",
              scale=1000, unit="m", raw_unit="mm"),
))  # fmt: skip
"""Bytes 38–68 of a host packet when the sub frame header (byte 37) is 0x01: the aircraft's
GNSS data (the ranges of :meth:`GcuClient.update_aircraft` and :class:`AircraftState`)."""

HOST_MAIN = HOST_MAIN_SCHEMA.struct
"""Bytes 5–36 of a host packet."""
HOST_SUB = HOST_SUB_SCHEMA.struct
"""Bytes 38–68 of a host packet when the sub frame header (byte 37) is 0x01."""
_M = HOST_MAIN_SCHEMA.by_name
_S = HOST_SUB_SCHEMA.by_name

CONTROL_ANGLE_RAW = _M["control_roll_raw"].raw_high  # 0.01°
CONTROL_RATE_RAW = 1500  # 0.1 °/s ÷ zoom
ZOOM_MAX = 6553.5
"""Largest zoom ratio the GCU can report (sub frame camera zoom: U16, 0.1×)."""
GNSS_WEEK_MAX = _S["gnss_week"].raw_high
"""The last GNSS week the host sub frame carries (S16)."""
_FLAG_BITS = flag_bits(HostFlags)

HOST_MAIN_RANGES = HOST_MAIN_SCHEMA.ranges
"""Each main-frame field's raw range but ``flags_raw`` (reserved bits: ``check_flags``),
in wire order (:class:`FieldRange`): the control values, then the rest."""
HOST_SUB_RANGES = HOST_SUB_SCHEMA.ranges
"""Each sub-frame field's raw range, in wire order (:class:`FieldRange`)."""
_aircraft_attitude = HOST_MAIN_SCHEMA.view(Attitude, "aircraft_roll_raw", "aircraft_pitch_raw",
                                           "aircraft_yaw_raw")  # fmt: skip
_acceleration = HOST_MAIN_SCHEMA.view(NorthEastUp, "accel_north_raw", "accel_east_raw",
                                      "accel_up_raw")  # fmt: skip
_velocity = HOST_MAIN_SCHEMA.view(NorthEastUp, "vel_north_raw", "vel_east_raw", "vel_up_raw")
_position = HOST_SUB_SCHEMA.view(GeoPosition, "latitude_raw", "longitude_raw", "altitude_raw")
_MAIN_SHOWN = ("control_roll_raw", "control_pitch_raw", "control_yaw_raw", "flags_raw",
               "aircraft_roll_raw", "aircraft_pitch_raw", "aircraft_yaw_raw", "accel_north_raw",
               "accel_east_raw", "accel_up_raw", "vel_north_raw", "vel_east_raw", "vel_up_raw",
               "subframe_request")  # fmt: skip
"""Main-frame fields ``as_dict`` presents its own way (the rest: ``FrameSchema.plain_dict``)."""
_SUB_SHOWN = ("longitude_raw", "latitude_raw", "altitude_raw", "satellites", "gnss_ms",
              "gnss_week", "relative_altitude_raw")  # fmt: skip


class ControlValues(NamedTuple):
    """Host main frame bytes 5–10 as raw S16 values; their meaning depends on the mode
    (docs/protocol-notes.md §5 "Control values change meaning with the mode"). Build them with
    :meth:`angles` or :meth:`rates`, which check their arguments.

    Invariant: each raw value is an ``int`` in [-18000, 18000] (±180° at 0.01°; rates use
    ±1500 of it). A ``NamedTuple`` cannot check itself when built raw
    (``ControlValues(99999, 0, 0)``), so every consumer checks it with :meth:`check` (or
    :meth:`validate`) before storing or sending it; :meth:`HostMainFrame.build` does.
    """

    roll_raw: int = 0
    pitch_raw: int = 0
    yaw_raw: int = 0

    @classmethod
    def check(cls, value: object, field: str = "control") -> ControlValues:
        """``value`` if it is a :class:`ControlValues` holding the invariant; else a
        ``TypeError`` (not a ControlValues, or a raw value not an ``int``) or a
        :class:`FieldRangeError` naming ``field.roll_raw`` etc."""
        control = check_instance(field, value, cls)
        control.validate(field)
        return control

    def validate(self, field: str = "control") -> None:
        """Raise unless each raw value is an ``int`` in the control range (see the class)."""
        r, p, y = self
        c = CONTROL_ANGLE_RAW
        if int is type(r) is type(p) is type(y) and -c <= r <= c and -c <= p <= c and -c <= y <= c:
            return
        for name, v in zip(self._fields, self, strict=True):
            check_int(f"{field}.{name}", v, -c, c, "raw")

    @classmethod
    def angles(cls, roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0) -> ControlValues:
        """Desired angles in degrees (Euler or relative, per mode), 0.01° resolution, ±180°."""
        r = CONTROL_ANGLE_RAW
        return cls(
            quantize("control roll angle", roll, 100, -r, r, "deg"),
            quantize("control pitch angle", pitch, 100, -r, r, "deg"),
            quantize("control yaw angle", yaw, 100, -r, r, "deg"),
        )

    @classmethod
    def rates(
        cls, roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0, *, zoom: float = 1.0
    ) -> ControlValues:
        """Desired angular rates in °/s. The wire value is in units of 0.1/zoom °/s (the
        current main-view zoom ratio), range ±1500, so the reachable rate shrinks with zoom.
        ``zoom`` is a real number in [1, 6553.5] (what the GCU can report)."""
        zoom = check_real("zoom", zoom, 1.0, ZOOM_MAX, "ratio")
        scale = 10.0 * zoom
        r = CONTROL_RATE_RAW
        return cls(
            quantize("control roll rate", roll, scale, -r, r, f"deg/s at zoom {zoom:g}x"),
            quantize("control pitch rate", pitch, scale, -r, r, f"deg/s at zoom {zoom:g}x"),
            quantize("control yaw rate", yaw, scale, -r, r, f"deg/s at zoom {zoom:g}x"),
        )

    def as_angles(self) -> Attitude:
        """Read the raw values as angles (degrees)."""
        return Attitude(self.roll_raw / 100, self.pitch_raw / 100, self.yaw_raw / 100)

    def as_rates(self, zoom: float = 1.0) -> Attitude:
        """Read the raw values as angular rates (°/s) at the given zoom ratio (checked as in
        :meth:`rates`)."""
        if type(zoom) is not float or not 1.0 <= zoom <= ZOOM_MAX:
            zoom = check_real("zoom", zoom, 1.0, ZOOM_MAX, "ratio")
        s = 10.0 * zoom
        return Attitude(self.roll_raw / s, self.pitch_raw / s, self.yaw_raw / s)


class HostMainFrame(NamedTuple):
    """Host main frame, bytes 5–36 (raw integers)."""

    control_roll_raw: int = 0
    """Bytes 5–6, S16: control value (rate or angle, per mode)."""
    control_pitch_raw: int = 0
    """Bytes 7–8, S16."""
    control_yaw_raw: int = 0
    """Bytes 9–10, S16."""
    flags_raw: int = 0
    """Byte 11: B2 control values valid, B0 aircraft INS valid."""
    aircraft_roll_raw: int = 0
    """Bytes 12–13, S16, 0.01° (range: ``HOST_MAIN_SCHEMA``)."""
    aircraft_pitch_raw: int = 0
    """Bytes 14–15, S16, 0.01° (range: ``HOST_MAIN_SCHEMA``)."""
    aircraft_yaw_raw: int = 0
    """Bytes 16–17, U16, 0.01° (range: ``HOST_MAIN_SCHEMA``)."""
    accel_north_raw: int = 0
    """Bytes 18–19, S16, 0.01 m/s², gravity excluded."""
    accel_east_raw: int = 0
    """Bytes 20–21."""
    accel_up_raw: int = 0
    """Bytes 22–23, up positive."""
    vel_north_raw: int = 0
    """Bytes 24–25, S16, 0.01 m/s."""
    vel_east_raw: int = 0
    """Bytes 26–27."""
    vel_up_raw: int = 0
    """Bytes 28–29, up positive."""
    subframe_request: int = 0
    """Byte 30: GCU sub-frame request code (0x01 standard, 0x00 none)."""

    @classmethod
    def build(
        cls,
        *,
        control: ControlValues | None = None,
        attitude: Attitude | tuple[float, float, float] | None = None,
        acceleration: NorthEastUp | tuple[float, float, float] | None = None,
        velocity: NorthEastUp | tuple[float, float, float] | None = None,
        subframe_request: int = SubFrameRequest.STANDARD,
    ) -> HostMainFrame:
        """Build from engineering units. ``control=None`` sends the control values invalid
        (B2 = 0). The INS-valid bit (B0) is set only when ``attitude``, ``acceleration`` and
        ``velocity`` are all given: a part left ``None`` is sent as zeros, and zeros are
        never marked valid (docs/protocol-notes.md, "10. Aircraft acceleration excludes
        gravity"). ``control`` is checked with :meth:`ControlValues.check`; the tuples are
        checked element by element (``aircraft roll``, ``aircraft velocity up``, …)."""
        flags = 0
        c = ControlValues.check(control) if control is not None else ControlValues()
        if control is not None:
            flags |= HostFlags.CONTROL_VALID
        if attitude is not None and acceleration is not None and velocity is not None:
            flags |= HostFlags.INS_VALID
        roll = pitch = yaw = 0
        if attitude is not None:
            a_roll, a_pitch, a_yaw = check_tuple("attitude", attitude, Attitude)
            roll, pitch, yaw = _ROLL(a_roll), _PITCH(a_pitch), _YAW(a_yaw)
        an, ae, au = _neu("acceleration", acceleration)
        vn, ve, vu = _neu("velocity", velocity)
        HOST_MAIN_SCHEMA.check("subframe_request", subframe_request)
        return cls(*c, int(flags), roll, pitch, yaw, an, ae, au, vn, ve, vu, int(subframe_request))

    # -- unit views --------------------------------------------------------------------
    @property
    def flags(self) -> HostFlags:
        return HostFlags(self.flags_raw)

    @property
    def control_valid(self) -> bool:
        return bool(self.flags_raw & HostFlags.CONTROL_VALID)

    @property
    def ins_valid(self) -> bool:
        return bool(self.flags_raw & HostFlags.INS_VALID)

    @property
    def control(self) -> ControlValues:
        return ControlValues(self.control_roll_raw, self.control_pitch_raw, self.control_yaw_raw)

    @property
    def aircraft_attitude(self) -> Attitude:
        """Aircraft absolute roll, pitch, yaw in degrees."""
        return _aircraft_attitude(self)

    @property
    def acceleration(self) -> NorthEastUp:
        """Aircraft acceleration north/east/up in m/s², gravity excluded."""
        return _acceleration(self)

    @property
    def velocity(self) -> NorthEastUp:
        """Aircraft velocity north/east/up in m/s."""
        return _velocity(self)

    def validate(self) -> None:
        """Raise :class:`FieldRangeError` for any raw field outside its wire range."""
        HOST_MAIN_SCHEMA.validate(self)

    @property
    def anomalies(self) -> tuple[Anomaly, ...]:
        """Fields of a decoded frame outside the ranges V2.0.6 gives them (control values,
        aircraft attitude) and reserved flag bits, kept raw and flagged (docs/client.md,
        "Liberal receive, strict send")."""
        return HOST_MAIN_SCHEMA.anomalies(self)

    def as_dict(self) -> dict[str, Any]:
        """Every field, in units and raw, for JSON output."""
        return {
            "control_raw": list(self.control),
            "control_as_angles_deg": list(self.control.as_angles()),
            "control_valid": self.control_valid,
            "ins_valid": self.ins_valid,
            "flags_raw": self.flags_raw,
            "aircraft_attitude_deg": self.aircraft_attitude._asdict(),
            "aircraft_attitude_raw": [
                self.aircraft_roll_raw, self.aircraft_pitch_raw, self.aircraft_yaw_raw
            ],
            "acceleration_m_s2": self.acceleration._asdict(),
            "acceleration_raw": [self.accel_north_raw, self.accel_east_raw, self.accel_up_raw],
            "velocity_m_s": self.velocity._asdict(),
            "velocity_raw": [self.vel_north_raw, self.vel_east_raw, self.vel_up_raw],
            "subframe_request": self.subframe_request,
            **HOST_MAIN_SCHEMA.plain_dict(self, _MAIN_SHOWN),
        }  # fmt: skip


def _neu(
    field: str, value: NorthEastUp | tuple[float, float, float] | None
) -> tuple[int, int, int]:
    if value is None:
        return (0, 0, 0)
    n, e, u = check_tuple(field, value, NorthEastUp)
    qn, qe, qu = _NEU[field]
    return qn(n), qe(e), qu(u)


_q = HOST_MAIN_SCHEMA.quantizer
_ROLL = _q("aircraft_roll_raw", "aircraft roll")
_PITCH = _q("aircraft_pitch_raw", "aircraft pitch")
_YAW = _q("aircraft_yaw_raw", "aircraft yaw")
_NEU = {field: tuple(_q(f"{prefix}_{axis}_raw", f"aircraft {field} {axis}")
                     for axis in ("north", "east", "up"))
        for field, prefix in (("acceleration", "accel"), ("velocity", "vel"))}  # fmt: skip


class HostSubFrame(NamedTuple):
    """Host sub frame 0x01, bytes 38–68 (raw integers): the aircraft's GNSS data."""

    longitude_raw: int = 0
    """Bytes 38–41, S32, 1e-7°."""
    latitude_raw: int = 0
    """Bytes 42–45, S32, 1e-7°."""
    altitude_raw: int = 0
    """Bytes 46–49, S32, mm above mean sea level."""
    satellites: int = 0
    """Byte 50, U8."""
    gnss_ms: int = 0
    """Bytes 51–54, U32: milliseconds of the GNSS week."""
    gnss_week: int = 0
    """Bytes 55–56, S16: GNSS week number."""
    relative_altitude_raw: int = 0
    """Bytes 57–60, S32, mm (0 if not needed)."""


    @classmethod
    def build(
        cls,
        *,
        latitude: float,
        longitude: float,
        altitude: float,
        satellites: int = 0,
        gnss_week: int = 0,
        gnss_ms: int = 0,
        gnss_time: datetime | None = None,
        relative_altitude: float = 0.0,
        apply_leap_seconds: bool = True,
    ) -> HostSubFrame:
        """Build from degrees and metres. ``gnss_time`` (an aware UTC datetime) replaces
        ``gnss_week``/``gnss_ms`` (giving both is a ``ValueError``), converted to GPS time
        with leap seconds applied unless ``apply_leap_seconds=False`` (the document's rule);
        :meth:`gnss_time` reads it back with the same default (see
        :mod:`gcu_async.protocol.gpstime`)."""
        lon, lat, alt = _LONGITUDE(longitude), _LATITUDE(latitude), _ALTITUDE(altitude)
        check = HOST_SUB_SCHEMA.check
        sats = check("satellites", satellites)
        ms = check("gnss_ms", gnss_ms)
        week = check("gnss_week", gnss_week)
        rel = _RELATIVE_ALTITUDE(relative_altitude)
        check_bool("apply_leap_seconds", apply_leap_seconds)
        if gnss_time is not None:
            from gcu_async.protocol.gpstime import utc_to_gps

            if week or ms:
                raise ValueError("gnss_time: give gnss_time or gnss_week/gnss_ms, not both "
                                 f"(got gnss_week={week}, gnss_ms={ms})")  # fmt: skip
            week, ms = utc_to_gps(gnss_time, apply_leap_seconds=apply_leap_seconds)
            check("gnss_week", week, "gnss_week (of gnss_time)")  # after the year 2608
        return cls(lon, lat, alt, sats, ms, week, rel)

    @property
    def latitude(self) -> float:
        return self.latitude_raw / _S["latitude_raw"].scale

    @property
    def longitude(self) -> float:
        return self.longitude_raw / _S["longitude_raw"].scale

    @property
    def altitude(self) -> float:
        """Metres above mean sea level."""
        return self.altitude_raw / _S["altitude_raw"].scale

    @property
    def relative_altitude(self) -> float:
        return self.relative_altitude_raw / _S["relative_altitude_raw"].scale

    @property
    def position(self) -> GeoPosition:
        return _position(self)

    def gnss_time(self, *, apply_leap_seconds: bool = True) -> datetime:
        """GNSS week + ms (GPS time) as a UTC datetime: leap seconds removed, as
        :meth:`build` and the client added them (``apply_leap_seconds=False``: the
        document's rule, which ignores them)."""
        from gcu_async.protocol.gpstime import gps_to_utc

        return gps_to_utc(self.gnss_week, self.gnss_ms, apply_leap_seconds=apply_leap_seconds)

    def validate(self) -> None:
        """Raise :class:`FieldRangeError` for any raw field outside its wire range."""
        HOST_SUB_SCHEMA.validate(self)

    @property
    def anomalies(self) -> tuple[Anomaly, ...]:
        """Fields of a decoded frame outside the ranges V2.0.6 gives them (longitude,
        latitude, GNSS time), kept raw and flagged (docs/client.md, "Liberal receive,
        strict send")."""
        return HOST_SUB_SCHEMA.anomalies(self)

    def as_dict(self) -> dict[str, Any]:
        return {
            "header": SUB_FRAME_HEADER,
            "latitude_deg": self.latitude,
            "longitude_deg": self.longitude,
            "altitude_m": self.altitude,
            "latitude_raw": self.latitude_raw,
            "longitude_raw": self.longitude_raw,
            "altitude_raw": self.altitude_raw,
            "satellites": self.satellites,
            "gnss_week": self.gnss_week,
            "gnss_ms": self.gnss_ms,
            "gnss_time_utc": self.gnss_time().isoformat(),
            "gnss_time_document_rule": self.gnss_time(apply_leap_seconds=False).isoformat(),
            "relative_altitude_m": self.relative_altitude,
            "relative_altitude_raw": self.relative_altitude_raw,
            **HOST_SUB_SCHEMA.plain_dict(self, _SUB_SHOWN),
        }


HOST_MAIN_SCHEMA.install(HostMainFrame)
HOST_SUB_SCHEMA.install(HostSubFrame)
_LONGITUDE = HOST_SUB_SCHEMA.quantizer("longitude_raw", "longitude")
_LATITUDE = HOST_SUB_SCHEMA.quantizer("latitude_raw", "latitude")
_ALTITUDE = HOST_SUB_SCHEMA.quantizer("altitude_raw", "altitude")
_RELATIVE_ALTITUDE = HOST_SUB_SCHEMA.quantizer("relative_altitude_raw", "relative altitude")
