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

from dataclasses import dataclass
from datetime import datetime

from gcu_async._checks import check_int
from gcu_async.protocol.enums import SubFrameRequest
from gcu_async.protocol.gpstime import utc_to_gps
from gcu_async.protocol.host_frames import (
    MS_PER_WEEK,
    ControlValues,
    HostMainFrame,
    HostSubFrame,
)
from gcu_async.protocol.layout import S32
from gcu_async.protocol.units import Attitude, GeoPosition, NorthEastUp, check_tuple, quantize

_ZERO_ATTITUDE = Attitude(0.0, 0.0, 0.0)
_ZERO_NEU = NorthEastUp(0.0, 0.0, 0.0)


@dataclass(frozen=True, slots=True)
class AircraftState:
    """Aircraft attitude (°; yaw in [0, 360)), acceleration (m/s², N/E/U, gravity excluded),
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
        check_int("satellites", self.satellites, 0, 255)
        check_int("gnss_week", self.gnss_week, 0, 32767)
        check_int("gnss_ms", self.gnss_ms, 0, MS_PER_WEEK - 1, "ms")
        quantize("relative altitude", self.relative_altitude, 1000, *S32, "m")
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
