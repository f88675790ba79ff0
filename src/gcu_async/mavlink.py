"""MAVLink → :class:`~gcu_async.protocol.aircraft.AircraftState` (optional: ``gcu-async[mavlink]``).

Feeds the aircraft data of host main frame bytes 11–29 and sub frame bytes 38–60 from an
autopilot's MAVLink stream. One pure function per conversion, plus :class:`MavlinkAircraftState`
which keeps the latest value of each field (``None`` until its source message arrived).

============================  =====================================================
MAVLink message               AircraftState field
============================  =====================================================
ATTITUDE                      attitude: rad → °, roll signed, yaw a compass heading
GLOBAL_POSITION_INT           position (1e-7 °, mm MSL), relative_altitude (mm),
                              velocity (cm/s NED → m/s N/E/U: up = −vz)
LOCAL_POSITION_NED            velocity (m/s NED → N/E/U); acceleration (its default
                              source) = Δvelocity/Δtime_boot_ms (up = −Δvz/Δt)
SCALED_IMU[2,3]/HIGHRES_IMU   acceleration = R·f + (0, 0, g) in NED, then up = −down
  /RAW_IMU
GPS_RAW_INT                   satellites (255 = unknown → 0)
SYSTEM_TIME                   gnss_week, gnss_ms (GPS time: leap seconds applied)
============================  =====================================================

Acceleration must exclude gravity (docs/protocol-notes.md §10 "Aircraft acceleration excludes
gravity": zero at rest or in straight, constant-speed flight; an autopilot driver
that sent raw accelerometer output made the gimbal drift), so it comes from exactly one
source chosen when the mapper is built. Velocity comes from whichever of GLOBAL_POSITION_INT
and LOCAL_POSITION_NED arrived last (both carry the estimator's north/east/down velocity), so
a vehicle without a global position still gives all three INS parts: the packets mark the
INS data valid only when attitude, acceleration and velocity are all known
(docs/client.md, "Aircraft data: what the packets claim").

Out-of-range values are **raised, not clamped or dropped**: :meth:`MavlinkAircraftState.update`
lets :class:`~gcu_async.errors.FieldRangeError` (e.g. an acceleration beyond the S16 field's
±327.67 m/s² after an estimator reset) propagate and leaves :attr:`~MavlinkAircraftState.state`
as it was, so the caller decides whether to log, skip or stop.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from datetime import datetime, timedelta, timezone
from typing import Any, Protocol

try:
    import pymavlink  # noqa: F401  (the mapper reads fields only; this checks the extra)
except ImportError as exc:
    raise ImportError(
        "gcu_async.mavlink needs pymavlink: pip install 'gcu-async[mavlink]'"
    ) from exc

from gcu_async.protocol.aircraft import AircraftState
from gcu_async.protocol.units import (
    Attitude,
    GeoPosition,
    NorthEastUp,
    wrap_degrees_180,
    wrap_degrees_360,
)

__all__ = [
    "ACCELERATION_SOURCES",
    "MILLI_G",
    "STANDARD_GRAVITY",
    "MavlinkAircraftState",
    "acceleration_from_imu",
    "acceleration_from_specific_force",
    "acceleration_from_velocity_change",
    "convert_attitude",
    "convert_local_velocity",
    "convert_position",
    "convert_relative_altitude",
    "convert_satellites",
    "convert_system_time",
    "convert_velocity",
]

STANDARD_GRAVITY = 9.80665
"""m/s², the g that MAVLink's milli-g (mG) unit refers to."""
MILLI_G = STANDARD_GRAVITY / 1000
"""m/s² per mG: the unit of SCALED_IMU* accelerations (and of ArduPilot's RAW_IMU)."""
IMU_SCALES: dict[str, float | None] = {
    "SCALED_IMU": MILLI_G,
    "SCALED_IMU2": MILLI_G,
    "SCALED_IMU3": MILLI_G,
    "HIGHRES_IMU": 1.0,
    "RAW_IMU": None,  # "raw sensor units": the caller must state the scale
}
ACCELERATION_SOURCES = ("LOCAL_POSITION_NED", *IMU_SCALES)
"""Message types :class:`MavlinkAircraftState` can derive acceleration from."""
_UNIX_EPOCH = datetime(1970, 1, 1, tzinfo=timezone.utc)
_TIME_BOOT_WRAP = 2**32


# -- the message fields read (pymavlink messages have no type hints) ----------------------
class MavlinkMessage(Protocol):
    def get_type(self) -> str: ...


class AttitudeMsg(Protocol):
    roll: float
    pitch: float
    yaw: float


class GlobalPositionIntMsg(Protocol):
    lat: int
    lon: int
    alt: int
    relative_alt: int
    vx: int
    vy: int
    vz: int


class LocalPositionNedMsg(Protocol):
    time_boot_ms: int
    vx: float
    vy: float
    vz: float


class ImuMsg(Protocol):
    xacc: float
    yacc: float
    zacc: float


class GpsRawIntMsg(Protocol):
    satellites_visible: int


class SystemTimeMsg(Protocol):
    time_unix_usec: int


