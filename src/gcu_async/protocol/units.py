"""Engineering-unit value types and the one place that turns units into raw wire integers.

Every conversion goes through :func:`quantize` (units → raw, rounded, range-checked in units)
or :func:`check_raw` (raw → range-checked), so every out-of-range value raises the same
:class:`~gcu_async.errors.FieldRangeError` naming the field, the allowed range and the value.
"""

from __future__ import annotations

from enum import IntFlag
from typing import NamedTuple

from gcu_async.errors import FieldRangeError


class Attitude(NamedTuple):
    """Euler angles in degrees (rotation order Z→Y→X)."""

    roll: float
    pitch: float
    yaw: float


class NorthEastUp(NamedTuple):
    """A vector in the local north/east/up frame (m/s or m/s², per field)."""

    north: float
    east: float
    up: float


class AxisAngles(NamedTuple):
    """Camera X/Y/Z axis values (degrees, or °/s for rates)."""

    x: float
    y: float
    z: float


class GeoPosition(NamedTuple):
    """WGS-84 position: degrees latitude/longitude, metres altitude."""

    latitude: float
    longitude: float
    altitude: float


def quantize(
    field: str,
    value: float,
    scale: float,
    raw_low: int,
    raw_high: int,
    unit: str = "",
    *,
    high_open: bool = False,
) -> int:
    """Return ``round(value * scale)`` after checking it lies in ``[raw_low, raw_high]``
    (``raw_high`` excluded when ``high_open``); errors speak in the caller's units."""
    if type(value) is not float and (
        isinstance(value, bool) or not isinstance(value, (int, float))
    ):  # the common float takes one cheap test
        raise TypeError(f"{field}: expected a number, got {type(value).__name__} {value!r}")
    high_limit = raw_high - 1 if high_open else raw_high
    try:
        raw: int | None = round(value * scale)
    except (OverflowError, ValueError):  # inf, nan, or too large for a float
        raw = None
    if raw is None or not raw_low <= raw <= high_limit:
        raise FieldRangeError(
            field, value, _unit(raw_low, scale), _unit(raw_high, scale), unit, high_open=high_open
        )
    return raw


def _unit(raw: int, scale: float) -> float | int:
    if scale == 1:
        return raw
    return round(raw / scale, 10)


def check_int(field: str, value: int, low: int, high: int, unit: str = "") -> int:
    """Check an integer-valued field (flags, counts, raw values) against ``[low, high]``."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise TypeError(f"{field}: expected an integer, got {type(value).__name__} {value!r}")
    if not low <= value <= high:
        raise FieldRangeError(field, value, low, high, unit)
    return int(value)


def check_flags(field: str, value: int, allowed: int | type[IntFlag]) -> int:
    """Check that ``value`` sets no bit outside ``allowed`` (reserved bits must be zero)."""
    mask = allowed if isinstance(allowed, int) else _all_bits(allowed)
    check_int(field, value, 0, 0xFFFF)
    if value & ~mask:
        raise FieldRangeError(
            field, value, 0, mask, detail=f"reserved bits 0x{value & ~mask:X} must be zero"
        )
    return value


def _all_bits(flag: type[IntFlag]) -> int:
    bits = 0
    for member in flag:
        bits |= int(member)
    return bits


def wrap_degrees_360(angle: float) -> float:
    """Wrap an angle into [0, 360), e.g. for yaw sources that report ±180° (call it explicitly)."""
    wrapped = angle % 360.0
    return 0.0 if wrapped >= 360.0 else wrapped


def wrap_degrees_180(angle: float) -> float:
    """Wrap an angle into [-180, 180)."""
    return wrap_degrees_360(angle + 180.0) - 180.0
