"""The API boundary of the protocol layer: generated misuse cases.

Every parameter of every public constructor, builder and function users build protocol values
with is described once in ``PARAMS`` (kind, field name in errors, allowed range, wire step).
From that table come, per parameter, wrong-type values (``True`` where an
int is meant, ``1.0``, ``"1"``, ``None``, ``b""``, ``[]``, ``object()``, ...) and out-of-range
values (NaN, ±inf, ±1e30, ±10**40, one wire step outside each bound). Each case must raise
``TypeError`` or ``ValueError`` (never OverflowError, AttributeError, struct.error, ...) whose
message names the field; range errors must be :class:`FieldRangeError` naming the allowed
range and the value. The positive side: every boundary value is accepted and reads back
exactly after a codec round trip. A hypothesis test throws arbitrary values of arbitrary
types at every scalar parameter and checks accepted ⇔ valid. ``test_misuse_cases_cover_*``
fail when a public parameter has no entry, so the cases grow with the API.
"""

from __future__ import annotations

import dataclasses
import inspect
import math
from collections.abc import Callable
from datetime import date, datetime, timedelta, timezone
from decimal import Decimal
from fractions import Fraction
from typing import Any, NamedTuple

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gcu_async.errors import FieldRangeError
from gcu_async.protocol import (
    COMMAND_TYPES,
    AircraftState,
    Attitude,
    AxisAngles,
    CameraMask,
    Command,
    ControlValues,
    Feedback,
    GcuMainFrame,
    GcuPacket,
    GcuSubFrame,
    GeoPosition,
    HostMainFrame,
    HostPacket,
    HostSubFrame,
    ImageBox,
    ImagePoint,
    Mode,
    NightVision,
    NightVisionMode,
    NorthEastUp,
    NullCommand,
    Opcode,
    Osd,
    OsdCoordinates,
    OsdCoordinateSource,
    PodModel,
    SpotTemperature,
    TakePhoto,
    Track,
    UnknownCommand,
    UnknownSubFrame,
    axes_to_euler,
    command_code,
    crc16_xmodem,
    decode_command,
    decode_gcu_packet,
    decode_host_packet,
    euler_to_axes,
    failure_status,
    gps_to_utc,
    is_radiometric,
    is_thermal,
    opcode_name,
    pod_name,
    resolve_pod_model,
    supports,
    utc_to_gps,
    wrap_degrees_180,
    wrap_degrees_360,
)
from gcu_async.protocol.catalogue import CATALOGUE
from gcu_async.protocol.command_decode import MAX_PARAMS
from gcu_async.protocol.command_fields import (
    ZOOM_FRACTION,
    ZOOM_RATIO,
    Box,
    Cameras,
    Choice,
    Integer,
    Point,
    Real,
    Switch,
    Thresholds,
    ZoomValue,
)
from gcu_async.protocol.enums import PIP_MODE_MASK
from gcu_async.protocol.frame_schema import Code, Flags, Value
from gcu_async.protocol.gpstime import GPS_EPOCH, gps_minus_utc
from helpers.protocol.boundary import MESSAGE, case_id
from helpers.protocol.catalogue_samples import required_samples
from helpers.protocol.strategies import FRAME_SCHEMAS, RAW_RANGES
from helpers.scale import FULL, scaled

INF, NAN = math.inf, math.nan
UTC = timezone.utc


class P(NamedTuple):
    """One parameter of the public API: how to call with a value, and what is allowed."""

    owner: str
    """The callable (``Track``, ``HostMainFrame.build``, ...)."""
    param: str
    """Its Python parameter (``box``); ``box.left`` for one element of a tuple parameter."""
    field: str
    """The field errors must name."""
    call: Callable[[Any], object]
    kind: str
    """bool, int, real, enum, tuple, bytes, datetime, model, part."""
    low: float = -INF
    high: float = INF
    step: float = 0.0
    """Wire resolution of a real (0: checked without rounding)."""
    high_open: bool = False
    optional: bool = False
    """``None`` is a valid value."""
    valid: tuple[Any, ...] = ()
    """Boundary values that must be accepted (and read back, with ``read``)."""
    read: Callable[[Any], Any] | None = None
    """Reads the value back from what ``call`` built, after a codec round trip."""
    expected: Callable[[Any], Any] | None = None
    """What ``read`` must give for a valid value (default: the value itself)."""
    wrong: tuple[Any, ...] = ()
    """Extra values that must be a TypeError."""
    bad: tuple[Any, ...] = ()
    """Extra values that must be a ValueError naming the field."""
    excluded: Callable[[int], bool] = lambda v: False
    """Integers inside [low, high] that are still invalid (a ValueError naming the field)."""


# --- codec round trips ------------------------------------------------------------------------
def _cmd_rt(c: Command) -> Command:
    return decode_command(command_code(c), c.encode_params())


def _host_rt(main: HostMainFrame, sub: HostSubFrame | None = None) -> Any:
    return decode_host_packet(HostPacket(main, sub).encode())


def _gcu_rt(main: GcuMainFrame, sub: GcuSubFrame | None = None) -> Any:
    return decode_gcu_packet(GcuPacket(main, sub).encode())


# --- the table ---------------------------------------------------------------------------------
PARAMS: list[P] = []
REQUIRED_SAMPLES: dict[type[Command], dict[str, Any]] = {
    cls: {f.name: required_samples(e)[f.name] for e in CATALOGUE if e.command is cls
          for f in dataclasses.fields(cls) if f.name in required_samples(e)}
    for cls in COMMAND_TYPES.values()
}  # fmt: skip
"""In-range values of the attributes without a default (from the catalogue's samples)."""
REQUIRED_SAMPLES[COMMAND_TYPES[Opcode.CLICK_TO_PAN]] = {"point": ImagePoint(0.5, 0.5)}
REQUIRED_SAMPLES[COMMAND_TYPES[Opcode.ZOOM_TO]] = {"ratio": 2.0}
TUPLE_BASE: dict[type[Any], tuple[float, ...]] = {
    ImageBox: (0.0, 0.0, 1.0, 1.0),
    ImagePoint: (0.5, 0.5),
    Attitude: (0.0, 0.0, 0.0),
    NorthEastUp: (0.0, 0.0, 0.0),
    GeoPosition: (0.0, 0.0, 0.0),
    AxisAngles: (0.0, 0.0, 0.0),
}
OTHER_TUPLE = {ImageBox: ImagePoint(0, 0), ImagePoint: AxisAngles(0, 0, 0),
               Attitude: AxisAngles(0, 0, 0), NorthEastUp: Attitude(0, 0, 0),
               GeoPosition: NorthEastUp(0, 0, 0), AxisAngles: Attitude(0, 0, 0)}  # fmt: skip
"""A NamedTuple of another kind (an AxisAngles where an Attitude is meant)."""
MASKS = (1, 255, CameraMask.CAMERA_2, CameraMask.CAMERA_1 | CameraMask.CAMERA_8)


def _with(cls: type[Any], element: str, v: Any) -> Any:
    values = dict(zip(cls._fields, TUPLE_BASE[cls], strict=True))
    values[element] = v
    return cls(**values)


def _tuple_wrong(cls: type[Any]) -> tuple[Any, ...]:
    n = len(cls._fields)
    return (list(TUPLE_BASE[cls]), TUPLE_BASE[cls][:-1], (*TUPLE_BASE[cls], 0.0), "abc", 1.0,
            b"", object(), OTHER_TUPLE[cls], dict.fromkeys(range(n), 0.0))  # fmt: skip


