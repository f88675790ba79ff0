"""Appendix 4: camera axis angles ↔ Euler angles (rotation order Z → Y → X).

    AngleZ += 90; WRAP(AngleZ, 360); CamPhi = +AngleY; CamThe = −AngleX; CamPsi = +AngleZ
"""

from __future__ import annotations

from gcu_async.protocol.units import Attitude, AxisAngles, wrap_degrees_180, wrap_degrees_360


def axes_to_euler(axes: AxisAngles | tuple[float, float, float]) -> Attitude:
    """Euler roll/pitch/yaw (yaw in [0, 360)) from camera X/Y/Z axis angles, degrees."""
    x, y, z = axes
    return Attitude(roll=y, pitch=-x, yaw=wrap_degrees_360(z + 90.0))


def euler_to_axes(attitude: Attitude | tuple[float, float, float]) -> AxisAngles:
    """Inverse of :func:`axes_to_euler`; the Z angle comes back in [-180, 180)."""
    roll, pitch, yaw = attitude
    return AxisAngles(x=-pitch, y=roll, z=wrap_degrees_180(yaw - 90.0))
