"""The command catalogue: one entry per client command method, the one place its names live.

Each :class:`CatalogueEntry` gives a command's client method name (a verb phrase), its
command class (the protocol's noun: the :class:`~gcu_async.protocol.Opcode` member's name in
CamelCase), its opcode, its ``gcu-async send`` name (the method name with dashes), its
parameters (:class:`Parameter`: name, kind, unit, range, default), a one-line doc and how
its feedback's execution status reads (:class:`StatusRule`, docs/protocol-notes.md §2
"Execution status per command"). The command line's ``send`` subcommands, the web example's
table and the docs' command table are made from it; the client's methods and the command
classes' own validation are checked against it by tests (tests/protocol/test_catalogue.py), so the
copies cannot drift. Sans-I/O and immutable: tuples of frozen dataclasses.

One opcode may have several entries (``track`` / ``stop_tracking`` both send 0x17); the
null command (0x00) has none: the client sends it by itself (docs/protocol-notes.md §4 "The
same-opcode rule").
"""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

from gcu_async.protocol import commands as c
from gcu_async.protocol.enums import CameraMask, NightVisionMode, Opcode, OsdCoordinateSource
from gcu_async.protocol.feedback import THERMAL_OPCODES, ZOOM_OPCODES
from gcu_async.protocol.host_frames import CONTROL_RATE_RAW
from gcu_async.protocol.layout import S32


class Required(enum.Enum):
    """The marker of a parameter without a default (:data:`REQUIRED`)."""

    REQUIRED = "required"

    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED = Required.REQUIRED
"""``Parameter.default`` of a parameter the caller must give."""


class Kind(enum.Enum):
    """What a parameter takes (the package rule, :mod:`gcu_async.protocol`)."""

    REAL = "real"
    """A finite ``int`` or ``float`` in ``[low, high]``."""
    INTEGER = "integer"
    """An ``int`` (not a bool) in ``[low, high]``."""
    SWITCH = "switch"
    """``True`` or ``False``."""
    CAMERAS = "cameras"
    """A camera mask, an ``int`` 1–255 (docs/protocol-notes.md §3 "Camera masks")."""
    CHOICE = "choice"
    """A member of ``Parameter.choices`` or its exact value."""
    BOX = "box"
    """An :class:`~gcu_async.protocol.ImageBox` or a plain 4-tuple of image fractions."""


class StatusRule(enum.Enum):
    """How the execution status of a command's feedback reads (docs/protocol-notes.md §2
    "Execution status per command"); the value is the rule in words."""

    STANDARD = "0x00 success, any other value failure (0x01)"
    CALIBRATION = "0x00 success, 0x02 in progress (a later reply brings the result), else failure"
    THERMAL = "0x00 success, any other value failure (0x02)"
    ZOOM = "0x00 success, else the camera mask of the cameras that failed"

    @classmethod
    def of(cls, opcode: Opcode) -> StatusRule:
        """The rule for ``opcode``, from the opcode sets :func:`read_status` and
        :func:`failure_status` use (so the two cannot disagree)."""
        if opcode == Opcode.CALIBRATION:
            return cls.CALIBRATION
        if opcode in ZOOM_OPCODES:
            return cls.ZOOM
        if opcode in THERMAL_OPCODES:
            return cls.THERMAL
        return cls.STANDARD


@dataclass(frozen=True, slots=True)
class Parameter:
    """One parameter of a command method, as the caller writes it."""

    name: str
    kind: Kind
    doc: str
    """A few words: what it is, beyond unit and range."""
    unit: str = ""
    low: float | None = None
    """Smallest value (``None``: no numeric range: switches, boxes, choices)."""
    high: float | None = None
    low_open: bool = False
    """``low`` itself is excluded."""
    high_open: bool = False
    """``high`` itself is excluded."""
    default: object = REQUIRED
    choices: type[enum.IntEnum] | None = None
    """The enum of a :attr:`Kind.CHOICE` parameter."""

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    def range_text(self) -> str:
        """The range in words (``"-180 to 180"``, ``"OFF, ON or AUTO"``), ``""`` if none."""
        if self.choices is not None:
            names = [m.name for m in self.choices]
            return f"{', '.join(names[:-1])} or {names[-1]}"
        if self.low is None or self.high is None:
            return ""
        low = f"{self.low:.12g}" + (" (excluded)" if self.low_open else "")
        high = "no limit" if math.isinf(self.high) else f"{self.high:.12g}"
        return f"{low} to {high}" + (" (excluded)" if self.high_open else "")