def add(*params: P) -> None:
    PARAMS.extend(params)


def add_command(cls: type[Command], param: str, kind: str, **kw: Any) -> None:
    base = kw.pop("base", REQUIRED_SAMPLES.get(cls, {}))
    add(P(cls.__name__, param, kw.pop("field", param),
          lambda v, cls=cls, param=param: cls(**{**base, param: v}), kind,
          read=lambda c, param=param: getattr(_cmd_rt(c), param), **kw))  # fmt: skip


def add_command_tuple(cls: type[Command], param: str, tcls: type[Any], step: float,
                      low: float = 0.0, high: float = 1.0) -> None:  # fmt: skip
    base = REQUIRED_SAMPLES.get(cls, {})
    add(P(cls.__name__, param, param, lambda v, cls=cls: cls(**{**base, param: v}), "tuple",
          valid=(TUPLE_BASE[tcls], tcls(*TUPLE_BASE[tcls])), wrong=_tuple_wrong(tcls),
          read=lambda c: tuple(getattr(_cmd_rt(c), param))))  # fmt: skip
    for element in tcls._fields:
        add(P(cls.__name__, f"{param}.{element}", f"{param}.{element}",
              lambda v, cls=cls, e=element: cls(**{**base, param: _with(tcls, e, v)}), "real",
              low, high, step, valid=(low, high),
              read=lambda c, e=element: getattr(getattr(_cmd_rt(c), param), e)))  # fmt: skip


BOOL_VALID = (True, False)


def _add_kind(cls: type[Command], kind: Any) -> None:
    """The boundary rows of one schema parameter of ``cls``: its range, step and types."""
    if isinstance(kind, Cameras):
        add_command(cls, "cameras", "int", low=1, high=255, valid=MASKS)
    elif isinstance(kind, Switch):
        add_command(cls, kind.name, "bool", valid=BOOL_VALID)
    elif isinstance(kind, (Box, Point)):
        add_command_tuple(cls, kind.name, ImageBox if isinstance(kind, Box) else ImagePoint, 1e-4)
    elif isinstance(kind, Integer):
        w = kind.field_
        zero = (0,) if w.raw_low < 0 < w.raw_high else ()
        add_command(cls, w.name, "int", low=w.raw_low, high=w.raw_high,
                    valid=(w.raw_low, *zero, w.raw_high))  # fmt: skip
    elif isinstance(kind, Choice):
        w = kind.wire[0]
        add_command(cls, w.name, "enum", low=w.raw_low, high=w.raw_high,
                    valid=(*kind.enum, w.raw_low, w.raw_high))  # fmt: skip
    elif isinstance(kind, Real):
        w = kind.field_
        low, high = w.raw_low / w.scale, w.raw_high / w.scale
        step = (1 / w.scale,) if low < 1 / w.scale < high else ()  # one wire step above 0
        add_command(cls, w.name, "real", low=low, high=high, step=1 / w.scale,
                    valid=(low, high, *step))  # fmt: skip
    elif isinstance(kind, Thresholds):
        h, lo = kind.wire
        low, high = h.raw_low / h.scale, h.raw_high / h.scale
        # high with low at its minimum, low with high at its maximum: only one bound moves
        add(P(cls.__name__, "high", "high", lambda v, c=cls: c(high=v, low=low), "real",
              low, high, 1 / h.scale, valid=(low, high), read=lambda c: _cmd_rt(c).high))
        add(P(cls.__name__, "low", "low", lambda v, c=cls: c(high=high, low=v), "real",
              low, high, 1 / lo.scale, valid=(low, high), read=lambda c: _cmd_rt(c).low))
    elif isinstance(kind, ZoomValue):
        for w, base in ((ZOOM_RATIO, {"ratio": 2.0}), (ZOOM_FRACTION, {})):
            low, high = w.raw_low / w.scale, w.raw_high / w.scale
            add_command(cls, w.name, "real", low=low, high=high, step=1 / w.scale,
                        optional=True, valid=(low, high), base=base)  # fmt: skip
    else:  # pragma: no cover - a new kind needs its rows here
        raise AssertionError(f"{cls.__name__}: no boundary rows for {type(kind).__name__}")


for _cls in COMMAND_TYPES.values():
    for _kind in _cls.SCHEMA.params:
        _add_kind(_cls, _kind)
_KNOWN = frozenset(COMMAND_TYPES)
add(P("UnknownCommand", "code", "opcode", lambda v: UnknownCommand(code=v), "int", 0, 255,
      valid=(0x02, 0xFF), excluded=_KNOWN.__contains__, bad=(0x00, 0x20, Opcode.TRACK),
      read=lambda c: _cmd_rt(c).code))  # fmt: skip
add(P("UnknownCommand", "params", "params",
      lambda v: UnknownCommand(code=0x42, params=v), "bytes", 0, MAX_PARAMS,
      valid=(b"", b"\x01\x02", bytearray(b"\x03"), bytes(184)),
      wrong=("abc", 5, [1, 2], memoryview(b"ab")), bad=(bytes(MAX_PARAMS + 1),),
      read=lambda c: _cmd_rt(c).params))  # fmt: skip

# --- ControlValues -------------------------------------------------------------------------------
def _sent_control(c: ControlValues) -> ControlValues:
    """The control values a host packet carrying ``c`` decodes to."""
    return _host_rt(HostMainFrame.build(control=c)).main.control  # type: ignore[no-any-return]


def _one(v: Any, i: int) -> tuple[Any, Any, Any]:
    return (v if i == 0 else 0, v if i == 1 else 0, v if i == 2 else 0)


for _i, _axis in enumerate(("roll", "pitch", "yaw")):
    add(P("ControlValues.angles", _axis, f"control {_axis} angle",
          lambda v, i=_i: ControlValues.angles(*_one(v, i)), "real", -180.0, 180.0, 0.01,
          valid=(-180.0, 180.0, 0.01), read=lambda c, i=_i: _sent_control(c).as_angles()[i]),
        P("ControlValues.rates", _axis, f"control {_axis} rate",
          lambda v, i=_i: ControlValues.rates(*_one(v, i)), "real", -150.0, 150.0, 0.1,
          valid=(-150.0, 150.0), read=lambda c, i=_i: _sent_control(c).as_rates()[i]),
        P("ControlValues.check", f"{_axis}_raw", f"control.{_axis}_raw",
          lambda v, i=_i: ControlValues.check(ControlValues(*_one(v, i))), "int", -18000, 18000,
          valid=(-18000, 18000), read=lambda c, i=_i: _sent_control(c)[i]),
    )  # fmt: skip
add(P("ControlValues.rates", "zoom", "zoom", lambda v: ControlValues.rates(0.0, zoom=v), "real",
      1.0, 6553.5, valid=(1.0, 6553.5)),
    P("ControlValues.as_rates", "zoom", "zoom", lambda v: ControlValues(10, 0, 0).as_rates(v),
      "real", 1.0, 6553.5, valid=(1.0, 2.0, 6553.5)),
    P("ControlValues.check", "value", "control", ControlValues.check, "part",
      valid=(ControlValues(),),
      wrong=(None, (0, 0, 0), [0, 0, 0], "control", Attitude(0, 0, 0), object())))  # fmt: skip

# --- HostMainFrame.build / HostSubFrame.build ----------------------------------------------------
_HMB = "HostMainFrame.build"
add(P(_HMB, "control", "control", lambda v: HostMainFrame.build(control=v), "part",
      optional=True, valid=(ControlValues(1, 2, 3), None),
      wrong=((0, 0, 0), [0, 0, 0], "x", 0, object()),
      bad=(ControlValues(99999, 0, 0), ControlValues(0, 0, -18001)),
      read=lambda f: _host_rt(f).main.control if f.control_valid else None))  # fmt: skip
