"""The client's API boundary: generated misuse cases over every public entry point.

Every parameter of every public method, setter, constructor option and ``connect()`` option
of the client layer is described once in ``PARAMS``: its kind, the name errors must use (the
parameter name as the caller spelled it), its documented range. From that table come
wrong-type values (``True`` where a number is meant, ``1.0`` for an int,
``"1"``, ``"false"``, ``None``, ``b""``, ``[]``, ``object()``, complex, Decimal, ...) and
out-of-range values (NaN, ±inf, ±1e30, ±10**40, ±10**400, one step outside each bound).
Each case runs against a fresh simulator over the in-memory transport and must

- raise ``TypeError`` or ``ValueError`` (a :class:`FieldRangeError` stating the violated
  bound for a range) and nothing else: no OverflowError, AttributeError, KeyError, ...;
- start its message with the caller's parameter name (transport options and the URL: name
  it after the URL the message starts with);
- send nothing and change nothing: ``session.stats.submitted``, the GCU's ``executions``
  and ``execution_log``, ``gcu.control`` and ``gcu.aircraft`` are unchanged, and the next
  command is the only thing the GCU executes;
- leave the session working (a command succeeds; :func:`test_every_misuse_case_on_one_session`
  also keeps the heartbeat running afterwards and checks the link stays up).

The positive side: documented boundary values are accepted and, where cheap, the GCU
received exactly that value (its execution log, or the host packet that carried it). A
hypothesis test throws arbitrary values of arbitrary types at every scalar parameter and
checks accepted ⇔ valid. ``test_misuse_cases_cover_*`` fail when a public parameter has no
entry.
"""

from __future__ import annotations

import asyncio
import contextlib
import inspect
import math
import random
import re
import time
from collections import Counter
from collections.abc import AsyncIterator, Awaitable, Callable
from dataclasses import dataclass
from datetime import date, datetime, timedelta, timezone
from decimal import Decimal
from fractions import Fraction
from typing import Any, NamedTuple

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gcu_async import GcuClient
from gcu_async.client.connect import CLIENT_OPTIONS, connect
from gcu_async.errors import CommandError, CommandFailed, FieldRangeError, WaitTimeout
from gcu_async.protocol import (
    AircraftState,
    Attitude,
    AxisAngles,
    CameraMask,
    Command,
    ControlValues,
    Feedback,
    Focus,
    GeoPosition,
    HostMainFrame,
    HostPacket,
    ImageBox,
    NightVisionMode,
    NorthEastUp,
    NullCommand,
    Opcode,
    OsdCoordinateSource,
    TakePhoto,
    ZoomTo,
)
from gcu_async.protocol.catalogue import CATALOGUE, Kind
from gcu_async.protocol.gpstime import GPS_EPOCH, MS_PER_WEEK
from gcu_async.session import TelemetrySample
from gcu_async.sim import GcuSimulator, SimulatorModel
from gcu_async.sim.aircraft import ReceivedAircraft
from gcu_async.transport.memory import MemoryTransport
from gcu_async.transport.url import _SCHEMES
from helpers.protocol.boundary import MESSAGE, case_id
from helpers.scale import FULL, scaled

pytestmark = pytest.mark.filterwarnings("ignore:rate_hz=")

INF, NAN = math.inf, math.nan
UTC = timezone.utc
WAIT = 5.0
"""Seconds: the bound on every wait (a case never hangs)."""
UDP_URL, TCP_URL, SERIAL_URL = "udp://127.0.0.1:9", "tcp://127.0.0.1:9", "serial:///dev/null"


# --- the rig: a fresh simulator and client over the in-memory transport -----------------------
@dataclass
class Rig:
    gcu: GcuClient
    model: SimulatorModel
    received: list[HostPacket]
    """Every host packet the GCU decoded, in order."""
    called_at: float = 0.0
    """``time.monotonic()`` (the client's clock) just before the call under test."""

    @property
    def last_command(self) -> Command:
        return self.model.execution_log[-1].command

    async def probe(self) -> HostPacket:
        """Run a focus command; the host packet that carried it (built after every earlier
        call, so it shows the aircraft state and control values those calls left)."""
        n = len(self.received)
        await asyncio.wait_for(self.gcu.focus(), WAIT)
        return next(p for p in reversed(self.received[n:]) if isinstance(p.command, Focus))


@contextlib.asynccontextmanager
async def open_rig(**options: Any) -> AsyncIterator[Rig]:
    model = SimulatorModel(record_executions=True, calibration_seconds=0.0)
    received: list[HostPacket] = []
    handle = model.handle

    def spy(packet: HostPacket) -> Any:
        received.append(packet)
        return handle(packet)

    model.handle = spy  # type: ignore[method-assign]
    server = GcuSimulator(model).serve_memory()
    await server.open()
    try:
        async with GcuClient(server.transport, **options) as gcu:
            yield Rig(gcu, model, received)
    finally:
        await server.close()


@pytest.fixture
async def rig() -> AsyncIterator[Rig]:
    async with open_rig() as r:
        yield r


async def attempt(rig: Rig, call: Callable[[Rig, Any], Any], value: Any) -> Any:
    """Call; await the result if it is awaitable (bounded) and not a client (``await
    connect(url)`` would open it: the constructor's cases only build one)."""
    result = call(rig, value)
    if inspect.isawaitable(result) and not isinstance(result, GcuClient):
        result = await asyncio.wait_for(result, WAIT)
    return result


# --- the table ---------------------------------------------------------------------------------
Setup = Callable[[Rig], Awaitable[None]]


class P(NamedTuple):
    """One parameter of the client's public API: how to call with a value, what is allowed."""

    owner: str
    """The entry point (``take_photo``, ``GcuClient``, ``connect``, ``connect?query``)."""
    param: str
    """Its parameter (``box``); ``box.left`` for one element of a tuple parameter."""
    field: str
    """The name errors must use: the caller's."""
    call: Callable[[Rig, Any], Any]
    kind: str
    """bool, int, real, enum, tuple, part, callable, datetime, url, text."""
    low: float = -INF
    high: float = INF
    high_open: bool = False
    low_open: bool = False
    step: float = 0.0
    """Resolution a range check rounds to (0: exact bounds)."""
    optional: bool = False
    """``None`` is valid."""
    valid: tuple[Any, ...] = ()
    read: Callable[[Rig, Any], Any] | None = None
    """What the GCU (or the client) got, after a valid call; may return an awaitable."""
    expected: Callable[[Any], Any] | None = None
    """What ``read`` must give for a valid value (default: the value)."""
    wrong: tuple[Any, ...] = ()
    """Extra values that must be a wrong-type error."""
    bad: tuple[Any, ...] = ()
    """Extra values that must be a ValueError naming the field."""
    setup: Setup | None = None
    transport: bool = False
    """A transport option: its errors are ValueErrors that name it after the URL."""
    refusable: bool = False
    """The GCU may refuse a valid value (CommandFailed; e.g. a zoom beyond the pod's): the
    value still reached it (read from its execution log)."""


PARAMS: list[P] = []


def add(*params: P) -> None:
    PARAMS.extend(params)


def cmd(attr: str) -> Callable[[Rig, Any], Any]:
    """Read ``attr`` of the command the GCU executed last."""
    return from_log(lambda rig, result: getattr(rig.last_command, attr))


def from_log(read: Callable[[Rig, Any], Any]) -> Callable[[Rig, Any], Any]:
    """Mark a read as taken from the GCU's execution log: it holds what the GCU received
    even when the GCU refused it (a camera the pod lacks, a zero-size box)."""
    read.from_log = True
    return read


def sent_control(kind: str, index: int) -> Callable[[Rig, Any], Awaitable[Any]]:
    """Read one control value (an angle or a rate at 1×) from the next packet."""

    async def read(rig: Rig, result: Any) -> Any:
        main = (await rig.probe()).main
        assert main.control_valid, "the control values went out invalid"
        values = main.control.as_angles() if kind == "angles" else main.control.as_rates()
        return values[index]

    return read


