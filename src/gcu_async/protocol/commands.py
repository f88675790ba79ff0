"""The command table: every command of V2.0.6 (byte 69 + parameters, bytes 70..S-3), once.

Each command is a class here — a frozen dataclass in engineering units whose ``OPCODE`` is
its :class:`~gcu_async.protocol.opcodes.Opcode` member and whose ``SCHEMA``
(:class:`~gcu_async.protocol.command_schema.CommandSchema`) lists its parameters in wire
order as kinds (:mod:`gcu_async.protocol.command_fields`: wire type, scale, unit, range,
doc), its status rule, its mode, whether it needs INS data and the client methods that send
it (names and docs). The codec is the base class's (:mod:`gcu_async.protocol.command_base`);
the catalogue, the mode tables, the feedback sets, the dissector's tables and the docs' and
tests' tables derive from this table (docs/architecture.md, "Changing the protocol").

A command is validated when it is built (so a bad argument raises before anything is sent)
under the package rule (:mod:`gcu_async.protocol`): ``bool`` fields take only
``True``/``False``, integer fields only ``int`` (camera masks within the range of
:data:`~gcu_async.protocol.command_fields.CAMERA_MASK`, ``CameraMask`` members welcome), real
fields finite ``int``/``float`` inside the field's range, enum fields a member or its exact
value, ``box``/``point`` an :class:`~gcu_async.protocol.ImageBox` /
:class:`~gcu_async.protocol.ImagePoint` (or a plain tuple, stored as the NamedTuple) checked
element by element, each in the order of the class's fields. The first parameter byte of
many commands is a camera mask (docs/protocol-notes.md §3 "Camera masks"): it is the
``cameras`` field, defaulting to the value the document shows.
"""

from __future__ import annotations

from dataclasses import dataclass

from gcu_async.protocol.command_base import Command, codec
from gcu_async.protocol.command_fields import (
    ZOOM_RATIO,
    Box,
    Cameras,
    Point,
    Switch,
    Thresholds,
    ZoomValue,
    choice,
    integer,
    real,
)
from gcu_async.protocol.command_schema import (
    CommandSchema,
    Kind,
    Method,
    ModeSpec,
    Parameter,
    StatusRule,
)
from gcu_async.protocol.enums import CameraMask, Mode, NightVisionMode, OsdCoordinateSource
from gcu_async.protocol.fields import LATITUDE_RANGE, LONGITUDE_RANGE
from gcu_async.protocol.host_frame_tables import CONTROL_ANGLE_RAW, CONTROL_RATE_RAW
from gcu_async.protocol.opcodes import Opcode
from gcu_async.protocol.units import YAW_INPUT_RANGE, ImageBox, ImagePoint

# -- parameters several commands share ---------------------------------------------------------
CAM1, CAM2 = Cameras(), Cameras()
"""The camera mask parameter (its default, camera 1 or 2, is the class attribute's)."""
RATE_LIMIT = CONTROL_RATE_RAW / 10
"""°/s at zoom 1×: the largest rate the control field carries (it shrinks with zoom)."""
ANGLE_LIMIT = CONTROL_ANGLE_RAW / 100
"""Degrees: the largest control angle."""
ZOOM_RATIO_MAX = ZOOM_RATIO.raw_high / ZOOM_RATIO.scale
"""The largest ratio zoom-to carries, in x."""


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
@codec
@dataclass(frozen=True, slots=True)
class NullCommand(Command):
    """Separates two commands with the same opcode (docs/protocol-notes.md §4 "The
    same-opcode rule"). The client sends it by itself: no method."""

    OPCODE = Opcode.NULL


@codec
@dataclass(frozen=True, slots=True)
class EulerControl(Command):
    """Euler-angle control mode. Control values: roll/pitch/yaw Euler angles."""

    OPCODE = Opcode.EULER_CONTROL
    SCHEMA = CommandSchema(mode=ModeSpec(Mode.EULER_CONTROL, "angles"), methods=(Method(
        "enter_euler_control",
        "Euler-angle control mode holding absolute angles (omitted: the current).", _EULER),))