add(P(_HMB, "control.roll_raw", "control.roll_raw",
      lambda v: HostMainFrame.build(control=ControlValues(v, 0, 0)), "int", -18000, 18000,
      valid=(-18000, 18000), read=lambda f: _host_rt(f).main.control_roll_raw))  # fmt: skip
for _param, _tcls in (("attitude", Attitude), ("acceleration", NorthEastUp),
                      ("velocity", NorthEastUp)):  # fmt: skip
    add(P(_HMB, _param, _param, lambda v, p=_param: HostMainFrame.build(**{p: v}), "tuple",
          optional=True, valid=(None, TUPLE_BASE[_tcls], _tcls(*TUPLE_BASE[_tcls])),
          wrong=_tuple_wrong(_tcls)))  # fmt: skip
def _units(cls: type[Any], name: str) -> tuple[float, float, float, bool]:
    """Frame field ``name``'s range in engineering units, from its schema: low, high (the
    first value past it when open), step, open."""
    f = FRAME_SCHEMAS[cls].by_name[name]
    return (f.raw_low / f.scale, (f.raw_high + f.high_open) / f.scale, 1 / f.scale,
            f.high_open)  # fmt: skip


def _ints(cls: type[Any], name: str) -> tuple[int, int]:
    f = FRAME_SCHEMAS[cls].by_name[name]
    return f.raw_low, f.raw_high


def _bounds(cls: type[Any], name: str) -> tuple[float, float, bool]:
    low, high, _, high_open = _units(cls, name)
    return low, high, high_open


_ATT = {axis: _bounds(HostMainFrame, f"aircraft_{axis}_raw") for axis in ("roll", "pitch", "yaw")}
_NEU_LOW, _NEU_HIGH = _units(HostMainFrame, "accel_north_raw")[:2]
assert _units(HostMainFrame, "vel_north_raw")[:2] == (_NEU_LOW, _NEU_HIGH)
for _i, (_e, (_lo, _hi, _open)) in enumerate(_ATT.items()):
    add(P(_HMB, f"attitude.{_e}", f"aircraft {_e}",
          lambda v, e=_e: HostMainFrame.build(attitude=_with(Attitude, e, v)), "real",
          _lo, _hi, 0.01, _open, valid=(_lo, round(_hi - 0.01, 2) if _open else _hi),
          read=lambda f, i=_i: _host_rt(f).main.aircraft_attitude[i]))  # fmt: skip
for _param in ("acceleration", "velocity"):
    for _i, _e in enumerate(NorthEastUp._fields):
        add(P(_HMB, f"{_param}.{_e}", f"aircraft {_param} {_e}",
              lambda v, p=_param, e=_e: HostMainFrame.build(**{p: _with(NorthEastUp, e, v)}),
              "real", _NEU_LOW, _NEU_HIGH, 0.01, valid=(_NEU_LOW, _NEU_HIGH),
              read=lambda f, p=_param, i=_i: getattr(_host_rt(f).main, p)[i]))  # fmt: skip
add(P(_HMB, "subframe_request", "subframe_request",
      lambda v: HostMainFrame.build(subframe_request=v), "int",
      *_ints(HostMainFrame, "subframe_request"), valid=(0, 1, 255),
      read=lambda f: _host_rt(f).main.subframe_request))  # fmt: skip

_HSB = "HostSubFrame.build"


def _sub(**kw: Any) -> HostSubFrame:
    return HostSubFrame.build(**{"latitude": 0.0, "longitude": 0.0, "altitude": 0.0, **kw})


_T0 = datetime(2023, 9, 7, 1, 58, 38, tzinfo=UTC)
_GEO_RANGES = {e: _units(HostSubFrame, f"{e}_raw")[:3]
               for e in ("latitude", "longitude", "altitude")}  # fmt: skip
_REL_LOW, _REL_HIGH, _REL_STEP, _ = _units(HostSubFrame, "relative_altitude_raw")


def _host_sub_read(attr: str) -> Callable[[Any], Any]:
    return lambda s: getattr(_host_rt(HostMainFrame(), s).sub, attr)


for _e, (_lo, _hi, _st) in _GEO_RANGES.items():
    add(P(_HSB, _e, _e, lambda v, e=_e: _sub(**{e: v}), "real", _lo, _hi, _st,
          valid=(_lo, _hi), read=_host_sub_read(_e)))  # fmt: skip
add(P(_HSB, "relative_altitude", "relative_altitude", lambda v: _sub(relative_altitude=v),
      "real", _REL_LOW, _REL_HIGH, _REL_STEP, valid=(_REL_LOW, _REL_HIGH),
      read=lambda s: _host_rt(HostMainFrame(), s).sub.relative_altitude),
    *(P(_HSB, _n, _n, lambda v, n=_n: _sub(**{n: v}), "int", *_ints(HostSubFrame, _n),
        valid=_ints(HostSubFrame, _n), read=_host_sub_read(_n))
      for _n in ("satellites", "gnss_week", "gnss_ms")),
    P(_HSB, "gnss_time", "gnss_time", lambda v: _sub(gnss_time=v), "datetime", optional=True,
      valid=(None, _T0, GPS_EPOCH), read=lambda s: _host_rt(HostMainFrame(), s).sub.gnss_time(),
      expected=lambda v: GPS_EPOCH if v is None else v),
    P(_HSB, "gnss_time (with week)", "gnss_time", lambda v: _sub(gnss_time=v, gnss_week=5),
      "part", bad=(_T0,)),
    P(_HSB, "gnss_time (late)", "gnss_week (of gnss_time)", lambda v: _sub(gnss_time=v),
      "part", bad=(datetime(2700, 1, 1, tzinfo=UTC),)),
    P(_HSB, "apply_leap_seconds", "apply_leap_seconds",
      lambda v: _sub(gnss_time=_T0, apply_leap_seconds=v), "bool", valid=BOOL_VALID),
)  # fmt: skip

# --- GcuMainFrame.build / GcuSubFrame.build ------------------------------------------------------
_GMB, _GSB = "GcuMainFrame.build", "GcuSubFrame.build"
add(P(_GMB, "mode", "mode", lambda v: GcuMainFrame.build(mode=v), "int",
      *_ints(GcuMainFrame, "mode_raw"), valid=(*_ints(GcuMainFrame, "mode_raw"),
                                               Mode.POINTING_FOLLOW, Mode.FPV),
      read=lambda f: _gcu_rt(f).main.mode_raw),
    P(_GMB, "pod_status", "pod_status", lambda v: GcuMainFrame.build(pod_status=v), "int",
      *_ints(GcuMainFrame, "pod_status_raw"), valid=_ints(GcuMainFrame, "pod_status_raw"),
      read=lambda f: _gcu_rt(f).main.pod_status_raw),
    P(_GMB, "miss_distance", "miss_distance", lambda v: GcuMainFrame.build(miss_distance=v),
      "tuple", valid=((0, 0), (-1000, 1000)), wrong=([0, 0], (0,), (0, 0, 0), "ab", None, 0),
      read=lambda f: (_gcu_rt(f).main.miss_x, _gcu_rt(f).main.miss_y)),
    P(_GMB, "miss_distance.x", "miss distance x",
      lambda v: GcuMainFrame.build(miss_distance=(v, 0)), "int", *_ints(GcuMainFrame, "miss_x"),
      valid=_ints(GcuMainFrame, "miss_x"), read=lambda f: _gcu_rt(f).main.miss_x),
    P(_GMB, "miss_distance.y", "miss distance y",
      lambda v: GcuMainFrame.build(miss_distance=(0, v)), "int", *_ints(GcuMainFrame, "miss_y"),
      valid=_ints(GcuMainFrame, "miss_y"), read=lambda f: _gcu_rt(f).main.miss_y),
)  # fmt: skip
for _param, _tcls in (("relative_angles", AxisAngles), ("attitude", Attitude),
                      ("angular_rates", AxisAngles)):  # fmt: skip
    add(P(_GMB, _param, _param, lambda v, p=_param: GcuMainFrame.build(**{p: v}), "tuple",
          valid=(TUPLE_BASE[_tcls],), wrong=(None, *_tuple_wrong(_tcls))))  # fmt: skip
