"""Every out-of-range value raises before anything is sent, with a message naming the field,
the allowed range and the value: build() unit arguments, raw fields (validate()), packet
fields and command parameters, including NaN/inf and wrong types."""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable
from datetime import datetime
from typing import Any, NamedTuple

import pytest

from gcu_async.errors import FieldRangeError, LocalProtocolError
from gcu_async.protocol import (
    COMMAND_TYPES,
    AreaTemperature,
    ClickToPan,
    Command,
    ControlValues,
    Feedback,
    FillLight,
    GazeAtCoordinates,
    GcuMainFrame,
    GcuPacket,
    GcuSubFrame,
    GeoPosition,
    HostMainFrame,
    HostPacket,
    HostSubFrame,
    ImageBox,
    ImagePoint,
    Isotherm,
    NightVision,
    OsdCoordinates,
    Palette,
    PictureInPicture,
    SpotTemperature,
    TemperatureAlarm,
    TimeZone,
    Track,
    UnknownCommand,
    UnknownSubFrame,
    ZoomTo,
)
from helpers.protocol.strategies import RAW_RANGES

INF, NAN = math.inf, math.nan
S16, S32 = (-32768, 32767), (-(2**31), 2**31 - 1)
MESSAGE = re.compile(
    r"^(?P<field>.+?): (?P<value>.+?) is outside the allowed range "
    r"\[(?P<low>[^,]+), (?P<high>[^\]\)]+)(?P<close>[\]\)])"
)


def check_error(
    err: FieldRangeError, field: str, value: Any, low: float, high: float, high_open: bool
) -> None:
    assert isinstance(err, ValueError)
    assert isinstance(err, LocalProtocolError)
    assert err.field == field
    assert (math.isnan(err.value) and math.isnan(value)) if value != value else err.value == value
    assert (err.low, err.high, err.high_open) == (low, high, high_open)
    m = MESSAGE.match(str(err))
    assert m, str(err)
    assert m["field"] == field
    assert m["value"] == repr(value)
    assert float(m["low"]) == low
    assert float(m["high"]) == high
    assert m["close"] == (")" if high_open else "]")


class Case(NamedTuple):
    call: Callable[[Any], object]
    field: str
    value: Any
    low: float
    high: float
    high_open: bool = False


def _cases(
    call: Callable[[Any], object],
    field: str,
    low: float,
    high: float,
    *bad: Any,
    high_open: bool = False,
) -> list[Any]:
    return [
        pytest.param(Case(call, field, v, low, high, high_open), id=f"{field}={v!r}") for v in bad
    ]


def _att(i: int, v: float) -> tuple[float, float, float]:
    a = [0.0, 0.0, 0.0]
    a[i] = v
    return (a[0], a[1], a[2])


def _sub(**kw: Any) -> HostSubFrame:
    return HostSubFrame.build(**{"latitude": 0.0, "longitude": 0.0, "altitude": 0.0, **kw})


def _target(position: GeoPosition) -> GcuSubFrame:
    return GcuSubFrame.build(target_distance=1.0, target_position=position)


