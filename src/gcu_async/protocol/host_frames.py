"""Host → GCU frames: main frame (bytes 5–36) and sub frame (bytes 37–68).

Each frame is one table, :data:`HOST_MAIN_SCHEMA` and :data:`HOST_SUB_SCHEMA`, as the GCU
frames' (:mod:`~gcu_async.protocol.gcu_frames`); the classes below the marker line are
generated from them by ``tools/gen_frames.py``. :class:`ControlValues` (bytes 5–10, whose
meaning depends on the mode) and the readings the tables cannot say are written here.
"""

from __future__ import annotations

from datetime import datetime
from typing import NamedTuple, TypedDict

from gcu_async._checks import check_bool, check_instance, check_int, check_real
from gcu_async.protocol.anomalies import Anomaly
from gcu_async.protocol.enums import HostFlags, SubFrameRequest
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
    Entry,
    Flags,
    FrameSchema,
    Group,
    Method,
    Value,
    flag_text,
    group_text,
    number_text,
)
from gcu_async.protocol.gpstime import MS_PER_WEEK as MS_PER_WEEK  # re-exported
from gcu_async.protocol.gpstime import gps_to_utc, utc_to_gps
from gcu_async.protocol.headings import HeadingRule, heading
from gcu_async.protocol.layout import MAIN_SIZE, MAIN_START, SUB_SIZE, SUB_START
from gcu_async.protocol.layout import SUB_FRAME_HEADER as SUB_FRAME_HEADER  # re-exported
from gcu_async.protocol.units import Attitude, GeoPosition, NorthEastUp, check_tuple, quantize

D001 = "0.01 deg"
CONTROL_RATE_RAW = 1500
"""The control values' rate range, ± this raw (0.1 °/s ÷ zoom): a part of the fields' range
(:data:`CONTROL_ANGLE_RAW`) the document gives the rates."""
ZOOM_MAX = CAMERA_ZOOM.limits[1]
"""Largest zoom ratio the GCU can report (sub frame camera zoom: U16, 0.1×)."""


class ControlValues(NamedTuple):
    """Host main frame bytes 5–10 as raw S16 values; their meaning depends on the mode
    (docs/protocol-notes.md §5 "Control values change meaning with the mode"). Build them with
    :meth:`angles` or :meth:`rates`, which check their arguments.

    Invariant: each raw value is an ``int`` in the control fields' range
    (± :data:`CONTROL_ANGLE_RAW`; rates use ± :data:`CONTROL_RATE_RAW` of it).
    A ``NamedTuple`` cannot check itself when built raw (``ControlValues(99999, 0, 0)``), so
    every consumer checks it with :meth:`check` (or :meth:`validate`) before storing or
    sending it; :meth:`HostMainFrame.build` does.
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
        """Desired angles in degrees (Euler or relative, per mode), 0.01° resolution, within
        the control fields' range."""
        r = CONTROL_ANGLE_RAW
        return cls(
            quantize("control roll angle", roll, _ANGLE, -r, r, "deg"),
            quantize("control pitch angle", pitch, _ANGLE, -r, r, "deg"),
            quantize("control yaw angle", yaw, _ANGLE, -r, r, "deg"),
        )

    @classmethod
    def rates(
        cls, roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0, *, zoom: float = 1.0
    ) -> ControlValues:
        """Desired angular rates in °/s. The wire value is in units of 0.1/zoom °/s (the
        current main-view zoom ratio), range ± :data:`CONTROL_RATE_RAW`, so the reachable
        rate shrinks with zoom. ``zoom`` is a real number from 1 to :data:`ZOOM_MAX` (what
        the GCU can report)."""
        zoom = check_real("zoom", zoom, 1.0, ZOOM_MAX, "ratio")
        scale = _RATE * zoom
        r = CONTROL_RATE_RAW
        return cls(
            quantize("control roll rate", roll, scale, -r, r, f"deg/s at zoom {zoom:g}x"),
            quantize("control pitch rate", pitch, scale, -r, r, f"deg/s at zoom {zoom:g}x"),
            quantize("control yaw rate", yaw, scale, -r, r, f"deg/s at zoom {zoom:g}x"),
        )

    def as_angles(self) -> Attitude:
        """Read the raw values as angles (degrees)."""
        return Attitude(self.roll_raw / _ANGLE, self.pitch_raw / _ANGLE, self.yaw_raw / _ANGLE)

    def as_rates(self, zoom: float = 1.0) -> Attitude:
        """Read the raw values as angular rates (°/s) at the given zoom ratio (checked as in
        :meth:`rates`)."""
        if type(zoom) is not float or not 1.0 <= zoom <= ZOOM_MAX:
            zoom = check_real("zoom", zoom, 1.0, ZOOM_MAX, "ratio")
        s = _RATE * zoom
        return Attitude(self.roll_raw / s, self.pitch_raw / s, self.yaw_raw / s)


