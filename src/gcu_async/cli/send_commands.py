"""The commands of ``gcu-async send``: one per client command method, with the arguments
each takes on the command line (units and ranges for its ``--help``) and how they map onto
the method's parameters (docs/cli.md, "gcu-async send")."""

from __future__ import annotations

import argparse
import asyncio
import inspect
import re
import textwrap
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple

from gcu_async.client.api import ALTITUDE_RANGE, RATE_LIMIT, CommandMethods
from gcu_async.client.client import GcuClient
from gcu_async.protocol.commands import ZOOM_RATIO_MAX, Command, command_code
from gcu_async.protocol.enums import CameraMask, NightVisionMode, OsdCoordinates
from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.gcu_frames import GcuSubFrame
from gcu_async.protocol.host_frames import ControlValues
from gcu_async.protocol.units import Attitude
from gcu_async.session import ControlKind


def _switch(text: str) -> bool:
    value = text.strip().lower()
    if value in ("on", "1", "true", "yes", "enable"):
        return True
    if value in ("off", "0", "false", "no", "disable"):
        return False
    raise argparse.ArgumentTypeError(f"expected on/off, got {text!r}")


def _night(text: str) -> NightVisionMode:
    try:
        return NightVisionMode[text.strip().upper()]
    except KeyError:
        raise argparse.ArgumentTypeError(f"expected off/on/auto, got {text!r}") from None


def _osd_coords(text: str) -> OsdCoordinates:
    try:
        return OsdCoordinates[text.strip().upper()]
    except KeyError:
        raise argparse.ArgumentTypeError(f"expected aircraft/target, got {text!r}") from None


CAMERA_NAMES: dict[str, CameraMask] = {
    **{f"camera_{n}": CameraMask(1 << (n - 1)) for n in range(1, 9)},
    "visible": CameraMask.VISIBLE,
    "thermal": CameraMask.THERMAL,
}
"""Names ``--cameras`` takes besides the camera numbers 1–8 (:class:`CameraMask`)."""


def parse_cameras(text: str) -> CameraMask:
    """The camera mask (``cameras=`` of the client's methods) from a comma-separated list
    of camera numbers 1–8 or names: ``1``, ``2``, ``1,2``, ``visible,thermal``,
    ``camera_3``. Raises ``argparse.ArgumentTypeError`` naming what is allowed."""
    mask = CameraMask(0)
    items = [item.strip().lower().replace("-", "_") for item in text.split(",")]
    for item in items:
        if item.isascii() and item.isdigit() and 1 <= int(item) <= 8:
            mask |= CameraMask(1 << (int(item) - 1))
        elif item in CAMERA_NAMES:
            mask |= CAMERA_NAMES[item]
        else:
            raise argparse.ArgumentTypeError(
                f"expected camera numbers 1-8 or names ({', '.join(CAMERA_NAMES)}), "
                f"comma-separated; got {text!r}"
            )
    return mask


class Param(NamedTuple):
    """One command-line argument of a command."""

    name: str
    convert: Callable[[str], Any]
    help: str
    """Unit and range, for the command's ``--help``."""
    optional: bool = False
    """May be left out (a trailing argument; the method's default applies)."""


Build = Callable[[list[Any]], tuple[tuple[Any, ...], dict[str, Any]]]


def _positional(values: list[Any]) -> tuple[tuple[Any, ...], dict[str, Any]]:
    return tuple(values), {}


def _keywords(*names: str) -> Build:
    """The values given (maybe fewer than ``names``) as keyword arguments."""
    return lambda values: ((), dict(zip(names, values, strict=False)))


def _switch_box(values: list[Any]) -> tuple[tuple[Any, ...], dict[str, Any]]:
    """``on`` and, if given, the box (left, top, right, bottom) as one tuple."""
    return ((values[0], tuple(values[1:])) if len(values) > 1 else (values[0],)), {}


def _switch_thresholds(values: list[Any]) -> tuple[tuple[Any, ...], dict[str, Any]]:
    return (values[0],), {"high": values[1], "low": values[2]}


