"""A steady, coordinated circle: the flight the demo MAVLink source plays.

Pure maths (no I/O, no pymavlink), so the source, the autopilot's smoke test and anyone
reading along agree on what "the truth" was. Frames: NED (north, east, down) as MAVLink
uses them; angles in degrees unless a name says ``_rad``.

The aircraft circles clockwise (seen from above) around ``centre`` at ``radius`` metres,
``height`` metres above home, at constant ``speed``: heading = bearing from the centre +
90°, acceleration = v²/r towards the centre (no vertical part), bank = atan(v²/(r·g)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

EARTH_RADIUS_M = 6_378_137.0
"""WGS-84 equatorial radius: a spherical local approximation is plenty for a 150 m circle."""
STANDARD_GRAVITY = 9.80665


@dataclass(frozen=True)
class FlightSample:
    """The aircraft at one instant."""

    t: float
    """Seconds since the start of the flight."""
    latitude: float
    longitude: float
    altitude: float
    """Metres above mean sea level."""
    relative_altitude: float
    """Metres above home."""
    position_ned: tuple[float, float, float]
    """Metres from home (the circle's centre on the ground), north/east/down."""
    velocity_ned: tuple[float, float, float]
    """m/s north/east/down."""
    acceleration_ned: tuple[float, float, float]
    """m/s² north/east/down, gravity excluded (what the GCU must be fed, as N/E/up)."""
    roll: float
    pitch: float
    yaw: float
    """Heading, [0, 360)."""
    body_rates: tuple[float, float, float]
    """Roll/pitch/yaw rates in rad/s (body frame)."""

    def specific_force_body(self) -> tuple[float, float, float]:
        """What an accelerometer measures (m/s², body forward/right/down): f = Rᵀ·(a − g),
        g = (0, 0, +9.81) in NED — at rest it reads −9.81 on the down axis."""
        an, ae, ad = self.acceleration_ned
        fn, fe, fd = an, ae, ad - STANDARD_GRAVITY
        phi, theta, psi = (math.radians(a) for a in (self.roll, self.pitch, self.yaw))
        sf, cf = math.sin(phi), math.cos(phi)
        st, ct = math.sin(theta), math.cos(theta)
        sp, cp = math.sin(psi), math.cos(psi)
        # rows of Rᵀ = columns of R (body → NED, Z-Y-X Euler angles)
        fx = ct * cp * fn + ct * sp * fe - st * fd
        fy = (sf * st * cp - cf * sp) * fn + (sf * st * sp + cf * cp) * fe + sf * ct * fd
        fz = (cf * st * cp + sf * sp) * fn + (cf * st * sp - sf * cp) * fe + cf * ct * fd
        return fx, fy, fz


@dataclass(frozen=True)
class CirclingFlight:
    """A clockwise circle at constant speed and height (defaults: a 150 m circle, 120 m
    above PX4's SITL home in Zürich, 15 m/s)."""

    centre_latitude: float = 47.397742
    centre_longitude: float = 8.545594
    home_altitude: float = 488.0
    """Metres MSL of home, the ground under the circle's centre."""
    height: float = 120.0
    radius: float = 150.0
    speed: float = 15.0
    pitch: float = 3.0
    """Nose-up attitude of level flight (angle of attack), degrees."""
    start_bearing: float = 0.0
    """Bearing from the centre to the aircraft at t = 0, degrees."""

    def __post_init__(self) -> None:
        if not self.radius > 0 or not self.speed > 0:
            raise ValueError(
                f"radius ({self.radius!r} m) and speed ({self.speed!r} m/s) must be > 0"
            )

    @property
    def turn_rate(self) -> float:
        """rad/s (clockwise seen from above, i.e. heading increases)."""
        return self.speed / self.radius

    @property
    def centripetal(self) -> float:
        """m/s², horizontal, towards the centre."""
        return self.speed**2 / self.radius

    @property
    def bank(self) -> float:
        """Roll of a coordinated turn, degrees (positive: right wing down)."""
        return math.degrees(math.atan2(self.centripetal, STANDARD_GRAVITY))

    def sample(self, t: float) -> FlightSample:
        """The aircraft ``t`` seconds into the flight."""
        omega = self.turn_rate
        bearing = math.radians(self.start_bearing) + omega * t
        cb, sb = math.cos(bearing), math.sin(bearing)
        north, east = self.radius * cb, self.radius * sb
        lat, lon = self.geodetic(north, east)
        a = self.centripetal
        phi, theta = math.radians(self.bank), math.radians(self.pitch)
        return FlightSample(
            t=t,
            latitude=lat,
            longitude=lon,
            altitude=self.home_altitude + self.height,
            relative_altitude=self.height,
            position_ned=(north, east, -self.height),
            velocity_ned=(-self.speed * sb, self.speed * cb, 0.0),
            acceleration_ned=(-a * cb, -a * sb, 0.0),
            roll=self.bank,
            pitch=self.pitch,
            yaw=math.degrees(bearing + math.pi / 2) % 360.0,
            body_rates=(
                0.0,
                omega * math.sin(phi) * math.cos(theta),
                omega * math.cos(phi) * math.cos(theta),
            ),
        )

    def geodetic(self, north: float, east: float) -> tuple[float, float]:
        """(latitude, longitude) of a point ``north``/``east`` metres from the centre."""
        lat = self.centre_latitude + math.degrees(north / EARTH_RADIUS_M)
        cos_lat = math.cos(math.radians(self.centre_latitude))
        lon = self.centre_longitude + math.degrees(east / (EARTH_RADIUS_M * cos_lat))
        return lat, lon

    def local(self, latitude: float, longitude: float) -> tuple[float, float]:
        """(north, east) metres of a coordinate from the centre (inverse of :meth:`geodetic`)."""
        north = math.radians(latitude - self.centre_latitude) * EARTH_RADIUS_M
        cos_lat = math.cos(math.radians(self.centre_latitude))
        east = math.radians(longitude - self.centre_longitude) * EARTH_RADIUS_M * cos_lat
        return north, east