@dataclass
class _VelocitySample:
    """A copy of the LOCAL_POSITION_NED fields the next difference needs."""

    time_boot_ms: int
    vx: float
    vy: float
    vz: float


# -- pure conversions ---------------------------------------------------------------------
def convert_attitude(msg: AttitudeMsg) -> Attitude:
    """ATTITUDE (rad) → degrees; roll wrapped signed
    (:func:`~gcu_async.protocol.units.wrap_degrees_180`), yaw to a compass heading
    (:func:`~gcu_async.protocol.units.wrap_degrees_360`).

    Wrapping happens at the wire's 0.01° resolution, so a yaw of −0.001° becomes 0.00°, not
    360.00° (which bytes 16–17 cannot carry). Pitch is converted as is (a quarter turn
    either way by definition).
    """
    return Attitude(
        wrap_degrees_180(round(math.degrees(msg.roll), 2)),
        math.degrees(msg.pitch),
        wrap_degrees_360(round(math.degrees(msg.yaw), 2)),
    )


def convert_position(msg: GlobalPositionIntMsg) -> GeoPosition:
    """GLOBAL_POSITION_INT lat/lon (1e-7 °) and alt (mm above MSL) → degrees, metres."""
    return GeoPosition(msg.lat / 1e7, msg.lon / 1e7, msg.alt / 1000)


def convert_relative_altitude(msg: GlobalPositionIntMsg) -> float:
    """GLOBAL_POSITION_INT relative_alt (mm above home) → metres."""
    return msg.relative_alt / 1000


def convert_velocity(msg: GlobalPositionIntMsg) -> NorthEastUp:
    """GLOBAL_POSITION_INT vx/vy/vz (cm/s, north/east/**down**) → m/s north/east/up."""
    return NorthEastUp(msg.vx / 100, msg.vy / 100, -msg.vz / 100)


def convert_local_velocity(msg: LocalPositionNedMsg) -> NorthEastUp:
    """LOCAL_POSITION_NED vx/vy/vz (m/s, north/east/**down**) → m/s north/east/up."""
    return NorthEastUp(float(msg.vx), float(msg.vy), -float(msg.vz))


def acceleration_from_velocity_change(
    previous: LocalPositionNedMsg, current: LocalPositionNedMsg, *, max_interval: float = 1.0
) -> NorthEastUp | None:
    """Mean acceleration (m/s², N/E/U) between two LOCAL_POSITION_NED samples (vx/vy/vz in
    m/s NED): gravity-free by construction. ``None`` when the interval is zero, longer than
    ``max_interval`` seconds, or negative (a reboot; time_boot_ms wrap-around is handled)."""
    dt_ms = (current.time_boot_ms - previous.time_boot_ms) % _TIME_BOOT_WRAP
    if dt_ms == 0 or dt_ms > max_interval * 1000:
        return None
    dt = dt_ms / 1000
    return NorthEastUp(
        (current.vx - previous.vx) / dt,
        (current.vy - previous.vy) / dt,
        -(current.vz - previous.vz) / dt,
    )


def acceleration_from_specific_force(
    force: tuple[float, float, float], attitude: Attitude, *, gravity: float = STANDARD_GRAVITY
) -> NorthEastUp:
    """Accelerometer specific force (m/s², body frame forward/right/down) → acceleration
    without gravity (m/s², N/E/U): a_NED = R·f + (0, 0, g) with R body→NED from the Euler
    angles (Z→Y→X); at rest f = Rᵀ·(0, 0, −g), so the result is zero at any attitude."""
    fx, fy, fz = force
    phi, theta, psi = (math.radians(a) for a in attitude)
    sf, cf = math.sin(phi), math.cos(phi)
    st, ct = math.sin(theta), math.cos(theta)
    sp, cp = math.sin(psi), math.cos(psi)
    north = ct * cp * fx + (sf * st * cp - cf * sp) * fy + (cf * st * cp + sf * sp) * fz
    east = ct * sp * fx + (sf * st * sp + cf * cp) * fy + (cf * st * sp - sf * cp) * fz
    down = -st * fx + sf * ct * fy + cf * ct * fz + gravity
    return NorthEastUp(north, east, -down)


def acceleration_from_imu(msg: ImuMsg, attitude: Attitude, *, scale: float) -> NorthEastUp:
    """IMU xacc/yacc/zacc × ``scale`` (m/s² per unit: :data:`MILLI_G` for SCALED_IMU*, 1.0
    for HIGHRES_IMU) rotated to the earth frame with ``attitude``, gravity removed."""
    force = (msg.xacc * scale, msg.yacc * scale, msg.zacc * scale)
    return acceleration_from_specific_force(force, attitude)


def convert_satellites(msg: GpsRawIntMsg) -> int:
    """GPS_RAW_INT satellites_visible; MAVLink's 255 ("unknown") becomes 0 (byte 50 has no
    "unknown" value, and 255 satellites would be a lie)."""
    return 0 if msg.satellites_visible == 255 else int(msg.satellites_visible)