for _i, _e in enumerate("xyz"):
    _rl, _rh, _rs, _ro = _units(GcuMainFrame, f"relative_{_e}_raw")
    _wl, _wh, _ws, _ = _units(GcuMainFrame, f"rate_{_e}_raw")
    add(P(_GMB, f"relative_angles.{_e}", f"relative {_e.upper()} angle",
          lambda v, e=_e: GcuMainFrame.build(relative_angles=_with(AxisAngles, e, v)), "real",
          _rl, _rh, _rs, _ro, valid=(_rl, round(_rh - _rs, 2)),
          read=lambda f, i=_i: _gcu_rt(f).main.relative_angles[i]),
        P(_GMB, f"angular_rates.{_e}", f"{_e.upper()} angular rate",
          lambda v, e=_e: GcuMainFrame.build(angular_rates=_with(AxisAngles, e, v)), "real",
          _wl, _wh, _ws, valid=(_wl, _wh),
          read=lambda f, i=_i: _gcu_rt(f).main.angular_rates[i]))  # fmt: skip
_CAM = {axis: _bounds(GcuMainFrame, f"{axis}_raw") for axis in ("roll", "pitch", "yaw")}
for _i, (_e, (_lo, _hi, _open)) in enumerate(_CAM.items()):
    add(P(_GMB, f"attitude.{_e}", f"camera {_e}",
          lambda v, e=_e: GcuMainFrame.build(attitude=_with(Attitude, e, v)), "real",
          _lo, _hi, 0.01, _open, valid=(_lo, round(_hi - 0.01, 2) if _open else _hi),
          read=lambda f, i=_i: _gcu_rt(f).main.attitude[i]))  # fmt: skip


def _gsub(v: Any, name: str) -> GcuSubFrame:
    return GcuSubFrame.build(**{name: v})


def _gsub_read(attr: str) -> Callable[[Any], Any]:
    return lambda s: getattr(_gcu_rt(GcuMainFrame(), s).sub, attr)


_GSB_PARAMS = {v.name: v.fields[0] for v in FRAME_SCHEMAS[GcuSubFrame].views
               if isinstance(v, (Value, Code, Flags)) and v.write is None}  # fmt: skip
"""GcuSubFrame.build's keywords that write one field each (errors name the keyword); the
target's and the pip mode's have rows of their own."""
for _name, _fname in _GSB_PARAMS.items():
    _f = FRAME_SCHEMAS[GcuSubFrame].by_name[_fname]
    _lo, _hi, _st, _ = _units(GcuSubFrame, _f.name)
    _kind = "int" if _f.scale == 1 else "real"
    if _kind == "int":
        _lo, _hi, _st = int(_lo), int(_hi), 0.0
    _attr = _f.name if _f.scale == 1 else _name
    flags = _name == "camera_flags"  # bits 2-0 carry pip_mode: never dropped silently
    add(P(_GSB, _name, _name, lambda v, n=_name: _gsub(v, n), _kind, _lo, _hi, _st,
          valid=(_lo, _hi & ~PIP_MODE_MASK if flags else _hi), read=_gsub_read(_attr),
          excluded=(lambda v: bool(v & PIP_MODE_MASK)) if flags else lambda v: False,
          bad=(1, PIP_MODE_MASK, _hi) if flags else ()))  # fmt: skip
add(P(_GSB, "pip_mode", "pip_mode", lambda v: _gsub(v, "pip_mode"), "int", 0, PIP_MODE_MASK,
      valid=(0, PIP_MODE_MASK), read=_gsub_read("pip_mode")))


def _ranged(position: Any) -> GcuSubFrame:
    return GcuSubFrame.build(target_distance=1.0, target_position=position)


add(P(_GSB, "target_distance", "target_distance", lambda v: _gsub(v, "target_distance"),
      "real", 0.0, 214748364.7, 0.1, optional=True, valid=(None, 0.1, 214748364.7),
      read=_gsub_read("target_distance")),
    P(_GSB, "target_position", "target_position", _ranged,
      "tuple", optional=True, valid=(None, (1.0, 2.0, 3.0)), wrong=_tuple_wrong(GeoPosition)),
    P(_GSB, "target_position (no distance)", "target_position",
      lambda v: _gsub(v, "target_position"), "part", bad=((1.0, 2.0, 3.0),)),
)  # fmt: skip
for _i, (_e, (_lo, _hi, _st)) in enumerate(_GEO_RANGES.items()):
    add(P(_GSB, f"target_position.{_e}", f"target {_e}",
          lambda v, e=_e: _ranged(_with(GeoPosition, e, v)), "real",
          _lo, _hi, _st, valid=(_lo, _hi),
          read=lambda s, i=_i: _gsub_read("target_position")(s)[i]))  # fmt: skip

# --- AircraftState -------------------------------------------------------------------------------
_AS = "AircraftState"
for _param, _tcls in (("attitude", Attitude), ("acceleration", NorthEastUp),
                      ("velocity", NorthEastUp), ("position", GeoPosition)):  # fmt: skip
    add(P(_AS, _param, _param, lambda v, p=_param: AircraftState(**{p: v}), "tuple",
          optional=True, valid=(None, TUPLE_BASE[_tcls]), wrong=_tuple_wrong(_tcls),
          read=lambda s, p=_param: getattr(s, p)))  # fmt: skip
for _e, (_lo, _hi, _open) in _ATT.items():
    add(P(_AS, f"attitude.{_e}", f"aircraft {_e}",
          lambda v, e=_e: AircraftState(attitude=_with(Attitude, e, v)), "real", _lo, _hi,
          0.01, _open, valid=(_lo,)))  # fmt: skip
for _param in ("acceleration", "velocity"):
    for _e in NorthEastUp._fields:
        add(P(_AS, f"{_param}.{_e}", f"aircraft {_param} {_e}",
              lambda v, p=_param, e=_e: AircraftState(**{p: _with(NorthEastUp, e, v)}), "real",
              _NEU_LOW, _NEU_HIGH, 0.01, valid=(_NEU_HIGH,)))  # fmt: skip
for _e, (_lo, _hi, _st) in _GEO_RANGES.items():
    add(P(_AS, f"position.{_e}", _e,
          lambda v, e=_e: AircraftState(position=_with(GeoPosition, e, v)), "real", _lo, _hi,
          _st, valid=(_lo, _hi),
          read=lambda s, e=_e: getattr(_host_rt(s.main_frame(), s.sub_frame()).sub,
                                       e)))  # fmt: skip