async def euler_mode(rig: Rig) -> None:
    await asyncio.wait_for(rig.gcu.enter_euler_control(), WAIT)


async def rate_mode(rig: Rig) -> None:
    await asyncio.wait_for(rig.gcu.enter_pointing_lock(), WAIT)


async def ins_valid(rig: Rig) -> None:
    rig.gcu.update_aircraft(attitude=(0.0, 0.0, 0.0), acceleration=(0.0, 0.0, 0.0),
                            velocity=(0.0, 0.0, 0.0), position=(22.5, 113.9, 50.0))


async def recording(rig: Rig) -> None:
    await asyncio.wait_for(rig.gcu.start_recording(), WAIT)


def method(name: str, param: str, kind: str, *, base: dict[str, Any] | None = None,
           **kw: Any) -> None:  # fmt: skip
    """A parameter of a GcuClient method, called by keyword (the others from ``base``)."""
    others = base or {}
    kw.setdefault("refusable", getattr(kw.get("read"), "from_log", False))
    add(P(name, param, kw.pop("field", param),
          lambda rig, v: getattr(rig.gcu, name)(**{**others, param: v}), kind, **kw))  # fmt: skip


MASKS = (1, 255, CameraMask.CAMERA_2, CameraMask.CAMERA_1 | CameraMask.CAMERA_8)


class Quad(NamedTuple):
    a: float
    b: float
    c: float
    d: float


def tuple_wrong(base: tuple[float, ...], other: tuple[Any, ...]) -> tuple[Any, ...]:
    """Wrong types for a tuple parameter (which takes its NamedTuple, a tuple or a list of
    the right length): wrong lengths (lists too), text, scalars, another NamedTuple of the
    right length, other sequences."""
    n = len(base)
    return (list(base[:-1]), [*base, 0.0], base[:-1], (*base, 0.0), "abc"[:n] + "d" * (n - 3),
            1.0, b"", object(), other, dict.fromkeys(range(n), 0.0), bytearray(n), range(n),
            memoryview(bytes(n)), True)  # fmt: skip


def with_element(base: tuple[float, ...], fields: tuple[str, ...], element: str,
                 v: Any) -> tuple[Any, ...]:  # fmt: skip
    return tuple(v if f == element else b for f, b in zip(fields, base, strict=True))


# -- command methods: modes and control values
for _name in ("enter_euler_control", "enter_angle_control", "enter_fpv"):
    for _i, _axis in enumerate(("roll", "pitch", "yaw")):
        _euler_yaw = _name == "enter_euler_control" and _axis == "yaw"
        method(_name, _axis, "real", low=-180.0, high=360.0 if _euler_yaw else 180.0,
               high_open=_euler_yaw, optional=_name == "enter_euler_control",  # None: keep current
               valid=(-180.0, 359.99, 180.0, 0.01) if _euler_yaw else (-180.0, 180.0, 0.01),
               read=sent_control("angles", _i),
               expected=(lambda v: round(v - 360.0 if v >= 180.0 else v, 2)) if _euler_yaw
               else None)  # fmt: skip
for _name, _params in (("enter_pointing_lock", ("pitch_rate", "yaw_rate")),
                       ("enter_pointing_follow", ("pitch_rate", "yaw_rate")),
                       ("enter_top_down", ("yaw_rate",)),
                       ("enter_gaze_lock", ("pitch_rate", "yaw_rate"))):  # fmt: skip
    for _param in _params:
        method(_name, _param, "real", low=-150.0, high=150.0, valid=(-150.0, 150.0, 0.1),
               setup=ins_valid if _name == "enter_gaze_lock" else None,
               read=sent_control("rates", 1 if _param == "pitch_rate" else 2))  # fmt: skip
_GAZE = {"latitude": 22.5, "longitude": 113.9, "altitude": 50.0}
_GAZE_RANGES = {"latitude": (-90.0, 90.0), "longitude": (-180.0, 180.0),
                "altitude": (-2147483.648, 2147483.647)}  # fmt: skip
for _param, (_lo, _hi) in _GAZE_RANGES.items():
    method("gaze_at", _param, "real", base=_GAZE, low=_lo, high=_hi, valid=(_lo, _hi),
           setup=ins_valid, read=cmd(_param))  # fmt: skip
for _i, _axis in enumerate(("roll", "pitch", "yaw")):
    method("set_angles", _axis, "real", low=-180.0, high=180.0, setup=euler_mode,
           valid=(-180.0, 180.0, 0.01), read=sent_control("angles", _i))  # fmt: skip
    method("set_rates", _axis, "real", low=-150.0, high=150.0, setup=rate_mode,
           valid=(-150.0, 150.0, 0.1), read=sent_control("rates", _i))  # fmt: skip
method("calibrate", "timeout", "real", low=0.0, low_open=True, valid=(1.0, 1e300),
       read=lambda rig, result: result.status, expected=lambda v: 0)  # fmt: skip

# -- command methods: image geometry, cameras and the rest
_CAMERA_METHODS = ("take_photo", "toggle_recording", "start_recording", "stop_recording",
                   "zoom_in", "zoom_out", "stop_zoom", "focus", "stop_tracking")  # fmt: skip
for _name in _CAMERA_METHODS:
    method(_name, "cameras", "int", low=1, high=255, valid=MASKS, read=cmd("cameras"),
           setup=recording if _name == "stop_recording" else None)  # fmt: skip
_BOX = (0.0, 0.0, 1.0, 1.0)
_BOX_BAD = ((0.6, 0.4, 0.5, 0.6), (0.1, 0.7, 0.5, 0.6))  # right < left, bottom < top
for _name, _base in (("track", {}), ("set_area_temperature", {"enabled": True})):
    method(_name, "box", "tuple", base=_base,
           valid=(_BOX, ImageBox(0.25, 0.5, 0.25, 0.75), [0.4, 0.4, 0.5, 0.5]),
           wrong=tuple_wrong(_BOX, Quad(0, 0, 1, 1)), bad=_BOX_BAD, read=cmd("box"),
           expected=tuple)  # fmt: skip
    for _e in ImageBox._fields:
        add(P(_name, f"box.{_e}", f"box.{_e}",
              lambda rig, v, n=_name, b=_base, e=_e: getattr(rig.gcu, n)(
                  **b, box=with_element(_BOX, ImageBox._fields, e, v)),
              "real", 0.0, 1.0, valid=(0.0, 1.0), refusable=True,
              read=from_log(lambda rig, r, e=_e: getattr(rig.last_command.box, e))))
    method(_name, "cameras", "int", base={**_base, "box": _BOX}, low=1, high=255, valid=MASKS,
           read=cmd("cameras"))  # fmt: skip
for _name, _base in (("click_to_pan", {"x": 0.5, "y": 0.5}),
                     ("set_spot_temperature", {"enabled": True})):  # fmt: skip
    for _e in ("x", "y"):
        method(_name, _e, "real", base=_base, low=0.0, high=1.0, valid=(0.0, 1.0),
               read=from_log(lambda rig, r, e=_e: getattr(rig.last_command.point, e)))
    method(_name, "cameras", "int", base=_base, low=1, high=255, valid=MASKS,
           read=cmd("cameras"))  # fmt: skip
method("zoom_to", "ratio", "real", low=1.0, high=3276.8, valid=(1.0, 3276.8, 2.5),
       read=cmd("ratio"), refusable=True)  # fmt: skip
method("zoom_to", "cameras", "int", base={"ratio": 2.0}, low=1, high=255, valid=MASKS,
       read=cmd("cameras"))  # fmt: skip
method("zoom_to_fraction", "fraction", "real", low=1e-4, high=1.0, valid=(1e-4, 1.0),
       read=cmd("fraction"))  # fmt: skip
