"""The host → GCU frame tables: main frame (bytes 5–36) and sub frame (bytes 37–68).

Each frame is one table, :data:`HOST_MAIN_SCHEMA` and :data:`HOST_SUB_SCHEMA`, as the GCU
frames' (:mod:`~gcu_async.protocol.gcu_frame_tables`); the frame classes
(:class:`~gcu_async.protocol.host_frames.HostMainFrame`, ``HostSubFrame``) are generated from
them into :mod:`~gcu_async.protocol.host_frames` by ``tools/gen_frames.py``.
:class:`ControlValues` (bytes 5–10, whose meaning depends on the mode: the main table's
``control`` view) and the readings the tables cannot say are written here.
"""

from __future__ import annotations

from datetime import datetime
from typing import NamedTuple

from gcu_async._checks import check_bool, check_instance, check_int, check_real
from gcu_async.protocol.enums import HostFlags, SubFrameRequest
from gcu_async.protocol.fields import (
    ANGLE_RANGE,
    CAMERA_ZOOM,
    CENTIDEGREE,
    LATITUDE_RANGE,
    LONGITUDE_RANGE,
    TILT_RANGE,
    WireField,
)
from gcu_async.protocol.frame_schema import Bit, Entry, Flags, FrameSchema, Group, Method, Value
from gcu_async.protocol.gpstime import MS_PER_WEEK, gps_to_utc, utc_to_gps
from gcu_async.protocol.headings import HeadingRule, heading
from gcu_async.protocol.layout import MAIN_SIZE, MAIN_START, SUB_FRAME_HEADER, SUB_SIZE, SUB_START
from gcu_async.protocol.units import Attitude, GeoPosition, NorthEastUp, quantize

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
    sending it; :meth:`gcu_async.protocol.HostMainFrame.build` does.
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
    WireField("aircraft_roll_raw", "h", "aircraft roll", *ANGLE_RANGE, 100, "deg", CENTIDEGREE,
              high_open=True),
    WireField("aircraft_pitch_raw", "h", "aircraft pitch", *TILT_RANGE, 100, "deg", CENTIDEGREE),
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
