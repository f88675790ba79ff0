"""Flat-earth geometry for gaze and ranging (local north/east/up around the aircraft).

Accurate to well under a metre over the few kilometres a gimbal camera sees; the simulator
needs plausibility, not geodesy.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from gcu_async.protocol.units import METRES_PER_DEGREE, GeoPosition, wrap_degrees_360


class Sight(NamedTuple):
    """Where a line of sight meets something: slant distance and the point's offset."""

    distance: float
    north: float
    east: float
    up: float


def direction_to(origin: GeoPosition, target: GeoPosition) -> tuple[float, float]:
    """(pitch, yaw) in degrees of the line from ``origin`` to ``target``; yaw a compass heading
    (:func:`~gcu_async.protocol.units.wrap_degrees_360`)."""
    north = (target.latitude - origin.latitude) * METRES_PER_DEGREE
    cos_lat = math.cos(math.radians(origin.latitude))
    d_lon = (target.longitude - origin.longitude + 180.0) % 360.0 - 180.0
    east = d_lon * METRES_PER_DEGREE * cos_lat
    up = target.altitude - origin.altitude
    horizontal = math.hypot(north, east)
    yaw = wrap_degrees_360(math.degrees(math.atan2(east, north))) if horizontal > 1e-3 else 0.0
    return math.degrees(math.atan2(up, horizontal)), yaw


def ground_hit(pitch: float, yaw: float, height: float, max_range: float) -> Sight | None:
    """Where a line of sight (``pitch`` < 0 looks down) from ``height`` metres above flat
    ground meets it, if within ``max_range`` metres."""
    if height <= 0 or pitch >= 0:
        return None
    down = math.sin(math.radians(-pitch))
    distance = height / down
    if distance > max_range:
        return None
    return along(pitch, yaw, distance)


def along(pitch: float, yaw: float, distance: float) -> Sight:
    """The point ``distance`` metres along a line of sight."""
    horizontal = distance * math.cos(math.radians(pitch))
    return Sight(
        distance,
        horizontal * math.cos(math.radians(yaw)),
        horizontal * math.sin(math.radians(yaw)),
        distance * math.sin(math.radians(pitch)),
    )