method("zoom_to_fraction", "cameras", "int", base={"fraction": 0.5}, low=1, high=255,
       valid=MASKS, read=cmd("cameras"))  # fmt: skip
method("set_palette", "palette", "int", low=0, high=10, valid=(0, 10), read=cmd("palette"))
method("set_palette", "cameras", "int", low=1, high=255, valid=MASKS, read=cmd("cameras"))
method("set_night_vision", "mode", "enum", low=0, high=2, read=cmd("mode"),
       valid=(*NightVisionMode, 0, 2), wrong=("ON", "1"))  # fmt: skip
method("set_night_vision", "cameras", "int", low=1, high=255, valid=MASKS, read=cmd("cameras"))
for _name in ("set_area_temperature", "set_temperature_alarm", "set_isotherm",
              "set_spot_temperature",
              "set_osd", "set_image_auto_flip", "set_target_detection", "set_digital_zoom",
              "set_ranging"):  # fmt: skip
    method(_name, "enabled", "bool", valid=(True, False), read=cmd("enabled"))
for _name in ("set_temperature_alarm", "set_isotherm"):
    # high with low at its minimum, low with high at its maximum: only one bound moves
    method(_name, "high", "real", base={"low": -3276.8}, low=-3276.8, high=3276.7, step=0.1,
           valid=(-3276.8, 3276.7), read=cmd("high"))  # fmt: skip
    method(_name, "low", "real", base={"high": 3276.7}, low=-3276.8, high=3276.7, step=0.1,
           valid=(-3276.8, 3276.7), read=cmd("low"))  # fmt: skip
    add(P(_name, "low (above high)", "low",
          lambda rig, v, n=_name: getattr(rig.gcu, n)(high=10.0, low=v), "part",
          bad=(20.0, 10.1, 3276.7)))  # fmt: skip
    method(_name, "cameras", "int", low=1, high=255, valid=MASKS, read=cmd("cameras"))
method("set_osd_coordinates", "coordinates", "enum", low=0, high=1, read=cmd("coordinates"),
       valid=(*OsdCoordinateSource, 0, 1), wrong=("TARGET",))  # fmt: skip
method("set_time_zone", "offset_hours", "int", low=-12, high=14, valid=(-12, 0, 14),
       read=cmd("offset_hours"))  # fmt: skip
method("set_picture_in_picture", "mode", "int", low=0, high=4, valid=(0, 4), read=cmd("mode"))
method("set_fill_light", "brightness", "int", low=0, high=255, valid=(0, 255),
       read=cmd("brightness"))  # fmt: skip

# the integer parameters no row above names (a new command's): from the catalogue's range
for _entry in CATALOGUE:
    for _p in _entry.parameters:
        _listed = {q.param for q in PARAMS if q.owner == _entry.method}
        if _p.kind is Kind.INTEGER and _p.name not in _listed:
            assert _p.low is not None and _p.high is not None
            method(_entry.method, _p.name, "int", low=int(_p.low), high=int(_p.high),
                   valid=(int(_p.low), int(_p.high)), read=cmd(_p.name))  # fmt: skip

# -- execute()
_CMD_WRONG = ("photo", None, 0x20, Opcode.TAKE_PHOTO, TakePhoto, Feedback(0x20),
              ControlValues(), object(), b"", [TakePhoto()])  # fmt: skip
add(P("execute", "command", "command", lambda rig, v: rig.gcu.execute(v), "part",
      valid=(Focus(), ZoomTo(ratio=2.0, cameras=3)), wrong=_CMD_WRONG, bad=(NullCommand(),),
      read=lambda rig, r: rig.last_command))  # fmt: skip
for _param in ("timeout", "queue_timeout"):
    add(P("execute", _param, _param, lambda rig, v, p=_param: rig.gcu.execute(Focus(), **{p: v}),
          "real", 0.0, low_open=True, optional=True, valid=(None, 1.0, 1e300),
          read=cmd("cameras"), expected=lambda v: 1))  # fmt: skip


# -- waits (docs/client.md, "Waiting for the gimbal, the zoom and the link"): valid values
# return at once (a predicate that holds, an unbounded tolerance, the link already up)
_ANY = {"tolerance": 1e300}
_PREDICATE_WRONG = (None, 5, "ready", b"", object(), True, [print])
method("wait_for", "predicate", "part", base={"timeout": 1.0}, valid=(lambda s: True,),
       wrong=_PREDICATE_WRONG)  # fmt: skip
method("wait_for", "timeout", "real", low=0.0, low_open=True, base={"predicate": lambda s: True},
       valid=(1e-3, 1.0, 1e300))  # fmt: skip
method("wait_for", "what", "text", base={"predicate": lambda s: True},
       valid=("", "the camera looking down"), wrong=(None, 5, b"x", ["x"], True))  # fmt: skip
_ATTITUDE_RANGES = {"roll": (-180.0, 180.0, False), "pitch": (-180.0, 180.0, False),
                    "yaw": (-180.0, 360.0, True)}  # fmt: skip
for _name in ("wait_attitude", "reach_attitude"):
    for _axis, (_low, _high, _open) in _ATTITUDE_RANGES.items():
        _other = {"pitch": 0.0} if _axis != "pitch" else {"roll": 0.0}
        method(_name, _axis, "real", low=_low, high=_high, high_open=_open, optional=True,
               base={**_other, **_ANY}, valid=(_low, 0.0, 89.99 if _axis == "pitch" else 179.9))
    method(_name, "tolerance", "real", low=0.0, low_open=True, base={"yaw": 0.0},
           valid=(1e300,))  # fmt: skip
    method(_name, "timeout", "real", low=0.0, low_open=True, base={"yaw": 0.0, **_ANY},
           valid=(1e-3, 1e300))  # fmt: skip
for _name, _high in (("wait_zoom", 6553.5), ("reach_zoom", 3276.8)):
    method(_name, "ratio", "real", low=1.0, high=_high, base=_ANY, valid=(1.0, 2.0))
    method(_name, "tolerance", "real", low=0.0, low_open=True, base={"ratio": 1.0},
           valid=(1e300,))  # fmt: skip
    method(_name, "timeout", "real", low=0.0, low_open=True, base={"ratio": 1.0, **_ANY},
           valid=(1e-3, 1e300))  # fmt: skip
method("wait_link", "up", "bool", base={"timeout": 0.05}, valid=(True,))
method("wait_link", "timeout", "real", low=0.0, low_open=True, valid=(1e-3, 1e300))


# -- aircraft state
def sent_aircraft(attr: str, index: int | None = None) -> Callable[[Rig, Any], Awaitable[Any]]:
    """Read the aircraft field ``attr`` (``main.x`` or ``sub.x``) of the next packet."""

    async def read(rig: Rig, result: Any) -> Any:
        packet = await rig.probe()
        part, name = attr.split(".")
        value = getattr(getattr(packet, part), name)
        return value if index is None else value[index]

    return read


def sent_gnss(index: int | None = None) -> Callable[[Rig, Any], Awaitable[Any]]:
    """Read the GNSS (week, ms) of the next packet (``index``: one of the two), taken back
    to the time given. The session advances a given time with its clock (rule 3 of
    docs/client.md), so the packet may carry it up to the time since the call later, on
    the client's clock (``time.monotonic``); ``result`` is the state the call returned."""

    async def read(rig: Rig, result: AircraftState) -> Any:
        sub = (await rig.probe()).sub
        since = math.floor((time.monotonic() - rig.called_at) * 1000)
        assert sub is not None
        given = result.gnss_week * MS_PER_WEEK + result.gnss_ms
        advance = sub.gnss_week * MS_PER_WEEK + sub.gnss_ms - given
        if not 0 <= advance <= since:
            return sub.gnss_week, sub.gnss_ms, f"advanced {advance} ms in {since} ms"
        pair = divmod(given, MS_PER_WEEK)
        return pair if index is None else pair[index]

    return read


