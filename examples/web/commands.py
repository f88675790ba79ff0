"""The command table of the web example: URL name → typed parameters → client method.

Each entry names the JSON parameters it accepts (type, default or required) and the
:class:`~gcu_async.GcuClient` method it calls. :func:`parse_params` checks a request body
against an entry and raises ``ValueError`` naming the parameter for anything wrong (unknown
names, wrong types, missing required values, non-finite numbers); ranges are checked by the
protocol core when the command is built (``FieldRangeError``, also a ``ValueError``).
"""

from __future__ import annotations

import math
from collections.abc import Awaitable, Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from gcu_async import GcuClient
from gcu_async.protocol import CameraMask, Feedback, NightVisionMode

REQUIRED: Any = object()
"""Marker default: the parameter must be given."""

CAM1 = int(CameraMask.CAMERA_1)
CAM2 = int(CameraMask.CAMERA_2)

Call = Callable[..., Awaitable[Feedback | None]]


@dataclass(frozen=True)
class Param:
    """One JSON parameter: ``kind`` is ``"float"``, ``"int"``, ``"bool"`` or ``"box"``
    (``[left, top, right, bottom]`` image fractions)."""

    kind: str
    default: Any = REQUIRED

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    def describe(self) -> dict[str, Any]:
        if self.required:
            return {"type": self.kind, "required": True}
        return {"type": self.kind, "default": self.default}


@dataclass(frozen=True)
class CommandSpec:
    """A command the web API exposes."""

    name: str
    method: str
    """Name of the :class:`GcuClient` method called with the parsed parameters."""
    doc: str
    params: Mapping[str, Param] = field(default_factory=dict)
    positional: tuple[str, ...] = ()
    """Parameters passed positionally (the rest go by keyword)."""

    def describe(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "doc": self.doc,
            "params": {name: p.describe() for name, p in self.params.items()},
        }

    async def run(self, gcu: GcuClient, values: Mapping[str, Any]) -> Feedback | None:
        """Call the client method with already parsed ``values``."""
        method: Call = getattr(gcu, self.method)
        args = [values[name] for name in self.positional]
        kwargs = {k: v for k, v in values.items() if k not in self.positional}
        return await method(*args, **kwargs)


def _cams(default: int = CAM1) -> dict[str, Param]:
    return {"cameras": Param("int", default)}


_F0 = Param("float", 0.0)
_ON = {"enabled": Param("bool", True)}
_ANGLES = {"roll": _F0, "pitch": _F0, "yaw": _F0}
_RATES = {"pitch_rate": _F0, "yaw_rate": _F0}