# -- the readings and keywords the tables cannot say ---------------------------------------
def control_raws(control: ControlValues | None = None) -> tuple[int, int, int]:
    """``None`` sends the control values invalid (zeros, B2 = 0); else checked with
    :meth:`ControlValues.check`."""
    return (0, 0, 0) if control is None else ControlValues.check(control)


def host_flags(
    control: ControlValues | None = None,
    attitude: Attitude | tuple[float, float, float] | None = None,
    acceleration: NorthEastUp | tuple[float, float, float] | None = None,
    velocity: NorthEastUp | tuple[float, float, float] | None = None,
) -> int:
    """B2 (control values valid) when ``control`` is given; B0 (INS valid) only when
    ``attitude``, ``acceleration`` and ``velocity`` all are: a part left ``None`` is sent as
    zeros, and zeros are never marked valid (docs/protocol-notes.md, "10. Aircraft
    acceleration excludes gravity")."""
    flags = HostFlags.CONTROL_VALID if control is not None else 0
    if attitude is not None and acceleration is not None and velocity is not None:
        flags |= HostFlags.INS_VALID
    return int(flags)


def control_as_angles(control_roll_raw: int, control_pitch_raw: int,
                      control_yaw_raw: int) -> list[float]:  # fmt: skip
    """The control values read as angles in degrees (``as_dict``: whatever the mode)."""
    return list(ControlValues(control_roll_raw, control_pitch_raw, control_yaw_raw).as_angles())


def gnss_raws(gnss_week: int = 0, gnss_ms: int = 0, gnss_time: datetime | None = None,
              apply_leap_seconds: bool = True) -> tuple[int, int]:  # fmt: skip
    """``gnss_time`` (an aware UTC datetime) replaces ``gnss_week``/``gnss_ms`` (giving both is
    a ``ValueError``), converted to GPS time with leap seconds applied unless
    ``apply_leap_seconds=False`` (the document's rule; :mod:`gcu_async.protocol.gpstime`)."""
    check = HOST_SUB_SCHEMA.check
    week, ms = check("gnss_week", gnss_week), check("gnss_ms", gnss_ms)
    check_bool("apply_leap_seconds", apply_leap_seconds)
    if gnss_time is None:
        return week, ms
    if week or ms:
        raise ValueError("gnss_time: give gnss_time or gnss_week/gnss_ms, not both "
                         f"(got gnss_week={week}, gnss_ms={ms})")  # fmt: skip
    week, ms = utc_to_gps(gnss_time, apply_leap_seconds=apply_leap_seconds)
    return check("gnss_week", week, "gnss_week (of gnss_time)"), ms  # after the year 2608


def gnss_time_utc(gnss_week: int, gnss_ms: int) -> str:
    """The GNSS time as UTC, ISO 8601, leap seconds removed (``as_dict``)."""
    return gps_to_utc(gnss_week, gnss_ms).isoformat()


def gnss_time_document_rule(gnss_week: int, gnss_ms: int) -> str:
    """The GNSS time by the document's rule (no leap seconds), ISO 8601 (``as_dict``)."""
    return gps_to_utc(gnss_week, gnss_ms, apply_leap_seconds=False).isoformat()