@dataclass(frozen=True)
class CliCommand:
    """A ``send`` command: which client method it calls, with which arguments."""

    method: str
    """The :class:`GcuClient` method it calls."""
    summary: str
    """One line for ``gcu-async send --help``."""
    params: tuple[Param, ...] = ()
    build: Build = _positional
    """The method's positional and keyword arguments from the values given."""
    together: bool = False
    """The optional parameters are given all together or not at all."""
    angle_target: bool = False
    """The parameters are roll/pitch/yaw targets of an angle mode."""
    holds: bool = False
    """A mode command whose control values need packets to act (default ``--hold`` 3 s)."""

    def parameter(self, name: str) -> inspect.Parameter | None:
        """The method's parameter ``name``, if it has one."""
        return inspect.signature(getattr(GcuClient, self.method)).parameters.get(name)

    @property
    def takes_cameras(self) -> bool:
        """The method has a ``cameras`` parameter (``--cameras`` applies)."""
        return self.parameter("cameras") is not None

    @property
    def takes_timeout(self) -> bool:
        """The method has its own ``timeout`` parameter (``--timeout`` is passed to it)."""
        return self.parameter("timeout") is not None

    def call(self, gcu: Any, values: list[Any], **extra: Any) -> Any:
        """Call the method on ``gcu`` with ``values`` and the ``extra`` keyword arguments
        (``cameras``, ``timeout``); returns what it returns (a coroutine)."""
        args, kwargs = self.build(values)
        return getattr(gcu, self.method)(*args, **kwargs, **extra)

    def check(self, values: list[Any], **extra: Any) -> None:
        """Check the arguments as the method does, with no GCU behind it: raises the same
        ``TypeError`` or :class:`~gcu_async.errors.FieldRangeError` it would, sends nothing.
        (Rate limits are checked at zoom 1x here; the method checks them again at the
        GCU's zoom.)"""
        asyncio.run(self.call(_Unconnected(), values, **extra))

    def description(self) -> str:
        """The command's ``--help`` text: the summary and the method's own docstring."""
        method = getattr(GcuClient, self.method)
        names = ", ".join(p for p in inspect.signature(method).parameters if p != "self")
        doc = _plain(inspect.getdoc(method) or "")
        paragraphs = [self.summary, f"Calls GcuClient.{self.method}({names}): {doc}"]
        return "\n\n".join(textwrap.fill(p, 78) for p in paragraphs)


class _Unconnected(CommandMethods):
    """The client's command methods with nothing behind them: every check runs, every
    command "succeeds" without a packet."""

    @property
    def _info(self) -> GcuSubFrame | None:
        return None

    async def _submit(
        self,
        command: Command,
        *,
        timeout: float | None = None,
        queue_timeout: float | None = None,
        control: ControlValues | None = None,
        recording_target: bool | None = None,
    ) -> Feedback | None:
        return Feedback(command_code(command), 0)

    def _set_control(self, control: ControlValues | None, kind: ControlKind) -> None:
        pass

    def _current_attitude(self) -> Attitude:
        return Attitude(0.0, 0.0, 0.0)


_ROLE = re.compile(r":[a-z]+:`~?([^`]+)`")


def _plain(doc: str) -> str:
    """A docstring as plain text: roles and double backquotes dropped, one paragraph."""
    return " ".join(_ROLE.sub(r"\1", doc).replace("``", "").split())


F, N = float, int
DEG = "degrees, -180 to 180"
RATE = f"deg/s, at most {RATE_LIMIT:g}/zoom either way (default 0)"
FRACTION = "image fraction, 0 (left/top) to 1"
CELSIUS = "degrees C, -3276.8 to 3276.7"
ON = "on or off (also 1/0, true/false, yes/no)"
_ALT = f"metres above mean sea level, {ALTITUDE_RANGE[0]:g} to {ALTITUDE_RANGE[1]:g}"
_BOX = tuple(Param(edge, F, FRACTION) for edge in ("left", "top", "right", "bottom"))
_BOX_OPTIONAL = tuple(p._replace(optional=True, help=f"{p.help} (all four or none: the whole "
                                 "image)") for p in _BOX)  # fmt: skip
_ANGLES = (Param("roll", F, DEG), Param("pitch", F, DEG), Param("yaw", F, DEG))