add(P(_AS, "relative_altitude", "relative_altitude",
      lambda v: AircraftState(relative_altitude=v), "real", _REL_LOW, _REL_HIGH, _REL_STEP,
      valid=(_REL_LOW,)),
    *(P(_AS, _n, _n, lambda v, n=_n: AircraftState(**{n: v}), "int", *_ints(HostSubFrame, _n),
        valid=_ints(HostSubFrame, _n)) for _n in ("satellites", "gnss_week", "gnss_ms")),
    P("AircraftState.main_frame", "control", "control",
      lambda v: AircraftState().main_frame(v), "part", optional=True,
      valid=(None, ControlValues(0, 0, 18000)), wrong=((0, 0, 0), "x", 1),
      bad=(ControlValues(99999, 0, 0),)),
    P("AircraftState.main_frame", "subframe_request", "subframe_request",
      lambda v: AircraftState().main_frame(None, v), "int", 0, 255, valid=(0, 255)),
    P("AircraftState.gnss_from_utc", "utc", "gnss_time", AircraftState.gnss_from_utc,
      "datetime", valid=(_T0,)),
    P("AircraftState.gnss_from_utc", "apply_leap_seconds", "apply_leap_seconds",
      lambda v: AircraftState.gnss_from_utc(_T0, apply_leap_seconds=v), "bool",
      valid=BOOL_VALID),
)  # fmt: skip

# --- packets: raw frames, parts and fields, validated where they are encoded ----------------------
_FRAME_PACKET: dict[type[Any], Callable[[Any], bytes]] = {
    HostMainFrame: lambda f: HostPacket(f).encode(),
    HostSubFrame: lambda f: HostPacket(HostMainFrame(), f).encode(),
    GcuMainFrame: lambda f: GcuPacket(f).encode(),
    GcuSubFrame: lambda f: GcuPacket(GcuMainFrame(), f).encode(),
}


def _raw_read(cls: type[Any], name: str) -> Callable[[bytes], Any]:
    part = "main" if cls in (HostMainFrame, GcuMainFrame) else "sub"
    decode = decode_host_packet if cls in (HostMainFrame, HostSubFrame) else decode_gcu_packet
    return lambda data: getattr(getattr(decode(data), part), name)


for _cls, _ranges in RAW_RANGES.items():
    for _name, (_lo, _hi) in _ranges.items():
        add(P(f"{_cls.__name__}(raw).encode", _name, _name,
              lambda v, c=_cls, n=_name: _FRAME_PACKET[c](c()._replace(**{n: v})), "int",
              _lo, _hi, valid=(0, 5) if _name == "flags_raw" else (_lo, _hi),
              # reserved bits of the host flags must be zero
              excluded=(lambda v: bool(v & ~5)) if _name == "flags_raw" else lambda v: False,
              read=_raw_read(_cls, _name)))  # fmt: skip
add(P("HostPacket.encode", "main", "main", lambda v: HostPacket(v).encode(), "part",
      valid=(HostMainFrame(),), wrong=(None, GcuMainFrame(), (0,) * 14, "x", object())),
    P("HostPacket.encode", "sub", "sub", lambda v: HostPacket(HostMainFrame(), v).encode(),
      "part", optional=True, valid=(None, HostSubFrame()),
      wrong=(GcuSubFrame(), (0,) * 7, "x", bytes(32), object())),
    P("HostPacket.encode", "command", "command",
      lambda v: HostPacket(HostMainFrame(), None, v).encode(), "part", valid=(NullCommand(),),
      wrong=(None, NullCommand, 0x20, "x", Feedback(0), object())),
    P("HostPacket.encode", "version", "version",
      lambda v: HostPacket(HostMainFrame(), version=v).encode(), "int", 0, 255, valid=(1, 2),
      read=lambda data: decode_host_packet(data).version),
    P("GcuPacket.encode", "main", "main", lambda v: GcuPacket(v).encode(), "part",
      valid=(GcuMainFrame(),), wrong=(None, HostMainFrame(), (0,) * 13, "x", object())),
    P("GcuPacket.encode", "sub", "sub", lambda v: GcuPacket(GcuMainFrame(), v).encode(),
      "part", optional=True, valid=(None, GcuSubFrame()),
      wrong=(HostSubFrame(), (0,) * 13, "x", object())),
    P("GcuPacket.encode", "feedback", "feedback",
      lambda v: GcuPacket(GcuMainFrame(), feedback=v).encode(), "part",
      valid=(Feedback(0x20, 0),), wrong=(None, (0x20, 0), 0x20, NullCommand(), object())),
    P("GcuPacket.encode", "version", "version",
      lambda v: GcuPacket(GcuMainFrame(), version=v).encode(), "int", 0, 255, valid=(1, 2),
      read=lambda data: decode_gcu_packet(data).version),
    P("Feedback(raw).encode", "opcode", "feedback opcode",
      lambda v: GcuPacket(GcuMainFrame(), feedback=Feedback(v, 0)).encode(), "int", 0, 255,
      valid=(0, 255), read=lambda data: decode_gcu_packet(data).feedback.opcode),
    P("Feedback(raw).encode", "status", "feedback status",
      lambda v: GcuPacket(GcuMainFrame(), feedback=Feedback(0x20, v)).encode(), "int", 0, 255,
      optional=True, valid=(None, 0, 255),
      read=lambda data: decode_gcu_packet(data).feedback.status),
    P("UnknownSubFrame(raw).encode", "header", "sub frame header",
      lambda v: HostPacket(HostMainFrame(), UnknownSubFrame(v, b"\x01" * 31)).encode(), "int",
      0, 255, valid=(0, 2, 255), excluded=(1).__eq__, bad=(1,),
      read=lambda data: decode_host_packet(data).sub.header),
    P("UnknownSubFrame(raw).encode", "data", "sub frame data",
      lambda v: GcuPacket(GcuMainFrame(), UnknownSubFrame(7, v)).encode(), "bytes",
      valid=(bytes(31), b"\xff" * 31), wrong=("x" * 31, None, 31, [0] * 31),
      bad=(b"", bytes(30), bytes(32)), read=lambda data: decode_gcu_packet(data).sub.data),
)  # fmt: skip

# --- functions -----------------------------------------------------------------------------------
add(P("utc_to_gps", "utc", "gnss_time", utc_to_gps, "datetime", valid=(_T0,),
      read=lambda wm: gps_to_utc(*wm)),
    P("utc_to_gps", "apply_leap_seconds", "apply_leap_seconds",
      lambda v: utc_to_gps(_T0, apply_leap_seconds=v), "bool", valid=BOOL_VALID),
    P("gps_to_utc", "week", "week", lambda v: gps_to_utc(v, 0, apply_leap_seconds=False),
      "int", -32768, 32767,
      valid=(-32768, 0, 32767), read=lambda t: t,
      expected=lambda w: GPS_EPOCH + timedelta(weeks=w)),
    P("gps_to_utc", "ms", "ms", lambda v: gps_to_utc(2278, v), "int", 0, 2**32 - 1,
      valid=(0, 604_799_999, 2**32 - 1)),
    P("gps_to_utc", "apply_leap_seconds", "apply_leap_seconds",
      lambda v: gps_to_utc(2278, 0, apply_leap_seconds=v), "bool", valid=BOOL_VALID),
    P("gps_minus_utc", "utc", "utc", gps_minus_utc, "datetime", valid=(_T0, GPS_EPOCH),
      bad=(datetime(2023, 9, 7),)),
    P("axes_to_euler", "axes", "axes", axes_to_euler, "tuple", valid=((0, 0, 0),),
      wrong=_tuple_wrong(AxisAngles)),
    P("euler_to_axes", "attitude", "attitude", euler_to_axes, "tuple", valid=((0, 0, 0),),
      wrong=_tuple_wrong(Attitude)),
)  # fmt: skip
for _e in "xyz":
    add(P("axes_to_euler", f"axes.{_e}", f"axes.{_e}",
          lambda v, e=_e: axes_to_euler(_with(AxisAngles, e, v)), "real", -360.0, 360.0,
          valid=(-360.0, 360.0)))  # fmt: skip