# -- the tables ------------------------------------------------------------------------------
_AXES = ("roll", "pitch", "yaw")
_NEU = ("north", "east", "up")
HOST_MAIN_SCHEMA = FrameSchema("HostMainFrame", "host main frame", MAIN_START, MAIN_SIZE, (
    *(WireField(f"control_{axis}_raw", "h", "control value (rate or angle, per mode)",
                *ANGLE_RANGE) for axis in _AXES),
    WireField("flags_raw", "B", "B2 control values valid, B0 aircraft INS valid"),
    WireField("aircraft_roll_raw", "h", "aircraft roll", *ANGLE_RANGE, 100, "deg", D001,
              high_open=True),
    WireField("aircraft_pitch_raw", "h", "aircraft pitch", *TILT_RANGE, 100, "deg", D001),
    heading("aircraft_yaw_raw", "aircraft yaw"),
    *(WireField(f"accel_{axis}_raw", "h", f"aircraft acceleration {axis}, gravity excluded",
                scale=100, unit="m/s^2", raw_unit="0.01 m/s^2") for axis in _NEU),
    *(WireField(f"vel_{axis}_raw", "h", f"aircraft velocity {axis}", scale=100, unit="m/s",
                raw_unit="0.01 m/s") for axis in _NEU),
    WireField("subframe_request", "B", "GCU sub-frame request code (0x01 standard, 0x00 none)"),
), (
    Group(name="control", fields=tuple(f"control_{a}_raw" for a in _AXES), cls=ControlValues,
          write=control_raws, key=None,
          doc="The control values, raw (their meaning depends on the mode)."),
    Entry(name="control_as_angles_deg", fields=tuple(f"control_{a}_raw" for a in _AXES),
          read=control_as_angles),
    Bit(name="control_valid", fields=("flags_raw",), member=HostFlags.CONTROL_VALID,
        doc="B2: the control values are valid."),
    Bit(name="ins_valid", fields=("flags_raw",), member=HostFlags.INS_VALID,
        doc="B0: the aircraft INS data (attitude, acceleration, velocity) is valid."),
    Flags(name="flags", fields=("flags_raw",), flags=HostFlags, write=host_flags, key=None,
          doc="The flags byte."),
    Group(name="aircraft_attitude", fields=tuple(f"aircraft_{a}_raw" for a in _AXES),
          cls=Attitude, keyword="attitude", labels=tuple(f"aircraft {a}" for a in _AXES),
          doc="Aircraft absolute roll, pitch, yaw in degrees."),
    Group(name="acceleration", fields=tuple(f"accel_{a}_raw" for a in _NEU), cls=NorthEastUp,
          labels=tuple(f"aircraft acceleration {a}" for a in _NEU),
          doc="Aircraft acceleration north/east/up in m/s², gravity excluded."),
    Group(name="velocity", fields=tuple(f"vel_{a}_raw" for a in _NEU), cls=NorthEastUp,
          labels=tuple(f"aircraft velocity {a}" for a in _NEU),
          doc="Aircraft velocity north/east/up in m/s."),
    Value(name="subframe_request", fields=("subframe_request",),
          default=SubFrameRequest.STANDARD),
), flags={"flags_raw": HostFlags})  # fmt: skip
"""Bytes 5–36 of a host packet: the one table of the main frame."""
AIRCRAFT_YAW = HeadingRule(HOST_MAIN_SCHEMA["aircraft_yaw_raw"])
"""The aircraft yaw read as a heading whatever the host sends (docs/protocol-notes.md §15):
what the simulator uses; decoding keeps the raw value."""
CONTROL_ANGLE_RAW = HOST_MAIN_SCHEMA["control_roll_raw"].raw_high
"""The control values' range, ± this raw (the rates use less of it: :data:`CONTROL_RATE_RAW`)."""
_ANGLE = 100  # raw steps per degree of a control angle (0.01°)
_RATE = 10  # raw steps per °/s of a control rate at zoom 1 (0.1 °/s ÷ zoom)