@dataclass(frozen=True, slots=True)
class CatalogueEntry:
    """One command method: its names, its command, its parameters."""

    method: str
    """The :class:`~gcu_async.client.GcuClient` method (a verb phrase)."""
    command: type[c.Command]
    """The command class it sends (the protocol's noun)."""
    doc: str
    """One line."""
    parameters: tuple[Parameter, ...] = ()
    needs_ins: bool = False
    """The GCU executes it only while the host packets carry valid INS data: the aircraft's
    attitude, acceleration and velocity with the INS-valid bit set (host byte 11 B0); without
    them it answers a failure status. The one place this is written: the CLI's ``send
    --aircraft`` help and :attr:`~gcu_async.errors.CommandFailed.likely_cause` derive from it."""

    @property
    def opcode(self) -> Opcode:
        return self.command.OPCODE

    @property
    def cli_name(self) -> str:
        """The ``gcu-async send`` subcommand: the method name with dashes."""
        return self.method.replace("_", "-")

    @property
    def status(self) -> StatusRule:
        return StatusRule.of(self.opcode)

    def parameter(self, name: str) -> Parameter:
        """The parameter ``name`` (``KeyError`` if it has none)."""
        for p in self.parameters:
            if p.name == name:
                return p
        raise KeyError(f"{self.method} has no parameter {name!r}")


# -- parameters shared by several commands --------------------------------------------------
RATE_LIMIT = CONTROL_RATE_RAW / 10
"""°/s at zoom 1×: the largest rate the control field carries (it shrinks with zoom)."""
ALTITUDE_RANGE = (S32[0] / 1000, S32[1] / 1000)
"""Metres: what the gaze-at altitude field (S32, 1 mm) carries."""
TEMPERATURE_RANGE = (c.TEMPERATURE_RAW[0] / 10, c.TEMPERATURE_RAW[1] / 10)
"""°C: what a threshold field (S16, 0.1 °C) carries."""
YAW_INPUT_RANGE = (-180.0, 360.0)
"""Degrees, half-open: how every absolute yaw or heading may be given (the Euler yaw of
``enter_euler_control``, the aircraft's yaw of ``update_aircraft``, the waits): MAVLink's
±180° headings and compass 0–360° alike; each is sent in the range its wire field takes."""


def _cameras(default: CameraMask) -> Parameter:
    return Parameter("cameras", Kind.CAMERAS, "camera mask", "", 1, 0xFF, default=default)


CAM1 = _cameras(CameraMask.CAMERA_1)
CAM2 = _cameras(CameraMask.CAMERA_2)


def _angle(name: str, doc: str, default: object = 0.0) -> Parameter:
    return Parameter(name, Kind.REAL, doc, "deg", -180.0, 180.0, default=default)


def _rate(name: str, doc: str) -> Parameter:
    return Parameter(name, Kind.REAL, f"{doc}; the limit is divided by the current zoom",
                     "deg/s", -RATE_LIMIT, RATE_LIMIT, default=0.0)  # fmt: skip


def _fraction(name: str, doc: str, default: object = REQUIRED) -> Parameter:
    return Parameter(name, Kind.REAL, doc, "image fraction", 0.0, 1.0, default=default)


def _switch(doc: str) -> Parameter:
    return Parameter("enabled", Kind.SWITCH, doc, default=True)


def _box(default: object = REQUIRED) -> Parameter:
    return Parameter("box", Kind.BOX, "(left, top, right, bottom) image fractions 0-1",
                     default=default)


def _temperature(name: str) -> Parameter:
    return Parameter(name, Kind.REAL, f"{name} threshold, 0.1 degC steps; low <= high", "degC",
                     *TEMPERATURE_RANGE, default=0.0)  # fmt: skip


_EULER = (_angle("roll", "Euler roll", None), _angle("pitch", "Euler pitch", None),
          Parameter("yaw", Kind.REAL, "Euler yaw (north = 0); 180-360 is sent as -180-0",
                    "deg", *YAW_INPUT_RANGE, high_open=True, default=None))  # fmt: skip
_ANGLES = (_angle("roll", "Euler roll"), _angle("pitch", "Euler pitch"),
           _angle("yaw", "relative to the aircraft"))  # fmt: skip