for _e in Attitude._fields:
    add(P("euler_to_axes", f"attitude.{_e}", f"attitude.{_e}",
          lambda v, e=_e: euler_to_axes(_with(Attitude, e, v)), "real", -360.0, 360.0,
          valid=(-360.0, 360.0)))  # fmt: skip
for _fn in (wrap_degrees_360, wrap_degrees_180):
    add(P(_fn.__name__, "angle", "angle", _fn, "real", valid=(0.0, -1e30, 1e30, 10**40)))
_MODEL_WRONG = (True, 45.0, None, b"45", [45], object())
_MODEL_BAD = (1, 99, -1, 10**40, PodModel.UNKNOWN, "D-99", "", "\u00b2", "45.0")
add(P("resolve_pod_model", "model", "pod model", resolve_pod_model, "model",
      valid=(PodModel.D_90AI, 41, "D-90AI", "d_90ai", " 41 "), wrong=_MODEL_WRONG,
      bad=_MODEL_BAD, read=lambda m: m, expected=lambda v: PodModel.D_90AI),
    P("supports", "model", "pod model", lambda v: supports(v, Opcode.TRACK), "model",
      valid=(45, "Z-6A"), wrong=_MODEL_WRONG, bad=_MODEL_BAD),
    P("supports", "opcode", "opcode", lambda v: supports(PodModel.D_90AI, v), "int", 0, 255,
      valid=(0, 0x17, Opcode.PALETTE, 255)),
    P("is_thermal", "model", "pod model", is_thermal, "model", valid=(45,),
      wrong=_MODEL_WRONG, bad=_MODEL_BAD),
    P("is_radiometric", "model", "pod model", is_radiometric, "model", valid=(45,),
      wrong=_MODEL_WRONG, bad=_MODEL_BAD),
    P("pod_name", "model", "pod model", pod_name, "int", 0, 255,
      valid=(0, 41, 255, PodModel.UNKNOWN, PodModel.Z_6A), wrong=("D-90AI",)),
    P("failure_status", "opcode", "opcode", failure_status, "int", 0, 255, valid=(0, 0x25, 255)),
    P("failure_status", "failed_cameras", "failed_cameras",
      lambda v: failure_status(Opcode.ZOOM_TO, v), "int", 1, 255, valid=MASKS, read=lambda s: s),
    P("opcode_name", "opcode", "opcode", opcode_name, "int", 0, 255,
      valid=(0, 0x73, Opcode.RANGING, 255)),
    P("command_code", "command", "command", command_code, "part",
      valid=(NullCommand(), UnknownCommand(0x42)),
      wrong=(None, 0x20, NullCommand, Opcode.TRACK, "TRACK", object())),
    P("crc16_xmodem", "data", "data", crc16_xmodem, "bytes",
      valid=(b"", bytearray(b"1"), memoryview(b"123456789")),
      wrong=("123456789", None, 5, [1, 2], object())),
)  # fmt: skip


# --- misuse generation ---------------------------------------------------------------------------
WRONG_BOOL = (0, 1, "false", "True", None, 1.0, b"", [], object(), Decimal(1))
WRONG_INT = (True, False, 1.0, 2.5, "1", None, b"", [], object(), complex(1, 0), Decimal(1),
             Fraction(1, 1))  # fmt: skip
WRONG_REAL = (True, False, "1", "nan", None, b"", [], object(), complex(1, 0), Decimal("1"),
              Fraction(1, 2))  # fmt: skip
WRONG_BYTES = ("abc", None, 5, True, [1, 2], object())
WRONG_DATETIME = ("2023-09-07", 0, 1.5, None, date(2023, 9, 7), object())
BAD_DATETIME = (datetime(2023, 9, 7), datetime(1980, 1, 5, 23, 59, tzinfo=UTC),
                datetime.max.replace(tzinfo=UTC),
                datetime(1979, 12, 31, tzinfo=timezone(timedelta(hours=-1))),
                datetime.min.replace(tzinfo=timezone(timedelta(hours=1))),
                datetime.max.replace(tzinfo=timezone(timedelta(hours=-1))))  # fmt: skip


class Case(NamedTuple):
    p: P
    value: Any
    expect: type[Exception]  # TypeError, FieldRangeError or ValueError (message checked)


def _outside(p: P) -> list[Any]:
    """Out-of-range values of an int or real parameter."""
    if p.kind == "int" or p.kind == "enum":
        lo, hi = int(p.low), int(p.high)
        return [lo - 1, hi + 1, 10**40, -(10**40)]
    values: list[Any] = [NAN, INF, -INF, 10**400, -(10**400)]
    if p.low > -INF:
        values += [p.low - p.step if p.step else math.nextafter(p.low, -INF), -1e30, -(10**40)]
    if p.high < INF:
        over = p.high if p.high_open else (p.high + p.step if p.step else
                                           math.nextafter(p.high, INF))  # fmt: skip
        values += [over, 1e30, 10**40]
    return values


def misuse(p: P) -> list[Case]:
    wrong: tuple[Any, ...] = {
        "bool": WRONG_BOOL, "int": WRONG_INT, "enum": WRONG_INT, "real": WRONG_REAL,
        "bytes": WRONG_BYTES, "datetime": WRONG_DATETIME,
    }.get(p.kind, ())  # fmt: skip
    wrong = (*wrong, *p.wrong)
    cases = [Case(p, v, TypeError) for v in wrong if not (p.optional and v is None)]
    if p.kind in ("int", "enum", "real") and (p.low > -INF or p.high < INF or p.kind == "real"):
        cases += [Case(p, v, FieldRangeError) for v in _outside(p)]
    if p.kind == "datetime" and not p.bad:
        cases += [Case(p, v, ValueError) for v in BAD_DATETIME]
    cases += [Case(p, v, ValueError) for v in p.bad]
    return cases


MISUSE_CASES = [c for p in PARAMS for c in misuse(p)]
POSITIVE = [(p, v) for p in PARAMS for v in p.valid]


def _id(p: P, v: Any) -> str:
    return case_id(p.owner, p.param, v)


def _shown(v: Any) -> list[str]:
    """How a message may show ``v``: its repr, str, float repr, hex, ISO form."""
    shown = [repr(v), str(v)]
    if isinstance(v, int) and not isinstance(v, bool):
        shown += [str(int(v)), f"0x{int(v):02X}"]
        if abs(v) < 2**1000:
            shown.append(repr(float(v)))
    if isinstance(v, datetime):
        shown.append(v.isoformat())
    return [s[:30] for s in shown]


def _check_error(case: Case, err: BaseException) -> None:
    p, v, expect = case
    assert type(err) in (TypeError, ValueError, FieldRangeError), (type(err), err)
    msg = str(err)
    assert msg.startswith((f"{p.field}:", f"{p.field}.")), msg
    if expect is TypeError:
        assert type(err) is TypeError, msg
        assert " expected " in msg and type(v).__name__ in msg, msg
        return
    assert isinstance(err, ValueError), msg
    if expect is FieldRangeError:
        assert isinstance(err, FieldRangeError), msg
        assert err.field == p.field
        m = MESSAGE.match(msg)
        assert m, msg
        # the value as given (check_real reports an int converted to float)
        assert m["value"][:30] in _shown(v), msg
        if p.kind in ("int", "enum", "real"):
            assert (err.low, err.high, err.high_open) == (p.low, p.high, p.high_open), msg
            assert float(m["low"]) == p.low and float(m["high"]) == p.high, msg
            assert m["close"] == (")" if p.high_open else "]"), msg
        return
    if isinstance(err, FieldRangeError):  # a range error where a ValueError was expected
        assert MESSAGE.match(msg), msg
    assert any(s in msg for s in _shown(v)) or p.kind in ("part", "bytes"), msg