HOST_SUB_SCHEMA = FrameSchema("HostSubFrame", "host sub frame 0x01", SUB_START, SUB_SIZE, (
    WireField("longitude_raw", "i", "aircraft longitude", *LONGITUDE_RANGE, 1e7, "deg",
              "1e-7 deg"),
    WireField("latitude_raw", "i", "aircraft latitude", *LATITUDE_RANGE, 1e7, "deg",
              "1e-7 deg"),
    WireField("altitude_raw", "i", "altitude above mean sea level", scale=1000, unit="m",
              raw_unit="mm"),
    WireField("satellites", "B", "satellites used"),
    WireField("gnss_ms", "I", "milliseconds of the GNSS week", 0, MS_PER_WEEK, unit="ms",
              raw_unit="ms", high_open=True),
    WireField("gnss_week", "h", "GNSS week number", 0),
    WireField("relative_altitude_raw", "i", "altitude relative to take-off (0 if not needed)",
              scale=1000, unit="m", raw_unit="mm"),
), (
    Group(name="position", fields=("latitude_raw", "longitude_raw", "altitude_raw"),
          cls=GeoPosition, keyword=None, key=None,
          doc="Aircraft position: degrees, metres above mean sea level."),
    Value(name="latitude", fields=("latitude_raw",), required=True, doc="Latitude, degrees."),
    Value(name="longitude", fields=("longitude_raw",), required=True,
          doc="Longitude, degrees."),
    Value(name="altitude", fields=("altitude_raw",), required=True,
          doc="Metres above mean sea level."),
    Value(name="satellites", fields=("satellites",)),
    Method(name="gnss_time", fields=("gnss_week", "gnss_ms"), read=gps_to_utc, write=gnss_raws,
           doc="GNSS week + ms (GPS time) as a UTC datetime: leap seconds removed, as "
               ":meth:`build` and the client added them (``apply_leap_seconds=False``: the "
               "document's rule, which ignores them)."),
    Entry(name="gnss_time_utc", fields=("gnss_week", "gnss_ms"), read=gnss_time_utc),
    Entry(name="gnss_time_document_rule", fields=("gnss_week", "gnss_ms"),
          read=gnss_time_document_rule),
    Value(name="relative_altitude", fields=("relative_altitude_raw",), default=0.0,
          doc="Altitude relative to take-off, metres (0 if not needed)."),
), header=SUB_FRAME_HEADER)  # fmt: skip
"""Bytes 38–68 of a host packet when the sub frame header (byte 37) is 0x01: the aircraft's
GNSS data (the ranges of :meth:`GcuClient.update_aircraft` and :class:`AircraftState`)."""
GNSS_WEEK_MAX = HOST_SUB_SCHEMA["gnss_week"].raw_high
"""The last GNSS week the host sub frame carries (S16)."""

# --- generated by tools/gen_frames.py from the tables above: edit them, then run it ---


class HostMainFrameDict(TypedDict):
    """What :meth:`HostMainFrame.as_dict` returns."""

    control_raw: list[int]
    control_as_angles_deg: list[float]
    control_valid: bool
    ins_valid: bool
    flags_raw: int
    aircraft_attitude_deg: dict[str, float]
    aircraft_attitude_raw: list[int]
    acceleration_m_s2: dict[str, float]
    acceleration_raw: list[int]
    velocity_m_s: dict[str, float]
    velocity_raw: list[int]
    subframe_request: int