_AIRCRAFT_TUPLES: dict[str, tuple[type[Any], Any, dict[str, tuple[float, float, bool]]]] = {
    "attitude": (Attitude, AxisAngles(0, 0, 0), {"roll": (-180.0, 180.0, True),
                                                 "pitch": (-90.0, 90.0, False),
                                                 "yaw": (-180.0, 360.0, True)}),
    "acceleration": (NorthEastUp, Attitude(0, 0, 0),
                     dict.fromkeys(NorthEastUp._fields, (-327.68, 327.67, False))),
    "velocity": (NorthEastUp, Attitude(0, 0, 0),
                 dict.fromkeys(NorthEastUp._fields, (-327.68, 327.67, False))),
    "position": (GeoPosition, NorthEastUp(0, 0, 0),
                 {"latitude": (-90.0, 90.0, False), "longitude": (-180.0, 180.0, False),
                  "altitude": (-2147483.648, 2147483.647, False)}),
}  # fmt: skip
_STEPS = {"attitude": 0.01, "acceleration": 0.01, "velocity": 0.01, "position": 1e-7}
_POSITION_STEPS = {"latitude": 1e-7, "longitude": 1e-7, "altitude": 1e-3}
_ZERO3 = (0.0, 0.0, 0.0)


def _aircraft_read(param: str, index: int) -> Callable[[Rig, Any], Awaitable[Any]]:
    if param == "position":
        return sent_aircraft("sub.position", index)
    attr = {"attitude": "aircraft_attitude"}.get(param, param)
    return sent_aircraft(f"main.{attr}", index)


_INS = ("attitude", "acceleration", "velocity")


def _with_ins(param: str) -> dict[str, Any]:
    """The other INS parts, at rest: the wire carries one only with all three."""
    return {p: _ZERO3 for p in _INS if p != param} if param in _INS else {}


for _param, (_cls, _other, _ranges) in _AIRCRAFT_TUPLES.items():
    _base = (22.5, 113.9, 50.0) if _param == "position" else _ZERO3
    add(P("update_aircraft", _param, _param,
          lambda rig, v, p=_param: rig.gcu.update_aircraft(**{p: v}), "tuple", optional=True,
          valid=(None, _base, _cls(*_base), list(_base)), wrong=tuple_wrong(_base, _other),
          expected=lambda v: None if v is None else tuple(v),
          read=lambda rig, r, p=_param: getattr(rig.gcu.aircraft, p)))  # fmt: skip
    for _i, (_e, (_lo, _hi, _open)) in enumerate(_ranges.items()):
        _step = _POSITION_STEPS[_e] if _param == "position" else _STEPS[_param]
        _top = round(_hi - _step, 2) if _open else _hi
        add(P("update_aircraft", f"{_param}.{_e}", f"{_param}.{_e}",
              lambda rig, v, p=_param, e=_e, c=_cls, b=_base: rig.gcu.update_aircraft(
                  **{p: with_element(b, c._fields, e, v)}, **_with_ins(p)),
              "real", _lo, _hi, _open, step=_step, valid=(_lo, _top),
              read=_aircraft_read(_param, _i),
              # a yaw goes out as its [0, 360) equivalent
              expected=(lambda v: v % 360.0) if _e == "yaw" else None))  # fmt: skip
add(P("update_aircraft", "relative_altitude", "relative_altitude",
      lambda rig, v: rig.gcu.update_aircraft(relative_altitude=v), "real", -2147483.648,
      2147483.647, step=1e-3, valid=(-2147483.648, 2147483.647), setup=ins_valid,
      read=sent_aircraft("sub.relative_altitude")),
    P("update_aircraft", "satellites", "satellites",
      lambda rig, v: rig.gcu.update_aircraft(satellites=v), "int", 0, 255, valid=(0, 255),
      setup=ins_valid, read=sent_aircraft("sub.satellites")),
    P("update_aircraft", "gnss_week", "gnss_week",
      lambda rig, v: rig.gcu.update_aircraft(gnss_week=v), "int", 0, 32767, valid=(0, 32767),
      setup=ins_valid, read=sent_gnss(0)),
    P("update_aircraft", "gnss_ms", "gnss_ms",
      lambda rig, v: rig.gcu.update_aircraft(gnss_ms=v), "int", 0, 604_799_999,
      valid=(0, 604_799_999), setup=ins_valid, read=sent_gnss(1)),
)  # fmt: skip
_T0 = datetime(2023, 9, 7, 1, 58, 38, tzinfo=UTC)


add(P("update_aircraft", "gnss_time", "gnss_time",
      lambda rig, v: rig.gcu.update_aircraft(gnss_time=v), "datetime", optional=True,
      valid=(_T0, GPS_EPOCH + timedelta(seconds=20)), setup=ins_valid, read=sent_gnss(),
      expected=AircraftState.gnss_from_utc,
      bad=(datetime(2023, 9, 7), datetime(1980, 1, 5, 23, 59, tzinfo=UTC),
           datetime.max.replace(tzinfo=UTC), datetime.min.replace(tzinfo=UTC),
           datetime(1979, 12, 31, tzinfo=timezone(timedelta(hours=-1))),
           datetime(2700, 1, 1, tzinfo=UTC))),
    P("update_aircraft", "gnss_time (with gnss_week)", "gnss_time",
      lambda rig, v: rig.gcu.update_aircraft(gnss_time=v, gnss_week=5), "part",
      bad=(_T0,)),
)  # fmt: skip


async def _read_state(rig: Rig, result: Any) -> Any:
    packet = await rig.probe()
    return packet.main.aircraft_attitude, packet.sub.position if packet.sub else None


_STATE = AircraftState(attitude=(1.0, -2.0, 3.0), acceleration=_ZERO3, velocity=_ZERO3,
                       position=(10.0, 20.0, 30.0))  # fmt: skip
add(P("set_aircraft", "state", "state", lambda rig, v: rig.gcu.set_aircraft(v), "part",
      valid=(AircraftState(), _STATE), read=_read_state,
      expected=lambda s: (s.attitude if s.ins_complete else Attitude(0.0, 0.0, 0.0),
                          s.position),
      wrong=(None, AircraftState, {}, (), HostMainFrame(), ReceivedAircraft(), "state",
             object(), [AircraftState()], _STATE.main_frame())))  # fmt: skip


async def _read_control(rig: Rig, result: Any) -> Any:
    main = (await rig.probe()).main
    return main.control if main.control_valid else None


_CV_WRONG = ((0, 0, 0), [0, 0, 0], "x", 0, object(), Attitude(0, 0, 0), ControlValues, b"",
             ControlValues(1.5, 0, 0), ControlValues(True, 0, 0), ControlValues(None, 0, 0),
             ControlValues(0, "1", 0), ControlValues(0, 0, Decimal(1)))  # fmt: skip
add(P("set_control", "control", "control", lambda rig, v: rig.gcu.set_control(v), "part",
      optional=True, setup=euler_mode, read=_read_control, wrong=_CV_WRONG,
      valid=(None, ControlValues(0, 0, 18000), ControlValues(-18000, -18000, -18000)),
      bad=(ControlValues(99999, 0, 0), ControlValues(0, 0, -18001),
           ControlValues(10**40, 0, 0))),
    P("set_control", "control (rate mode)", "control", lambda rig, v: rig.gcu.set_control(v),
      "part", setup=rate_mode, read=_read_control,
      valid=(ControlValues(1500, 0, -1500),), bad=(ControlValues(1501, 0, 0),
                                                  ControlValues(0, 0, -1501))),
)  # fmt: skip


# -- telemetry and callbacks
async def first_sample(rig: Rig, maxsize: Any) -> TelemetrySample:
    """The first sample of ``telemetry(maxsize)`` (the iterator is closed again)."""
    stream = rig.gcu.telemetry(maxsize)
    try:
        return await asyncio.wait_for(stream.__anext__(), WAIT)
    finally:
        await stream.aclose()


