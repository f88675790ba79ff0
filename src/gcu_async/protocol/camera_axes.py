"""Appendix 4: camera axis angles ↔ Euler angles (rotation order Z → Y → X).

    AngleZ += 90; WRAP(AngleZ, 360); CamPhi = +AngleY; CamThe = −AngleX; CamPsi = +AngleZ
"""

from __future__ import annotations

from gcu_async._checks import check_real
from gcu_async.protocol.units import (
    Attitude,
    AxisAngles,
    check_tuple,
    wrap_degrees_180,
    wrap_degrees_360,
)

TURN = 360.0
"""Both functions take angles within one turn either way: [-360, 360] degrees."""


def _angles(field: str, value: object, cls: type[Attitude] | type[AxisAngles]) -> list[float]:
    names = cls._fields
    return [check_real(f"{field}.{n}", v, -TURN, TURN, "deg")
            for n, v in zip(names, check_tuple(field, value, cls), strict=True)]  # fmt: skip


def axes_to_euler(axes: AxisAngles | tuple[float, float, float]) -> Attitude:
    """Euler roll/pitch/yaw (the yaw wrapped by :func:`wrap_degrees_360`) from camera X/Y/Z
    axis angles, degrees.
    ``axes`` is an :class:`AxisAngles` or a plain 3-tuple of real numbers in [-360, 360]."""
    x, y, z = _angles("axes", axes, AxisAngles)
    return Attitude(roll=y, pitch=-x, yaw=wrap_degrees_360(z + 90.0))


def euler_to_axes(attitude: Attitude | tuple[float, float, float]) -> AxisAngles:
    """Inverse of :func:`axes_to_euler`; the Z angle comes back wrapped by
    :func:`wrap_degrees_180`.
    ``attitude`` is an :class:`Attitude` or a plain 3-tuple of real numbers in [-360, 360]."""
    roll, pitch, yaw = _angles("attitude", attitude, Attitude)
    return AxisAngles(x=-pitch, y=roll, z=wrap_degrees_180(yaw - 90.0))