class HostMainFrame(NamedTuple):
    """Host main frame, bytes 5–36 (raw integers): the fields of ``HOST_MAIN_SCHEMA``."""

    control_roll_raw: int = 0
    """Bytes 5–6, S16, [-18000, 18000]: control value (rate or angle, per mode)."""
    control_pitch_raw: int = 0
    """Bytes 7–8, S16, [-18000, 18000]: control value (rate or angle, per mode)."""
    control_yaw_raw: int = 0
    """Bytes 9–10, S16, [-18000, 18000]: control value (rate or angle, per mode)."""
    flags_raw: int = 0
    """Byte 11, U8: B2 control values valid, B0 aircraft INS valid."""
    aircraft_roll_raw: int = 0
    """Bytes 12–13, S16, 0.01 deg, [-18000, 18000): aircraft roll."""
    aircraft_pitch_raw: int = 0
    """Bytes 14–15, S16, 0.01 deg, [-9000, 9000]: aircraft pitch."""
    aircraft_yaw_raw: int = 0
    """Bytes 16–17, U16, 0.01 deg, [0, 36000): aircraft yaw."""
    accel_north_raw: int = 0
    """Bytes 18–19, S16, 0.01 m/s^2: aircraft acceleration north, gravity excluded."""
    accel_east_raw: int = 0
    """Bytes 20–21, S16, 0.01 m/s^2: aircraft acceleration east, gravity excluded."""
    accel_up_raw: int = 0
    """Bytes 22–23, S16, 0.01 m/s^2: aircraft acceleration up, gravity excluded."""
    vel_north_raw: int = 0
    """Bytes 24–25, S16, 0.01 m/s: aircraft velocity north."""
    vel_east_raw: int = 0
    """Bytes 26–27, S16, 0.01 m/s: aircraft velocity east."""
    vel_up_raw: int = 0
    """Bytes 28–29, S16, 0.01 m/s: aircraft velocity up."""
    subframe_request: int = 0
    """Byte 30, U8: GCU sub-frame request code (0x01 standard, 0x00 none)."""

    @property
    def control(self) -> ControlValues:
        """The control values, raw (their meaning depends on the mode)."""
        return ControlValues(self.control_roll_raw, self.control_pitch_raw, self.control_yaw_raw)

    @property
    def control_valid(self) -> bool:
        """B2: the control values are valid."""
        return bool(self.flags_raw & HostFlags.CONTROL_VALID)

    @property
    def ins_valid(self) -> bool:
        """B0: the aircraft INS data (attitude, acceleration, velocity) is valid."""
        return bool(self.flags_raw & HostFlags.INS_VALID)

    @property
    def flags(self) -> HostFlags:
        """The flags byte."""
        return HostFlags(self.flags_raw)

    @property
    def aircraft_attitude(self) -> Attitude:
        """Aircraft absolute roll, pitch, yaw in degrees."""
        return Attitude(
            self.aircraft_roll_raw / 100, self.aircraft_pitch_raw / 100,
            self.aircraft_yaw_raw / 100)

    @property
    def acceleration(self) -> NorthEastUp:
        """Aircraft acceleration north/east/up in m/s², gravity excluded."""
        return NorthEastUp(
            self.accel_north_raw / 100, self.accel_east_raw / 100, self.accel_up_raw / 100)

    @property
    def velocity(self) -> NorthEastUp:
        """Aircraft velocity north/east/up in m/s."""
        return NorthEastUp(self.vel_north_raw / 100, self.vel_east_raw / 100, self.vel_up_raw / 100)

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
        """Build from engineering units: each value checked and converted to its raw field
        (rounded to the wire's step), a ``TypeError`` or :class:`FieldRangeError` naming it;
        integer codes and flags take their enum members or any value of the field."""
        control_roll_raw, control_pitch_raw, control_yaw_raw = control_raws(control=control)
        flags_raw = host_flags(
            control=control, attitude=attitude, acceleration=acceleration, velocity=velocity)
        if attitude is None:
            aircraft_roll_raw = aircraft_pitch_raw = aircraft_yaw_raw = 0
        else:
            attitude = check_tuple("attitude", attitude, Attitude)
            aircraft_roll_raw = HOST_MAIN_SCHEMA["aircraft_roll_raw"].to_raw(
                attitude[0], "aircraft roll")
            aircraft_pitch_raw = HOST_MAIN_SCHEMA["aircraft_pitch_raw"].to_raw(
                attitude[1], "aircraft pitch")
            aircraft_yaw_raw = HOST_MAIN_SCHEMA["aircraft_yaw_raw"].to_raw(
                attitude[2], "aircraft yaw")
        if acceleration is None:
            accel_north_raw = accel_east_raw = accel_up_raw = 0
        else:
            acceleration = check_tuple("acceleration", acceleration, NorthEastUp)
            accel_north_raw = HOST_MAIN_SCHEMA["accel_north_raw"].to_raw(
                acceleration[0], "aircraft acceleration north")
            accel_east_raw = HOST_MAIN_SCHEMA["accel_east_raw"].to_raw(
                acceleration[1], "aircraft acceleration east")
            accel_up_raw = HOST_MAIN_SCHEMA["accel_up_raw"].to_raw(
                acceleration[2], "aircraft acceleration up")
        if velocity is None:
            vel_north_raw = vel_east_raw = vel_up_raw = 0
        else:
            velocity = check_tuple("velocity", velocity, NorthEastUp)
            vel_north_raw = HOST_MAIN_SCHEMA["vel_north_raw"].to_raw(
                velocity[0], "aircraft velocity north")
            vel_east_raw = HOST_MAIN_SCHEMA["vel_east_raw"].to_raw(
                velocity[1], "aircraft velocity east")
            vel_up_raw = HOST_MAIN_SCHEMA["vel_up_raw"].to_raw(velocity[2], "aircraft velocity up")
        subframe_request = HOST_MAIN_SCHEMA.check(
            "subframe_request", subframe_request, "subframe_request")
        return cls(
            control_roll_raw, control_pitch_raw, control_yaw_raw, flags_raw, aircraft_roll_raw,
            aircraft_pitch_raw, aircraft_yaw_raw, accel_north_raw, accel_east_raw, accel_up_raw,
            vel_north_raw, vel_east_raw, vel_up_raw, subframe_request)

    def validate(self) -> None:
        """Raise ``TypeError`` / :class:`FieldRangeError` for the first field (wire order) that
        is not an ``int`` in its range (``HOST_MAIN_SCHEMA``; flags: no reserved bit set)."""
        (control_roll_raw, control_pitch_raw, control_yaw_raw, flags_raw, aircraft_roll_raw,
            aircraft_pitch_raw, aircraft_yaw_raw, accel_north_raw, accel_east_raw, accel_up_raw,
            vel_north_raw, vel_east_raw, vel_up_raw, subframe_request) = self
        if type(flags_raw) is HostFlags:
            flags_raw = int(flags_raw)
        if (int is type(control_roll_raw) is type(control_pitch_raw) is type(control_yaw_raw) is
            type(flags_raw) is type(aircraft_roll_raw) is type(aircraft_pitch_raw) is
            type(aircraft_yaw_raw) is type(accel_north_raw) is type(accel_east_raw) is
            type(accel_up_raw) is type(vel_north_raw) is type(vel_east_raw) is type(vel_up_raw) is
            type(subframe_request) and
            -18000 <= control_roll_raw <= 18000 and -18000 <= control_pitch_raw <= 18000 and
            -18000 <= control_yaw_raw <= 18000 and flags_raw >= 0 and not flags_raw & ~0x05 and
            -18000 <= aircraft_roll_raw <= 17999 and -9000 <= aircraft_pitch_raw <= 9000 and
            0 <= aircraft_yaw_raw <= 35999 and -32768 <= accel_north_raw <= 32767 and
            -32768 <= accel_east_raw <= 32767 and -32768 <= accel_up_raw <= 32767 and
            -32768 <= vel_north_raw <= 32767 and -32768 <= vel_east_raw <= 32767 and
            -32768 <= vel_up_raw <= 32767 and 0 <= subframe_request <= 255):
            return
        HOST_MAIN_SCHEMA.validate(self)

    @property
    def anomalies(self) -> tuple[Anomaly, ...]:
        """Fields of a decoded frame outside the ranges V2.0.6 gives them (or with reserved bits
        set), kept raw and flagged (docs/client.md, "Liberal receive, strict send"); empty for
        an ordinary frame."""
        (control_roll_raw, control_pitch_raw, control_yaw_raw, flags_raw, aircraft_roll_raw,
            aircraft_pitch_raw, aircraft_yaw_raw, accel_north_raw, accel_east_raw, accel_up_raw,
            vel_north_raw, vel_east_raw, vel_up_raw, subframe_request) = self
        if (-18000 <= control_roll_raw <= 18000 and -18000 <= control_pitch_raw <= 18000 and
            -18000 <= control_yaw_raw <= 18000 and flags_raw >= 0 and not flags_raw & ~0x05 and
            -18000 <= aircraft_roll_raw <= 17999 and -9000 <= aircraft_pitch_raw <= 9000 and
            0 <= aircraft_yaw_raw <= 35999 and -32768 <= accel_north_raw <= 32767 and
            -32768 <= accel_east_raw <= 32767 and -32768 <= accel_up_raw <= 32767 and
            -32768 <= vel_north_raw <= 32767 and -32768 <= vel_east_raw <= 32767 and
            -32768 <= vel_up_raw <= 32767 and 0 <= subframe_request <= 255):
            return ()
        return HOST_MAIN_SCHEMA.anomalies(self)

    def __str__(self) -> str:
        """Engineering units (``print(frame)``); ``repr()`` keeps the raw fields."""
        return (f"HostMainFrame(control {group_text(self.control, '')}, "
                f"flags {flag_text(self.flags)}, "
                f"aircraft attitude {group_text(self.aircraft_attitude, 'deg')}, "
                f"acceleration {group_text(self.acceleration, 'm/s^2')}, "
                f"velocity {group_text(self.velocity, 'm/s')}, "
                f"subframe request {number_text(self.subframe_request, '')})"
        )

    def as_dict(self) -> HostMainFrameDict:
        """Every field, in engineering units and raw, for JSON output
        (:class:`HostMainFrameDict`)."""
        return {
            "control_raw": [self.control_roll_raw, self.control_pitch_raw, self.control_yaw_raw],
            "control_as_angles_deg": control_as_angles(
                self.control_roll_raw, self.control_pitch_raw, self.control_yaw_raw
            ),
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
        }