COMMANDS: dict[str, CliCommand] = {
    "calibrate": CliCommand("calibrate", "calibrate the gimbal (0x01)"),
    "centre": CliCommand("centre", "centre pitch and heading (0x03)"),
    "euler": CliCommand("euler_control", "Euler-angle control mode, hold angles (0x14)",
                        (*_ANGLES[:2], Param("yaw", F, "degrees, -180 to 360 (north = 0)")),
                        _keywords("roll", "pitch", "yaw"), angle_target=True, holds=True),
    "angle-control": CliCommand("angle_control", "angle-control mode, yaw relative to the "
                                "aircraft (0x10)", _ANGLES, _keywords("roll", "pitch", "yaw"),
                                holds=True),
    "fpv": CliCommand("fpv", "FPV mode, angles relative to the aircraft (0x1C)", _ANGLES,
                      _keywords("roll", "pitch", "yaw"), holds=True),
    "pointing-lock": CliCommand("pointing_lock", "pointing-lock mode with rates (0x11)",
                                (Param("pitch_rate", F, RATE, True),
                                 Param("yaw_rate", F, RATE, True)),
                                _keywords("pitch_rate", "yaw_rate")),
    "pointing-follow": CliCommand("pointing_follow", "pointing-follow mode with rates (0x12)",
                                  (Param("pitch_rate", F, RATE, True),
                                   Param("yaw_rate", F, RATE, True)),
                                  _keywords("pitch_rate", "yaw_rate")),
    "top-down": CliCommand("top_down", "top-down mode, pitch -90 (0x13)",
                           (Param("yaw_rate", F, RATE, True),), _keywords("yaw_rate")),
    "gaze-at": CliCommand("gaze_at", "gaze at a coordinate (0x15; needs INS data)",
                          (Param("latitude", F, "degrees, -90 to 90"),
                           Param("longitude", F, "degrees, -180 to 180"),
                           Param("altitude", F, _ALT))),
    "gaze-lock": CliCommand("gaze_lock", "gaze at the image centre (0x16; needs INS data)"),
    "track": CliCommand("track", "track the target in a box (0x17)", _BOX,
                        lambda v: ((tuple(v),), {})),
    "stop-tracking": CliCommand("stop_tracking", "exit tracking (0x17)"),
    "click-to-pan": CliCommand("click_to_pan", "bring an image point to the centre (0x1A)",
                               (Param("x", F, FRACTION), Param("y", F, FRACTION))),
    "photo": CliCommand("take_photo", "take a photo (0x20)"),
    "record": CliCommand("toggle_recording", "start or stop recording, a toggle (0x21)"),
    "zoom-in": CliCommand("zoom_in", "start zooming in (0x22)"),
    "zoom-out": CliCommand("zoom_out", "start zooming out (0x23)"),
    "zoom-stop": CliCommand("zoom_stop", "stop zooming (0x24)"),
    "zoom-to": CliCommand("zoom_to", "zoom to a ratio (0x25)",
                          (Param("ratio", F, f"x, 1 to {ZOOM_RATIO_MAX:g}, 0.1 steps"),)),
    "zoom-fraction": CliCommand("zoom_to_fraction", "zoom to a fraction of the maximum (0x25)",
                                (Param("fraction", F, "of the maximum ratio, 0.0001 to 1"),)),
    "focus": CliCommand("focus", "trigger focus (0x26)"),
    "palette": CliCommand("set_palette", "thermal palette (0x2A)",
                          (Param("palette", N, "1 to 10, or 0 to cycle"),)),
    "night-vision": CliCommand("set_night_vision", "night vision (0x2B)",
                               (Param("mode", _night, "off, on or auto"),)),
    "area-temperature": CliCommand("area_temperature", "area temperature measurement (0x30)",
                                   (Param("on", _switch, ON), *_BOX_OPTIONAL), _switch_box,
                                   together=True),
    "temperature-alarm": CliCommand("temperature_alarm", "temperature alarm (0x31)",
                                    (Param("on", _switch, ON), Param("high", F, CELSIUS),
                                     Param("low", F, CELSIUS)), _switch_thresholds),
    "isotherm": CliCommand("isotherm", "isotherm between two temperatures (0x32)",
                           (Param("on", _switch, ON), Param("high", F, CELSIUS),
                            Param("low", F, CELSIUS)), _switch_thresholds),
    "spot-temperature": CliCommand("spot_temperature", "spot temperature at a point (0x33)",
                                   (Param("on", _switch, ON), Param("x", F, FRACTION),
                                    Param("y", F, FRACTION))),
    "osd": CliCommand("set_osd", "on-screen display (0x73)", (Param("on", _switch, ON),)),
    "osd-coordinates": CliCommand("set_osd_coordinates", "OSD coordinates shown (0x06)",
                                  (Param("coordinates", _osd_coords, "aircraft or target"),)),
    "auto-flip": CliCommand("set_image_auto_flip", "image auto-flip (0x07)",
                            (Param("on", _switch, ON),)),
    "time-zone": CliCommand("set_time_zone", "the pod's UTC offset (0x08)",
                            (Param("hours", N, "whole hours, -12 to 14"),)),
    "pip": CliCommand("set_picture_in_picture", "picture-in-picture mode (0x74)",
                      (Param("mode", N, "1 to 4, or 0 to cycle"),)),
    "target-detection": CliCommand("set_target_detection", "AI target detection (0x75)",
                                   (Param("on", _switch, ON),)),
    "digital-zoom": CliCommand("set_digital_zoom", "digital zoom (0x76)",
                               (Param("on", _switch, ON),)),
    "fill-light": CliCommand("set_fill_light", "fill light brightness (0x80)",
                             (Param("brightness", N, "0 (off) to 255"),)),
    "ranging": CliCommand("set_ranging", "continuous laser ranging (0x81)",
                          (Param("on", _switch, ON),)),
}  # fmt: skip
"""Every ``send`` command by name, in the order of docs/cli.md's table."""