COMMANDS: dict[str, CommandSpec] = {
    spec.name: spec
    for spec in (
        CommandSpec("photo", "take_photo", "Take a photo (0x20).", _cams()),
        CommandSpec("record", "toggle_recording", "Toggle recording (0x21).", _cams()),
        CommandSpec("record_start", "start_recording",
                    "Start recording unless already recording (feedback null then).", _cams()),
        CommandSpec("record_stop", "stop_recording",
                    "Stop recording if recording (feedback null otherwise).", _cams()),
        CommandSpec("zoom_in", "zoom_in", "Zoom in until zoom_stop (0x22).", _cams()),
        CommandSpec("zoom_out", "zoom_out", "Zoom out until zoom_stop (0x23).", _cams()),
        CommandSpec("zoom_stop", "zoom_stop", "Stop a continuous zoom (0x24).", _cams()),
        CommandSpec("zoom_to", "zoom_to", "Zoom to a ratio, 0.1x resolution (0x25).",
                    {"ratio": Param("float"), **_cams()}, ("ratio",)),
        CommandSpec("zoom_to_fraction", "zoom_to_fraction",
                    "Zoom to a fraction (0, 1] of the maximum (0x25).",
                    {"fraction": Param("float"), **_cams()}, ("fraction",)),
        CommandSpec("focus", "focus", "Trigger focus (0x26).", _cams()),
        CommandSpec("euler_control", "euler_control",
                    "Euler-angle mode holding roll/pitch/yaw in degrees (0x14).", _ANGLES),
        CommandSpec("angle_control", "angle_control",
                    "Angle-control mode, yaw relative to the aircraft (0x10).", _ANGLES),
        CommandSpec("fpv", "fpv", "FPV mode, angles relative to the aircraft (0x1C).", _ANGLES),
        CommandSpec("pointing_lock", "pointing_lock",
                    "Pointing-lock mode with pitch/yaw rates in deg/s (0x11).", _RATES),
        CommandSpec("pointing_follow", "pointing_follow",
                    "Pointing-follow mode with pitch/yaw rates in deg/s (0x12).", _RATES),
        CommandSpec("top_down", "top_down", "Top-down mode, yaw rate in deg/s (0x13).",
                    {"yaw_rate": _F0}),
        CommandSpec("centre", "centre", "Centre pitch and heading (0x03)."),
        CommandSpec("calibrate", "calibrate", "Calibrate; waits while in progress (0x01).",
                    {"timeout": Param("float", 15.0)}),
        CommandSpec("track", "track",
                    "Track the target in box [left, top, right, bottom] fractions (0x17).",
                    {"box": Param("box"), **_cams()}, ("box",)),
        CommandSpec("stop_tracking", "stop_tracking", "Exit tracking (0x17, TT = 0).", _cams()),
        CommandSpec("click_to_pan", "click_to_pan",
                    "Bring image point (x, y) fractions to the centre (0x1A).",
                    {"x": Param("float"), "y": Param("float"), **_cams()}, ("x", "y")),
        CommandSpec("palette", "set_palette", "Thermal palette 1-10, 0 cycles (0x2A).",
                    {"palette": Param("int", 0), **_cams(CAM2)}, ("palette",)),
        CommandSpec("night_vision", "set_night_vision",
                    "Night vision mode 0 off, 1 on, 2 auto (0x2B).",
                    {"mode": Param("int", int(NightVisionMode.ON)), **_cams()}, ("mode",)),
        CommandSpec("ranging", "set_ranging", "Continuous laser ranging on/off (0x81).",
                    _ON, ("enabled",)),
        CommandSpec("osd", "set_osd", "On-screen display on/off (0x73).", _ON, ("enabled",)),
        CommandSpec("digital_zoom", "set_digital_zoom", "Digital zoom on/off (0x76).",
                    _ON, ("enabled",)),
        CommandSpec("target_detection", "set_target_detection",
                    "AI target detection on/off (0x75).", _ON, ("enabled",)),
        CommandSpec("picture_in_picture", "set_picture_in_picture",
                    "Picture-in-picture mode 1-4, 0 cycles (0x74).",
                    {"mode": Param("int", 0)}, ("mode",)),
        CommandSpec("fill_light", "set_fill_light", "Fill light brightness 0-255 (0x80).",
                    {"brightness": Param("int")}, ("brightness",)),
    )
}  # fmt: skip
"""Every command the web API exposes, by URL name."""


def parse_params(spec: CommandSpec, body: object) -> dict[str, Any]:
    """The parameters of ``spec`` from a decoded JSON body (an object, or ``None`` for no
    body), with defaults filled in. Raises ``ValueError`` naming the offending parameter."""
    if body is None:
        body = {}
    if not isinstance(body, dict):
        raise ValueError(f"{spec.name}: the body must be a JSON object, got {_json_type(body)}")
    unknown = sorted(set(body) - set(spec.params))
    if unknown:
        allowed = ", ".join(spec.params) or "none"
        raise ValueError(f"{spec.name}: unknown parameter(s) {', '.join(unknown)} "
                         f"(allowed: {allowed})")  # fmt: skip
    values: dict[str, Any] = {}
    for name, param in spec.params.items():
        if name in body:
            values[name] = _convert(name, param.kind, body[name])
        elif param.required:
            raise ValueError(f"{name}: required parameter of {spec.name} is missing")
        else:
            values[name] = param.default
    return values


def _convert(name: str, kind: str, value: object) -> Any:
    if kind == "float":
        return _number(name, value)
    if kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError(f"{name}: expected an integer, got {_json_type(value)} {value!r}")
        return value
    if kind == "bool":
        if not isinstance(value, bool):
            raise ValueError(f"{name}: expected true or false, got {_json_type(value)} {value!r}")
        return value
    if kind == "box":
        if not isinstance(value, list) or len(value) != 4:
            raise ValueError(
                f"{name}: expected [left, top, right, bottom] (4 numbers), got {value!r}"
            )
        return tuple(_number(f"{name}[{i}]", v) for i, v in enumerate(value))
    raise AssertionError(f"unknown parameter kind {kind!r}")  # pragma: no cover


def _number(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{name}: expected a number, got {_json_type(value)} {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"{name}: {value!r} is not a finite number")
    return float(value)


def _json_type(value: object) -> str:
    names = {dict: "object", list: "array", str: "string", bool: "boolean", type(None): "null"}
    return names.get(type(value), "number")