class HostSubFrameDict(TypedDict):
    """What :meth:`HostSubFrame.as_dict` returns."""

    header: int
    """Byte 37, the sub frame header: 0x01, the standard sub frame (an :class:`UnknownSubFrame`'s
    dict gives its own header)."""
    latitude_deg: float
    latitude_raw: int
    longitude_deg: float
    longitude_raw: int
    altitude_m: float
    altitude_raw: int
    satellites: int
    gnss_week: int
    gnss_ms: int
    gnss_time_utc: str
    gnss_time_document_rule: str
    relative_altitude_m: float
    relative_altitude_raw: int


class HostSubFrame(NamedTuple):
    """Host sub frame 0x01, bytes 38–68 (raw integers): the fields of ``HOST_SUB_SCHEMA``."""

    longitude_raw: int = 0
    """Bytes 38–41, S32, 1e-7 deg, [-1800000000, 1800000000]: aircraft longitude."""
    latitude_raw: int = 0
    """Bytes 42–45, S32, 1e-7 deg, [-900000000, 900000000]: aircraft latitude."""
    altitude_raw: int = 0
    """Bytes 46–49, S32, mm: altitude above mean sea level."""
    satellites: int = 0
    """Byte 50, U8: satellites used."""
    gnss_ms: int = 0
    """Bytes 51–54, U32, [0, 604800000): milliseconds of the GNSS week."""
    gnss_week: int = 0
    """Bytes 55–56, S16, [0, 32767]: GNSS week number."""
    relative_altitude_raw: int = 0
    """Bytes 57–60, S32, mm: altitude relative to take-off (0 if not needed)."""

    @property
    def position(self) -> GeoPosition:
        """Aircraft position: degrees, metres above mean sea level."""
        return GeoPosition(
            self.latitude_raw / 10000000.0, self.longitude_raw / 10000000.0,
            self.altitude_raw / 1000)

    @property
    def latitude(self) -> float:
        """Latitude, degrees."""
        return self.latitude_raw / 10000000.0

    @property
    def longitude(self) -> float:
        """Longitude, degrees."""
        return self.longitude_raw / 10000000.0

    @property
    def altitude(self) -> float:
        """Metres above mean sea level."""
        return self.altitude_raw / 1000

    def gnss_time(self, *, apply_leap_seconds: bool = True) -> datetime:
        """GNSS week + ms (GPS time) as a UTC datetime: leap seconds removed, as :meth:`build`
        and the client added them (``apply_leap_seconds=False``: the document's rule, which
        ignores them)."""
        return gps_to_utc(self.gnss_week, self.gnss_ms, apply_leap_seconds=apply_leap_seconds)

    @property
    def relative_altitude(self) -> float:
        """Altitude relative to take-off, metres (0 if not needed)."""
        return self.relative_altitude_raw / 1000

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
        apply_leap_seconds: bool = True,
        relative_altitude: float = 0.0,
    ) -> HostSubFrame:
        """Build from engineering units: each value checked and converted to its raw field
        (rounded to the wire's step), a ``TypeError`` or :class:`FieldRangeError` naming it;
        integer codes and flags take their enum members or any value of the field."""
        latitude_raw = HOST_SUB_SCHEMA["latitude_raw"].to_raw(latitude, "latitude")
        longitude_raw = HOST_SUB_SCHEMA["longitude_raw"].to_raw(longitude, "longitude")
        altitude_raw = HOST_SUB_SCHEMA["altitude_raw"].to_raw(altitude, "altitude")
        satellites = HOST_SUB_SCHEMA.check("satellites", satellites, "satellites")
        gnss_week, gnss_ms = gnss_raws(
            gnss_week=gnss_week, gnss_ms=gnss_ms, gnss_time=gnss_time,
            apply_leap_seconds=apply_leap_seconds)
        relative_altitude_raw = HOST_SUB_SCHEMA["relative_altitude_raw"].to_raw(
            relative_altitude, "relative_altitude")
        return cls(
            longitude_raw, latitude_raw, altitude_raw, satellites, gnss_ms, gnss_week,
            relative_altitude_raw)

    def validate(self) -> None:
        """Raise ``TypeError`` / :class:`FieldRangeError` for the first field (wire order) that
        is not an ``int`` in its range (``HOST_SUB_SCHEMA``; flags: no reserved bit set)."""
        (longitude_raw, latitude_raw, altitude_raw, satellites, gnss_ms, gnss_week,
            relative_altitude_raw) = self
        if (int is type(longitude_raw) is type(latitude_raw) is type(altitude_raw) is
            type(satellites) is type(gnss_ms) is type(gnss_week) is type(relative_altitude_raw) and
            -1800000000 <= longitude_raw <= 1800000000 and
            -900000000 <= latitude_raw <= 900000000 and
            -2147483648 <= altitude_raw <= 2147483647 and 0 <= satellites <= 255 and
            0 <= gnss_ms <= 604799999 and 0 <= gnss_week <= 32767 and
            -2147483648 <= relative_altitude_raw <= 2147483647):
            return
        HOST_SUB_SCHEMA.validate(self)

    @property
    def anomalies(self) -> tuple[Anomaly, ...]:
        """Fields of a decoded frame outside the ranges V2.0.6 gives them (or with reserved bits
        set), kept raw and flagged (docs/client.md, "Liberal receive, strict send"); empty for
        an ordinary frame."""
        (longitude_raw, latitude_raw, altitude_raw, satellites, gnss_ms, gnss_week,
            relative_altitude_raw) = self
        if (-1800000000 <= longitude_raw <= 1800000000 and
            -900000000 <= latitude_raw <= 900000000 and
            -2147483648 <= altitude_raw <= 2147483647 and 0 <= satellites <= 255 and
            0 <= gnss_ms <= 604799999 and 0 <= gnss_week <= 32767 and
            -2147483648 <= relative_altitude_raw <= 2147483647):
            return ()
        return HOST_SUB_SCHEMA.anomalies(self)

    def __str__(self) -> str:
        """Engineering units (``print(frame)``); ``repr()`` keeps the raw fields."""
        return (f"HostSubFrame(latitude {number_text(self.latitude, 'deg')}, "
                f"longitude {number_text(self.longitude, 'deg')}, "
                f"altitude {number_text(self.altitude, 'm')}, "
                f"satellites {number_text(self.satellites, '')}, "
                f"relative altitude {number_text(self.relative_altitude, 'm')})"
        )

    def as_dict(self) -> HostSubFrameDict:
        """Every field, in engineering units and raw, for JSON output
        (:class:`HostSubFrameDict`)."""
        return {
            "header": 0x01,
            "latitude_deg": self.latitude,
            "latitude_raw": self.latitude_raw,
            "longitude_deg": self.longitude,
            "longitude_raw": self.longitude_raw,
            "altitude_m": self.altitude,
            "altitude_raw": self.altitude_raw,
            "satellites": self.satellites,
            "gnss_week": self.gnss_week,
            "gnss_ms": self.gnss_ms,
            "gnss_time_utc": gnss_time_utc(self.gnss_week, self.gnss_ms),
            "gnss_time_document_rule": gnss_time_document_rule(self.gnss_week, self.gnss_ms),
            "relative_altitude_m": self.relative_altitude,
            "relative_altitude_raw": self.relative_altitude_raw,
        }


# --- end of generated code ---