# --- build() unit arguments ---------------------------------------------------------------------
# fmt: off
BUILD_CASES = [
    *_cases(lambda v: HostMainFrame.build(attitude=_att(0, v)), "aircraft roll", -180.0, 180.0,
            180.0, -180.01, 1e300, NAN, INF, high_open=True),
    *_cases(lambda v: HostMainFrame.build(attitude=_att(1, v)), "aircraft pitch", -90.0, 90.0,
            90.01, -90.01, -INF),
    *_cases(lambda v: HostMainFrame.build(attitude=_att(2, v)), "aircraft yaw", 0.0, 360.0,
            360.0, -0.01, high_open=True),
    *[c for i, axis in enumerate(("north", "east", "up")) for kind in ("acceleration", "velocity")
      for c in _cases(lambda v, i=i, kind=kind: HostMainFrame.build(**{kind: _att(i, v)}),
                      f"aircraft {kind} {axis}", -327.68, 327.67, 327.68, -327.69, NAN)],
    *[c for i, axis in enumerate(("roll", "pitch", "yaw"))
      for c in _cases(lambda v, i=i: ControlValues.angles(*_att(i, v)),
                      f"control {axis} angle", -180.0, 180.0, 180.01, -180.01, NAN)],
    *[c for i, axis in enumerate(("roll", "pitch", "yaw"))
      for c in _cases(lambda v, i=i: ControlValues.rates(*_att(i, v)),
                      f"control {axis} rate", -150.0, 150.0, 150.1, -150.1, INF)],
    *_cases(lambda v: ControlValues.rates(v, zoom=2.0), "control roll rate", -75.0, 75.0, 75.1),
    *_cases(lambda v: HostMainFrame.build(subframe_request=v), "subframe_request", 0, 255,
            256, -1),
    *_cases(lambda v: _sub(longitude=v), "longitude", -180.0, 180.0, 180.0000001, -181.0, NAN),
    *_cases(lambda v: _sub(latitude=v), "latitude", -90.0, 90.0, 90.0000001, -90.1, INF),
    *_cases(lambda v: _sub(altitude=v), "altitude", -2147483.648, 2147483.647,
            2147483.648, -2147483.649, 1e300),
    *_cases(lambda v: _sub(relative_altitude=v), "relative_altitude", -2147483.648,
            2147483.647, 2147483.648, NAN),
    *_cases(lambda v: _sub(satellites=v), "satellites", 0, 255, 256, -1),
    *_cases(lambda v: _sub(gnss_ms=v), "gnss_ms", 0, 604_799_999, 604_800_000, -1),
    *_cases(lambda v: _sub(gnss_week=v), "gnss_week", 0, 32767, 32768, -1),
    *_cases(lambda v: GcuMainFrame.build(mode=v), "mode", 0, 255, 256, -1),
    *_cases(lambda v: GcuMainFrame.build(pod_status=v), "pod_status", 0, 0xFFFF, 0x10000),
    *_cases(lambda v: GcuMainFrame.build(miss_distance=(v, 0)), "miss distance x", -1000,
            1000, 1001, -1001),
    *_cases(lambda v: GcuMainFrame.build(miss_distance=(0, v)), "miss distance y", -1000,
            1000, 1001),
    *[c for i, axis in enumerate("XYZ")
      for c in _cases(lambda v, i=i: GcuMainFrame.build(relative_angles=_att(i, v)),
                      f"relative {axis} angle", -180.0, 180.0, 180.0, -180.01, NAN,
                      high_open=True)],
    *_cases(lambda v: GcuMainFrame.build(attitude=_att(0, v)), "camera roll", -90.0, 90.0,
            90.01, -90.01),
    *_cases(lambda v: GcuMainFrame.build(attitude=_att(1, v)), "camera pitch", -180.0, 180.0,
            180.0, -180.01, high_open=True),
    *_cases(lambda v: GcuMainFrame.build(attitude=_att(2, v)), "camera yaw", 0.0, 360.0,
            360.0, -0.01, high_open=True),
    *[c for i, axis in enumerate("XYZ")
      for c in _cases(lambda v, i=i: GcuMainFrame.build(angular_rates=_att(i, v)),
                      f"{axis} angular rate", -3276.8, 3276.7, 3276.8, -3276.9, INF)],
    *_cases(lambda v: GcuSubFrame.build(hardware_version=v), "hardware_version", 0.0, 25.5,
            25.6, -0.1),
    *_cases(lambda v: GcuSubFrame.build(firmware_version=v), "firmware_version", 0.0, 25.5,
            25.6, NAN),
    *_cases(lambda v: GcuSubFrame.build(pod_model=v), "pod_model", 0, 255, 256),
    *_cases(lambda v: GcuSubFrame.build(faults=v), "faults", 0, 0xFFFF, 0x10000),
    *_cases(lambda v: GcuSubFrame.build(target_distance=v), "target_distance", 0.0,
            214748364.7, -0.1, 214748364.8, INF),
    *_cases(lambda v: _target(GeoPosition(0.0, v, 0.0)),
            "target longitude", -180.0, 180.0, 180.1),
    *_cases(lambda v: _target(GeoPosition(v, 0.0, 0.0)),
            "target latitude", -90.0, 90.0, -90.1),
    *_cases(lambda v: _target(GeoPosition(0.0, 0.0, v)),
            "target altitude", -2147483.648, 2147483.647, 2147483.648),
    *_cases(lambda v: GcuSubFrame.build(camera1_zoom=v), "camera1_zoom", 0.0, 6553.5,
            6553.6, -0.1),
    *_cases(lambda v: GcuSubFrame.build(camera2_zoom=v), "camera2_zoom", 0.0, 6553.5, NAN),
    *_cases(lambda v: GcuSubFrame.build(thermal_flags=v), "thermal_flags", 0, 0xFF, 256),
    *_cases(lambda v: GcuSubFrame.build(camera_flags=v), "camera_flags", 0, 0xFFFF, 0x10000),
    *_cases(lambda v: GcuSubFrame.build(pip_mode=v), "pip_mode", 0, 7, 8, -1),
    *_cases(lambda v: GcuSubFrame.build(time_zone=v), "time_zone", -128, 127, 128, -129),
]
# fmt: on


