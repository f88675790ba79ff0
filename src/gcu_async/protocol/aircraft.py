"""The aircraft state a host sends in every packet (host main frame bytes 11–29, sub frame).

Acceleration is north/east/up **without gravity** (zero at rest or in straight,
constant-speed flight) and velocity north/east/up (docs/protocol-notes.md §10 "Aircraft
acceleration excludes gravity"); wrong values corrupt the gimbal's attitude solution.
Fields left ``None`` are never invented: the INS-valid bit is set only when attitude,
acceleration and velocity are all given (else the INS bytes are zeros, marked invalid); no
position → no sub frame. How long a given state stays current is the session's business
(:mod:`gcu_async.session.feed`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from datetime import datetime
from typing import Any, NamedTuple

from gcu_async._checks import check_instance, check_int, check_real
from gcu_async.protocol.enums import SubFrameRequest
from gcu_async.protocol.fields import WireField
from gcu_async.protocol.gpstime import utc_to_gps
from gcu_async.protocol.host_frame_tables import (
    GNSS_WEEK_MAX,
    HOST_MAIN_SCHEMA,
    HOST_SUB_SCHEMA,
    ControlValues,
)
from gcu_async.protocol.host_frames import HostMainFrame, HostSubFrame
from gcu_async.protocol.units import (
    YAW_INPUT_RANGE,
    Attitude,
    GeoPosition,
    NorthEastUp,
    check_sequence,
    check_tuple,
    wrap_degrees_360,
)

_ZERO_ATTITUDE = Attitude(0.0, 0.0, 0.0)
_ZERO_NEU = NorthEastUp(0.0, 0.0, 0.0)


@dataclass(frozen=True, slots=True)
class AircraftState:
    """Aircraft attitude (°; yaw a heading), acceleration (m/s², N/E/U, gravity excluded),
    velocity (m/s, N/E/U), position (°, ° , m MSL), relative altitude (m), satellites and
    GNSS week + milliseconds of week. Validated on construction under the package rule: each
    tuple field is ``None``, its NamedTuple or a plain tuple (stored as the NamedTuple),
    checked element by element; the integers are ``int``. A ``dataclasses.replace`` of a
    state validates again. ``gnss_week`` = ``gnss_ms`` = 0 means "no GNSS time" (the
    wire's all-zero)."""

    attitude: Attitude | None = None
    acceleration: NorthEastUp | None = None
    velocity: NorthEastUp | None = None
    position: GeoPosition | None = None
    relative_altitude: float = 0.0
    satellites: int = 0
    gnss_week: int = 0
    gnss_ms: int = 0

    def __post_init__(self) -> None:
        for name, cls in (("attitude", Attitude), ("acceleration", NorthEastUp),
                          ("velocity", NorthEastUp), ("position", GeoPosition)):  # fmt: skip
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, check_tuple(name, value, cls))
        # every part given is checked against its wire field, even while the others are not
        HostMainFrame.build(
            attitude=_ZERO_ATTITUDE if self.attitude is None else self.attitude,
            acceleration=_ZERO_NEU if self.acceleration is None else self.acceleration,
            velocity=_ZERO_NEU if self.velocity is None else self.velocity,
        )
        # the sub-frame fields are checked even while no position makes a sub frame
        check = HOST_SUB_SCHEMA.check
        check("satellites", self.satellites)
        check("gnss_week", self.gnss_week)
        check("gnss_ms", self.gnss_ms)
        _S["relative_altitude_raw"].to_raw(self.relative_altitude, "relative_altitude")
        self.sub_frame()

    @staticmethod
    def gnss_from_utc(utc: datetime, *, apply_leap_seconds: bool = True) -> tuple[int, int]:
        """(week, ms) for a UTC time; GNSS receivers count GPS time, so leap seconds are
        applied by default, as :meth:`HostSubFrame.gnss_time` removes them (the document's
        Appendix 6 functions do neither: ``apply_leap_seconds=False``)."""
        return utc_to_gps(utc, apply_leap_seconds=apply_leap_seconds)

    @property
    def ins_complete(self) -> bool:
        """True when attitude, acceleration and velocity are all given: only then may the
        INS-valid bit be set."""
        return not (self.attitude is None or self.acceleration is None or self.velocity is None)

    def main_frame(
        self,
        control: ControlValues | None = None,
        subframe_request: int = SubFrameRequest.STANDARD,
    ) -> HostMainFrame:
        """Host main frame with this state and the given control values (None = invalid;
        checked with :meth:`ControlValues.check`). The INS bytes carry attitude,
        acceleration and velocity marked valid when :attr:`ins_complete`; otherwise they are
        all zeros and the INS-valid bit is clear (a part given alone is not sent)."""
        if self.ins_complete:
            return HostMainFrame.build(
                control=control,
                attitude=self.attitude,
                acceleration=self.acceleration,
                velocity=self.velocity,
                subframe_request=subframe_request,
            )
        return HostMainFrame.build(control=control, subframe_request=subframe_request)

    def sub_frame(self) -> HostSubFrame | None:
        """Host sub frame 0x01, or ``None`` when no position is known."""
        if self.position is None:
            return None
        lat, lon, alt = self.position
        return HostSubFrame.build(
            latitude=lat,
            longitude=lon,
            altitude=alt,
            satellites=self.satellites,
            gnss_week=self.gnss_week,
            gnss_ms=self.gnss_ms,
            relative_altitude=self.relative_altitude,
        )