CHUNK = 1 if FULL else 60
"""Cases per test item: one at full size (each its own item), at reduced size every case
still, in items of this many (pytest's cost per item is most of a case's)."""


def _chunks(cases: list[Any], ids: list[str]) -> list[Any]:
    return [pytest.param(cases[i:i + CHUNK], id=ids[i] if CHUNK == 1 else f"{ids[i]}+{CHUNK - 1}")
            for i in range(0, len(cases), CHUNK)]  # fmt: skip


@pytest.mark.parametrize("cases", _chunks(MISUSE_CASES, [_id(c.p, c.value) for c in MISUSE_CASES]))
def test_misuse_is_rejected_naming_the_field(cases: list[Case]) -> None:
    for case in cases:
        try:
            case.p.call(case.value)
        except Exception as exc:
            _check_error(case, exc)
        else:
            pytest.fail(f"{_id(case.p, case.value)}: accepted")


@pytest.mark.parametrize("cases", _chunks(POSITIVE, [_id(p, v) for p, v in POSITIVE]))
def test_boundary_values_are_accepted_and_round_trip(cases: list[tuple[P, Any]]) -> None:
    for p, value in cases:
        try:
            _round_trip(p, value)
        except Exception as exc:
            raise AssertionError(f"{_id(p, value)}: {exc!r}") from exc


def _round_trip(p: P, value: Any) -> None:
    built = p.call(value)
    if p.read is None:
        return
    back = p.read(built)
    if p.expected is not None:
        expected = p.expected(value)
    elif isinstance(value, (bytearray, memoryview)):
        expected = bytes(value)
    else:
        expected = value
    assert back == expected, (p.owner, p.param, value, back)
    assert type(back) is not bool or type(value) is bool  # no int read back as a bool


def test_misuse_case_count() -> None:
    kinds: dict[str, int] = {}
    for c in MISUSE_CASES:
        key = c.expect.__name__
        kinds[key] = kinds.get(key, 0) + 1
    print(f"\nprotocol misuse: {len(MISUSE_CASES)} cases over {len(PARAMS)} parameters "
          f"({kinds}); {len(POSITIVE)} boundary values accepted")  # fmt: skip
    assert len(PARAMS) >= 200
    assert len(MISUSE_CASES) >= 2500
    assert len(POSITIVE) >= 350


# --- the misuse cases cover the whole public API ------------------------------------------------
def _covered(owner: str) -> set[str]:
    return {p.param.split(".")[0].split(" ")[0] for p in PARAMS if p.owner == owner}


@pytest.mark.parametrize("cls", [*COMMAND_TYPES.values(), UnknownCommand],
                         ids=lambda c: c.__name__)  # fmt: skip
def test_misuse_cases_cover_every_command_field(cls: type[Command]) -> None:
    assert {f.name for f in dataclasses.fields(cls)} <= _covered(cls.__name__)


@pytest.mark.parametrize(
    ("owner", "func"),
    [
        ("ControlValues.angles", ControlValues.angles),
        ("ControlValues.rates", ControlValues.rates),
        ("ControlValues.as_rates", ControlValues.as_rates),
        ("ControlValues.check", ControlValues.check),
        ("HostMainFrame.build", HostMainFrame.build),
        ("HostSubFrame.build", HostSubFrame.build),
        ("GcuMainFrame.build", GcuMainFrame.build),
        ("GcuSubFrame.build", GcuSubFrame.build),
        ("AircraftState", AircraftState),
        ("AircraftState.main_frame", AircraftState.main_frame),
        ("AircraftState.gnss_from_utc", AircraftState.gnss_from_utc),
        ("HostPacket.encode", HostPacket),
        ("GcuPacket.encode", GcuPacket),
        ("Feedback(raw).encode", Feedback),
        ("UnknownSubFrame(raw).encode", UnknownSubFrame),
        ("utc_to_gps", utc_to_gps),
        ("gps_to_utc", gps_to_utc),
        ("gps_minus_utc", gps_minus_utc),
        ("axes_to_euler", axes_to_euler),
        ("euler_to_axes", euler_to_axes),
        ("wrap_degrees_360", wrap_degrees_360),
        ("wrap_degrees_180", wrap_degrees_180),
        ("resolve_pod_model", resolve_pod_model),
        ("supports", supports),
        ("is_thermal", is_thermal),
        ("is_radiometric", is_radiometric),
        ("pod_name", pod_name),
        ("failure_status", failure_status),
        ("opcode_name", opcode_name),
        ("crc16_xmodem", crc16_xmodem),
        ("command_code", command_code),
    ],
    ids=lambda x: x if isinstance(x, str) else "",
)
def test_misuse_cases_cover_every_builder_parameter(owner: str, func: Callable[..., Any]) -> None:
    names = {n for n in inspect.signature(func).parameters if n not in ("self", "cls", "field")}
    aliases = {"ControlValues.check": {"value"}, "Feedback(raw).encode": {"opcode", "status"}}
    covered = _covered(owner) | ({"zoom"} if owner == "ControlValues.rates" else set())
    if owner == "ControlValues.check":
        names = aliases[owner]
    if owner == "Feedback(raw).encode":
        names = aliases[owner]
    assert names <= covered, names - covered


@pytest.mark.parametrize("cls", list(RAW_RANGES), ids=lambda c: c.__name__)
def test_misuse_cases_cover_every_raw_frame_field(cls: type[Any]) -> None:
    assert set(cls._fields) == _covered(f"{cls.__name__}(raw).encode")


# --- adversarial: arbitrary values of arbitrary types at every scalar parameter --------------
SCALARS = [p for p in PARAMS if p.kind in ("bool", "int", "enum", "real")]


def _values(p: P) -> st.SearchStrategy[Any]:
    near: list[st.SearchStrategy[Any]] = []
    if p.kind in ("int", "enum"):
        near.append(st.integers(int(p.low) - 3, int(p.high) + 3))
    if p.kind == "real" and p.low > -INF and p.high < INF:
        span = max(p.step, 1e-9) * 3
        near.append(st.floats(p.low - span, p.low + span))
        near.append(st.floats(p.high - span, p.high + span))
        near.append(st.floats(p.low, p.high))
    anything = st.one_of(
        st.booleans(), st.none(), st.integers(), st.floats(), st.text(max_size=3),
        st.binary(max_size=2), st.decimals(allow_nan=True), st.fractions(),
        st.complex_numbers(max_magnitude=10), st.just(object()),
        st.lists(st.integers(), max_size=2),
        st.sampled_from([*CameraMask, *NightVisionMode, *OsdCoordinateSource]),
    )  # fmt: skip
    values = st.one_of(*near, anything)
    return values.filter(lambda v: not (p.optional and v is None))