@pytest.mark.parametrize("case", BUILD_CASES)
def test_build_argument_out_of_range(case: Case) -> None:
    with pytest.raises(FieldRangeError) as info:
        case.call(case.value)
    check_error(info.value, case.field, case.value, case.low, case.high, case.high_open)


# The zoom ends at 6553.5, the largest ratio the GCU can report (U16, 0.1x): before, any
# finite zoom passed and a huge one made even a zero rate fail (0 * inf is NaN).
@pytest.mark.parametrize("zoom", [0.5, 0.0, -1.0, 6553.6, 1e300, NAN, INF])
def test_rate_zoom_out_of_range(zoom: float) -> None:
    with pytest.raises(ValueError, match=r"^zoom: .* is outside the allowed range \[1, 6553.5\]"):
        ControlValues.rates(1.0, zoom=zoom)
    assert ControlValues.rates(0.0, zoom=6553.5) == ControlValues(0, 0, 0)


@pytest.mark.parametrize(
    "call",
    [
        lambda: HostMainFrame.build(attitude=(True, 0.0, 0.0)),
        lambda: HostMainFrame.build(velocity=(0.0, "1", 0.0)),
        lambda: ControlValues.angles(None),  # type: ignore[arg-type]
        lambda: _sub(latitude=True),
        lambda: _sub(satellites=1.0),
        lambda: GcuSubFrame.build(camera1_zoom=False),
        lambda: GazeAtCoordinates(latitude=True, longitude=0.0, altitude=0.0),
        lambda: ZoomTo(ratio=True),
        lambda: TimeZone(8.0),  # type: ignore[arg-type]
        lambda: TemperatureAlarm(high="30"),  # type: ignore[arg-type]
    ],
)
def test_wrong_type_is_a_type_error(call: Callable[[], object]) -> None:
    with pytest.raises(TypeError, match="expected"):
        call()


def test_naive_gnss_time_is_rejected() -> None:
    with pytest.raises(ValueError, match="naive"):
        _sub(gnss_time=datetime(2023, 9, 7, 1, 58, 38))


# --- raw fields: validate() --------------------------------------------------------------------
RAW_CASES = [
    pytest.param(cls, field, value, low, high, id=f"{cls.__name__}.{field}={value}")
    for cls, ranges in RAW_RANGES.items()
    for field, (low, high) in ranges.items()
    for value in (low - 1, high + 1)
]


@pytest.mark.parametrize("cls", list(RAW_RANGES), ids=lambda c: c.__name__)
def test_every_raw_field_has_a_range_case(cls: type[Any]) -> None:
    assert set(RAW_RANGES[cls]) == set(cls._fields)


@pytest.mark.parametrize(("cls", "field", "value", "low", "high"), RAW_CASES)
def test_validate_raw_field_out_of_range(
    cls: type[Any], field: str, value: int, low: int, high: int
) -> None:
    frame = cls()._replace(**{field: value})
    with pytest.raises(FieldRangeError) as info:
        frame.validate()
    check_error(info.value, field, value, low, high, False)
    # encoding validates too: nothing out of range reaches the wire
    packet = (
        HostPacket(frame)
        if cls is HostMainFrame
        else (
            HostPacket(HostMainFrame(), frame)
            if cls is HostSubFrame
            else (GcuPacket(frame) if cls is GcuMainFrame else GcuPacket(GcuMainFrame(), frame))
        )
    )
    with pytest.raises(FieldRangeError):
        packet.encode()


@pytest.mark.parametrize("flags", [0x02, 0x08, 0x80, 0xFF])
def test_host_flags_reserved_bits(flags: int) -> None:
    with pytest.raises(FieldRangeError, match="reserved bits") as info:
        HostMainFrame(flags_raw=flags).validate()
    check_error(info.value, "flags_raw", flags, 0, 5, False)