class CallRecorder:
    """A callback that counts its calls."""

    def __init__(self) -> None:
        self.calls: list[Any] = []

    def __call__(self, arg: Any) -> None:
        self.calls.append(arg)


async def _called(rig: Rig, result: Any) -> bool:
    callback = _TELEMETRY_CALLBACK
    n = len(callback.calls)
    deadline = time.monotonic() + WAIT
    while len(callback.calls) <= n and time.monotonic() < deadline:
        await asyncio.sleep(0.005)
    result()  # unsubscribes
    return len(callback.calls) > n


_TELEMETRY_CALLBACK = CallRecorder()
_CALLBACK_WRONG = (None, 5, "print", b"", object(), [print], True, lambda: None,
                   lambda a, b: None)  # fmt: skip
add(P("telemetry", "maxsize", "maxsize", first_sample, "int", 1, valid=(1, 2, 64),
      read=lambda rig, r: type(r), expected=lambda v: TelemetrySample),
    P("on_telemetry", "callback", "callback", lambda rig, v: rig.gcu.on_telemetry(v),
      "callable", valid=(_TELEMETRY_CALLBACK,), read=_called, expected=lambda v: True,
      wrong=_CALLBACK_WRONG),
    P("on_link_change", "callback", "callback", lambda rig, v: rig.gcu.on_link_change(v),
      "callable", valid=(CallRecorder(),), wrong=_CALLBACK_WRONG),
)  # fmt: skip


# -- the constructor and connect(): client options
def spare_transport() -> MemoryTransport:
    """An unopened transport for clients that are only built."""
    return MemoryTransport.pair(("a", "b"))[0]


def _client_options(owner: str, build: Callable[[dict[str, Any]], GcuClient],
                    default_guard: float) -> None:  # fmt: skip
    def opt(name: str, kind: str, **kw: Any) -> None:
        add(P(owner, name, name, lambda rig, v: build({name: v}), kind, **kw))

    positive = {"low": 0.0, "low_open": True}
    # silence_timeout must exceed the heartbeat period: 1 / rate_hz (50 Hz by default)
    opt("rate_hz", "real", low=2.0, high=200.0, valid=(2.0, 30.0, 50.0, 200.0),
        read=lambda rig, c: c.rate_hz)
    opt("silence_timeout", "real", low=0.02, low_open=True, valid=(0.0200001, 1.0, 1e300),
        read=lambda rig, c: c.session.config.silence_timeout)
    opt("aircraft_timeout", "real", low=0.0, low_open=True, high=10.0,
        valid=(5e-324, 0.02, 1.0, 10.0), read=lambda rig, c: c.aircraft_timeout)
    for name in ("command_timeout", "queue_timeout", "connect_timeout"):
        opt(name, "real", valid=(5e-324, 1.0, 1e300),
            read=lambda rig, c, n=name: getattr(c, n) if n == "connect_timeout"
            else getattr(c.session.config, n), **positive)  # fmt: skip
    opt("open_timeout", "real", optional=True, valid=(None, 5e-324, 1.0, 1e300, INF),
        read=lambda rig, c: c.open_timeout, **positive)  # inf: until closed
    opt("wait", "bool", valid=(True, False), read=lambda rig, c: c.wait)
    opt("restore", "bool", valid=(True, False), read=lambda rig, c: c.restore)
    opt("conformance", "bool", valid=(True, False), read=lambda rig, c: c.conformance)
    opt("reorder_guard", "real", low=0.0, optional=True, valid=(None, 0.0, 0.015, 1e300),
        read=lambda rig, c: c.reorder_guard,
        expected=lambda v: default_guard if v is None else v)  # fmt: skip
    opt("check_support", "bool", valid=(True, False), read=lambda rig, c: c.check_support)
    opt("max_zoom", "real", low=1.0, high=3276.8, optional=True,
        valid=(None, 1.0, 30.0, 3276.8), read=lambda rig, c: c.max_zoom)
    opt("version", "int", low=1, high=2, valid=(1, 2), read=_read_version,
        expected=lambda v: {v})
    opt("clock", "callable", valid=(time.monotonic, time.perf_counter),
        # 1234.5 stands for clock=time.monotonic() (a reading, not the clock); a fixed value
        # keeps the test id the same in every pytest-xdist worker
        wrong=(None, 5, "time", b"", object(), 1234.5, [time.monotonic],
               lambda: "x", lambda: None), bad=(lambda: NAN, lambda: -INF))
    opt("capture", "part", optional=True, valid=(None,),
        wrong=(5, 1.5, True, b"x.pcapng", object(), ["x.pcapng"]), bad=("",))


async def _read_version(rig: Rig, client: GcuClient) -> Any:
    """Open a client with this version against a simulator of its own: the version byte the
    GCU received."""
    version = client.version
    async with open_rig(version=version) as own:
        await asyncio.wait_for(own.gcu.take_photo(), WAIT)
        return {p.version for p in own.received}


_client_options("GcuClient", lambda kw: GcuClient(spare_transport(), **kw), 0.0)
_client_options("connect", lambda kw: connect(UDP_URL, **kw), 0.015)
add(P("GcuClient", "transport", "transport", lambda rig, v: GcuClient(v), "part",
      valid=(spare_transport(),), wrong=(None, UDP_URL, object(), MemoryTransport, 5,
                                          SimulatorModel)),
    P("connect", "url", "url", lambda rig, v: connect(v), "url",
      valid=(UDP_URL, "udp://[::1]", TCP_URL, SERIAL_URL + "?baudrate=115200"),
      wrong=(None, b"udp://127.0.0.1", 5, object(), [UDP_URL], True),
      bad=("", "udp://", "http://127.0.0.1", "udp://127.0.0.1:0", "udp://127.0.0.1:65536",
           "udp://[::1", "udp://127.0.0.1/x", "udp://u@127.0.0.1", "udp://127.0.0.1#f",
           "udp://127.0.0.1?local_port=1&local_port=2", "udp://127.0.0.1?nope=1",
           "serial://", "tcp://300.1.1.1", "udp://127.0.0.1?rate_hz=30", "udp:127.0.0.1")),
)  # fmt: skip

# -- connect(): transport options, as keywords and in the URL query
_TEXT_WRONG = ("1", "false", "True", "2.5")


_WORDS = {"1", "0", "true", "false", "yes", "no", "on", "off"}




def topt(scheme_url: str, name: str, kind: str, *, query: tuple[Any, ...] = (),
         query_valid: tuple[str, ...] = (), **kw: Any) -> None:  # fmt: skip
    """A transport option of ``connect()``: as a keyword, and as text in the URL query."""
    if kind != "query-only":
        add(P("connect", name, name, lambda rig, v: connect(scheme_url, **{name: v}), kind,
              transport=True, **kw))  # fmt: skip
    add(P("connect?query", name, name, lambda rig, v: connect(f"{scheme_url}?{name}={v}"),
          "text", transport=True, bad=query, valid=query_valid))  # fmt: skip


_INT_TEXT = ("abc", "1.5", "", "true", "0x10", "1e3", " ", "1_0")
_BOOL_TEXT = ("maybe", "2", "", "none", "yes please", "-1")
_FLOAT_TEXT = ("abc", "", "nan", "inf", "-inf", "-1", "0", "1e400", "0x10")
topt(UDP_URL, "local_port", "int", low=0, high=65535, valid=(0, 65535),
     wrong=_TEXT_WRONG, query=(*_INT_TEXT, "-1", "65536", "9" * 30),
     query_valid=("0", "65535"))  # fmt: skip
topt(UDP_URL, "local_host", "host", valid=("127.0.0.1", "0.0.0.0", "localhost"),
     wrong=(5, None, b"127.0.0.1", object(), True, ["127.0.0.1"]),
     bad=("", "300.1.1.1", "bad host", "-x", "a..b", "::1::", "1.2.3"),
     query=("300.1.1.1", "bad%20host", "-x"), query_valid=("127.0.0.1",))  # fmt: skip