def convert_system_time(msg: SystemTimeMsg) -> tuple[int, int] | None:
    """SYSTEM_TIME time_unix_usec (UTC) → (GNSS week, ms of week) with leap seconds applied
    (sub frame bytes 51–56); ``None`` for 0, MAVLink's "no time". A time before the GPS
    epoch raises ``ValueError``."""
    if msg.time_unix_usec == 0:
        return None
    utc = _UNIX_EPOCH + timedelta(microseconds=msg.time_unix_usec)
    return AircraftState.gnss_from_utc(utc, apply_leap_seconds=True)


# -- the stateful mapper ------------------------------------------------------------------
class MavlinkAircraftState:
    """Latest aircraft state assembled from MAVLink messages (pymavlink ``MAVLink_message``
    objects or anything with ``get_type()`` and the same fields).

    ``acceleration_source`` picks the one message acceleration comes from:
    ``"LOCAL_POSITION_NED"`` (default: differentiated estimator velocity, at most
    ``max_interval`` s apart), an IMU message (``"SCALED_IMU"``, ``"SCALED_IMU2"``,
    ``"SCALED_IMU3"``, ``"HIGHRES_IMU"``, or ``"RAW_IMU"`` with ``raw_imu_scale`` in m/s² per
    unit — ArduPilot sends mG, i.e. :data:`MILLI_G`; IMU messages need an ATTITUDE first), or
    ``None`` (acceleration stays ``None``).
    """

    def __init__(
        self,
        *,
        acceleration_source: str | None = "LOCAL_POSITION_NED",
        raw_imu_scale: float | None = None,
        max_interval: float = 1.0,
    ) -> None:
        if acceleration_source is not None and acceleration_source not in ACCELERATION_SOURCES:
            raise ValueError(
                f"acceleration_source: {acceleration_source!r} is not one of "
                f"{', '.join(ACCELERATION_SOURCES)} or None"
            )
        if acceleration_source == "RAW_IMU" and raw_imu_scale is None:
            raise ValueError(
                "raw_imu_scale: RAW_IMU is in raw sensor units; give the scale in m/s² per "
                "unit (MILLI_G for ArduPilot)"
            )
        if raw_imu_scale is not None and acceleration_source != "RAW_IMU":
            raise ValueError("raw_imu_scale: only used with acceleration_source='RAW_IMU'")
        self._accel_source = acceleration_source
        self._imu_scale = IMU_SCALES.get(acceleration_source or "") or raw_imu_scale
        self._max_interval = max_interval
        self._previous_local: _VelocitySample | None = None
        self._state = AircraftState()
        self._changes: dict[str, Any] = {}
        self._used: set[str] = set()

    @property
    def state(self) -> AircraftState:
        """The current state (fields without a source message yet are ``None`` / 0)."""
        return self._state

    @property
    def changes(self) -> dict[str, Any]:
        """The fields the last message used gave (a new dict each time): pass them on with
        ``gcu.update_aircraft(**mapper.changes)`` so that each part counts as current only
        while its own message keeps arriving (``gcu.set_aircraft(mapper.state)`` counts the
        whole state as current at every message)."""
        return dict(self._changes)

    @property
    def used_types(self) -> frozenset[str]:
        """MAVLink message types that have contributed so far."""
        return frozenset(self._used)

    def update(self, msg: MavlinkMessage) -> bool:
        """Apply one message; True if it was used. Raises FieldRangeError (or ValueError for
        a SYSTEM_TIME before 1980) and keeps the previous state when a value cannot be sent."""
        kind = msg.get_type()
        changes = self._changes_of(kind, msg)
        if changes is None:
            return False
        if changes:
            self._state = replace(self._state, **changes)
        self._changes = changes
        self._used.add(kind)
        return True

    def _changes_of(self, kind: str, msg: Any) -> dict[str, Any] | None:
        if kind == "ATTITUDE":
            return {"attitude": convert_attitude(msg)}
        if kind == "GLOBAL_POSITION_INT":
            return {
                "position": convert_position(msg),
                "relative_altitude": convert_relative_altitude(msg),
                "velocity": convert_velocity(msg),
            }
        if kind == "GPS_RAW_INT":
            return {"satellites": convert_satellites(msg)}
        if kind == "SYSTEM_TIME":
            gnss = convert_system_time(msg)
            return None if gnss is None else {"gnss_week": gnss[0], "gnss_ms": gnss[1]}
        if kind == "LOCAL_POSITION_NED":
            changes: dict[str, Any] = {"velocity": convert_local_velocity(msg)}
            if self._accel_source != kind:
                return changes
            previous = self._previous_local
            self._previous_local = _VelocitySample(msg.time_boot_ms, msg.vx, msg.vy, msg.vz)
            accel = (
                None
                if previous is None
                else acceleration_from_velocity_change(
                    previous, msg, max_interval=self._max_interval
                )
            )
            if accel is not None:
                changes["acceleration"] = accel
            return changes
        if kind != self._accel_source:
            return None
        attitude = self._state.attitude
        if attitude is None or self._imu_scale is None:
            return None  # no attitude yet: the body-frame force cannot be rotated
        return {"acceleration": acceleration_from_imu(msg, attitude, scale=self._imu_scale)}
