"""Host → GCU frames: main frame (bytes 5–36) and sub frame (bytes 37–68).

Frames are immutable ``NamedTuple``s of the raw wire integers (cheap to build from
``struct.unpack``) with engineering-unit properties; ``build()`` constructs one from units.
"""

from __future__ import annotations

import struct
from datetime import datetime
from typing import Any, NamedTuple

from gcu_async._checks import check_bool, check_instance, check_int, check_real
from gcu_async.protocol.anomalies import (
    Anomaly,
    FieldRange,
    check_ranges,
    range_anomalies,
    reserved_bits_detail,
)
from gcu_async.protocol.enums import HostFlags, SubFrameRequest
from gcu_async.protocol.layout import S16, S32
from gcu_async.protocol.layout import SUB_FRAME_HEADER as SUB_FRAME_HEADER  # re-exported
from gcu_async.protocol.units import (
    Attitude,
    GeoPosition,
    NorthEastUp,
    check_flags,
    check_tuple,
    quantize,
)

HOST_MAIN = struct.Struct("<hhhBhhHhhhhhhB6x")
"""Bytes 5–36 of a host packet."""
HOST_SUB = struct.Struct("<iiiBIhi8x")
"""Bytes 38–68 of a host packet when the sub frame header (byte 37) is 0x01."""

CONTROL_ANGLE_RAW = 18000  # 0.01°
CONTROL_RATE_RAW = 1500  # 0.1 °/s ÷ zoom
ZOOM_MAX = 6553.5
"""Largest zoom ratio the GCU can report (sub frame camera zoom: U16, 0.1×)."""
MS_PER_WEEK = 604_800_000
_FLAG_BITS = 0
for _flag in HostFlags:
    _FLAG_BITS |= int(_flag)
_NOT_FLAG_BITS = ~_FLAG_BITS
"""Reserved bits of byte 11 (what ``check_flags(..., HostFlags)`` rejects)."""

HOST_MAIN_RANGES = (
    *(FieldRange(f"control_{axis}_raw", -CONTROL_ANGLE_RAW, CONTROL_ANGLE_RAW)
      for axis in ("roll", "pitch", "yaw")),
    FieldRange("aircraft_roll_raw", -18000, 17999, "0.01 deg"),
    FieldRange("aircraft_pitch_raw", -9000, 9000, "0.01 deg"),
    FieldRange("aircraft_yaw_raw", 0, 35999, "0.01 deg"),
    *(FieldRange(f"{kind}_{axis}_raw", *S16)
      for kind in ("accel", "vel") for axis in ("north", "east", "up")),
    FieldRange("subframe_request", 0, 255),
)  # fmt: skip
"""Each main-frame field's raw range but ``flags_raw`` (reserved bits: ``check_flags``),
in wire order (:class:`FieldRange`): the control values, then the rest."""
HOST_SUB_RANGES = (
    FieldRange("longitude_raw", -1_800_000_000, 1_800_000_000, "1e-7 deg"),
    FieldRange("latitude_raw", -900_000_000, 900_000_000, "1e-7 deg"),
    FieldRange("altitude_raw", *S32, "mm"),
    FieldRange("satellites", 0, 255),
    FieldRange("gnss_ms", 0, MS_PER_WEEK - 1, "ms"),
    FieldRange("gnss_week", 0, 32767),
    FieldRange("relative_altitude_raw", *S32, "mm"),
)
"""Each sub-frame field's raw range, in wire order (:class:`FieldRange`)."""


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
        """Raise unless each raw value is an ``int`` in [-18000, 18000] (see the class)."""
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
    """Bytes 12–13, S16, 0.01°, [-18000, 18000)."""
    aircraft_pitch_raw: int = 0
    """Bytes 14–15, S16, 0.01°, [-9000, 9000]."""
    aircraft_yaw_raw: int = 0
    """Bytes 16–17, U16, 0.01°, [0, 36000)."""
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
            roll = quantize("aircraft roll", a_roll, 100, -18000, 18000, "deg", high_open=True)
            pitch = quantize("aircraft pitch", a_pitch, 100, -9000, 9000, "deg")
            yaw = quantize("aircraft yaw", a_yaw, 100, 0, 36000, "deg", high_open=True)
        an, ae, au = _neu("aircraft acceleration", acceleration, "m/s^2")
        vn, ve, vu = _neu("aircraft velocity", velocity, "m/s")
        check_int("subframe_request", subframe_request, 0, 255)
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
        return Attitude(
            self.aircraft_roll_raw / 100, self.aircraft_pitch_raw / 100, self.aircraft_yaw_raw / 100
        )

    @property
    def acceleration(self) -> NorthEastUp:
        """Aircraft acceleration north/east/up in m/s², gravity excluded."""
        return NorthEastUp(
            self.accel_north_raw / 100, self.accel_east_raw / 100, self.accel_up_raw / 100
        )

    @property
    def velocity(self) -> NorthEastUp:
        """Aircraft velocity north/east/up in m/s."""
        return NorthEastUp(self.vel_north_raw / 100, self.vel_east_raw / 100, self.vel_up_raw / 100)

    def validate(self) -> None:
        """Raise :class:`FieldRangeError` for any raw field outside its wire range."""
        # Fast path (encode is hot): plain ints inside the very ranges checked below.
        # Anything else (bools, other int subclasses, wrong types, out of range) takes
        # the field-by-field checks, which raise the error naming the field.
        c1, c2, c3, fl, ar, ap, ay, a1, a2, a3, v1, v2, v3, req = self
        if type(fl) is HostFlags:  # what build() stores
            fl = int(fl)
        c = CONTROL_ANGLE_RAW
        if (
            int is type(c1) is type(c2) is type(c3) is type(fl) is type(ar) is type(ap)
            is type(ay) is type(a1) is type(a2) is type(a3) is type(v1) is type(v2)
            is type(v3) is type(req)
            and -c <= c1 <= c and -c <= c2 <= c and -c <= c3 <= c
            and fl >= 0 and not fl & _NOT_FLAG_BITS
            and -18000 <= ar <= 17999 and -9000 <= ap <= 9000 and 0 <= ay <= 35999
            and -32768 <= a1 <= 32767 and -32768 <= a2 <= 32767 and -32768 <= a3 <= 32767
            and -32768 <= v1 <= 32767 and -32768 <= v2 <= 32767 and -32768 <= v3 <= 32767
            and 0 <= req <= 255
        ):  # fmt: skip
            return
        check_ranges(self, HOST_MAIN_RANGES[:3])
        check_flags("flags_raw", self.flags_raw, HostFlags)
        check_ranges(self, HOST_MAIN_RANGES[3:])

    @property
    def anomalies(self) -> tuple[Anomaly, ...]:
        """Fields of a decoded frame outside the ranges V2.0.6 gives them (control values,
        aircraft attitude) and reserved flag bits, kept raw and flagged (docs/client.md,
        "Liberal receive, strict send")."""
        found = range_anomalies(self, HOST_MAIN_RANGES[:3])
        reserved = self.flags_raw & _NOT_FLAG_BITS
        if reserved:
            detail = reserved_bits_detail(reserved)
            found += (Anomaly("flags_raw", self.flags_raw, 0, _FLAG_BITS, "", detail),)
        return found + range_anomalies(self, HOST_MAIN_RANGES[3:])

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
        }  # fmt: skip