for _name in ("broadcast", "discovery", "follow_peer"):
    topt(UDP_URL, _name, "bool", valid=(True, False), wrong=_TEXT_WRONG,
         query=_BOOL_TEXT, query_valid=("1", "0", "true", "no", "on"))  # fmt: skip
topt(UDP_URL, "reuse_port", "bool", optional=True, valid=(True, False, None), wrong=_TEXT_WRONG,
     query=tuple(t for t in _BOOL_TEXT if t != "none"),
     query_valid=("1", "0", "none"))  # fmt: skip
topt(TCP_URL, "reconnect", "bool", valid=(True, False), wrong=_TEXT_WRONG,
     query=_BOOL_TEXT, query_valid=("yes", "off"))  # fmt: skip
topt(TCP_URL, "connect_timeout", "query-only", query=_FLOAT_TEXT, query_valid=("0.5", "10"))
for _name, _lo, _hi in (("backoff_base", 0.0, 2.0), ("backoff_cap", 0.05, INF),
                        ("backoff_factor", 1.0, INF)):  # fmt: skip
    topt(TCP_URL, _name, "real", low=_lo, high=_hi, low_open=_name == "backoff_base",
         valid=(_lo if _name == "backoff_factor" else 0.001 if _lo == 0.0 else _lo, 2.0),
         wrong=_TEXT_WRONG, query=_FLOAT_TEXT,
         query_valid=("1", "2.0"))  # fmt: skip
topt(TCP_URL, "max_attempts", "int", low=1, optional=True, valid=(1, 10**40),
     wrong=_TEXT_WRONG, query=(*_INT_TEXT, "0", "-1"),
     query_valid=("1", "3"))  # None is valid with max_total (test_transport_url)
topt(TCP_URL, "max_total", "real", low=0.0, low_open=True, optional=True,
     valid=(None, 0.001, 1e300), wrong=_TEXT_WRONG, query=_FLOAT_TEXT,
     query_valid=("none", "30"))  # fmt: skip
add(P("connect", "rng", "rng", lambda rig, v: connect(TCP_URL, rng=v), "part", transport=True,
      valid=(random.Random(1), random.SystemRandom()),
      wrong=(None, 5, "rng", random, object(), random.random, b"")),
    P("connect?query", "rng", "rng", lambda rig, v: connect(f"{TCP_URL}?rng={v}"), "text",
      transport=True, bad=("1", "random")),
)  # fmt: skip
topt(SERIAL_URL, "baudrate", "int", low=115200, high=1000000,
     valid=(115200, 250000, 500000, 1000000), wrong=_TEXT_WRONG,
     bad=(9600, 115201, 999999), query=(*_INT_TEXT, "9600", "115200.0"),
     query_valid=("1000000",))  # fmt: skip


# --- misuse generation -------------------------------------------------------------------------
WRONG_BOOL = (0, 1, "false", "True", None, 1.0, b"", [], object(), Decimal(1), complex(1, 0))
WRONG_INT = (True, False, 1.0, 1.5, "1", None, b"", [], object(), complex(1, 0), Decimal(1),
             Fraction(1, 1))  # fmt: skip
WRONG_REAL = (True, False, "1", "nan", None, b"", [], object(), complex(1, 0), Decimal("1"),
              Fraction(1, 2))  # fmt: skip
WRONG_DATETIME = ("2023-09-07", 0, 1.5, date(2023, 9, 7), object(), b"", _T0.timestamp())
WRONG_TEXT = (None, b"", 5, object(), [])


class Case(NamedTuple):
    p: P
    value: Any
    expect: type[Exception]
    """TypeError, FieldRangeError or ValueError (the message is checked)."""


def _outside(p: P) -> list[Any]:
    """Out-of-range values of an int or real parameter."""
    values: list[Any] = []
    if p.kind == "int" or p.kind == "enum":
        if p.low > -INF:
            values += [int(p.low) - 1, -(10**40)]
        if p.high < INF:
            values += [int(p.high) + 1, 10**40]
        return values
    values = [NAN, INF, -INF]
    if p.low > -INF:
        below = p.low if p.low_open else (p.low - p.step if p.step
                                          else math.nextafter(p.low, -INF))  # fmt: skip
        values += [below, -1e30, -(10**40), -(10**400)]
    if p.high < INF:
        above = p.high if p.high_open else (p.high + p.step if p.step
                                            else math.nextafter(p.high, INF))  # fmt: skip
        values += [above, 1e30, 10**40]
    values.append(10**400)
    return values


def misuse(p: P) -> list[Case]:
    wrong: tuple[Any, ...] = {
        "bool": WRONG_BOOL, "int": WRONG_INT, "enum": WRONG_INT, "real": WRONG_REAL,
        "datetime": WRONG_DATETIME, "url": WRONG_TEXT,
    }.get(p.kind, ())  # fmt: skip
    wrong = tuple({(type(v), repr(v)): v for v in (*wrong, *p.wrong)
                   if not (p.optional and v is None)}.values())  # fmt: skip
    type_error = ValueError if p.transport else TypeError
    cases = [Case(p, v, type_error) for v in wrong]
    if p.kind in ("int", "enum", "real"):
        range_error = ValueError if p.transport else FieldRangeError
        cases += [Case(p, v, range_error) for v in _outside(p) if v not in p.valid]
    cases += [Case(p, v, ValueError) for v in p.bad]
    return cases


MISUSE_CASES = [c for p in PARAMS for c in misuse(p)]
POSITIVE = [(p, v) for p in PARAMS for v in p.valid]


def _id(p: P, v: Any) -> str:
    return case_id(p.owner, p.param, v)


def _shown(v: Any) -> list[str]:
    """How a message may show ``v``: its repr, str, float repr."""
    shown = [repr(v), str(v)]
    if isinstance(v, int) and not isinstance(v, bool):
        shown += [str(int(v))]
        if abs(v) < 2**1000:
            shown.append(repr(float(v)))
    if isinstance(v, datetime):
        shown.append(v.isoformat())
    return [s[:30] for s in shown]


ALLOWED = (TypeError, ValueError, FieldRangeError)


def check_error(case: Case, err: BaseException, *, message: bool = True) -> None:
    """``err`` is what ``case`` must raise; ``message=False`` checks only its type."""
    p, v, expect = case
    assert type(err) in ALLOWED, f"{type(err).__name__}: {err}"
    assert isinstance(err, TypeError if expect is TypeError else ValueError), err
    if not message:
        return
    msg = str(err)
    if p.kind == "url" and expect is ValueError:  # the transport names the URL, then the part
        assert msg.startswith(f"{v or repr(v)}: "), msg
    elif p.transport:
        assert re.search(rf"\b{re.escape(p.field)}\b", msg), msg
    else:
        assert msg.startswith((f"{p.field}:", f"{p.field}.")), msg
    if expect is TypeError:
        assert type(err) is TypeError, msg
        if p.kind != "part":
            assert " expected " in msg and type(v).__name__ in msg, msg
        return
    assert isinstance(err, ValueError), msg
    if expect is FieldRangeError:
        _check_range(p, v, err, msg)
    elif p.kind not in ("part", "tuple", "callable", "text", "url"):
        assert any(s in msg for s in _shown(v)), msg


def _check_range(p: P, v: Any, err: ValueError, msg: str) -> None:
    """A range error states the field, the value and the bound the value violates."""
    assert isinstance(err, FieldRangeError), msg
    assert err.field == p.field, msg
    m = MESSAGE.match(msg)
    assert m, msg
    assert m["value"][:30] in _shown(v), msg
    try:
        f = float(v)
    except OverflowError:
        f = INF if v > 0 else -INF
    if f < p.low or (p.low_open and f <= p.low):
        assert err.low == p.low, msg
    elif f > p.high or (p.high_open and f >= p.high):
        assert err.high == p.high and err.high_open == p.high_open, msg
    else:  # NaN, or an infinity at an unbounded end: the whole range is stated
        assert not math.isfinite(f), (p, v)
        assert (err.low, err.high) == (p.low, p.high), msg


