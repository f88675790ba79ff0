"""Every command of V2.0.6 (byte 69 + parameters, bytes 70..S-3) as a typed value.

Each command is a frozen dataclass in engineering units, validated when it is built (so a
bad argument raises before anything is sent) under the package rule
(:mod:`gcu_async.protocol`): ``bool`` fields take only ``True``/``False``, integer fields
only ``int`` (camera masks 1–255, ``CameraMask`` members welcome), real fields finite
``int``/``float`` inside the wire range, enum fields a member or its exact value,
``box``/``point`` an :class:`ImageBox` / :class:`ImagePoint` (or a plain tuple, stored as
the NamedTuple) checked element by element. ``encode_params()`` gives the parameter bytes;
:func:`decode_command` turns opcode + parameter bytes back into the typed command — or, when
they hold a value outside its range or have the wrong length, into an
:class:`AnomalousCommand` that keeps the bytes and lists the :class:`Anomaly` of each field
(receive is liberal, send is strict: docs/client.md, "Liberal receive, strict send").
The first parameter byte of many commands is a camera mask (docs/protocol-notes.md §3 "Camera
masks"): it is the ``cameras`` field, defaulting to the value the document shows.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field, fields
from typing import Any, ClassVar, NamedTuple, TypeVar

from gcu_async._checks import check_bool, check_int, type_error
from gcu_async.errors import FieldRangeError
from gcu_async.protocol.anomalies import Anomaly, check_raw
from gcu_async.protocol.enums import (
    CameraMask,
    NightVisionMode,
    Opcode,
    OsdCoordinateSource,
    opcode_name,
)
from gcu_async.protocol.layout import S16, S32
from gcu_async.protocol.units import check_member, check_tuple, quantize

_C = TypeVar("_C", bound="Command")
_T = TypeVar("_T", bound="_Thresholds")

IMAGE_SCALE = 10000  # image coordinates: U16 [0, 10000], origin top-left
MAX_PARAMS = 0xFFFF - 72
"""Most parameter bytes a packet can carry (S, a U16, counts 72 bytes besides them)."""


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


def _img(field_name: str, value: float) -> int:
    return quantize(field_name, value, IMAGE_SCALE, 0, IMAGE_SCALE, "image fraction")


def _box_raw(name: str, box: ImageBox) -> tuple[int, int, int, int]:
    x0, y0 = _img(f"{name}.left", box.left), _img(f"{name}.top", box.top)
    x1, y1 = _img(f"{name}.right", box.right), _img(f"{name}.bottom", box.bottom)
    if x1 < x0:
        raise FieldRangeError(f"{name}.right", box.right, box.left, 1.0, "image fraction",
                              detail="right edge must not be left of the left edge")  # fmt: skip
    if y1 < y0:
        raise FieldRangeError(f"{name}.bottom", box.bottom, box.top, 1.0, "image fraction",
                              detail="bottom edge must not be above the top edge")  # fmt: skip
    return x0, y0, x1, y1


def _box(x0: int, y0: int, x1: int, y1: int) -> ImageBox:
    s = IMAGE_SCALE
    return ImageBox(x0 / s, y0 / s, x1 / s, y1 / s)


def _mask(name: str, cameras: object) -> int:
    return check_int(name, cameras, 1, 0xFF, "camera mask")


def _store(command: Command, name: str, value: object) -> None:
    """Store a checked, normalised field value on a frozen command."""
    object.__setattr__(command, name, value)


def _switch(name: str, value: int, on: int = 1) -> bool:
    if value not in (0, on):
        raise ValueError(f"{name}: parameter byte 0x{value:02X} is neither 0x00 nor 0x{on:02X}")
    return value == on


# --- raw checks of decoded parameters (the receive side: each gives the anomalies) -----------
IMAGE_UNIT = "1/10000 of the image"
TEMPERATURE_UNIT = "0.1 degC"


def _mask_raw(value: int) -> tuple[Anomaly, ...]:
    return check_raw("cameras", value, 1, 0xFF, "camera mask", "0x00 selects no camera")


def _switch_raw(name: str, value: int, on: int = 1, meaning: str = "") -> tuple[Anomaly, ...]:
    if value in (0, on):
        return ()
    meaning = meaning or f"0x00 = off, 0x{on:02X} = on"
    return (Anomaly(name, value, 0, on, "", f"only {meaning}"),)


def _point_raw(name: str, x: int, y: int) -> tuple[Anomaly, ...]:
    return (check_raw(f"{name}.x", x, 0, IMAGE_SCALE, IMAGE_UNIT)
            + check_raw(f"{name}.y", y, 0, IMAGE_SCALE, IMAGE_UNIT))  # fmt: skip


def _box_raw_anomalies(name: str, x0: int, y0: int, x1: int, y1: int) -> tuple[Anomaly, ...]:
    found: tuple[Anomaly, ...] = ()
    for edge, value in (("left", x0), ("top", y0), ("right", x1), ("bottom", y1)):
        found += check_raw(f"{name}.{edge}", value, 0, IMAGE_SCALE, IMAGE_UNIT)
    if x1 < x0:
        found += (Anomaly(f"{name}.right", x1, x0, IMAGE_SCALE, IMAGE_UNIT,
                          "right edge must not be left of the left edge"),)  # fmt: skip
    if y1 < y0:
        found += (Anomaly(f"{name}.bottom", y1, y0, IMAGE_SCALE, IMAGE_UNIT,
                          "bottom edge must not be above the top edge"),)  # fmt: skip
    return found


@dataclass(frozen=True, slots=True)
class Command:
    """Base of all commands. ``OPCODE`` is the protocol opcode; ``LAYOUT`` the parameter
    layout (little-endian)."""

    OPCODE: ClassVar[Opcode]
    LAYOUT: ClassVar[struct.Struct] = struct.Struct("<")

    def __post_init__(self) -> None:
        if not hasattr(self, "OPCODE"):
            raise TypeError(f"{type(self).__name__} is abstract: build one of its subclasses")
        self._normalize()
        self.raw_params()  # validates every field, raising before anything is sent

    def _normalize(self) -> None:
        """Check tuple and enum fields and store them as their classes (none here)."""

    @property
    def opcode(self) -> Opcode:
        return self.OPCODE

    def raw_params(self) -> tuple[int, ...]:
        """The parameter values as the raw integers that go on the wire."""
        return ()

    @classmethod
    def from_raw_params(cls: type[_C], raw: tuple[int, ...]) -> _C:
        return cls()

    def encode_params(self) -> bytes:
        """Parameter bytes (70..S-3 of the host packet)."""
        return self.LAYOUT.pack(*self.raw_params())

    @classmethod
    def raw_anomalies(cls, raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
        """Every value of the raw parameters (as unpacked by ``LAYOUT``) outside its range:
        empty exactly when :meth:`from_raw_params` accepts them."""
        return ()

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
        params: dict[str, Any] = {}
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, tuple) and hasattr(v, "_asdict"):
                v = v._asdict()
            elif isinstance(v, CameraMask):
                v = int(v)
            elif isinstance(v, (NightVisionMode, OsdCoordinateSource)):
                v = v.name
            params[f.name] = v
        return {
            "command": self.OPCODE.name,
            "opcode": int(self.OPCODE),
            "params": params,
            "params_raw": list(self.raw_params()),
            "params_hex": self.encode_params().hex(" "),
        }


# --- no-parameter commands ------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class NullCommand(Command):
    """0x00: separates two commands with the same opcode (docs/protocol-notes.md §4 "The
    same-opcode rule")."""

    OPCODE = Opcode.NULL


@dataclass(frozen=True, slots=True)
class Calibration(Command):
    """0x01: calibrate the pod (keep it still; answers "in progress" for a few seconds)."""

    OPCODE = Opcode.CALIBRATION


@dataclass(frozen=True, slots=True)
class Centre(Command):
    """0x03: centre pitch and heading (lock/follow), heading (top-down). Control values must
    be sent invalid while it runs."""

    OPCODE = Opcode.CENTRE


@dataclass(frozen=True, slots=True)
class AngleControl(Command):
    """0x10: angle-control mode. Control values: roll, pitch = Euler angle; yaw = angle
    relative to the aircraft."""

    OPCODE = Opcode.ANGLE_CONTROL


@dataclass(frozen=True, slots=True)
class PointingLock(Command):
    """0x11: pointing-lock mode. Control values: pitch/yaw angular rates."""

    OPCODE = Opcode.POINTING_LOCK


@dataclass(frozen=True, slots=True)
class PointingFollow(Command):
    """0x12: pointing-follow mode. Control values: pitch/yaw rates (yaw 0 → follow aircraft)."""

    OPCODE = Opcode.POINTING_FOLLOW


@dataclass(frozen=True, slots=True)
class TopDown(Command):
    """0x13: top-down mode (pitch −90°). Control values: yaw rate."""

    OPCODE = Opcode.TOP_DOWN


@dataclass(frozen=True, slots=True)
class EulerControl(Command):
    """0x14: Euler-angle control mode. Control values: roll/pitch/yaw Euler angles."""

    OPCODE = Opcode.EULER_CONTROL


@dataclass(frozen=True, slots=True)
class GazeLock(Command):
    """0x16: gaze (geographic target lock) at the image centre; needs valid aircraft INS."""

    OPCODE = Opcode.GAZE_LOCK


@dataclass(frozen=True, slots=True)
class Fpv(Command):
    """0x1C: FPV mode. Control values: roll/pitch/yaw angles relative to the aircraft."""

    OPCODE = Opcode.FPV


# --- pod commands with parameters -----------------------------------------------------
@dataclass(frozen=True, slots=True)
class GazeAtCoordinates(Command):
    """0x15: gaze at a geographic coordinate (PP lon, QQ lat: S32 1e-7°; RR alt: S32 mm)."""

    OPCODE = Opcode.GAZE_AT_COORDINATES
    LAYOUT = struct.Struct("<iii")
    latitude: float
    longitude: float
    altitude: float

    def raw_params(self) -> tuple[int, ...]:
        return (
            quantize("longitude", self.longitude, 1e7, -1_800_000_000, 1_800_000_000, "deg"),
            quantize("latitude", self.latitude, 1e7, -900_000_000, 900_000_000, "deg"),
            quantize("altitude", self.altitude, 1000, *S32, "m"),
        )

    @classmethod
    def from_raw_params(cls, raw: tuple[int, ...]) -> GazeAtCoordinates:
        lon, lat, alt = raw
        return cls(latitude=lat / 1e7, longitude=lon / 1e7, altitude=alt / 1000)

    @classmethod
    def raw_anomalies(cls, raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
        lon, lat, _ = raw
        return (check_raw("longitude", lon, -1_800_000_000, 1_800_000_000, "1e-7 deg")
                + check_raw("latitude", lat, -900_000_000, 900_000_000, "1e-7 deg"))  # fmt: skip


@dataclass(frozen=True, slots=True)
class Track(Command):
    """0x17: enter (``enter=True``) or exit image tracking of the target in ``box``."""

    OPCODE = Opcode.TRACK
    LAYOUT = struct.Struct("<BBHHHH")
    enter: bool = True
    box: ImageBox = ImageBox(0.0, 0.0, 0.0, 0.0)
    cameras: CameraMask | int = CameraMask.CAMERA_1

    def _normalize(self) -> None:
        _store(self, "box", check_tuple("box", self.box, ImageBox))

    def raw_params(self) -> tuple[int, ...]:
        return (_mask("cameras", self.cameras), int(check_bool("enter", self.enter)),
                *_box_raw("box", self.box))  # fmt: skip

    @classmethod
    def from_raw_params(cls, raw: tuple[int, ...]) -> Track:
        kk, tt, *box = raw
        return cls(_switch("enter", tt), _box(*box), CameraMask(kk))

    @classmethod
    def raw_anomalies(cls, raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
        kk, tt, x0, y0, x1, y1 = raw
        return (_mask_raw(kk) + _switch_raw("enter", tt, meaning="0x00 = exit, 0x01 = enter")
                + _box_raw_anomalies("box", x0, y0, x1, y1))  # fmt: skip


@dataclass(frozen=True, slots=True)
class ClickToPan(Command):
    """0x1A: turn the camera so that ``point`` comes to the image centre; the pod then
    switches to pointing-lock. Control values must be invalid while it runs."""

    OPCODE = Opcode.CLICK_TO_PAN
    LAYOUT = struct.Struct("<BHH")
    point: ImagePoint
    cameras: CameraMask | int = CameraMask.CAMERA_1

    def _normalize(self) -> None:
        _store(self, "point", check_tuple("point", self.point, ImagePoint))

    def raw_params(self) -> tuple[int, ...]:
        return (
            _mask("cameras", self.cameras),
            _img("point.x", self.point.x),
            _img("point.y", self.point.y),
        )

    @classmethod
    def from_raw_params(cls, raw: tuple[int, ...]) -> ClickToPan:
        kk, x, y = raw
        return cls(ImagePoint(x / IMAGE_SCALE, y / IMAGE_SCALE), CameraMask(kk))

    @classmethod
    def raw_anomalies(cls, raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
        kk, x, y = raw
        return _mask_raw(kk) + _point_raw("point", x, y)


# --- camera commands ------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class OsdCoordinates(Command):
    """0x06: which coordinates the OSD shows (aircraft or target)."""

    OPCODE = Opcode.OSD_COORDINATES
    LAYOUT = struct.Struct("<B")
    coordinates: OsdCoordinateSource = OsdCoordinateSource.AIRCRAFT

    def _normalize(self) -> None:
        value = check_member("coordinates", self.coordinates, OsdCoordinateSource)
        _store(self, "coordinates", value)

    def raw_params(self) -> tuple[int, ...]:
        return (int(self.coordinates),)

    @classmethod
    def from_raw_params(cls, raw: tuple[int, ...]) -> OsdCoordinates:
        return cls(OsdCoordinateSource(check_int("coordinates", raw[0], 0, 1)))

    @classmethod
    def raw_anomalies(cls, raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
        return check_raw("coordinates", raw[0], 0, 1, "", "0 = aircraft, 1 = target")


@dataclass(frozen=True, slots=True)
class ImageAutoFlip(Command):
    """0x07: image auto-flip on/off (wire: 0x00 = on, 0x01 = off)."""

    OPCODE = Opcode.IMAGE_AUTO_FLIP
    LAYOUT = struct.Struct("<B")
    enabled: bool = True

    def raw_params(self) -> tuple[int, ...]:
        return (0 if check_bool("enabled", self.enabled) else 1,)

    @classmethod
    def from_raw_params(cls, raw: tuple[int, ...]) -> ImageAutoFlip:
        return cls(not _switch("auto flip off", raw[0]))

    @classmethod
    def raw_anomalies(cls, raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
        return _switch_raw("enabled", raw[0], meaning="0x00 = on, 0x01 = off")


@dataclass(frozen=True, slots=True)
class TimeZone(Command):
    """0x08: the pod's time zone as a whole-hour UTC offset (S8; real zones −12 … +14)."""

    OPCODE = Opcode.TIME_ZONE
    LAYOUT = struct.Struct("<b")
    offset_hours: int = 0

    def raw_params(self) -> tuple[int, ...]:
        return (check_int("offset_hours", self.offset_hours, -12, 14, "h"),)

    @classmethod
    def from_raw_params(cls, raw: tuple[int, ...]) -> TimeZone:
        return cls(raw[0])

    @classmethod
    def raw_anomalies(cls, raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
        return check_raw("offset_hours", raw[0], -12, 14, "h")


@dataclass(frozen=True, slots=True)
class _MaskOnly(Command):
    LAYOUT = struct.Struct("<B")
    cameras: CameraMask | int = CameraMask.CAMERA_1

    def raw_params(self) -> tuple[int, ...]:
        return (_mask("cameras", self.cameras),)

    @classmethod
    def from_raw_params(cls: type[_C], raw: tuple[int, ...]) -> _C:
        return cls(CameraMask(raw[0]))  # type: ignore[call-arg]

    @classmethod
    def raw_anomalies(cls, raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
        return _mask_raw(raw[0])


@dataclass(frozen=True, slots=True)
class TakePhoto(_MaskOnly):
    """0x20: take a photo with the masked cameras."""

    OPCODE = Opcode.TAKE_PHOTO


@dataclass(frozen=True, slots=True)
class Record(_MaskOnly):
    """0x21: start or stop recording (a toggle)."""

    OPCODE = Opcode.RECORD


@dataclass(frozen=True, slots=True)
class ZoomIn(_MaskOnly):
    """0x22: zoom in continuously until :class:`ZoomStop`."""

    OPCODE = Opcode.ZOOM_IN


@dataclass(frozen=True, slots=True)
class ZoomOut(_MaskOnly):
    """0x23: zoom out continuously until :class:`ZoomStop`."""

    OPCODE = Opcode.ZOOM_OUT


@dataclass(frozen=True, slots=True)
class ZoomStop(_MaskOnly):
    """0x24: stop a continuous zoom."""

    OPCODE = Opcode.ZOOM_STOP


@dataclass(frozen=True, slots=True)
class Focus(_MaskOnly):
    """0x26: trigger focus."""

    OPCODE = Opcode.FOCUS


ZOOM_RATIO_MAX = 3276.8
ZOOM_FRACTION_RAW_MAX = 10000


@dataclass(frozen=True, slots=True)
class ZoomTo(Command):
    """0x25: zoom to a ratio (``ratio=10.0`` → wire −100) or to a fraction of the maximum
    ratio (``fraction=0.5`` → wire 5000; 1/10000 → minimum, 1.0 → maximum). Give exactly one.
    """

    OPCODE = Opcode.ZOOM_TO
    LAYOUT = struct.Struct("<Bh")
    ratio: float | None = None
    fraction: float | None = None
    cameras: CameraMask | int = CameraMask.CAMERA_1

    def raw_params(self) -> tuple[int, ...]:
        return (_mask("cameras", self.cameras), self.raw_value)

    @property
    def raw_value(self) -> int:
        """The S16 ZZ ZZ value: −(ratio × 10), or fraction × 10000."""
        if (self.ratio is None) == (self.fraction is None):
            raise ValueError("ZoomTo: give exactly one of ratio= or fraction=")
        if self.ratio is not None:
            return -quantize("ratio", self.ratio, 10, 10, 32768, "x")
        assert self.fraction is not None
        return quantize("fraction", self.fraction, ZOOM_FRACTION_RAW_MAX, 1, ZOOM_FRACTION_RAW_MAX,
                        "of maximum ratio")  # fmt: skip

    @classmethod
    def from_raw_params(cls, raw: tuple[int, ...]) -> ZoomTo:
        kk, zz = raw
        if zz <= -10:
            return cls(ratio=-zz / 10, cameras=CameraMask(kk))
        if 1 <= zz <= ZOOM_FRACTION_RAW_MAX:
            return cls(fraction=zz / ZOOM_FRACTION_RAW_MAX, cameras=CameraMask(kk))
        raise ValueError(f"ZOOM_TO: value {zz} is in neither [-32768, -10] nor [1, 10000]")

    @classmethod
    def raw_anomalies(cls, raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
        kk, zz = raw
        found = _mask_raw(kk)
        if not (zz <= -10 or 1 <= zz <= ZOOM_FRACTION_RAW_MAX):
            detail = "a ratio -32768 to -10 (-0.1x) or a fraction 1 to 10000"
            found += (Anomaly("raw_value", zz, -32768, ZOOM_FRACTION_RAW_MAX, "", detail),)
        return found


@dataclass(frozen=True, slots=True)
class Palette(Command):
    """0x2A: thermal palette 1–10, or 0 to cycle."""

    OPCODE = Opcode.PALETTE
    LAYOUT = struct.Struct("<BB")
    palette: int = 0
    cameras: CameraMask | int = CameraMask.CAMERA_2

    def raw_params(self) -> tuple[int, ...]:
        return (_mask("cameras", self.cameras), check_int("palette", self.palette, 0, 10))

    @classmethod
    def from_raw_params(cls, raw: tuple[int, ...]) -> Palette:
        return cls(raw[1], CameraMask(raw[0]))

    @classmethod
    def raw_anomalies(cls, raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
        return _mask_raw(raw[0]) + check_raw("palette", raw[1], 0, 10, "", "0 cycles")


@dataclass(frozen=True, slots=True)
class NightVision(Command):
    """0x2B: night vision off / on / auto."""

    OPCODE = Opcode.NIGHT_VISION
    LAYOUT = struct.Struct("<BB")
    mode: NightVisionMode = NightVisionMode.ON
    cameras: CameraMask | int = CameraMask.CAMERA_1

    def _normalize(self) -> None:
        _store(self, "mode", check_member("mode", self.mode, NightVisionMode))

    def raw_params(self) -> tuple[int, ...]:
        return (_mask("cameras", self.cameras), int(self.mode))

    @classmethod
    def from_raw_params(cls, raw: tuple[int, ...]) -> NightVision:
        return cls(NightVisionMode(check_int("mode", raw[1], 0, 2)), CameraMask(raw[0]))

    @classmethod
    def raw_anomalies(cls, raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
        return _mask_raw(raw[0]) + check_raw("mode", raw[1], 0, 2, "", "0 off, 1 on, 2 auto")


@dataclass(frozen=True, slots=True)
class AreaTemperature(Command):
    """0x30: area temperature measurement on/off over ``box``."""

    OPCODE = Opcode.AREA_TEMPERATURE
    LAYOUT = struct.Struct("<BBHHHH")
    enabled: bool = True
    box: ImageBox = ImageBox(0.0, 0.0, 1.0, 1.0)
    cameras: CameraMask | int = CameraMask.CAMERA_2

    def _normalize(self) -> None:
        _store(self, "box", check_tuple("box", self.box, ImageBox))

    def raw_params(self) -> tuple[int, ...]:
        return (_mask("cameras", self.cameras), int(check_bool("enabled", self.enabled)),
                *_box_raw("box", self.box))  # fmt: skip

    @classmethod
    def from_raw_params(cls, raw: tuple[int, ...]) -> AreaTemperature:
        kk, tt, *box = raw
        return cls(_switch("enabled", tt), _box(*box), CameraMask(kk))

    @classmethod
    def raw_anomalies(cls, raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
        kk, tt, x0, y0, x1, y1 = raw
        return _mask_raw(kk) + _switch_raw("enabled", tt) + _box_raw_anomalies("box", x0, y0,
                                                                               x1, y1)  # fmt: skip


TEMPERATURE_RAW = S16  # 0.1 °C


def _temps_raw(raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
    kk, tt, hh, ll = raw
    found = _mask_raw(kk) + _switch_raw("enabled", tt)
    if ll > hh:
        found += (Anomaly("low", ll, TEMPERATURE_RAW[0], hh, TEMPERATURE_UNIT,
                          "low must not exceed high"),)  # fmt: skip
    return found


def _temps(high: float, low: float) -> tuple[int, int]:
    hh = quantize("high", high, 10, *TEMPERATURE_RAW, "degC")
    ll = quantize("low", low, 10, *TEMPERATURE_RAW, "degC")
    if ll > hh:
        raise FieldRangeError("low", low, TEMPERATURE_RAW[0] / 10, high, "degC",
                              detail="low must not exceed high")  # fmt: skip
    return hh, ll


@dataclass(frozen=True, slots=True)
class _Thresholds(Command):
    """Body of the two threshold commands: on/off, high/low in °C (0.1 °C resolution, S16),
    ``low`` not above ``high``, and the cameras."""

    LAYOUT = struct.Struct("<BBhh")
    enabled: bool = True
    high: float = 0.0
    low: float = 0.0
    cameras: CameraMask | int = CameraMask.CAMERA_2

    def raw_params(self) -> tuple[int, ...]:
        return (_mask("cameras", self.cameras), int(check_bool("enabled", self.enabled)),
                *_temps(self.high, self.low))  # fmt: skip

    @classmethod
    def from_raw_params(cls: type[_T], raw: tuple[int, ...]) -> _T:
        kk, tt, hh, ll = raw
        return cls(_switch("enabled", tt), hh / 10, ll / 10, CameraMask(kk))

    @classmethod
    def raw_anomalies(cls, raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
        return _temps_raw(raw)


@dataclass(frozen=True, slots=True)
class TemperatureAlarm(_Thresholds):
    """0x31: temperature alarm on/off with high/low thresholds in °C (0.1 °C resolution)."""

    OPCODE = Opcode.TEMPERATURE_ALARM


@dataclass(frozen=True, slots=True)
class Isotherm(_Thresholds):
    """0x32: isotherm off, or on in "inside the interval" mode with high/low thresholds (°C)."""

    OPCODE = Opcode.ISOTHERM


@dataclass(frozen=True, slots=True)
class SpotTemperature(Command):
    """0x33: spot temperature measurement on/off at ``point``."""

    OPCODE = Opcode.SPOT_TEMPERATURE
    LAYOUT = struct.Struct("<BBHH")
    enabled: bool = True
    point: ImagePoint = ImagePoint(0.5, 0.5)
    cameras: CameraMask | int = CameraMask.CAMERA_2

    def _normalize(self) -> None:
        _store(self, "point", check_tuple("point", self.point, ImagePoint))

    def raw_params(self) -> tuple[int, ...]:
        return (
            _mask("cameras", self.cameras),
            int(check_bool("enabled", self.enabled)),
            _img("point.x", self.point.x),
            _img("point.y", self.point.y),
        )

    @classmethod
    def from_raw_params(cls, raw: tuple[int, ...]) -> SpotTemperature:
        kk, tt, x, y = raw
        point = ImagePoint(x / IMAGE_SCALE, y / IMAGE_SCALE)
        return cls(_switch("enabled", tt), point, CameraMask(kk))

    @classmethod
    def raw_anomalies(cls, raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
        kk, tt, x, y = raw
        return _mask_raw(kk) + _switch_raw("enabled", tt) + _point_raw("point", x, y)


@dataclass(frozen=True, slots=True)
class _Switch(Command):
    LAYOUT = struct.Struct("<B")
    enabled: bool = True

    def raw_params(self) -> tuple[int, ...]:
        return (int(check_bool("enabled", self.enabled)),)

    @classmethod
    def from_raw_params(cls: type[_C], raw: tuple[int, ...]) -> _C:
        return cls(_switch("enabled", raw[0]))  # type: ignore[call-arg]

    @classmethod
    def raw_anomalies(cls, raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
        return _switch_raw("enabled", raw[0])


@dataclass(frozen=True, slots=True)
class Osd(_Switch):
    """0x73: on-screen display on/off."""

    OPCODE = Opcode.OSD


@dataclass(frozen=True, slots=True)
class TargetDetection(_Switch):
    """0x75: AI target detection on/off."""

    OPCODE = Opcode.TARGET_DETECTION


@dataclass(frozen=True, slots=True)
class DigitalZoom(_Switch):
    """0x76: digital zoom of the zoom camera on/off."""

    OPCODE = Opcode.DIGITAL_ZOOM


@dataclass(frozen=True, slots=True)
class PictureInPicture(Command):
    """0x74: picture-in-picture mode 1–4, or 0 to cycle."""

    OPCODE = Opcode.PICTURE_IN_PICTURE
    LAYOUT = struct.Struct("<B")
    mode: int = 0

    def raw_params(self) -> tuple[int, ...]:
        return (check_int("mode", self.mode, 0, 4),)

    @classmethod
    def from_raw_params(cls, raw: tuple[int, ...]) -> PictureInPicture:
        return cls(raw[0])

    @classmethod
    def raw_anomalies(cls, raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
        return check_raw("mode", raw[0], 0, 4, "", "0 cycles")


@dataclass(frozen=True, slots=True)
class FillLight(Command):
    """0x80: fill light brightness 0–255 (0 = off). Turning it on also turns night vision on."""

    OPCODE = Opcode.FILL_LIGHT
    LAYOUT = struct.Struct("<B")
    brightness: int = 255

    def raw_params(self) -> tuple[int, ...]:
        return (check_int("brightness", self.brightness, 0, 255),)

    @classmethod
    def from_raw_params(cls, raw: tuple[int, ...]) -> FillLight:
        return cls(raw[0])


@dataclass(frozen=True, slots=True)
class Ranging(Command):
    """0x81: continuous laser ranging on/off (wire: 0x02 = on, 0x00 = off)."""

    OPCODE = Opcode.RANGING
    LAYOUT = struct.Struct("<B")
    enabled: bool = True

    def raw_params(self) -> tuple[int, ...]:
        return (2 if check_bool("enabled", self.enabled) else 0,)

    @classmethod
    def from_raw_params(cls, raw: tuple[int, ...]) -> Ranging:
        return cls(_switch("enabled", raw[0], on=2))

    @classmethod
    def raw_anomalies(cls, raw: tuple[int, ...]) -> tuple[Anomaly, ...]:
        return _switch_raw("enabled", raw[0], on=2)


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


COMMAND_TYPES: dict[int, type[Command]] = {
    int(cls.OPCODE): cls
    for cls in (
        NullCommand, Calibration, Centre, AngleControl, PointingLock, PointingFollow, TopDown,
        EulerControl, GazeAtCoordinates, GazeLock, Track, ClickToPan, Fpv, OsdCoordinates,
        ImageAutoFlip, TimeZone, TakePhoto, Record, ZoomIn, ZoomOut, ZoomStop, ZoomTo, Focus,
        Palette, NightVision, AreaTemperature, TemperatureAlarm, Isotherm, SpotTemperature, Osd,
        PictureInPicture, TargetDetection, DigitalZoom, FillLight, Ranging,
    )
}  # fmt: skip
"""Opcode → command class, one entry per command of V2.0.6."""

MODE_COMMANDS: frozenset[Opcode] = frozenset({
    Opcode.ANGLE_CONTROL, Opcode.POINTING_LOCK, Opcode.POINTING_FOLLOW, Opcode.TOP_DOWN,
    Opcode.EULER_CONTROL, Opcode.GAZE_AT_COORDINATES, Opcode.GAZE_LOCK, Opcode.TRACK, Opcode.FPV,
})  # fmt: skip
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
