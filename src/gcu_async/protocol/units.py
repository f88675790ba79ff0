"""Engineering-unit value types and the one place that turns units into raw wire integers.

Every conversion goes through :func:`quantize` (units → raw, rounded, range-checked in units)
or :func:`~gcu_async._checks.check_int` (raw → range-checked), so every out-of-range value
raises the same :class:`~gcu_async.errors.FieldRangeError` naming the field, the allowed range
and the value, and every wrong type a ``TypeError`` naming the field (the package rule in
:mod:`gcu_async.protocol`). :func:`check_tuple` and :func:`check_member` check the tuple and
enum arguments of the builders.
"""

from __future__ import annotations

import math
from enum import IntEnum, IntFlag
from typing import Any, NamedTuple, TypeVar

from gcu_async._checks import check_enum, check_int, check_real, type_error
from gcu_async.errors import FieldRangeError
from gcu_async.protocol.anomalies import reserved_bits_detail

_NT = TypeVar("_NT", bound=tuple[Any, ...])
_new = tuple.__new__
_IE = TypeVar("_IE", bound=IntEnum)


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


class ImagePoint(NamedTuple):
    """A point in the image as fractions of its width/height: (0, 0) top-left, (1, 1)
    bottom-right. Wire resolution 1/10000."""

    x: float
    y: float


class ImageBox(NamedTuple):
    """A box in the image as fractions (0 … 1) of width/height, top-left and bottom-right."""

    left: float
    top: float
    right: float
    bottom: float


YAW_INPUT_RANGE = (-180.0, 360.0)
"""Degrees, half-open: how every absolute yaw or heading may be given (the Euler yaw of
``enter_euler_control``, the aircraft's yaw of ``update_aircraft``, the waits): MAVLink's
signed headings and compass headings alike; each is sent in the range its wire field takes."""


METRES_PER_DEGREE = 111_320.0
"""Length of one degree of latitude (and of longitude at the equator), metres: the
flat-earth approximation, good to well under a metre over the few kilometres a gimbal camera
sees."""


def offset_position(origin: GeoPosition, north: float, east: float, up: float) -> GeoPosition:
    """``origin`` moved by a local north/east/up offset in metres (flat earth; latitude kept
    within ±90°, longitude wrapped to [-180, 180))."""
    lat = origin.latitude + north / METRES_PER_DEGREE
    cos_lat = max(math.cos(math.radians(origin.latitude)), 1e-6)
    lon = origin.longitude + east / (METRES_PER_DEGREE * cos_lat)
    lon = (lon + 180.0) % 360.0 - 180.0
    return GeoPosition(max(-90.0, min(90.0, lat)), lon, origin.altitude + up)


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
    (``raw_high`` excluded when ``high_open``); errors speak in the caller's units.

    ``value`` must be a real number (``int`` or ``float``, not a ``bool``): anything else is a
    ``TypeError``. NaN, infinities and values too large for a float are out of range. The
    range applies to the rounded value, so a value less than half a wire step outside a
    bound is sent as that bound (rounding to the wire resolution, never clipping)."""
    if type(value) is not float and (
        isinstance(value, bool) or not isinstance(value, (int, float))
    ):  # the common float takes one cheap test
        raise type_error(field, "a real number", value)
    high_limit = raw_high - 1 if high_open else raw_high
    try:
        raw: int | None = round(value * scale)
    except (OverflowError, ValueError):  # inf, nan, or too large for a float
        raw = None
    if raw is None or not raw_low <= raw <= high_limit:
        raise FieldRangeError(
            field, value, _unit(raw_low, scale), _unit(raw_high, scale), unit, high_open=high_open,
            detail="" if raw is not None or isinstance(value, int) else "not a finite number",
        )  # fmt: skip
    return raw


def _unit(raw: int, scale: float) -> float | int:
    if scale == 1:
        return raw
    return round(raw / scale, 10)


def check_flags(field: str, value: object, allowed: int | type[IntFlag]) -> int:
    """Check that ``value`` is an ``int`` that sets no bit outside ``allowed`` (reserved
    bits must be zero)."""
    mask = allowed if isinstance(allowed, int) else _all_bits(allowed)
    bits = check_int(field, value, 0, 0xFFFF)
    if bits & ~mask:
        raise FieldRangeError(
            field, value, 0, mask, detail=reserved_bits_detail(bits & ~mask)
        )
    return bits


def _all_bits(flag: type[IntFlag]) -> int:
    bits = 0
    for member in flag:
        bits |= int(member)
    return bits


def check_tuple(field: str, value: object, cls: type[_NT]) -> _NT:
    """``value`` as a ``cls`` (one of the NamedTuples above): an instance of ``cls`` or a
    plain ``tuple`` of the same length. Lists, other NamedTuples (an :class:`AxisAngles`
    where an :class:`Attitude` is meant) and anything else are a ``TypeError``. The elements
    are the caller's to check, each under ``field.element``."""
    if type(value) is cls:
        return value
    names: tuple[str, ...] = cls._fields  # type: ignore[attr-defined]
    if (type(value) is tuple or isinstance(value, cls)) and len(value) == len(names):
        return _new(cls, value)  # what NamedTuple._make does, without its checks
    expected = f"a {cls.__name__} or a tuple ({', '.join(names)})"
    raise type_error(field, expected, value)