class Snapshot(NamedTuple):
    submitted: int
    executions: Counter[int]
    log: int
    control: Any
    aircraft: AircraftState


def snapshot(rig: Rig) -> Snapshot:
    g = rig.gcu
    return Snapshot(g.session.stats.submitted, Counter(rig.model.executions),
                    len(rig.model.execution_log), g.control, g.aircraft)  # fmt: skip


async def run_case(rig: Rig, case: Case) -> None:
    """One misuse case: the right error, nothing sent or changed, the session still works."""
    if case.p.setup is not None:
        await case.p.setup(rig)
    before = snapshot(rig)
    with pytest.raises(Exception) as info:  # noqa: PT011 - the type is checked below
        await attempt(rig, case.p.call, case.value)
    check_error(case, info.value)
    assert snapshot(rig) == before, case
    await rig.probe()  # the session works, and nothing else ran on the GCU before it
    after = snapshot(rig)
    assert after.submitted == before.submitted + 1
    assert after.executions == before.executions + Counter({Opcode.FOCUS: 1})
    assert (after.control, after.aircraft) == (before.control, before.aircraft)


STRIDE = 1 if FULL else 3
"""Each case on a client of its own: all at full size, every third at reduced size (every
case still runs at every size on one session: test_every_misuse_case_on_one_session)."""


@pytest.mark.parametrize(
    "case",
    [pytest.param(c, id=_id(c.p, c.value)) for c in MISUSE_CASES[::STRIDE]],
)
async def test_misuse_is_rejected_naming_the_parameter(rig: Rig, case: Case) -> None:
    await run_case(rig, case)


@pytest.mark.parametrize(("p", "value"), POSITIVE[::STRIDE],
                         ids=[_id(p, v) for p, v in POSITIVE[::STRIDE]])
async def test_boundary_values_are_accepted(rig: Rig, p: P, value: Any) -> None:
    if p.setup is not None:
        await p.setup(rig)
    rig.called_at = time.monotonic()
    try:
        result = await attempt(rig, p.call, value)
    except CommandFailed:
        if not p.refusable:
            raise
        result = None  # the GCU received it and refused: read what it received
    if p.read is None:
        return
    back = p.read(rig, result)
    if inspect.isawaitable(back):
        back = await asyncio.wait_for(back, WAIT)
    expected = p.expected(value) if p.expected is not None else value
    assert back == expected, (p.owner, p.param, value, back)


def test_misuse_case_count() -> None:
    kinds = Counter(c.expect.__name__ for c in MISUSE_CASES)
    owners = {p.owner for p in PARAMS}
    print(f"\nclient misuse: {len(MISUSE_CASES)} cases over {len(PARAMS)} parameters "
          f"of {len(owners)} entry points ({dict(kinds)}); "
          f"{len(POSITIVE)} boundary values accepted")  # fmt: skip
    assert len(MISUSE_CASES) >= 1500
    assert len(PARAMS) >= 150
    assert len(POSITIVE) >= 250


# --- every misuse case on one session: nothing accumulates, the link stays up -----------------
async def test_every_misuse_case_on_one_session() -> None:
    # grouped by set-up (each runs once); a command every 100 cases
    cases = sorted(MISUSE_CASES, key=lambda c: getattr(c.p.setup, "__name__", ""))
    setup: Setup | None = None
    async with open_rig() as rig:
        for i, case in enumerate(cases):
            if case.p.setup is not setup and case.p.setup is not None:
                await case.p.setup(rig)
            setup = case.p.setup
            before = snapshot(rig)
            with pytest.raises(Exception) as info:  # noqa: PT011 - checked below
                await attempt(rig, case.p.call, case.value)
            try:
                check_error(case, info.value)
                assert snapshot(rig) == before
            except AssertionError as exc:
                raise AssertionError(f"{_id(case.p, case.value)}: {exc}") from exc
            if i % 100 == 0:
                executions = Counter(rig.model.executions)
                await rig.probe()
                assert rig.model.executions - executions == Counter({Opcode.FOCUS: 1})
        await _keeps_running(rig)  # the heartbeat still encodes, the GCU still answers
        assert rig.model.stats.malformed == 0


# --- the issue's regressions, by name ------------------------------------------------------------
async def _keeps_running(rig: Rig, seconds: float = 0.5) -> None:
    """The heartbeat goes on and the GCU answers for ``seconds``; then a command succeeds."""
    before = rig.gcu.link
    await asyncio.sleep(seconds)
    after = rig.gcu.link
    assert after.up and after.lost_count == 0 and after.send_errors == 0
    assert after.packets_received - before.packets_received >= seconds * 50 * 0.4
    await asyncio.wait_for(rig.gcu.take_photo(), WAIT)


REGRESSIONS: list[tuple[str, Callable[[GcuClient], Any], type[Exception], str]] = [
    ('set_osd("false")', lambda g: g.set_osd("false"), TypeError, "enabled: "),
    ("take_photo(cameras=1.5)", lambda g: g.take_photo(cameras=1.5), TypeError, "cameras: "),
    ("enter_euler_control(yaw=1e30)", lambda g: g.enter_euler_control(yaw=1e30),
     FieldRangeError, "yaw: "),
    ("set_control(ControlValues(99999, 0, 0))",
     lambda g: g.set_control(ControlValues(99999, 0, 0)), FieldRangeError, "control.roll_raw: "),
    ("set_aircraft(None)", lambda g: g.set_aircraft(None), TypeError, "state: "),
]  # fmt: skip


@pytest.mark.parametrize(("name", "call", "error", "prefix"), REGRESSIONS,
                         ids=[r[0] for r in REGRESSIONS])  # fmt: skip
async def test_issue_regressions(rig: Rig, name: str, call: Callable[[GcuClient], Any],
                                 error: type[Exception], prefix: str) -> None:  # fmt: skip
    await euler_mode(rig)  # a mode is confirmed: control values would be stored and sent
    rig.gcu.set_angles(pitch=-30.0)
    before = snapshot(rig)
    with pytest.raises(error) as info:
        await attempt(rig, lambda r, _: call(r.gcu), None)
    assert str(info.value).startswith(prefix), str(info.value)
    assert snapshot(rig) == before
    await _keeps_running(rig)
    assert (await rig.probe()).main.control == ControlValues.angles(pitch=-30.0)
    assert rig.model.stats.malformed == 0
    # every later update still works after set_aircraft(None) was refused
    rig.gcu.update_aircraft(attitude=(1.0, 2.0, 3.0), acceleration=_ZERO3, velocity=_ZERO3)
    assert (await rig.probe()).main.aircraft_attitude == Attitude(1.0, 2.0, 3.0)


@pytest.mark.parametrize("gcu_sim_transport", ["udp"])
async def test_connect_version_true_fails_at_once_and_version_1_connects(gcu_sim: Any) -> None:
    with pytest.raises(TypeError, match=r"^version: expected an integer, got bool True"):
        gcu_sim.client(version=True)
    received: list[int] = []
    handle = gcu_sim.simulator.model.handle

    def spy(packet: HostPacket) -> Any:
        received.append(packet.version)
        return handle(packet)

    gcu_sim.simulator.model.handle = spy
    async with gcu_sim.client(version=1, connect_timeout=WAIT) as gcu:  # real UDP, loopback
        await asyncio.wait_for(gcu.take_photo(), WAIT)
        assert gcu.version == 1
    assert received and set(received) == {1}


# --- adversarial: arbitrary values of arbitrary types at every scalar parameter -----------------
SCALARS = [p for p in PARAMS if p.kind in ("bool", "int", "enum", "real")
           and not p.transport]  # fmt: skip


