"""Appendix 4: AngleZ += 90; WRAP(AngleZ, 360); CamPhi = +AngleY; CamThe = −AngleX;
CamPsi = +AngleZ — and its inverse."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcu_async.protocol import (
    Attitude,
    AxisAngles,
    axes_to_euler,
    euler_to_axes,
    wrap_degrees_180,
    wrap_degrees_360,
)

centi = st.integers  # angles on the 0.01° wire grid


def close(a: tuple[float, ...], b: tuple[float, ...]) -> bool:
    return all(math.isclose(x, y, abs_tol=1e-9) for x, y in zip(a, b, strict=True))


@pytest.mark.parametrize(
    ("axes", "euler"),
    [
        ((0.0, 0.0, 0.0), (0.0, 0.0, 90.0)),
        ((10.0, 20.0, 30.0), (20.0, -10.0, 120.0)),
        ((-45.0, 5.5, 270.0), (5.5, 45.0, 0.0)),  # 270 + 90 wraps to 0
        ((0.0, 0.0, -90.0), (0.0, 0.0, 0.0)),
        ((0.0, 0.0, -180.0), (0.0, 0.0, 270.0)),
        ((90.0, -90.0, 359.0), (-90.0, -90.0, 89.0)),
    ],
)
def test_appendix_rule(axes: tuple[float, float, float], euler: tuple[float, float, float]) -> None:
    assert axes_to_euler(axes) == Attitude(*euler)
    assert isinstance(axes_to_euler(AxisAngles(*axes)), Attitude)


@given(x=centi(-18000, 17999), y=centi(-18000, 17999), z=centi(-18000, 17999))
def test_euler_to_axes_inverts_axes_to_euler(x: int, y: int, z: int) -> None:
    axes = AxisAngles(x / 100, y / 100, z / 100)
    euler = axes_to_euler(axes)
    assert 0.0 <= euler.yaw < 360.0
    assert close(euler_to_axes(euler), axes)


@given(roll=centi(-9000, 9000), pitch=centi(-18000, 17999), yaw=centi(0, 35999))
def test_axes_to_euler_inverts_euler_to_axes(roll: int, pitch: int, yaw: int) -> None:
    euler = Attitude(roll / 100, pitch / 100, yaw / 100)
    axes = euler_to_axes(euler)
    assert -180.0 <= axes.z < 180.0
    assert close(axes_to_euler(axes), euler)


@given(st.floats(-1e6, 1e6, allow_nan=False))
def test_wrap_ranges(angle: float) -> None:
    w360, w180 = wrap_degrees_360(angle), wrap_degrees_180(angle)
    assert 0.0 <= w360 < 360.0
    assert -180.0 <= w180 < 180.0
    assert math.isclose(math.remainder(w360 - angle, 360.0), 0.0, abs_tol=1e-6)
    assert math.isclose(math.remainder(w180 - angle, 360.0), 0.0, abs_tol=1e-6)