def _valid(p: P, v: Any) -> bool | None:
    """True: must be accepted; False: must be rejected; None: either (a real within one wire
    step of a bound may round onto it or past it)."""
    if p.kind == "bool":
        return v is True or v is False
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return False
    if p.kind in ("int", "enum"):
        return isinstance(v, int) and p.low <= v <= p.high and not p.excluded(v)
    try:
        f = float(v)
    except OverflowError:
        return False
    if not math.isfinite(f):
        return False
    m = p.step
    inside = p.low + m <= f and (f < p.high - m if p.high_open else f <= p.high - m)
    outside = f < p.low - m or f > p.high + m or (p.high_open and f >= p.high)
    return True if inside else False if outside else None


@settings(max_examples=scaled(1000, 100), deadline=None)
@given(st.data())
def test_arbitrary_values_accepted_iff_valid(data: st.DataObject) -> None:
    p = data.draw(st.sampled_from(SCALARS), label="parameter")
    v = data.draw(_values(p), label="value")
    expected = _valid(p, v)
    error: TypeError | ValueError | None = None
    try:  # anything but TypeError / ValueError propagates and fails the test
        p.call(v)
    except (TypeError, ValueError) as exc:
        error = exc
    if error is None:
        assert expected is not False, (p.owner, p.param, v)
        return
    assert expected is not True, (p.owner, p.param, v, error)
    assert type(error) in (TypeError, ValueError, FieldRangeError), error
    assert str(error).startswith(f"{p.field}:"), (p.field, str(error))
    if isinstance(error, FieldRangeError):
        assert error.field == p.field
    else:
        wrong_type = (
            not (v is True or v is False) if p.kind == "bool"
            else isinstance(v, bool) or not isinstance(v, (int, float))
            or (p.kind in ("int", "enum") and not isinstance(v, int))
        )  # fmt: skip
        assert wrong_type or p.excluded(v), (p.param, v, error)


# --- no coercion: the examples and what used to slip through -----------------------------
@pytest.mark.parametrize(
    ("call", "error", "field"),
    [
        (lambda: Track(enter=1), TypeError, "enter"),  # type: ignore[arg-type]
        (lambda: TakePhoto(cameras=1.5), TypeError, "cameras"),  # type: ignore[arg-type]
        (lambda: ControlValues.angles(yaw=1e30), FieldRangeError, "control yaw angle"),
        (lambda: Osd("false"), TypeError, "enabled"),  # type: ignore[arg-type]
        (lambda: Osd(None), TypeError, "enabled"),  # type: ignore[arg-type]
        (lambda: NightVision(mode=1.0), TypeError, "mode"),  # type: ignore[arg-type]
        (lambda: OsdCoordinates(True), TypeError, "coordinates"),  # type: ignore[arg-type]
        (lambda: ControlValues.check(ControlValues(99999, 0, 0)), FieldRangeError,
         "control.roll_raw"),
        (lambda: HostMainFrame.build(control=ControlValues(99999, 0, 0)), FieldRangeError,
         "control.roll_raw"),
        (lambda: AircraftState(attitude=[0.0, 0.0, 0.0]), TypeError, "attitude"),  # type: ignore[arg-type]
        (lambda: GcuSubFrame.build(target_position=()), TypeError, "target_position"),  # type: ignore[arg-type]
        (lambda: GcuMainFrame.build(mode=17.0), TypeError, "mode"),
        (lambda: UnknownCommand(0x42, 5), TypeError, "params"),  # type: ignore[arg-type]
        (lambda: HostPacket(GcuMainFrame()).encode(), TypeError, "main"),  # type: ignore[arg-type]
        (lambda: HostPacket(HostMainFrame(), GcuSubFrame()).encode(), TypeError, "sub"),  # type: ignore[arg-type]
        (lambda: HostPacket(HostMainFrame()._replace(vel_up_raw=10**40)).encode(),
         FieldRangeError, "vel_up_raw"),
        (lambda: HostPacket(HostMainFrame()._replace(vel_up_raw=1.0)).encode(), TypeError,
         "vel_up_raw"),
        (lambda: HostPacket(HostMainFrame(), UnknownSubFrame(1, bytes(31))).encode(), ValueError,
         "sub frame header"),
        (lambda: resolve_pod_model(41.0), TypeError, "pod model"),  # type: ignore[arg-type]
        (lambda: resolve_pod_model("\u00b2"), ValueError, "pod model"),
        (lambda: utc_to_gps(datetime.max.replace(tzinfo=UTC), apply_leap_seconds=True),
         ValueError, "gnss_time"),
        (lambda: gps_to_utc(10**40, 0), FieldRangeError, "week"),
        (lambda: axes_to_euler((1e30, 0.0, 0.0)), FieldRangeError, "axes.x"),
        (lambda: wrap_degrees_360(NAN), FieldRangeError, "angle"),
        (lambda: opcode_name("0x20"), TypeError, "opcode"),  # type: ignore[arg-type]
        (lambda: crc16_xmodem("abc"), TypeError, "data"),  # type: ignore[arg-type]
        (lambda: Command(), TypeError, "Command is abstract"),
    ],
)
def test_no_coercion(call: Callable[[], object], error: type[Exception], field: str) -> None:
    with pytest.raises(error) as info:
        call()
    assert str(info.value).startswith(field), str(info.value)


def test_checked_values_are_stored_as_their_types() -> None:
    # plain tuples become the NamedTuple, enum values their member: later reads and as_dict
    # see the same types a decoded command has
    track = Track(box=(0.0, 0.25, 0.5, 1.0))
    assert type(track.box) is ImageBox and track.box.bottom == 1.0
    assert type(SpotTemperature(point=(0.5, 0.5)).point) is ImagePoint
    night = NightVision(1)  # type: ignore[arg-type]
    assert night.mode is NightVisionMode.ON and night.as_dict()["params"]["mode"] == "ON"
    assert OsdCoordinates(1).coordinates is OsdCoordinateSource.TARGET  # type: ignore[arg-type]
    state = AircraftState(attitude=(1.0, 2.0, 3.0), position=(1.0, 2.0, 3.0))
    assert type(state.attitude) is Attitude and type(state.position) is GeoPosition
    command = UnknownCommand(0x42, bytearray(b"\x01"))
    assert type(command.params) is bytes and hash(command)
    assert Track(box=(0, 0, 1, 1)) == _cmd_rt(Track(box=(0, 0, 1, 1)))


def test_decoding_stays_liberal() -> None:
    # values no builder accepts still decode: a negative GNSS week, an unknown mode and pod
    # code, a reserved host flag bit, a pip mode in the camera flags, an unknown sub frame
    host = HostPacket(HostMainFrame(), HostSubFrame()._replace(gnss_week=0)).encode()
    raw = bytearray(host)
    raw[55:57] = (-5).to_bytes(2, "little", signed=True)  # gnss_week S16
    raw[11] = 0xFF  # reserved flag bits
    from helpers.protocol.strategies import seal

    packet = decode_host_packet(seal(raw[:2], bytes(raw[5:-2])))
    assert packet.sub.gnss_week == -5 and packet.main.flags_raw == 0xFF  # type: ignore[union-attr]
    assert packet.sub.gnss_time().year < 1980  # type: ignore[union-attr]
    assert packet.as_dict()["sub"]["gnss_week"] == -5
    gcu = bytearray(GcuPacket(GcuMainFrame(), GcuSubFrame()).encode())
    gcu[5], gcu[40] = 0x99, 200  # mode, pod code
    decoded = decode_gcu_packet(seal(gcu[:2], bytes(gcu[5:-2])))
    assert decoded.main.mode_raw == 0x99 and decoded.sub.pod_code == 200  # type: ignore[union-attr]
    assert pod_name(decoded.sub.pod_code) == "unknown (code 200)"  # type: ignore[union-attr]
