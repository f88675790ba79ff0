"""Pure geometry of the bridge: Euler ⇄ quaternion in MAVLink's frames, the image centre's
ground point, and the distance checks of a region of interest.

MAVLink's gimbal protocol gives attitudes as quaternions ``(w, x, y, z)`` of the rotation
from the reference frame (north-east-down, or the vehicle's forward-right-down frame for a
yaw "in vehicle frame") to the camera's forward-right-down frame; Euler angles are applied
yaw → pitch → roll (Z → Y → X, aerospace order), pitch positive up, yaw positive clockwise
seen from above. The GCU reports the same Euler angles in degrees (yaw a compass heading), so
the conversion is the textbook one (docs/mavlink-bridge.md, "Frames").

The ground point is flat-earth: good to well under a metre over the few kilometres a
gimbal camera sees on level ground, and nothing more is claimed.
"""

from __future__ import annotations

import math

from gcu_async.protocol.units import (
    Attitude,
    GeoPosition,
    offset_position,
    wrap_degrees_180,
    wrap_degrees_360,
)

Quaternion = tuple[float, float, float, float]
"""(w, x, y, z); (1, 0, 0, 0) is no rotation."""
MAX_GROUND_RANGE_M = 10_000.0
"""A line of sight meeting the ground farther than this counts as not meeting it (a ray
near the horizon gives a meaningless point)."""


def quaternion_from_euler(roll: float, pitch: float, yaw: float) -> Quaternion:
    """Degrees → unit quaternion (w, x, y, z), rotation order Z → Y → X."""
    hr, hp, hy = (math.radians(a) / 2 for a in (roll, pitch, yaw))
    cr, sr = math.cos(hr), math.sin(hr)
    cp, sp = math.cos(hp), math.sin(hp)
    cy, sy = math.cos(hy), math.sin(hy)
    return (
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    )


def euler_from_quaternion(q: tuple[float, ...] | list[float]) -> Attitude:
    """Quaternion (w, x, y, z) → Euler degrees: roll and yaw in [-180, 180), pitch in
    [-90, 90]. The quaternion is normalised first; ``ValueError`` for a zero, non-finite or
    wrongly sized one (MAVLink marks "no attitude" with NaN components)."""
    if len(q) != 4:
        raise ValueError(f"q: expected 4 components (w, x, y, z), got {len(q)}")
    if not all(math.isfinite(c) for c in q):
        raise ValueError(f"q: {tuple(q)!r} has a non-finite component")
    norm = math.sqrt(sum(c * c for c in q))
    if norm < 1e-6:
        raise ValueError(f"q: {tuple(q)!r} is not a rotation (norm {norm:g})")
    w, x, y, z = (c / norm for c in q)
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return Attitude(
        wrap_degrees_180(math.degrees(roll)),
        math.degrees(pitch),
        wrap_degrees_180(math.degrees(yaw)),
    )


def ground_point(
    camera: GeoPosition,
    pitch: float,
    yaw: float,
    ground_altitude: float,
    *,
    max_range: float = MAX_GROUND_RANGE_M,
) -> GeoPosition | None:
    """Where the camera's line of sight (``pitch`` < 0 looks down, ``yaw`` clockwise from
    north, degrees) meets flat ground at ``ground_altitude`` metres MSL; ``None`` if it
    looks level or up, the camera is not above the ground, or the point lies farther than
    ``max_range`` metres along the line of sight."""
    height = camera.altitude - ground_altitude
    if height <= 0 or pitch >= 0:
        return None
    distance = height / math.sin(math.radians(-pitch))
    if distance > max_range:
        return None
    horizontal = distance * math.cos(math.radians(pitch))
    yaw_rad = math.radians(wrap_degrees_360(yaw))
    return offset_position(camera, horizontal * math.cos(yaw_rad),
                           horizontal * math.sin(yaw_rad), -height)  # fmt: skip