def check_sequence(field: str, value: object, cls: type[_NT]) -> _NT:
    """``value`` as a ``cls`` (a NamedTuple of units): an instance, a plain tuple or a list
    (JSON gives lists) of the right length, and nothing else (a ``TypeError`` naming what
    is accepted). The elements are the caller's to check."""
    try:
        return check_tuple(field, tuple(value) if type(value) is list else value, cls)
    except TypeError:
        name = cls.__name__
        article = "an" if name[0] in "AEIOU" else "a"
        fields = ", ".join(cls._fields)  # type: ignore[attr-defined]
        raise type_error(field, f"{article} {name} or a tuple or list ({fields})",
                         value) from None  # fmt: skip


def check_member(field: str, value: object, enum: type[_IE]) -> _IE:
    """A member of the integer enum ``enum`` from a member or its exact ``int`` value
    (:func:`~gcu_async._checks.check_enum`); an ``int`` that names no member is a
    :class:`FieldRangeError` listing the members."""
    try:
        return check_enum(field, value, enum)
    except TypeError:
        raise
    except ValueError:
        codes = [int(m) for m in enum]
        allowed = ", ".join(f"{m.name}={int(m)}" for m in enum)
        raise FieldRangeError(field, value, min(codes), max(codes),
                              detail=f"one of {allowed}") from None  # fmt: skip


def check_finite(field: str, value: object) -> float:
    """``value`` as a finite ``float``: :func:`~gcu_async._checks.check_real` without bounds
    lets ±inf through (they lie inside [-inf, inf]), so infinities are rejected here."""
    f = check_real(field, value)
    if not -math.inf < f < math.inf:
        raise FieldRangeError(field, value, -math.inf, math.inf, detail="not a finite number")
    return f


def wrap_degrees_360(angle: float) -> float:
    """Wrap an angle into [0, 360), e.g. for yaw sources that report signed headings (call it
    explicitly). ``angle`` is any finite real number (``float % 360`` is exact); NaN and
    infinities are a :class:`FieldRangeError`, non-numbers a ``TypeError``."""
    if type(angle) is not float or not -math.inf < angle < math.inf:
        angle = check_finite("angle", angle)
    wrapped = angle % 360.0
    return 0.0 if wrapped >= 360.0 else wrapped


def wrap_degrees_180(angle: float) -> float:
    """Wrap an angle into [-180, 180) (same checks as :func:`wrap_degrees_360`)."""
    if type(angle) is not float or not -math.inf < angle < math.inf:
        angle = check_finite("angle", angle)
    return wrap_degrees_360(angle + 180.0) - 180.0