@codec
@dataclass(frozen=True, slots=True)
class AngleControl(Command):
    """Angle-control mode. Control values: roll, pitch = Euler angle; yaw = angle
    relative to the aircraft."""

    OPCODE = Opcode.ANGLE_CONTROL
    SCHEMA = CommandSchema(mode=ModeSpec(Mode.ANGLE_CONTROL, "angles"), methods=(Method(
        "enter_angle_control",
        "Angle-control mode: Euler roll/pitch, yaw relative to the aircraft.", _ANGLES),))


@codec
@dataclass(frozen=True, slots=True)
class Fpv(Command):
    """FPV mode. Control values: roll/pitch/yaw angles relative to the aircraft."""

    OPCODE = Opcode.FPV
    SCHEMA = CommandSchema(mode=ModeSpec(Mode.FPV, "angles"), methods=(Method(
        "enter_fpv", "FPV mode: angles relative to the aircraft.", _RELATIVE),))


@codec
@dataclass(frozen=True, slots=True)
class PointingLock(Command):
    """Pointing-lock mode. Control values: pitch/yaw angular rates."""

    OPCODE = Opcode.POINTING_LOCK
    SCHEMA = CommandSchema(mode=ModeSpec(Mode.POINTING_LOCK, "rates"), methods=(Method(
        "enter_pointing_lock", "Pointing-lock mode with pitch/yaw rates.", _PITCH_YAW_RATES),))


@codec
@dataclass(frozen=True, slots=True)
class PointingFollow(Command):
    """Pointing-follow mode. Control values: pitch/yaw rates (yaw 0 → follow aircraft)."""

    OPCODE = Opcode.POINTING_FOLLOW
    SCHEMA = CommandSchema(mode=ModeSpec(Mode.POINTING_FOLLOW, "rates"), methods=(Method(
        "enter_pointing_follow", "Pointing-follow mode; yaw rate 0 follows the aircraft's heading.",
        _PITCH_YAW_RATES),))


@codec
@dataclass(frozen=True, slots=True)
class TopDown(Command):
    """Top-down mode (pitch −90°). Control values: yaw rate."""

    OPCODE = Opcode.TOP_DOWN
    SCHEMA = CommandSchema(mode=ModeSpec(Mode.TOP_DOWN, "rates"), methods=(Method(
        "enter_top_down", "Top-down mode (pitch -90 deg) with a yaw rate.",
        (_rate("yaw_rate", "yaw rate"),)),))


@codec
@dataclass(frozen=True, slots=True)
class GazeLock(Command):
    """Gaze (geographic target lock) at the image centre; needs valid aircraft INS."""

    OPCODE = Opcode.GAZE_LOCK
    SCHEMA = CommandSchema(mode=ModeSpec(Mode.GAZE, "rates"), needs_ins=True, methods=(Method(
        "enter_gaze_lock", "Geographic lock on the image centre; needs valid aircraft INS data.",
        _PITCH_YAW_RATES),))


@codec
@dataclass(frozen=True, slots=True)
class GazeAtCoordinates(Command):
    """Gaze at a geographic coordinate (PP lon, QQ lat: S32 1e-7°; RR alt: S32 mm)."""

    OPCODE = Opcode.GAZE_AT_COORDINATES
    SCHEMA = CommandSchema(
        params=(real("longitude", "i", "WGS84, 1e-7 deg steps", *LONGITUDE_RANGE, 1e7, "deg",
                     "1e-7 deg"),
                real("latitude", "i", "WGS84, 1e-7 deg steps", *LATITUDE_RANGE, 1e7, "deg",
                     "1e-7 deg"),
                real("altitude", "i", "above mean sea level, 1 mm steps", None, None, 1000, "m")),
        mode=ModeSpec(Mode.GAZE, "rates"), needs_ins=True,
        methods=(Method("gaze_at", "Gaze at a coordinate; needs valid aircraft INS data."),))
    latitude: float
    longitude: float
    altitude: float


@codec
@dataclass(frozen=True, slots=True)
class Calibration(Command):
    """Calibrate the pod (keep it still; answers "in progress" for a few seconds)."""

    OPCODE = Opcode.CALIBRATION
    SCHEMA = CommandSchema(status=StatusRule.CALIBRATION, methods=(Method(
        "calibrate", "Calibrate the pod; waits while the GCU answers \"in progress\".",
        (Parameter("timeout", Kind.REAL, "how long to wait for the result", "s", 0.0, float("inf"),
                   low_open=True, high_open=True, default=15.0),)),))  # fmt: skip