@pytest.mark.parametrize(("lo", "hi"), [(0, 0), (255, 255)])
def test_raw_range_edges_are_accepted(lo: int, hi: int) -> None:
    for cls, ranges in RAW_RANGES.items():
        for field, (low, high) in ranges.items():
            if field == "flags_raw":
                continue
            cls()._replace(**{field: low if lo == 0 else high}).validate()


def test_unknown_sub_frame_validation() -> None:
    with pytest.raises(FieldRangeError) as info:
        UnknownSubFrame(256, bytes(31)).validate()
    check_error(info.value, "sub frame header", 256, 0, 255, False)
    with pytest.raises(ValueError, match="31 bytes, got 30"):
        HostPacket(HostMainFrame(), UnknownSubFrame(2, bytes(30))).encode()


@pytest.mark.parametrize(
    ("packet", "field", "value"),
    [
        (HostPacket(HostMainFrame(), version=256), "version", 256),
        (GcuPacket(GcuMainFrame(), version=-1), "version", -1),
        (GcuPacket(GcuMainFrame(), feedback=Feedback(256, 0)), "feedback opcode", 256),
        (GcuPacket(GcuMainFrame(), feedback=Feedback(0x20, 256)), "feedback status", 256),
        (GcuPacket(GcuMainFrame(), feedback=Feedback(0x20, -1)), "feedback status", -1),
    ],
)
def test_packet_fields_out_of_range(packet: HostPacket | GcuPacket, field: str, value: int) -> None:
    with pytest.raises(FieldRangeError) as info:
        packet.encode()
    check_error(info.value, field, value, 0, 255, False)


# --- command parameters --------------------------------------------------------------------------
REQUIRED_ARGS: dict[type[Command], dict[str, Any]] = {
    GazeAtCoordinates: {"latitude": 0.0, "longitude": 0.0, "altitude": 0.0},
    ClickToPan: {"point": ImagePoint(0.5, 0.5)},
    ZoomTo: {"ratio": 2.0},
}
MASKED = [
    cls for cls in COMMAND_TYPES.values() if "cameras" in {f.name for f in dataclasses.fields(cls)}
]


def test_masked_commands_are_the_documented_ones() -> None:
    # docs/protocol-notes.md §3 "Camera masks": photo/record/zoom/focus/track/click-to-pan/night
    # vision + palette/thermal
    assert {cls.OPCODE for cls in MASKED} == {
        0x17,
        0x1A,
        0x20,
        0x21,
        0x22,
        0x23,
        0x24,
        0x25,
        0x26,
        0x2A,
        0x2B,
        0x30,
        0x31,
        0x32,
        0x33,
    }


@pytest.mark.parametrize("cls", MASKED, ids=lambda c: c.__name__)
@pytest.mark.parametrize("mask", [0, 256, -1])
def test_camera_mask_out_of_range(cls: type[Command], mask: int) -> None:
    kwargs = REQUIRED_ARGS.get(cls, {})
    cls(**kwargs)  # valid with the document's default mask
    with pytest.raises(FieldRangeError) as info:
        cls(**kwargs, cameras=mask)
    check_error(info.value, "cameras", mask, 1, 255, False)


def _box(left: float = 0.0, top: float = 0.0, right: float = 1.0, bottom: float = 1.0) -> ImageBox:
    return ImageBox(left, top, right, bottom)


def _gaze(**kw: float) -> GazeAtCoordinates:
    return GazeAtCoordinates(**{"latitude": 0.0, "longitude": 0.0, "altitude": 0.0, **kw})