def _values(p: P) -> st.SearchStrategy[Any]:
    near: list[st.SearchStrategy[Any]] = []
    if p.kind in ("int", "enum"):
        lo = int(p.low) if p.low > -INF else -(10**6)
        hi = int(p.high) if p.high < INF else 10**6
        near.append(st.integers(lo - 3, hi + 3))
    if p.kind == "real":
        lo = p.low if p.low > -INF else -1e6
        hi = p.high if p.high < INF else 1e6
        span = max(p.step, 1e-9) * 3
        near += [st.floats(lo - span, lo + span), st.floats(hi - span, hi + span),
                 st.floats(lo, hi)]  # fmt: skip
    anything = st.one_of(
        st.booleans(), st.none(), st.integers(), st.floats(), st.text(max_size=3),
        st.binary(max_size=2), st.decimals(allow_nan=True), st.fractions(),
        st.complex_numbers(max_magnitude=10), st.just(object()),
        st.lists(st.integers(), max_size=2),
        st.sampled_from([*CameraMask, *NightVisionMode, *OsdCoordinateSource]),
    )  # fmt: skip
    return st.one_of(*near, anything).filter(lambda v: not (p.optional and v is None))


def _valid(p: P, v: Any) -> bool | None:
    """True: must be accepted; False: must be rejected; None: either (a real within one
    resolution step of a bound may round onto it or past it)."""
    if p.kind == "bool":
        return v is True or v is False
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return False
    if p.kind in ("int", "enum"):
        return isinstance(v, int) and p.low <= v <= p.high
    try:
        f = float(v)
    except OverflowError:
        return False
    if not math.isfinite(f):
        return False
    m = p.step
    above_low = f > p.low + m if p.low_open else f >= p.low + m
    below_high = f < p.high - m if p.high_open else f <= p.high - m
    outside = (f < p.low - m or (p.low_open and f <= p.low) or f > p.high + m
               or (p.high_open and f >= p.high))  # fmt: skip
    return True if above_low and below_high else False if outside else None


async def _try(p: P, v: Any) -> BaseException | None:
    async with open_rig() as rig:
        if p.setup is not None:
            await p.setup(rig)
        before = snapshot(rig)
        try:
            await attempt(rig, p.call, v)
        except (CommandError, WaitTimeout):  # refused, timed out: accepted at the boundary
            return None
        except (TypeError, ValueError) as exc:
            assert snapshot(rig) == before
            return exc
        return None


@settings(max_examples=scaled(600, 60), deadline=None)
@given(st.data())
def test_arbitrary_values_accepted_iff_valid(data: st.DataObject) -> None:
    p = data.draw(st.sampled_from(SCALARS), label="parameter")
    v = data.draw(_values(p), label="value")
    expected = _valid(p, v)
    error = asyncio.run(_try(p, v))  # anything but TypeError / ValueError fails the test
    if error is None:
        assert expected is not False, (p.owner, p.param, v)
        return
    assert expected is not True, (p.owner, p.param, v, error)
    assert type(error) in ALLOWED, error
    assert str(error).startswith(f"{p.field}:"), (p.field, str(error))


# --- properties and argument-free entry points --------------------------------------------------
PROPERTIES = sorted(n for n, v in inspect.getmembers(GcuClient) if isinstance(v, property)
                    and not n.startswith("_"))  # fmt: skip
NO_ARGUMENTS = ("open", "close", "centre", "release_control", "link_events",
                "conformance_report")


async def test_properties_do_not_raise_on_an_open_client(rig: Rig) -> None:
    await rig.gcu.take_photo()
    values = {name: getattr(rig.gcu, name) for name in PROPERTIES}
    assert values["rate_hz"] == 50.0 and values["version"] == 2 and values["link"].up
    for name in ("transport", "session", "connect_timeout", "check_support",
                 "telemetry_dropped"):  # fmt: skip
        getattr(rig.gcu, name)
    assert len(PROPERTIES) >= 14


async def test_argument_free_entry_points(rig: Rig) -> None:
    await euler_mode(rig)
    rig.gcu.set_angles(yaw=45.0)
    assert (await _read_control(rig, None)) == ControlValues.angles(yaw=45.0)
    rig.gcu.release_control()
    assert rig.gcu.control is None and not rig.gcu.control_valid
    assert (await _read_control(rig, None)) is None
    await rate_mode(rig)  # centre works in the lock/follow modes
    feedback = await asyncio.wait_for(rig.gcu.centre(), WAIT)
    assert feedback.opcode == Opcode.CENTRE and feedback.status == 0
    await rig.gcu.close()
    await rig.gcu.close()  # idempotent
    await asyncio.wait_for(rig.gcu.open(), WAIT)  # reusable
    await asyncio.wait_for(rig.gcu.take_photo(), WAIT)


async def test_setters_without_a_mode_change_nothing(rig: Rig) -> None:
    # not a parameter error: no mode takes values yet; nothing is stored or sent
    before = snapshot(rig)
    for call in (lambda: rig.gcu.set_angles(yaw=10.0), lambda: rig.gcu.set_rates(yaw=1.0),
                 lambda: rig.gcu.set_control(ControlValues(1, 2, 3))):  # fmt: skip
        with pytest.raises(ValueError, match="no mode is confirmed or pending"):
            call()
    assert snapshot(rig) == before


async def test_telemetry_maxsize_beyond_a_deque(rig: Rig) -> None:
    # accepted (a sample arrives) or rejected naming maxsize; never an OverflowError
    error: Exception | None = None
    try:
        await first_sample(rig, 10**40)
    except (TypeError, ValueError) as exc:
        error = exc
    assert error is None or str(error).startswith("maxsize: "), error


async def test_unsubscribing_twice_is_harmless(rig: Rig) -> None:
    for subscribe in (rig.gcu.on_telemetry, rig.gcu.on_link_change):
        unsubscribe = subscribe(CallRecorder())
        unsubscribe()
        unsubscribe()


# --- the misuse cases cover the whole public API -------------------------------------------------
def _covered(owner: str) -> set[str]:
    return {p.param.split(".")[0].split(" ")[0] for p in PARAMS if p.owner == owner}


PUBLIC_METHODS = sorted(
    n for n, v in inspect.getmembers(GcuClient)
    if not n.startswith("_") and callable(v) and not isinstance(v, type)
)  # fmt: skip


@pytest.mark.parametrize("name", PUBLIC_METHODS)
def test_misuse_cases_cover_every_method_parameter(name: str) -> None:
    params = set(inspect.signature(getattr(GcuClient, name)).parameters) - {"self"}
    if not params:
        assert name in NO_ARGUMENTS, f"{name} takes no arguments: test it there"
    assert params <= _covered(name), params - _covered(name)


def test_misuse_cases_cover_the_constructor_and_connect() -> None:
    params = set(inspect.signature(GcuClient).parameters)
    assert params <= _covered("GcuClient"), params - _covered("GcuClient")
    options = set(CLIENT_OPTIONS) | {"url"}
    options |= {name for scheme in _SCHEMES.values() for name in scheme} - {"connect_timeout"}
    assert options <= _covered("connect"), options - _covered("connect")
    query = {n for scheme in _SCHEMES.values() for n in scheme}
    assert query <= _covered("connect?query"), query - _covered("connect?query")


@pytest.mark.parametrize(("owner", "param", "value"), [
    ("set_osd", "enabled", "false"), ("take_photo", "cameras", 1.5),
    ("enter_euler_control", "yaw", 1e30), ("set_control", "control", ControlValues(99999, 0, 0)),
    ("set_aircraft", "state", None), ("connect", "version", True),
])  # fmt: skip
def test_misuse_cases_hold_the_reported_cases(owner: str, param: str, value: Any) -> None:
    assert any(c.p.owner == owner and c.p.param == param and type(c.value) is type(value)
               and c.value == value for c in MISUSE_CASES)  # fmt: skip