_RELATIVE = tuple(_angle(n, "relative to the aircraft") for n in ("roll", "pitch", "yaw"))
_PITCH_YAW_RATES = (_rate("pitch_rate", "pitch rate"), _rate("yaw_rate", "yaw rate"))

CATALOGUE: tuple[CatalogueEntry, ...] = (
    # -- pod: modes (they switch the pod's working mode) ------------------------------------
    CatalogueEntry("enter_euler_control", c.EulerControl,
                   "Euler-angle control mode holding absolute angles (omitted: the current).",
                   _EULER),
    CatalogueEntry("enter_angle_control", c.AngleControl,
                   "Angle-control mode: Euler roll/pitch, yaw relative to the aircraft.",
                   _ANGLES),
    CatalogueEntry("enter_fpv", c.Fpv, "FPV mode: angles relative to the aircraft.", _RELATIVE),
    CatalogueEntry("enter_pointing_lock", c.PointingLock,
                   "Pointing-lock mode with pitch/yaw rates.", _PITCH_YAW_RATES),
    CatalogueEntry("enter_pointing_follow", c.PointingFollow,
                   "Pointing-follow mode; yaw rate 0 follows the aircraft's heading.",
                   _PITCH_YAW_RATES),
    CatalogueEntry("enter_top_down", c.TopDown, "Top-down mode (pitch -90 deg) with a yaw rate.",
                   (_rate("yaw_rate", "yaw rate"),)),
    CatalogueEntry("enter_gaze_lock", c.GazeLock,
                   "Geographic lock on the image centre; needs valid aircraft INS data.",
                   _PITCH_YAW_RATES, needs_ins=True),
    CatalogueEntry("gaze_at", c.GazeAtCoordinates,
                   "Gaze at a coordinate; needs valid aircraft INS data.",
                   (Parameter("latitude", Kind.REAL, "WGS84, 1e-7 deg steps", "deg", -90.0, 90.0),
                    Parameter("longitude", Kind.REAL, "WGS84, 1e-7 deg steps", "deg", -180.0,
                              180.0),
                    Parameter("altitude", Kind.REAL, "above mean sea level, 1 mm steps", "m",
                              *ALTITUDE_RANGE)), needs_ins=True),
    # -- pod: other ---------------------------------------------------------------------------
    CatalogueEntry("calibrate", c.Calibration,
                   "Calibrate the pod; waits while the GCU answers \"in progress\".",
                   (Parameter("timeout", Kind.REAL, "how long to wait for the result", "s", 0.0,
                              math.inf, low_open=True, high_open=True, default=15.0),)),
    CatalogueEntry("centre", c.Centre,
                   "Centre pitch and heading; control values are sent invalid meanwhile."),
    CatalogueEntry("track", c.Track, "Enter image tracking of the target in the box.",
                   (_box(), CAM1)),
    CatalogueEntry("stop_tracking", c.Track, "Exit image tracking (same opcode, TT = 0).",
                   (CAM1,)),
    CatalogueEntry("click_to_pan", c.ClickToPan,
                   "Bring an image point to the centre; the pod ends in pointing-lock.",
                   (_fraction("x", "from the left"), _fraction("y", "from the top"), CAM1)),
    # -- camera -------------------------------------------------------------------------------
    CatalogueEntry("take_photo", c.TakePhoto, "Take a photo.", (CAM1,)),
    CatalogueEntry("toggle_recording", c.Record,
                   "Start or stop recording (a toggle on the wire).", (CAM1,)),
    CatalogueEntry("start_recording", c.Record,
                   "Start recording unless the camera records (then None, nothing sent).",
                   (CAM1,)),
    CatalogueEntry("stop_recording", c.Record,
                   "Stop recording if the camera records (else None, nothing sent).", (CAM1,)),
    CatalogueEntry("zoom_in", c.ZoomIn, "Zoom in continuously until stop_zoom.", (CAM1,)),
    CatalogueEntry("zoom_out", c.ZoomOut, "Zoom out continuously until stop_zoom.", (CAM1,)),
    CatalogueEntry("stop_zoom", c.ZoomStop, "Stop a continuous zoom.", (CAM1,)),
    CatalogueEntry("zoom_to", c.ZoomTo, "Zoom to a ratio; sent as -(ratio x 10).",
                   (Parameter("ratio", Kind.REAL, "zoom ratio, 0.1 steps", "x", 1.0,
                              c.ZOOM_RATIO_MAX), CAM1)),
    CatalogueEntry("zoom_to_fraction", c.ZoomTo,
                   "Zoom to a fraction of the maximum ratio; sent as fraction x 10000.",
                   (Parameter("fraction", Kind.REAL, "1/10000 steps", "of maximum ratio",
                              1 / c.ZOOM_FRACTION_RAW_MAX, 1.0), CAM1)),
    CatalogueEntry("focus", c.Focus, "Trigger focus.", (CAM1,)),
    CatalogueEntry("set_palette", c.Palette, "Thermal palette.",
                   (Parameter("palette", Kind.INTEGER, "1-10, or 0 to cycle", "", 0, 10,
                              default=0), CAM2)),
    CatalogueEntry("set_night_vision", c.NightVision, "Night vision off, on or auto.",
                   (Parameter("mode", Kind.CHOICE, "night vision mode", default=NightVisionMode.ON,
                              choices=NightVisionMode), CAM1)),
    CatalogueEntry("set_area_temperature", c.AreaTemperature,
                   "Area temperature measurement over a box (radiometric thermal).",
                   (_switch("measurement on/off"), _box((0.0, 0.0, 1.0, 1.0)), CAM2)),
    CatalogueEntry("set_temperature_alarm", c.TemperatureAlarm,
                   "Temperature alarm with high/low thresholds (radiometric thermal).",
                   (_switch("alarm on/off"), _temperature("high"), _temperature("low"), CAM2)),
    CatalogueEntry("set_isotherm", c.Isotherm,
                   "Isotherm between low and high (radiometric thermal).",
                   (_switch("isotherm on/off"), _temperature("high"), _temperature("low"), CAM2)),
    CatalogueEntry("set_spot_temperature", c.SpotTemperature,
                   "Spot temperature measurement at an image point (radiometric thermal).",
                   (_switch("measurement on/off"), _fraction("x", "from the left", 0.5),
                    _fraction("y", "from the top", 0.5), CAM2)),
    CatalogueEntry("set_osd", c.Osd, "On-screen display on/off.", (_switch("OSD on/off"),)),
    CatalogueEntry("set_osd_coordinates", c.OsdCoordinates,
                   "Which coordinates the OSD shows.",
                   (Parameter("coordinates", Kind.CHOICE, "aircraft or target",
                              default=OsdCoordinateSource.AIRCRAFT,
                              choices=OsdCoordinateSource),)),
    CatalogueEntry("set_image_auto_flip", c.ImageAutoFlip, "Image auto-flip on/off.",
                   (_switch("auto-flip on/off"),)),
    CatalogueEntry("set_time_zone", c.TimeZone, "The pod's UTC offset in whole hours.",
                   (Parameter("offset_hours", Kind.INTEGER, "whole hours", "h", -12, 14),)),
    CatalogueEntry("set_picture_in_picture", c.PictureInPicture, "Picture-in-picture mode.",
                   (Parameter("mode", Kind.INTEGER, "1-4, or 0 to cycle", "", 0, 4, default=0),)),
    CatalogueEntry("set_target_detection", c.TargetDetection, "AI target detection on/off.",
                   (_switch("detection on/off"),)),
    CatalogueEntry("set_digital_zoom", c.DigitalZoom, "Digital zoom on/off.",
                   (_switch("digital zoom on/off"),)),
    CatalogueEntry("set_fill_light", c.FillLight,
                   "Fill light brightness; turning it on also turns night vision on.",
                   (Parameter("brightness", Kind.INTEGER, "0 = off", "", 0, 255),)),
    CatalogueEntry("set_ranging", c.Ranging, "Continuous laser ranging on/off.",
                   (_switch("ranging on/off"),)),
)  # fmt: skip
"""Every command method of the client, in the order of the docs' command table."""

BY_METHOD: Mapping[str, CatalogueEntry] = MappingProxyType({e.method: e for e in CATALOGUE})
"""The catalogue by method name."""
NEEDS_INS: frozenset[Opcode] = frozenset(e.opcode for e in CATALOGUE if e.needs_ins)
"""The opcodes the GCU executes only with valid INS data (:attr:`CatalogueEntry.needs_ins`)."""