def _neu(
    field: str, value: NorthEastUp | tuple[float, float, float] | None, unit: str
) -> tuple[int, int, int]:
    if value is None:
        return (0, 0, 0)
    n, e, u = check_tuple(field.removeprefix("aircraft "), value, NorthEastUp)
    lo, hi = S16
    return (
        quantize(f"{field} north", n, 100, lo, hi, unit),
        quantize(f"{field} east", e, 100, lo, hi, unit),
        quantize(f"{field} up", u, 100, lo, hi, unit),
    )


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
        lon = quantize("longitude", longitude, 1e7, -1_800_000_000, 1_800_000_000, "deg")
        lat = quantize("latitude", latitude, 1e7, -900_000_000, 900_000_000, "deg")
        alt = quantize("altitude", altitude, 1000, *S32, "m")
        sats = check_int("satellites", satellites, 0, 255)
        ms = check_int("gnss_ms", gnss_ms, 0, MS_PER_WEEK - 1, "ms")
        week = check_int("gnss_week", gnss_week, 0, 32767)
        rel = quantize("relative altitude", relative_altitude, 1000, *S32, "m")
        check_bool("apply_leap_seconds", apply_leap_seconds)
        if gnss_time is not None:
            from gcu_async.protocol.gpstime import utc_to_gps

            if week or ms:
                raise ValueError("gnss_time: give gnss_time or gnss_week/gnss_ms, not both "
                                 f"(got gnss_week={week}, gnss_ms={ms})")  # fmt: skip
            week, ms = utc_to_gps(gnss_time, apply_leap_seconds=apply_leap_seconds)
            check_int("gnss_week (of gnss_time)", week, 0, 32767)  # after the year 2608
        return cls(lon, lat, alt, sats, ms, week, rel)

    @property
    def latitude(self) -> float:
        return self.latitude_raw / 1e7

    @property
    def longitude(self) -> float:
        return self.longitude_raw / 1e7

    @property
    def altitude(self) -> float:
        """Metres above mean sea level."""
        return self.altitude_raw / 1000

    @property
    def relative_altitude(self) -> float:
        return self.relative_altitude_raw / 1000

    @property
    def position(self) -> GeoPosition:
        return GeoPosition(self.latitude, self.longitude, self.altitude)

    def gnss_time(self, *, apply_leap_seconds: bool = True) -> datetime:
        """GNSS week + ms (GPS time) as a UTC datetime: leap seconds removed, as
        :meth:`build` and the client added them (``apply_leap_seconds=False``: the
        document's rule, which ignores them)."""
        from gcu_async.protocol.gpstime import gps_to_utc

        return gps_to_utc(self.gnss_week, self.gnss_ms, apply_leap_seconds=apply_leap_seconds)

    def validate(self) -> None:
        """Raise :class:`FieldRangeError` for any raw field outside its wire range."""
        # Fast path: plain ints inside the very ranges checked below (see HostMainFrame).
        lon, lat, alt, sats, ms, week, rel = self
        if (
            int is type(lon) is type(lat) is type(alt) is type(sats) is type(ms)
            is type(week) is type(rel)
            and -1_800_000_000 <= lon <= 1_800_000_000 and -900_000_000 <= lat <= 900_000_000
            and -(2**31) <= alt <= 2**31 - 1 and 0 <= sats <= 255
            and 0 <= ms <= MS_PER_WEEK - 1 and 0 <= week <= 32767
            and -(2**31) <= rel <= 2**31 - 1
        ):  # fmt: skip
            return
        check_ranges(self, HOST_SUB_RANGES)

    @property
    def anomalies(self) -> tuple[Anomaly, ...]:
        """Fields of a decoded frame outside the ranges V2.0.6 gives them (longitude,
        latitude, GNSS time), kept raw and flagged (docs/client.md, "Liberal receive,
        strict send")."""
        return range_anomalies(self, HOST_SUB_RANGES)

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
        }