# -- an update's arguments, checked with no client (GcuClient.update_aircraft delegates) -----
_M = HOST_MAIN_SCHEMA.by_name
_S = HOST_SUB_SCHEMA.by_name


class InputRange(NamedTuple):
    """What an aircraft update accepts for one value, in engineering units."""

    low: float
    high: float
    high_open: bool
    unit: str


def input_range(field: WireField) -> InputRange:
    """The engineering-unit range of a host frame field (``raw / scale``)."""
    high = field.raw_high + field.high_open
    return InputRange(field.raw_low / field.scale, high / field.scale, field.high_open, field.unit)


AIRCRAFT_INPUTS: dict[str, tuple[type[Any], tuple[InputRange, ...]]] = {
    "attitude": (Attitude, (input_range(_M["aircraft_roll_raw"]),
                            input_range(_M["aircraft_pitch_raw"]),
                            InputRange(*YAW_INPUT_RANGE, True, "deg"))),  # sent wrapped [0, 360)
    "acceleration": (NorthEastUp, tuple(input_range(_M[f"accel_{axis}_raw"])
                                        for axis in ("north", "east", "up"))),
    "velocity": (NorthEastUp, tuple(input_range(_M[f"vel_{axis}_raw"])
                                    for axis in ("north", "east", "up"))),
    "position": (GeoPosition, (input_range(_S["latitude_raw"]), input_range(_S["longitude_raw"]),
                               input_range(_S["altitude_raw"]))),
}  # fmt: skip
"""The aircraft values given as triples: their type and each element's range, derived from
the host frame schema (the main frame's aircraft data and the sub frame); the attitude's yaw
also takes MAVLink's signed yaw (:data:`~gcu_async.protocol.catalogue.YAW_INPUT_RANGE`)."""
RELATIVE_ALTITUDE_INPUT = input_range(_S["relative_altitude_raw"])
AIRCRAFT_UPDATE_FIELDS = ("attitude", "acceleration", "velocity", "position",
                          "relative_altitude", "satellites", "gnss_week", "gnss_ms",
                          "gnss_time")  # fmt: skip
"""The values :func:`aircraft_update` takes, in the order it checks them."""


def _triple(name: str, value: object) -> Any:
    kind, ranges = AIRCRAFT_INPUTS[name]
    elements: tuple[Any, ...] = check_sequence(name, value, kind)
    fields: tuple[str, ...] = kind._fields
    checked = [check_real(f"{name}.{field}", v, r.low, r.high, r.unit, high_open=r.high_open)
               for field, v, r in zip(fields, elements, ranges, strict=True)]  # fmt: skip
    if kind is Attitude:
        checked[2] = wrap_degrees_360(checked[2])
    return kind(*checked)


def aircraft_update(given: Mapping[str, object]) -> dict[str, Any]:
    """Check the arguments of an aircraft update, with no client: ``given`` maps the names
    of :data:`AIRCRAFT_UPDATE_FIELDS` that were given to their values (a triple: a
    NamedTuple, a tuple or a list of three, or ``None`` to clear it; ``gnss_time``: an
    aware UTC ``datetime``, ``None`` meaning not given). Returns the changes for
    ``Session.update_aircraft``: the triples as their NamedTuples (the attitude's yaw
    wrapped into a heading), ``gnss_time`` as ``gnss_week`` + ``gnss_ms`` (leap seconds applied).

    Raises, checking in the order of :data:`AIRCRAFT_UPDATE_FIELDS`, ``TypeError`` or
    :class:`FieldRangeError` naming the value (``attitude.pitch``, ``gnss_week``), or
    ``ValueError`` for ``gnss_time`` given with ``gnss_week``/``gnss_ms`` or past the last
    GNSS week the packet carries. This is what :meth:`GcuClient.update_aircraft` checks."""
    unknown = sorted(str(k) for k in given if k not in AIRCRAFT_UPDATE_FIELDS)
    if unknown:
        raise TypeError(f"aircraft update: {', '.join(unknown)}: not one of "
                        f"{', '.join(AIRCRAFT_UPDATE_FIELDS)}")  # fmt: skip
    changes: dict[str, Any] = {}
    for name in ("attitude", "acceleration", "velocity", "position"):
        if name in given:
            value = given[name]
            changes[name] = None if value is None else _triple(name, value)
    if "relative_altitude" in given:
        r = RELATIVE_ALTITUDE_INPUT
        changes["relative_altitude"] = check_real("relative_altitude", given["relative_altitude"],
                                                  r.low, r.high, r.unit)  # fmt: skip
    for name in ("satellites", "gnss_week", "gnss_ms"):
        if name in given:
            f = _S[name]
            changes[name] = check_int(name, given[name], f.raw_low, f.raw_high)
    if given.get("gnss_time") is not None:
        gnss_time = check_instance("gnss_time", given["gnss_time"], datetime)
        if "gnss_week" in given or "gnss_ms" in given:
            raise ValueError("gnss_time: give either gnss_time or gnss_week/gnss_ms, "
                             "not both")  # fmt: skip
        week, ms = AircraftState.gnss_from_utc(gnss_time)
        if week > GNSS_WEEK_MAX:
            raise ValueError(f"gnss_time: {gnss_time.isoformat()} is after the last GNSS "
                             f"week the packet carries ({GNSS_WEEK_MAX})")  # fmt: skip
        changes["gnss_week"], changes["gnss_ms"] = week, ms
    return changes