# fmt: off
COMMAND_CASES = [
    *_cases(lambda v: _gaze(latitude=v), "latitude", -90.0, 90.0, 90.0000001, -90.01, NAN),
    *_cases(lambda v: _gaze(longitude=v), "longitude", -180.0, 180.0, 180.0000001, -INF),
    *_cases(lambda v: _gaze(altitude=v), "altitude", -2147483.648, 2147483.647, 2147483.648,
            INF),
    *[c for cls in (Track, AreaTemperature)
      for edge in ("left", "top", "right", "bottom")
      for c in _cases(lambda v, cls=cls, edge=edge: cls(box=_box(**{edge: v})),
                      f"box.{edge}", 0.0, 1.0, -0.0001, 1.0001, NAN)],
    *_cases(lambda v: Track(box=_box(left=0.5, right=v)), "box.right", 0.5, 1.0, 0.4),
    *_cases(lambda v: Track(box=_box(top=0.6, bottom=v)), "box.bottom", 0.6, 1.0, 0.0),
    *_cases(lambda v: AreaTemperature(box=_box(left=0.5, right=v)), "box.right", 0.5, 1.0,
            0.25),
    *_cases(lambda v: ClickToPan(point=ImagePoint(v, 0.5)), "point.x", 0.0, 1.0, 1.0001, NAN),
    *_cases(lambda v: ClickToPan(point=ImagePoint(0.5, v)), "point.y", 0.0, 1.0, -0.0001),
    *_cases(lambda v: SpotTemperature(point=ImagePoint(v, 0.5)), "point.x", 0.0, 1.0, 2.0),
    *_cases(lambda v: SpotTemperature(point=ImagePoint(0.5, v)), "point.y", 0.0, 1.0, -1.0),
    *_cases(lambda v: OsdCoordinates(v), "coordinates", 0, 1, 2, -1),
    *_cases(lambda v: TimeZone(v), "offset_hours", -12, 14, 15, -13),
    *_cases(lambda v: ZoomTo(ratio=v), "ratio", 1.0, 3276.8, 0.9, 3276.9, -2.0, NAN, INF),
    *_cases(lambda v: ZoomTo(fraction=v), "fraction", 0.0001, 1.0, 0.0, 1.0001, NAN),
    *_cases(lambda v: Palette(v), "palette", 0, 10, 11, -1),
    *_cases(lambda v: NightVision(v), "mode", 0, 2, 3),
    *[c for cls in (TemperatureAlarm, Isotherm) for c in [
        *_cases(lambda v, cls=cls: cls(high=v), "high", -3276.8, 3276.7, 3276.8, NAN),
        *_cases(lambda v, cls=cls: cls(high=100.0, low=v), "low", -3276.8, 3276.7, -3276.9,
                INF),
        # low above high: the allowed range of low ends at high
        *_cases(lambda v, cls=cls: cls(high=10.0, low=v), "low", -3276.8, 10.0, 10.1, 50.0),
    ]],
    *_cases(lambda v: PictureInPicture(v), "mode", 0, 4, 5, -1),
    *_cases(lambda v: FillLight(v), "brightness", 0, 255, 256, -1),
    *_cases(lambda v: UnknownCommand(code=v), "opcode", 0, 255, 256, -1),
]
# fmt: on


@pytest.mark.parametrize("case", COMMAND_CASES)
def test_command_parameter_out_of_range(case: Case) -> None:
    with pytest.raises(FieldRangeError) as info:
        case.call(case.value)
    check_error(info.value, case.field, case.value, case.low, case.high, case.high_open)


@pytest.mark.parametrize("kwargs", [{}, {"ratio": 2.0, "fraction": 0.5}])
def test_zoom_to_needs_exactly_one_of_ratio_and_fraction(kwargs: dict[str, float]) -> None:
    with pytest.raises(ValueError, match=r"exactly one of ratio= or fraction="):
        ZoomTo(**kwargs)


@pytest.mark.parametrize("code", [*sorted(COMMAND_TYPES)[:3], 37, 129])
def test_unknown_command_rejects_known_opcodes(code: int) -> None:
    with pytest.raises(ValueError, match=f"0x{code:02X} is a known command"):
        UnknownCommand(code=code)


def test_range_edges_are_accepted() -> None:
    # the ends of each documented range encode (the checks are not off by one)
    HostMainFrame.build(attitude=(-180.0, 90.0, 359.99), acceleration=(-327.68, 327.67, 0))
    ControlValues.rates(150.0, -150.0)
    _sub(latitude=-90.0, longitude=180.0, gnss_ms=604_799_999, gnss_week=32767)
    GcuSubFrame.build(hardware_version=25.5, camera1_zoom=6553.5, pip_mode=7, time_zone=-128)
    assert ZoomTo(ratio=1.0).raw_value == -10
    assert ZoomTo(ratio=3276.8).raw_value == -32768
    assert ZoomTo(fraction=0.0001).raw_value == 1
    assert ZoomTo(fraction=1.0).raw_value == 10000
    assert TimeZone(-12).encode_params() == b"\xf4"
    assert TemperatureAlarm(high=5.0, low=5.0).encode_params() == b"\x02\x01\x32\x00\x32\x00"
    assert Track(box=ImageBox(0.25, 0.25, 0.25, 0.25)).raw_params() == (
        1,
        1,
        2500,
        2500,
        2500,
        2500,
    )