@codec
@dataclass(frozen=True, slots=True)
class Centre(Command):
    """Centre pitch and heading (lock/follow), heading (top-down). Control values must
    be sent invalid while it runs."""

    OPCODE = Opcode.CENTRE
    SCHEMA = CommandSchema(changes_mode=True, methods=(Method(
        "centre", "Centre pitch and heading; control values are sent invalid meanwhile.", ()),))


@codec
@dataclass(frozen=True, slots=True)
class Track(Command):
    """Enter (``enter=True``) or exit image tracking of the target in ``box``."""

    OPCODE = Opcode.TRACK
    SCHEMA = CommandSchema(
        params=(CAM1, Switch("enter", "enter or exit tracking",
                             meaning="0x00 = exit, 0x01 = enter"), Box()),
        mode=ModeSpec(Mode.TRACK, "none"),
        methods=(Method("track", "Enter image tracking of the target in the box.",
                        ("box", "cameras"), required=("box",)),
                 Method("stop_tracking", "Exit image tracking (same opcode, TT = 0).",
                        ("cameras",))))  # fmt: skip
    enter: bool = True
    box: ImageBox = ImageBox(0.0, 0.0, 0.0, 0.0)
    cameras: CameraMask | int = CameraMask.CAMERA_1


@codec
@dataclass(frozen=True, slots=True)
class ClickToPan(Command):
    """Turn the camera so that ``point`` comes to the image centre; the pod then
    switches to pointing-lock. Control values must be invalid while it runs."""

    OPCODE = Opcode.CLICK_TO_PAN
    SCHEMA = CommandSchema(params=(CAM1, Point()), changes_mode=True, methods=(Method(
        "click_to_pan", "Bring an image point to the centre; the pod ends in pointing-lock.",
        ("point", "cameras")),))
    point: ImagePoint
    cameras: CameraMask | int = CameraMask.CAMERA_1


@codec
@dataclass(frozen=True, slots=True)
class TakePhoto(Command):
    """Take a photo with the masked cameras."""

    OPCODE = Opcode.TAKE_PHOTO
    SCHEMA = CommandSchema(params=(CAM1,), methods=(Method("take_photo", "Take a photo."),))
    cameras: CameraMask | int = CameraMask.CAMERA_1


@codec
@dataclass(frozen=True, slots=True)
class Record(Command):
    """Start or stop recording (a toggle)."""

    OPCODE = Opcode.RECORD
    SCHEMA = CommandSchema(params=(CAM1,), methods=(
        Method("toggle_recording", "Start or stop recording (a toggle on the wire)."),
        Method("start_recording",
               "Start recording unless the camera records (then None, nothing sent)."),
        Method("stop_recording",
               "Stop recording if the camera records (else None, nothing sent).")))
    cameras: CameraMask | int = CameraMask.CAMERA_1


@codec
@dataclass(frozen=True, slots=True)
class ZoomIn(Command):
    """Zoom in continuously until :class:`ZoomStop`."""

    OPCODE = Opcode.ZOOM_IN
    SCHEMA = CommandSchema(params=(CAM1,), status=StatusRule.ZOOM,
                           methods=(Method("zoom_in", "Zoom in continuously until stop_zoom."),))
    cameras: CameraMask | int = CameraMask.CAMERA_1


@codec
@dataclass(frozen=True, slots=True)
class ZoomOut(Command):
    """Zoom out continuously until :class:`ZoomStop`."""

    OPCODE = Opcode.ZOOM_OUT
    SCHEMA = CommandSchema(params=(CAM1,), status=StatusRule.ZOOM,
                           methods=(Method("zoom_out", "Zoom out continuously until stop_zoom."),))
    cameras: CameraMask | int = CameraMask.CAMERA_1


@codec
@dataclass(frozen=True, slots=True)
class ZoomStop(Command):
    """Stop a continuous zoom."""

    OPCODE = Opcode.ZOOM_STOP
    SCHEMA = CommandSchema(params=(CAM1,), status=StatusRule.ZOOM,
                           methods=(Method("stop_zoom", "Stop a continuous zoom."),))
    cameras: CameraMask | int = CameraMask.CAMERA_1


