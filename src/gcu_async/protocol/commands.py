"""The command schema: every command of V2.0.6 (byte 69 + parameters, bytes 70..S-3), once.

This module is the one place a command is written: its :class:`Opcode` member, and its class
— a frozen dataclass in engineering units whose ``SCHEMA`` (:class:`CommandSchema`) lists
its parameters in wire order as kinds (:mod:`gcu_async.protocol.command_fields`: wire type,
scale, unit, range, doc), its status rule, its mode, its Appendix 8 row, whether it needs INS
data and the client methods that send it (names and docs). The codec is compiled from the
schema when this module loads; the catalogue, the mode tables, the feedback sets, the support
matrix, the dissector's tables (:func:`wire_rows`) and the docs' and tests' tables derive from
it (docs/architecture.md, "Changing the protocol").

A command is validated when it is built (so a bad argument raises before anything is sent)
under the package rule (:mod:`gcu_async.protocol`): ``bool`` fields take only
``True``/``False``, integer fields only ``int`` (camera masks 1–255, ``CameraMask`` members
welcome), real fields finite ``int``/``float`` inside the wire range, enum fields a member or
its exact value, ``box``/``point`` an :class:`ImageBox` / :class:`ImagePoint` (or a plain
tuple, stored as the NamedTuple) checked element by element. ``encode_params()`` gives the
parameter bytes; :func:`decode_command` turns opcode + parameter bytes back into the typed
command — or, when they hold a value outside its range or have the wrong length, into an
:class:`AnomalousCommand` that keeps the bytes and lists the :class:`Anomaly` of each field
(receive is liberal, send is strict: docs/client.md, "Liberal receive, strict send"). The
first parameter byte of many commands is a camera mask (docs/protocol-notes.md §3 "Camera
masks"): it is the ``cameras`` field, defaulting to the value the document shows.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field, fields
from enum import IntEnum
from typing import Any, ClassVar, NamedTuple, TypeVar

from gcu_async._checks import check_int, type_error
from gcu_async.errors import FieldRangeError
from gcu_async.protocol.anomalies import Anomaly
from gcu_async.protocol.command_fields import (
    IMAGE_SCALE as IMAGE_SCALE,
)
from gcu_async.protocol.command_fields import (
    IMAGE_UNIT as IMAGE_UNIT,
)
from gcu_async.protocol.command_fields import (
    TEMPERATURE,
    ZOOM_FRACTION,
    ZOOM_RATIO,
    Box,
    Cameras,
    CommandSchema,
    Kind,
    Method,
    ModeSpec,
    Parameter,
    Point,
    StatusRule,
    Switch,
    Thresholds,
    ZoomValue,
    choice,
    integer,
    real,
)
from gcu_async.protocol.enums import CameraMask, Mode, NightVisionMode, OsdCoordinateSource
from gcu_async.protocol.fields import WIRE_RANGES, struct_of
from gcu_async.protocol.host_frames import CONTROL_ANGLE_RAW, CONTROL_RATE_RAW


class Opcode(IntEnum):
    """Command opcodes of V2.0.6 (byte 69 of both directions)."""

    NULL = 0x00
    CALIBRATION = 0x01
    CENTRE = 0x03
    OSD_COORDINATES = 0x06
    IMAGE_AUTO_FLIP = 0x07
    TIME_ZONE = 0x08
    ANGLE_CONTROL = 0x10
    POINTING_LOCK = 0x11
    POINTING_FOLLOW = 0x12
    TOP_DOWN = 0x13
    EULER_CONTROL = 0x14
    GAZE_AT_COORDINATES = 0x15
    GAZE_LOCK = 0x16
    TRACK = 0x17
    CLICK_TO_PAN = 0x1A
    FPV = 0x1C
    TAKE_PHOTO = 0x20
    RECORD = 0x21
    ZOOM_IN = 0x22
    ZOOM_OUT = 0x23
    ZOOM_STOP = 0x24
    ZOOM_TO = 0x25
    FOCUS = 0x26
    PALETTE = 0x2A
    NIGHT_VISION = 0x2B
    AREA_TEMPERATURE = 0x30
    TEMPERATURE_ALARM = 0x31
    ISOTHERM = 0x32
    SPOT_TEMPERATURE = 0x33
    OSD = 0x73
    PICTURE_IN_PICTURE = 0x74
    TARGET_DETECTION = 0x75
    DIGITAL_ZOOM = 0x76
    FILL_LIGHT = 0x80
    RANGING = 0x81


_OPCODE_VALUES = frozenset(int(o) for o in Opcode)


def opcode_name(opcode: int) -> str:
    """The protocol name of ``opcode`` (``"UNKNOWN_0x42"`` for opcodes V2.0.6 does not define);
    ``opcode`` is an ``int`` 0–255 (``TypeError`` / ``FieldRangeError`` otherwise)."""
    if type(opcode) is not int or not 0 <= opcode <= 0xFF:
        opcode = check_int("opcode", opcode, 0, 0xFF)
    return Opcode(opcode).name if opcode in _OPCODE_VALUES else f"UNKNOWN_0x{opcode:02X}"


_C = TypeVar("_C", bound="Command")

MAX_PARAMS = 0xFFFF - 72
"""Most parameter bytes a packet can carry (S, a U16, counts 72 bytes besides them)."""
TEMPERATURE_UNIT = TEMPERATURE.raw_unit
TEMPERATURE_RAW = (TEMPERATURE.raw_low, TEMPERATURE.raw_high)  # 0.1 °C
ZOOM_RATIO_MAX = ZOOM_RATIO.raw_high / ZOOM_RATIO.scale
ZOOM_FRACTION_RAW_MAX = ZOOM_FRACTION.raw_high


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


def _store(command: Command, name: str, value: object) -> None:
    """Store a checked, normalised field value on a frozen command."""
    object.__setattr__(command, name, value)


@dataclass(frozen=True, slots=True)
class Command:
    """Base of all commands. ``OPCODE`` is the protocol opcode, ``SCHEMA`` the rest of its
    description; ``LAYOUT`` the parameter layout (little-endian), compiled from the schema."""

    OPCODE: ClassVar[Opcode]
    SCHEMA: ClassVar[CommandSchema] = CommandSchema()
    LAYOUT: ClassVar[struct.Struct] = struct.Struct("<")

    def __post_init__(self) -> None:
        if not hasattr(self, "OPCODE"):
            raise TypeError(f"{type(self).__name__} is abstract: build one of its subclasses")
        self._normalize()
        self.raw_params()  # validates every field, raising before anything is sent

    def _normalize(self) -> None:
        """Check tuple and enum fields and store them as their classes (compiled)."""

    @property
    def opcode(self) -> Opcode:
        return self.OPCODE

    def raw_params(self) -> tuple[int, ...]:
        """The parameter values as the raw integers that go on the wire."""
        return ()

    @classmethod
    def from_raw_params(cls: type[_C], raw: tuple[int, ...]) -> _C:
        """The command of raw parameters (``ValueError`` for values V2.0.6 does not allow)."""
        return cls()

    def encode_params(self) -> bytes:
        """Parameter bytes (70..S-3 of the host packet)."""
        return self.LAYOUT.pack(*self.raw_params())

    @classmethod
    def raw_anomalies(cls, raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
        """Every value of the raw parameters (as unpacked by ``LAYOUT``) outside its range:
        empty exactly when :meth:`from_raw_params` accepts them."""
        found: tuple[Anomaly, ...] = ()
        at = 0
        for kind in cls.SCHEMA.params:
            n = len(kind.wire)
            found += kind.anomalies(*raw[at : at + n])
            at += n
        return found

    @classmethod
    def decode_params(cls, params: bytes) -> Command:
        """Inverse of :meth:`encode_params`. Parameters of the wrong length or with a value
        outside its range give an :class:`AnomalousCommand` (bytes kept, fields flagged)."""
        layout = cls.LAYOUT
        if len(params) != layout.size:
            found = Anomaly("params", len(params), layout.size, layout.size, "bytes",
                            f"{cls.OPCODE.name} has {layout.size} parameter bytes")  # fmt: skip
            return AnomalousCommand(int(cls.OPCODE), bytes(params), (found,))
        raw = layout.unpack(params)
        try:
            return cls.from_raw_params(raw)
        except ValueError:  # the slow path: out of range
            return AnomalousCommand(int(cls.OPCODE), bytes(params), cls.raw_anomalies(raw))

    def as_dict(self) -> dict[str, Any]:
        """Name, opcode, parameters in units and raw, for JSON output."""
        kinds = {a: k for k in self.SCHEMA.params for a in k.attrs}
        params: dict[str, Any] = {}
        for f in fields(self):
            v = getattr(self, f.name)
            params[f.name] = v if v is None else kinds[f.name].json(v)
        return {
            "command": self.OPCODE.name,
            "opcode": int(self.OPCODE),
            "params": params,
            "params_raw": list(self.raw_params()),
            "params_hex": self.encode_params().hex(" "),
        }


_DEFINED: list[type[Command]] = []


def _compile(cls: type[_C]) -> type[_C]:
    """Register a command class and compile its codec from its schema: ``LAYOUT``,
    ``raw_params``, ``from_raw_params`` and ``_normalize`` as straight-line functions (the hot
    path runs no loop over the schema)."""
    kinds = cls.SCHEMA.params
    attrs = [f.name for f in fields(cls)]
    owned = [a for k in kinds for a in k.attrs]
    if sorted(owned) != sorted(attrs):
        raise TypeError(f"{cls.__name__}: attributes {attrs} but schema parameters {owned}")
    env: dict[str, Any] = {"_store": _store}
    enc, dec, norm, unpack = [], [], [], []
    at = 0
    for i, k in enumerate(kinds):
        env[f"e{i}"], env[f"d{i}"], env[f"n{i}"] = k.encoder(), k.decode, k.normalize
        args = ", ".join(f"self.{a}" for a in k.attrs)
        raw = ", ".join(f"r{j}" for j in range(at, at + len(k.wire)))
        at += len(k.wire)
        enc.append(f"e{i}({args})" if k.scalar else f"*e{i}({args})")
        if len(k.attrs) == 1:
            dec.append(f"{k.attrs[0]}=d{i}({raw})")
        else:
            unpack.append(f"    v{i} = d{i}({raw})")
            dec += [f"{a}=v{i}[{j}]" for j, a in enumerate(k.attrs)]
        if k.normalizes:
            norm += [f"    _store(self, {a!r}, n{i}(self.{a}))" for a in k.attrs]
    targets = "".join(f"r{j}, " for j in range(at))
    src = (f"def raw_params(self):\n    return ({', '.join(enc)}{',' if len(enc) == 1 else ''})\n"
           f"def from_raw_params(cls, raw):\n    {targets or '_'} = {'raw' if at else '()'}\n"
           + "".join(line + "\n" for line in unpack)
           + f"    return cls({', '.join(dec)})\n"
           f"def _normalize(self):\n" + ("\n".join(norm) or "    pass") + "\n")  # fmt: skip
    exec(compile(src, f"<codec of {cls.__name__}>", "exec"), env)  # our own text, from the schema
    cls.LAYOUT = struct_of(cls.SCHEMA.wire)
    cls.raw_params = env["raw_params"]  # type: ignore[method-assign]
    cls.from_raw_params = classmethod(env["from_raw_params"])  # type: ignore[method-assign,assignment]
    cls._normalize = env["_normalize"]  # type: ignore[method-assign]
    _DEFINED.append(cls)
    return cls


# -- parameters several commands share ---------------------------------------------------------
CAM1, CAM2 = Cameras(), Cameras()
"""The camera mask parameter (its default, camera 1 or 2, is the class attribute's)."""
RATE_LIMIT = CONTROL_RATE_RAW / 10
"""°/s at zoom 1×: the largest rate the control field carries (it shrinks with zoom)."""
ANGLE_LIMIT = CONTROL_ANGLE_RAW / 100
"""Degrees: the largest control angle."""
YAW_INPUT_RANGE = (-180.0, 360.0)
"""Degrees, half-open: how every absolute yaw or heading may be given (the Euler yaw of
``enter_euler_control``, the aircraft's yaw of ``update_aircraft``, the waits): MAVLink's
±180° headings and compass 0–360° alike; each is sent in the range its wire field takes."""


def _angle(name: str, doc: str, default: object = 0.0) -> Parameter:
    return Parameter(name, Kind.REAL, doc, "deg", -ANGLE_LIMIT, ANGLE_LIMIT, default=default)


def _rate(name: str, doc: str) -> Parameter:
    return Parameter(name, Kind.REAL, f"{doc}; the limit is divided by the current zoom",
                     "deg/s", -RATE_LIMIT, RATE_LIMIT, default=0.0)  # fmt: skip


_EULER = (_angle("roll", "Euler roll", None), _angle("pitch", "Euler pitch", None),
          Parameter("yaw", Kind.REAL, "Euler yaw (north = 0); 180-360 is sent as -180-0",
                    "deg", *YAW_INPUT_RANGE, high_open=True, default=None))  # fmt: skip
_ANGLES = (_angle("roll", "Euler roll"), _angle("pitch", "Euler pitch"),
           _angle("yaw", "relative to the aircraft"))  # fmt: skip
_RELATIVE = tuple(_angle(n, "relative to the aircraft") for n in ("roll", "pitch", "yaw"))
_PITCH_YAW_RATES = (_rate("pitch_rate", "pitch rate"), _rate("yaw_rate", "yaw rate"))


# -- the commands, in the order of the docs' command table -------------------------------------
@_compile
@dataclass(frozen=True, slots=True)
class NullCommand(Command):
    """0x00: separates two commands with the same opcode (docs/protocol-notes.md §4 "The
    same-opcode rule"). The client sends it by itself: no method."""

    OPCODE = Opcode.NULL


@_compile
@dataclass(frozen=True, slots=True)
class EulerControl(Command):
    """0x14: Euler-angle control mode. Control values: roll/pitch/yaw Euler angles."""

    OPCODE = Opcode.EULER_CONTROL
    SCHEMA = CommandSchema(mode=ModeSpec(Mode.EULER_CONTROL, "angles"), methods=(Method(
        "enter_euler_control",
        "Euler-angle control mode holding absolute angles (omitted: the current).", _EULER),))


@_compile
@dataclass(frozen=True, slots=True)
class AngleControl(Command):
    """0x10: angle-control mode. Control values: roll, pitch = Euler angle; yaw = angle
    relative to the aircraft."""

    OPCODE = Opcode.ANGLE_CONTROL
    SCHEMA = CommandSchema(mode=ModeSpec(Mode.ANGLE_CONTROL, "angles"), methods=(Method(
        "enter_angle_control",
        "Angle-control mode: Euler roll/pitch, yaw relative to the aircraft.", _ANGLES),))


@_compile
@dataclass(frozen=True, slots=True)
class Fpv(Command):
    """0x1C: FPV mode. Control values: roll/pitch/yaw angles relative to the aircraft."""

    OPCODE = Opcode.FPV
    SCHEMA = CommandSchema(mode=ModeSpec(Mode.FPV, "angles"), methods=(Method(
        "enter_fpv", "FPV mode: angles relative to the aircraft.", _RELATIVE),))


@_compile
@dataclass(frozen=True, slots=True)
class PointingLock(Command):
    """0x11: pointing-lock mode. Control values: pitch/yaw angular rates."""

    OPCODE = Opcode.POINTING_LOCK
    SCHEMA = CommandSchema(mode=ModeSpec(Mode.POINTING_LOCK, "rates"), methods=(Method(
        "enter_pointing_lock", "Pointing-lock mode with pitch/yaw rates.", _PITCH_YAW_RATES),))


@_compile
@dataclass(frozen=True, slots=True)
class PointingFollow(Command):
    """0x12: pointing-follow mode. Control values: pitch/yaw rates (yaw 0 → follow aircraft)."""

    OPCODE = Opcode.POINTING_FOLLOW
    SCHEMA = CommandSchema(mode=ModeSpec(Mode.POINTING_FOLLOW, "rates"), methods=(Method(
        "enter_pointing_follow", "Pointing-follow mode; yaw rate 0 follows the aircraft's heading.",
        _PITCH_YAW_RATES),))


@_compile
@dataclass(frozen=True, slots=True)
class TopDown(Command):
    """0x13: top-down mode (pitch −90°). Control values: yaw rate."""

    OPCODE = Opcode.TOP_DOWN
    SCHEMA = CommandSchema(mode=ModeSpec(Mode.TOP_DOWN, "rates"), methods=(Method(
        "enter_top_down", "Top-down mode (pitch -90 deg) with a yaw rate.",
        (_rate("yaw_rate", "yaw rate"),)),))


@_compile
@dataclass(frozen=True, slots=True)
class GazeLock(Command):
    """0x16: gaze (geographic target lock) at the image centre; needs valid aircraft INS."""

    OPCODE = Opcode.GAZE_LOCK
    SCHEMA = CommandSchema(mode=ModeSpec(Mode.GAZE, "rates"), needs_ins=True, methods=(Method(
        "enter_gaze_lock", "Geographic lock on the image centre; needs valid aircraft INS data.",
        _PITCH_YAW_RATES),))


@_compile
@dataclass(frozen=True, slots=True)
class GazeAtCoordinates(Command):
    """0x15: gaze at a geographic coordinate (PP lon, QQ lat: S32 1e-7°; RR alt: S32 mm)."""

    OPCODE = Opcode.GAZE_AT_COORDINATES
    SCHEMA = CommandSchema(
        params=(real("longitude", "i", "WGS84, 1e-7 deg steps", -1_800_000_000, 1_800_000_000,
                     1e7, "deg", "1e-7 deg"),
                real("latitude", "i", "WGS84, 1e-7 deg steps", -900_000_000, 900_000_000, 1e7,
                     "deg", "1e-7 deg"),
                real("altitude", "i", "above mean sea level, 1 mm steps", None, None, 1000, "m")),
        mode=ModeSpec(Mode.GAZE, "rates"), needs_ins=True,
        methods=(Method("gaze_at", "Gaze at a coordinate; needs valid aircraft INS data."),))
    latitude: float
    longitude: float
    altitude: float


@_compile
@dataclass(frozen=True, slots=True)
class Calibration(Command):
    """0x01: calibrate the pod (keep it still; answers "in progress" for a few seconds)."""

    OPCODE = Opcode.CALIBRATION
    SCHEMA = CommandSchema(status=StatusRule.CALIBRATION, methods=(Method(
        "calibrate", "Calibrate the pod; waits while the GCU answers \"in progress\".",
        (Parameter("timeout", Kind.REAL, "how long to wait for the result", "s", 0.0, float("inf"),
                   low_open=True, high_open=True, default=15.0),)),))  # fmt: skip


@_compile
@dataclass(frozen=True, slots=True)
class Centre(Command):
    """0x03: centre pitch and heading (lock/follow), heading (top-down). Control values must
    be sent invalid while it runs."""

    OPCODE = Opcode.CENTRE
    SCHEMA = CommandSchema(changes_mode=True, methods=(Method(
        "centre", "Centre pitch and heading; control values are sent invalid meanwhile.", ()),))


@_compile
@dataclass(frozen=True, slots=True)
class Track(Command):
    """0x17: enter (``enter=True``) or exit image tracking of the target in ``box``."""

    OPCODE = Opcode.TRACK
    SCHEMA = CommandSchema(
        params=(CAM1, Switch("enter", "enter or exit tracking",
                             meaning="0x00 = exit, 0x01 = enter"), Box()),
        mode=ModeSpec(Mode.TRACK, "none"), matrix_row=0,
        methods=(Method("track", "Enter image tracking of the target in the box.",
                        ("box", "cameras"), required=("box",)),
                 Method("stop_tracking", "Exit image tracking (same opcode, TT = 0).",
                        ("cameras",))))  # fmt: skip
    enter: bool = True
    box: ImageBox = ImageBox(0.0, 0.0, 0.0, 0.0)
    cameras: CameraMask | int = CameraMask.CAMERA_1


@_compile
@dataclass(frozen=True, slots=True)
class ClickToPan(Command):
    """0x1A: turn the camera so that ``point`` comes to the image centre; the pod then
    switches to pointing-lock. Control values must be invalid while it runs."""

    OPCODE = Opcode.CLICK_TO_PAN
    SCHEMA = CommandSchema(params=(CAM1, Point()), changes_mode=True, methods=(Method(
        "click_to_pan", "Bring an image point to the centre; the pod ends in pointing-lock.",
        ("point", "cameras")),))
    point: ImagePoint
    cameras: CameraMask | int = CameraMask.CAMERA_1


@_compile
@dataclass(frozen=True, slots=True)
class TakePhoto(Command):
    """0x20: take a photo with the masked cameras."""

    OPCODE = Opcode.TAKE_PHOTO
    SCHEMA = CommandSchema(params=(CAM1,), methods=(Method("take_photo", "Take a photo."),))
    cameras: CameraMask | int = CameraMask.CAMERA_1


@_compile
@dataclass(frozen=True, slots=True)
class Record(Command):
    """0x21: start or stop recording (a toggle)."""

    OPCODE = Opcode.RECORD
    SCHEMA = CommandSchema(params=(CAM1,), methods=(
        Method("toggle_recording", "Start or stop recording (a toggle on the wire)."),
        Method("start_recording",
               "Start recording unless the camera records (then None, nothing sent)."),
        Method("stop_recording",
               "Stop recording if the camera records (else None, nothing sent).")))
    cameras: CameraMask | int = CameraMask.CAMERA_1


@_compile
@dataclass(frozen=True, slots=True)
class ZoomIn(Command):
    """0x22: zoom in continuously until :class:`ZoomStop`."""

    OPCODE = Opcode.ZOOM_IN
    SCHEMA = CommandSchema(params=(CAM1,), status=StatusRule.ZOOM,
                           methods=(Method("zoom_in", "Zoom in continuously until stop_zoom."),))
    cameras: CameraMask | int = CameraMask.CAMERA_1


@_compile
@dataclass(frozen=True, slots=True)
class ZoomOut(Command):
    """0x23: zoom out continuously until :class:`ZoomStop`."""

    OPCODE = Opcode.ZOOM_OUT
    SCHEMA = CommandSchema(params=(CAM1,), status=StatusRule.ZOOM,
                           methods=(Method("zoom_out", "Zoom out continuously until stop_zoom."),))
    cameras: CameraMask | int = CameraMask.CAMERA_1


@_compile
@dataclass(frozen=True, slots=True)
class ZoomStop(Command):
    """0x24: stop a continuous zoom."""

    OPCODE = Opcode.ZOOM_STOP
    SCHEMA = CommandSchema(params=(CAM1,), status=StatusRule.ZOOM,
                           methods=(Method("stop_zoom", "Stop a continuous zoom."),))
    cameras: CameraMask | int = CameraMask.CAMERA_1


@_compile
@dataclass(frozen=True, slots=True)
class ZoomTo(Command):
    """0x25: zoom to a ratio (``ratio=10.0`` → wire −100) or to a fraction of the maximum
    ratio (``fraction=0.5`` → wire 5000; 1/10000 → minimum, 1.0 → maximum). Give exactly one.
    """

    OPCODE = Opcode.ZOOM_TO
    SCHEMA = CommandSchema(
        params=(CAM1, ZoomValue()), status=StatusRule.ZOOM, matrix_row=4,
        methods=(Method("zoom_to", "Zoom to a ratio; sent as -(ratio x 10).",
                        ("ratio", "cameras"), required=("ratio",)),
                 Method("zoom_to_fraction",
                        "Zoom to a fraction of the maximum ratio; sent as fraction x 10000.",
                        ("fraction", "cameras"), required=("fraction",))))  # fmt: skip
    ratio: float | None = None
    fraction: float | None = None
    cameras: CameraMask | int = CameraMask.CAMERA_1

    @property
    def raw_value(self) -> int:
        """The S16 ZZ ZZ value: −(ratio × 10), or fraction × 10000."""
        value: int = self.raw_params()[1]
        return value


@_compile
@dataclass(frozen=True, slots=True)
class Focus(Command):
    """0x26: trigger focus."""

    OPCODE = Opcode.FOCUS
    SCHEMA = CommandSchema(params=(CAM1,), matrix_row=5,
                           methods=(Method("focus", "Trigger focus."),))
    cameras: CameraMask | int = CameraMask.CAMERA_1


@_compile
@dataclass(frozen=True, slots=True)
class Palette(Command):
    """0x2A: thermal palette 1–10, or 0 to cycle."""

    OPCODE = Opcode.PALETTE
    SCHEMA = CommandSchema(
        params=(CAM2, integer("palette", "B", "1-10, or 0 to cycle", 0, 10, detail="0 cycles")),
        status=StatusRule.THERMAL, matrix_row=6,
        methods=(Method("set_palette", "Thermal palette."),))
    palette: int = 0
    cameras: CameraMask | int = CameraMask.CAMERA_2


@_compile
@dataclass(frozen=True, slots=True)
class NightVision(Command):
    """0x2B: night vision off / on / auto."""

    OPCODE = Opcode.NIGHT_VISION
    SCHEMA = CommandSchema(
        params=(CAM1, choice("mode", NightVisionMode, "night vision mode", "0 off, 1 on, 2 auto")),
        matrix_row=7, methods=(Method("set_night_vision", "Night vision off, on or auto."),))
    mode: NightVisionMode = NightVisionMode.ON
    cameras: CameraMask | int = CameraMask.CAMERA_1


@_compile
@dataclass(frozen=True, slots=True)
class AreaTemperature(Command):
    """0x30: area temperature measurement on/off over ``box``."""

    OPCODE = Opcode.AREA_TEMPERATURE
    SCHEMA = CommandSchema(
        params=(CAM2, Switch(doc="measurement on/off"), Box()),
        status=StatusRule.THERMAL, matrix_row=8,
        methods=(Method("set_area_temperature",
                        "Area temperature measurement over a box (radiometric thermal)."),))
    enabled: bool = True
    box: ImageBox = ImageBox(0.0, 0.0, 1.0, 1.0)
    cameras: CameraMask | int = CameraMask.CAMERA_2


@dataclass(frozen=True, slots=True)
class _Thresholds(Command):
    """Body of the two threshold commands: on/off, high/low in °C (0.1 °C resolution, S16),
    ``low`` not above ``high``, and the cameras."""

    enabled: bool = True
    high: float = 0.0
    low: float = 0.0
    cameras: CameraMask | int = CameraMask.CAMERA_2


@_compile
@dataclass(frozen=True, slots=True)
class TemperatureAlarm(_Thresholds):
    """0x31: temperature alarm on/off with high/low thresholds in °C (0.1 °C resolution)."""

    OPCODE = Opcode.TEMPERATURE_ALARM
    SCHEMA = CommandSchema(
        params=(CAM2, Switch(doc="alarm on/off"), Thresholds()), status=StatusRule.THERMAL,
        matrix_row=9, methods=(Method(
            "set_temperature_alarm",
            "Temperature alarm with high/low thresholds (radiometric thermal)."),))


@_compile
@dataclass(frozen=True, slots=True)
class Isotherm(_Thresholds):
    """0x32: isotherm off, or on in "inside the interval" mode with high/low thresholds (°C)."""

    OPCODE = Opcode.ISOTHERM
    SCHEMA = CommandSchema(
        params=(CAM2, Switch(doc="isotherm on/off"), Thresholds()), status=StatusRule.THERMAL,
        matrix_row=10, methods=(Method(
            "set_isotherm", "Isotherm between low and high (radiometric thermal)."),))


@_compile
@dataclass(frozen=True, slots=True)
class SpotTemperature(Command):
    """0x33: spot temperature measurement on/off at ``point``."""

    OPCODE = Opcode.SPOT_TEMPERATURE
    SCHEMA = CommandSchema(
        params=(CAM2, Switch(doc="measurement on/off"), Point()), status=StatusRule.THERMAL,
        matrix_row=11, methods=(Method(
            "set_spot_temperature",
            "Spot temperature measurement at an image point (radiometric thermal)."),))
    enabled: bool = True
    point: ImagePoint = ImagePoint(0.5, 0.5)
    cameras: CameraMask | int = CameraMask.CAMERA_2


@_compile
@dataclass(frozen=True, slots=True)
class Osd(Command):
    """0x73: on-screen display on/off."""

    OPCODE = Opcode.OSD
    SCHEMA = CommandSchema(params=(Switch(doc="OSD on/off"),), matrix_row=12,
                           methods=(Method("set_osd", "On-screen display on/off."),))
    enabled: bool = True


@_compile
@dataclass(frozen=True, slots=True)
class OsdCoordinates(Command):
    """0x06: which coordinates the OSD shows (aircraft or target)."""

    OPCODE = Opcode.OSD_COORDINATES
    SCHEMA = CommandSchema(
        params=(choice("coordinates", OsdCoordinateSource, "aircraft or target",
                       "0 = aircraft, 1 = target"),), matrix_row=1,
        methods=(Method("set_osd_coordinates", "Which coordinates the OSD shows."),))
    coordinates: OsdCoordinateSource = OsdCoordinateSource.AIRCRAFT


@_compile
@dataclass(frozen=True, slots=True)
class ImageAutoFlip(Command):
    """0x07: image auto-flip on/off (wire: 0x00 = on, 0x01 = off)."""

    OPCODE = Opcode.IMAGE_AUTO_FLIP
    SCHEMA = CommandSchema(
        params=(Switch(doc="auto-flip on/off", on=0, off=1, meaning="0x00 = on, 0x01 = off"),),
        matrix_row=2, methods=(Method("set_image_auto_flip", "Image auto-flip on/off."),))
    enabled: bool = True


@_compile
@dataclass(frozen=True, slots=True)
class TimeZone(Command):
    """0x08: the pod's time zone as a whole-hour UTC offset (S8; real zones −12 … +14)."""

    OPCODE = Opcode.TIME_ZONE
    SCHEMA = CommandSchema(
        params=(integer("offset_hours", "b", "whole hours", -12, 14, "h"),), matrix_row=3,
        methods=(Method("set_time_zone", "The pod's UTC offset in whole hours.",
                        required=("offset_hours",)),))
    offset_hours: int = 0


@_compile
@dataclass(frozen=True, slots=True)
class PictureInPicture(Command):
    """0x74: picture-in-picture mode 1–4, or 0 to cycle."""

    OPCODE = Opcode.PICTURE_IN_PICTURE
    SCHEMA = CommandSchema(
        params=(integer("mode", "B", "1-4, or 0 to cycle", 0, 4, detail="0 cycles"),),
        matrix_row=13, methods=(Method("set_picture_in_picture", "Picture-in-picture mode."),))
    mode: int = 0


@_compile
@dataclass(frozen=True, slots=True)
class TargetDetection(Command):
    """0x75: AI target detection on/off."""

    OPCODE = Opcode.TARGET_DETECTION
    SCHEMA = CommandSchema(params=(Switch(doc="detection on/off"),), matrix_row=14,
                           methods=(Method("set_target_detection", "AI target detection on/off."),))
    enabled: bool = True


@_compile
@dataclass(frozen=True, slots=True)
class DigitalZoom(Command):
    """0x76: digital zoom of the zoom camera on/off."""

    OPCODE = Opcode.DIGITAL_ZOOM
    SCHEMA = CommandSchema(params=(Switch(doc="digital zoom on/off"),), matrix_row=15,
                           methods=(Method("set_digital_zoom", "Digital zoom on/off."),))
    enabled: bool = True


@_compile
@dataclass(frozen=True, slots=True)
class FillLight(Command):
    """0x80: fill light brightness 0–255 (0 = off). Turning it on also turns night vision on."""

    OPCODE = Opcode.FILL_LIGHT
    SCHEMA = CommandSchema(
        params=(integer("brightness", "B", "0 = off"),), matrix_row=16,
        methods=(Method("set_fill_light",
                        "Fill light brightness; turning it on also turns night vision on.",
                        required=("brightness",)),))
    brightness: int = 255


@_compile
@dataclass(frozen=True, slots=True)
class Ranging(Command):
    """0x81: continuous laser ranging on/off (wire: 0x02 = on, 0x00 = off)."""

    OPCODE = Opcode.RANGING
    SCHEMA = CommandSchema(params=(Switch(doc="ranging on/off", on=2),), matrix_row=17,
                           methods=(Method("set_ranging", "Continuous laser ranging on/off."),))
    enabled: bool = True


# -- what is not a V2.0.6 command ----------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class UnknownCommand(Command):
    """An opcode V2.0.6 does not define, kept byte for byte."""

    OPCODE = Opcode.NULL  # placeholder; the real opcode is ``code``
    code: int = 0
    params: bytes = field(default=b"")

    def __post_init__(self) -> None:
        check_int("opcode", self.code, 0, 255)
        if self.code in COMMAND_TYPES:
            name = COMMAND_TYPES[self.code].__name__
            raise ValueError(f"opcode: 0x{self.code:02X} is a known command; use {name}")
        if not isinstance(self.params, (bytes, bytearray)):
            raise type_error("params", "bytes", self.params)
        if len(self.params) > MAX_PARAMS:
            raise FieldRangeError("params", len(self.params), 0, MAX_PARAMS, "bytes",
                                  detail="its length: the packet length S is a U16")  # fmt: skip
        _store(self, "params", bytes(self.params))  # an immutable copy

    @property
    def opcode(self) -> Opcode:  # pragma: no cover - unknown opcodes have no Opcode member
        raise AttributeError("UnknownCommand has no Opcode member; use .code")

    def encode_params(self) -> bytes:
        return bytes(self.params)

    def as_dict(self) -> dict[str, Any]:
        return {"command": f"UNKNOWN_0x{self.code:02X}", "opcode": self.code,
                "params_hex": bytes(self.params).hex(" ")}  # fmt: skip


@dataclass(frozen=True, slots=True)
class AnomalousCommand(Command):
    """A known opcode whose parameter bytes V2.0.6 does not allow (a value outside its
    range, or the wrong number of bytes), as decoded from a CRC-valid packet: the bytes are
    kept (``params``), every offending field is listed (``anomalies``, raw values and raw
    ranges). Receive is liberal, send is strict (docs/client.md, "Liberal receive, strict
    send"): it is never re-encoded — :meth:`encode_params`, and so ``HostPacket.encode`` and
    the client, raise the :class:`FieldRangeError` of its first anomaly."""

    OPCODE = Opcode.NULL  # placeholder; the real opcode is ``code``
    code: int = 0
    params: bytes = b""
    anomalies: tuple[Anomaly, ...] = ()

    def __post_init__(self) -> None:
        if check_int("opcode", self.code, 0, 255) not in COMMAND_TYPES:
            raise ValueError(f"opcode: 0x{self.code:02X} is not a V2.0.6 command; use "
                             "UnknownCommand")  # fmt: skip
        if not isinstance(self.params, (bytes, bytearray)):
            raise type_error("params", "bytes", self.params)
        _store(self, "params", bytes(self.params))
        anomalies = tuple(self.anomalies)
        if not anomalies or not all(isinstance(a, Anomaly) for a in anomalies):
            raise ValueError("anomalies: give at least one, each an Anomaly")
        _store(self, "anomalies", anomalies)

    @property
    def opcode(self) -> Opcode:
        return Opcode(self.code)

    @property
    def command_type(self) -> type[Command]:
        """The command class its opcode names."""
        return COMMAND_TYPES[self.code]

    @property
    def raw(self) -> tuple[int, ...] | None:
        """The parameters unpacked with the command's layout (``None`` for a wrong length)."""
        layout = self.command_type.LAYOUT
        return layout.unpack(self.params) if len(self.params) == layout.size else None

    def error(self) -> FieldRangeError:
        """The error sending it raises: that of its first anomaly."""
        return self.anomalies[0].error()

    def raw_params(self) -> tuple[int, ...]:
        raise self.error()

    def encode_params(self) -> bytes:
        raise self.error()

    def as_dict(self) -> dict[str, Any]:
        """Name, opcode, raw parameters (``None`` for a wrong length) and their bytes; the
        anomalies are listed by the packet's ``as_dict``."""
        raw = self.raw
        return {"command": opcode_name(self.code), "opcode": self.code,
                "params_raw": None if raw is None else list(raw),
                "params_hex": self.params.hex(" ")}  # fmt: skip


COMMAND_TYPES: dict[int, type[Command]] = {int(cls.OPCODE): cls for cls in _DEFINED}
"""Opcode → command class, one entry per command of V2.0.6."""
if sorted(COMMAND_TYPES) != sorted(_OPCODE_VALUES) or len(COMMAND_TYPES) != len(_DEFINED):
    raise TypeError("every Opcode member needs exactly one command class (and no more)")

MODE_COMMANDS: frozenset[Opcode] = frozenset(
    c.OPCODE for c in COMMAND_TYPES.values() if c.SCHEMA.mode is not None
)
"""Commands that switch the pod's working mode."""


def command_code(command: Command) -> int:
    """The opcode byte of ``command`` (works for :class:`UnknownCommand` and
    :class:`AnomalousCommand` too)."""
    if isinstance(command, (UnknownCommand, AnomalousCommand)):
        return command.code
    if not isinstance(command, Command):
        raise type_error("command", "a Command", command)
    return int(command.OPCODE)


def decode_command(opcode: int, params: bytes) -> Command:
    """Typed command for ``opcode`` + parameter bytes; unknown opcodes give
    :class:`UnknownCommand`, parameters V2.0.6 does not allow an :class:`AnomalousCommand`.
    Never raises for bytes: receive is liberal (docs/client.md, "Liberal receive, strict
    send")."""
    cls = COMMAND_TYPES.get(opcode)
    if cls is None:
        return UnknownCommand(code=opcode, params=bytes(params))
    return cls.decode_params(params)


# -- the dissector's view (re-exported by gcu_async.protocol.schema_tables) ----------------------
class WireParam(NamedTuple):
    """One parameter field on the wire, for table-driven decoders (the Lua dissector)."""

    name: str
    """``"cameras"``, ``"box.left"``, ``"point.x"``."""
    fmt: str
    """One struct code: B b H h I i (little-endian)."""
    scale: float
    """Engineering value = raw / scale (1 for plain integers)."""
    unit: str
    """Engineering unit, ``""`` if none."""
    low: int | None
    """Raw range, inclusive; ``None`` = the wire type's own range."""
    high: int | None
    enum: str | None
    """Name of the IntEnum of a choice field, or of the IntFlag whose bits a mask field names
    (in :mod:`gcu_async.protocol`), else ``None``."""


class WireRow(NamedTuple):
    """One command's parameter bytes, field by field in wire order."""

    opcode: int
    command: str
    """The :class:`Opcode` member name, e.g. ``"ZOOM_TO"``."""
    params: tuple[WireParam, ...]


def wire_rows() -> tuple[WireRow, ...]:
    """Every opcode (the null command included), ascending, with its parameter fields."""
    rows = []
    for opcode in sorted(COMMAND_TYPES):
        params = []
        for kind in COMMAND_TYPES[opcode].SCHEMA.params:
            enum_name = getattr(getattr(kind, "enum", None), "__name__", None)
            for w in kind.wire:
                own = WIRE_RANGES[w.fmt]
                low = None if w.raw_low == own[0] else w.raw_low
                high = None if w.raw_high == own[1] else w.raw_high
                params.append(WireParam(w.name, w.fmt, float(w.scale), w.unit, low, high,
                                        enum_name))  # fmt: skip
        rows.append(WireRow(opcode, Opcode(opcode).name, tuple(params)))
    return tuple(rows)