@codec
@dataclass(frozen=True, slots=True)
class ZoomTo(Command):
    """Zoom to a ratio (``ratio=10.0`` → wire −100) or to a fraction of the maximum
    ratio (``fraction=0.5`` → wire 5000; 1/10000 → minimum, 1.0 → maximum). Give exactly one.
    """

    OPCODE = Opcode.ZOOM_TO
    SCHEMA = CommandSchema(
        params=(CAM1, ZoomValue()), status=StatusRule.ZOOM,
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


@codec
@dataclass(frozen=True, slots=True)
class Focus(Command):
    """Trigger focus."""

    OPCODE = Opcode.FOCUS
    SCHEMA = CommandSchema(params=(CAM1,),
                           methods=(Method("focus", "Trigger focus."),))
    cameras: CameraMask | int = CameraMask.CAMERA_1


@codec
@dataclass(frozen=True, slots=True)
class Palette(Command):
    """Thermal palette 1–10, or 0 to cycle."""

    OPCODE = Opcode.PALETTE
    SCHEMA = CommandSchema(
        params=(CAM2, integer("palette", "B", "1-10, or 0 to cycle", 0, 10, detail="0 cycles")),
        status=StatusRule.THERMAL,
        methods=(Method("set_palette", "Thermal palette."),))
    palette: int = 0
    cameras: CameraMask | int = CameraMask.CAMERA_2


@codec
@dataclass(frozen=True, slots=True)
class NightVision(Command):
    """Night vision off / on / auto."""

    OPCODE = Opcode.NIGHT_VISION
    SCHEMA = CommandSchema(
        params=(CAM1, choice("mode", NightVisionMode, "night vision mode", "0 off, 1 on, 2 auto")),
        methods=(Method("set_night_vision", "Night vision off, on or auto."),))
    mode: NightVisionMode | int = NightVisionMode.ON
    cameras: CameraMask | int = CameraMask.CAMERA_1


@codec
@dataclass(frozen=True, slots=True)
class AreaTemperature(Command):
    """Area temperature measurement on/off over ``box``."""

    OPCODE = Opcode.AREA_TEMPERATURE
    SCHEMA = CommandSchema(
        params=(CAM2, Switch(doc="measurement on/off"), Box()),
        status=StatusRule.THERMAL,
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


@codec
@dataclass(frozen=True, slots=True)
class TemperatureAlarm(_Thresholds):
    """Temperature alarm on/off with high/low thresholds in °C (0.1 °C resolution)."""

    OPCODE = Opcode.TEMPERATURE_ALARM
    SCHEMA = CommandSchema(
        params=(CAM2, Switch(doc="alarm on/off"), Thresholds()), status=StatusRule.THERMAL,
        methods=(Method(
            "set_temperature_alarm",
            "Temperature alarm with high/low thresholds (radiometric thermal)."),))


@codec
@dataclass(frozen=True, slots=True)
class Isotherm(_Thresholds):
    """Isotherm off, or on in "inside the interval" mode with high/low thresholds (°C)."""

    OPCODE = Opcode.ISOTHERM
    SCHEMA = CommandSchema(
        params=(CAM2, Switch(doc="isotherm on/off"), Thresholds()), status=StatusRule.THERMAL,
        methods=(Method(
            "set_isotherm", "Isotherm between low and high (radiometric thermal)."),))


@codec
@dataclass(frozen=True, slots=True)
class SpotTemperature(Command):
    """Spot temperature measurement on/off at ``point``."""

    OPCODE = Opcode.SPOT_TEMPERATURE
    SCHEMA = CommandSchema(
        params=(CAM2, Switch(doc="measurement on/off"), Point()), status=StatusRule.THERMAL,
        methods=(Method(
            "set_spot_temperature",
            "Spot temperature measurement at an image point (radiometric thermal)."),))
    enabled: bool = True
    point: ImagePoint = ImagePoint(0.5, 0.5)
    cameras: CameraMask | int = CameraMask.CAMERA_2


@codec
@dataclass(frozen=True, slots=True)
class Osd(Command):
    """On-screen display on/off."""

    OPCODE = Opcode.OSD
    SCHEMA = CommandSchema(params=(Switch(doc="OSD on/off"),),
                           methods=(Method("set_osd", "On-screen display on/off."),))
    enabled: bool = True


@codec
@dataclass(frozen=True, slots=True)
class OsdCoordinates(Command):
    """Which coordinates the OSD shows (aircraft or target)."""

    OPCODE = Opcode.OSD_COORDINATES
    SCHEMA = CommandSchema(
        params=(choice("coordinates", OsdCoordinateSource, "aircraft or target",
                       "0 = aircraft, 1 = target"),),
        methods=(Method("set_osd_coordinates", "Which coordinates the OSD shows."),))
    coordinates: OsdCoordinateSource | int = OsdCoordinateSource.AIRCRAFT


@codec
@dataclass(frozen=True, slots=True)
class ImageAutoFlip(Command):
    """Image auto-flip on/off (wire: 0x00 = on, 0x01 = off)."""

    OPCODE = Opcode.IMAGE_AUTO_FLIP
    SCHEMA = CommandSchema(
        params=(Switch(doc="auto-flip on/off", on=0, off=1, meaning="0x00 = on, 0x01 = off"),),
        methods=(Method("set_image_auto_flip", "Image auto-flip on/off."),))
    enabled: bool = True


@codec
@dataclass(frozen=True, slots=True)
class TimeZone(Command):
    """The pod's time zone as a whole-hour UTC offset (S8; real zones −12 … +14)."""

    OPCODE = Opcode.TIME_ZONE
    SCHEMA = CommandSchema(
        params=(integer("offset_hours", "b", "whole hours", -12, 14, "h"),),
        methods=(Method("set_time_zone", "The pod's UTC offset in whole hours.",
                        required=("offset_hours",)),))
    offset_hours: int = 0


@codec
@dataclass(frozen=True, slots=True)
class PictureInPicture(Command):
    """Picture-in-picture mode 1–4, or 0 to cycle."""

    OPCODE = Opcode.PICTURE_IN_PICTURE
    SCHEMA = CommandSchema(
        params=(integer("mode", "B", "1-4, or 0 to cycle", 0, 4, detail="0 cycles"),),
        methods=(Method("set_picture_in_picture", "Picture-in-picture mode."),))
    mode: int = 0


@codec
@dataclass(frozen=True, slots=True)
class TargetDetection(Command):
    """AI target detection on/off."""

    OPCODE = Opcode.TARGET_DETECTION
    SCHEMA = CommandSchema(params=(Switch(doc="detection on/off"),),
                           methods=(Method("set_target_detection", "AI target detection on/off."),))
    enabled: bool = True


@codec
@dataclass(frozen=True, slots=True)
class DigitalZoom(Command):
    """Digital zoom of the zoom camera on/off."""

    OPCODE = Opcode.DIGITAL_ZOOM
    SCHEMA = CommandSchema(params=(Switch(doc="digital zoom on/off"),),
                           methods=(Method("set_digital_zoom", "Digital zoom on/off."),))
    enabled: bool = True


@codec
@dataclass(frozen=True, slots=True)
class FillLight(Command):
    """Fill light brightness 0–255 (0 = off). Turning it on also turns night vision on."""

    OPCODE = Opcode.FILL_LIGHT
    SCHEMA = CommandSchema(
        params=(integer("brightness", "B", "0 = off"),),
        methods=(Method("set_fill_light",
                        "Fill light brightness; turning it on also turns night vision on.",
                        required=("brightness",)),))
    brightness: int = 255


@codec
@dataclass(frozen=True, slots=True)
class Ranging(Command):
    """Continuous laser ranging on/off (wire: 0x02 = on, 0x00 = off)."""

    OPCODE = Opcode.RANGING
    SCHEMA = CommandSchema(params=(Switch(doc="ranging on/off", on=2),),
                           methods=(Method("set_ranging", "Continuous laser ranging on/off."),))
    enabled: bool = True


_CLASSES = [cls for cls in list(globals().values())
            if isinstance(cls, type) and issubclass(cls, Command) and "OPCODE" in cls.__dict__]
COMMAND_TYPES: dict[int, type[Command]] = {int(cls.OPCODE): cls for cls in _CLASSES}
"""Opcode → command class, one entry per command of V2.0.6 (every class of this table)."""
if sorted(COMMAND_TYPES) != sorted(int(o) for o in Opcode) or len(_CLASSES) != len(Opcode):
    raise TypeError("every Opcode member needs exactly one command class (and no more)")

MODE_COMMANDS: frozenset[Opcode] = frozenset(
    c.OPCODE for c in COMMAND_TYPES.values() if c.SCHEMA.mode is not None
)
"""Commands that switch the pod's working mode."""
