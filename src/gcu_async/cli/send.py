"""``gcu-async send URL COMMAND [ARGS…]``: run one command, print its feedback as JSON.

Exit status: 0 success, 1 failure / timeout / no link, 2 usage error.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from gcu_async.capture import CaptureUnavailable, PacketCapture, as_capture
from gcu_async.cli._exit import (
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_USAGE,
    Interrupted,
    interruptible,
)
from gcu_async.client.client import GcuClient
from gcu_async.client.connect import connect
from gcu_async.errors import CommandFailed, GcuError, LinkLost
from gcu_async.protocol.enums import NightVisionMode, OsdCoordinates
from gcu_async.protocol.feedback import Feedback


def _switch(text: str) -> bool:
    value = text.strip().lower()
    if value in ("on", "1", "true", "yes", "enable"):
        return True
    if value in ("off", "0", "false", "no", "disable"):
        return False
    raise ValueError(f"expected on/off, got {text!r}")


def _night(text: str) -> NightVisionMode:
    try:
        return NightVisionMode[text.strip().upper()]
    except KeyError:
        raise ValueError(f"expected off/on/auto, got {text!r}") from None


def _osd_coords(text: str) -> OsdCoordinates:
    try:
        return OsdCoordinates[text.strip().upper()]
    except KeyError:
        raise ValueError(f"expected aircraft/target, got {text!r}") from None


Call = Callable[[GcuClient, list[Any]], Any]


@dataclass(frozen=True)
class CliCommand:
    params: tuple[tuple[str, Callable[[str], Any]], ...]
    call: Call
    optional: int = 0
    """How many trailing parameters may be omitted (the method's defaults apply)."""
    angle_target: bool = False
    """The parameters are roll/pitch/yaw targets of an angle mode."""
    holds: bool = False
    """A mode command whose control values need packets to act (default ``--hold`` 3 s)."""


F, N = float, int
COMMANDS: dict[str, CliCommand] = {
    "calibrate": CliCommand((), lambda g, a: g.calibrate()),
    "centre": CliCommand((), lambda g, a: g.centre()),
    "euler": CliCommand((("roll", F), ("pitch", F), ("yaw", F)),
                        lambda g, a: g.euler_control(roll=a[0], pitch=a[1], yaw=a[2]),
                        angle_target=True, holds=True),
    "angle-control": CliCommand((("roll", F), ("pitch", F), ("yaw", F)),
                                lambda g, a: g.angle_control(roll=a[0], pitch=a[1], yaw=a[2]),
                                holds=True),
    "fpv": CliCommand((("roll", F), ("pitch", F), ("yaw", F)),
                      lambda g, a: g.fpv(roll=a[0], pitch=a[1], yaw=a[2]), holds=True),
    "pointing-lock": CliCommand((("pitch_rate", F), ("yaw_rate", F)),
                                lambda g, a: g.pointing_lock(**_kw(a, "pitch_rate", "yaw_rate")),
                                optional=2),
    "pointing-follow": CliCommand(
        (("pitch_rate", F), ("yaw_rate", F)),
        lambda g, a: g.pointing_follow(**_kw(a, "pitch_rate", "yaw_rate")), optional=2),
    "top-down": CliCommand((("yaw_rate", F),), lambda g, a: g.top_down(**_kw(a, "yaw_rate")),
                           optional=1),
    "gaze-at": CliCommand((("latitude", F), ("longitude", F), ("altitude", F)),
                          lambda g, a: g.gaze_at(*a)),
    "gaze-lock": CliCommand((), lambda g, a: g.gaze_lock()),
    "track": CliCommand((("left", F), ("top", F), ("right", F), ("bottom", F)),
                        lambda g, a: g.track(tuple(a))),
    "stop-tracking": CliCommand((), lambda g, a: g.stop_tracking()),
    "click-to-pan": CliCommand((("x", F), ("y", F)), lambda g, a: g.click_to_pan(*a)),
    "photo": CliCommand((), lambda g, a: g.take_photo()),
    "record": CliCommand((), lambda g, a: g.toggle_recording()),
    "zoom-in": CliCommand((), lambda g, a: g.zoom_in()),
    "zoom-out": CliCommand((), lambda g, a: g.zoom_out()),
    "zoom-stop": CliCommand((), lambda g, a: g.zoom_stop()),
    "zoom-to": CliCommand((("ratio", F),), lambda g, a: g.zoom_to(a[0])),
    "zoom-fraction": CliCommand((("fraction", F),), lambda g, a: g.zoom_to_fraction(a[0])),
    "focus": CliCommand((), lambda g, a: g.focus()),
    "palette": CliCommand((("palette", N),), lambda g, a: g.set_palette(a[0])),
    "night-vision": CliCommand((("mode", _night),), lambda g, a: g.set_night_vision(a[0])),
    "area-temperature": CliCommand(
        (("on", _switch), ("left", F), ("top", F), ("right", F), ("bottom", F)),
        lambda g, a: g.area_temperature(a[0], tuple(a[1:]) if len(a) > 1 else (0, 0, 1, 1)),
        optional=4),
    "temperature-alarm": CliCommand((("on", _switch), ("high", F), ("low", F)),
                                    lambda g, a: g.temperature_alarm(a[0], high=a[1], low=a[2])),
    "isotherm": CliCommand((("on", _switch), ("high", F), ("low", F)),
                           lambda g, a: g.isotherm(a[0], high=a[1], low=a[2])),
    "spot-temperature": CliCommand((("on", _switch), ("x", F), ("y", F)),
                                   lambda g, a: g.spot_temperature(*a)),
    "osd": CliCommand((("on", _switch),), lambda g, a: g.set_osd(a[0])),
    "osd-coordinates": CliCommand((("coordinates", _osd_coords),),
                                  lambda g, a: g.set_osd_coordinates(a[0])),
    "auto-flip": CliCommand((("on", _switch),), lambda g, a: g.set_image_auto_flip(a[0])),
    "time-zone": CliCommand((("hours", N),), lambda g, a: g.set_time_zone(a[0])),
    "pip": CliCommand((("mode", N),), lambda g, a: g.set_picture_in_picture(a[0])),
    "target-detection": CliCommand((("on", _switch),),
                                   lambda g, a: g.set_target_detection(a[0])),
    "digital-zoom": CliCommand((("on", _switch),), lambda g, a: g.set_digital_zoom(a[0])),
    "fill-light": CliCommand((("brightness", N),), lambda g, a: g.set_fill_light(a[0])),
    "ranging": CliCommand((("on", _switch),), lambda g, a: g.set_ranging(a[0])),
}  # fmt: skip


def _kw(values: list[Any], *names: str) -> dict[str, Any]:
    """Keyword arguments for the given (possibly fewer) positional values."""
    return dict(zip(names, values, strict=False))


def register(sub: Any) -> None:
    names = ", ".join(COMMANDS)
    p = sub.add_parser(
        "send",
        help="send one command to a GCU and print its feedback as JSON",
        description=f"Commands: {names}. Exit 0 on success, 1 on failure or timeout, 2 on "
        "a usage error.",
    )
    p.add_argument("url", help="udp://HOST[:PORT], tcp://HOST[:PORT] or serial:///dev/…")
    p.add_argument("name", metavar="COMMAND", help="command name (see above)")
    p.add_argument("args", nargs="*", metavar="ARG", help="command arguments")
    p.add_argument("--timeout", type=float, default=5.0, help="seconds to wait (default 5)")
    p.add_argument("--rate", type=float, default=50.0, help="heartbeat rate in Hz (default 50)")
    p.add_argument(
        "--hold",
        type=float,
        default=None,
        metavar="SECONDS",
        help="after a mode command, keep sending its control values this long (default 3 s "
        "for euler/angle-control/fpv, stopping early once the camera is there; 0 otherwise)",
    )
    p.add_argument("--capture", type=Path, metavar="FILE",
                   help="write the packets exchanged to FILE (pcapng; open it in Wireshark "
                   "with the dissector: gcu-async wireshark --install)")  # fmt: skip
    p.set_defaults(run=run)


def parse_args(name: str, raw: Sequence[str]) -> tuple[CliCommand, list[Any]]:
    """Look up ``name`` and convert its arguments; raise ValueError with a one-line reason."""
    spec = COMMANDS.get(name)
    if spec is None:
        raise ValueError(f"unknown command {name!r}; one of: {', '.join(COMMANDS)}")
    need = len(spec.params) - spec.optional
    if not need <= len(raw) <= len(spec.params):
        expected = " ".join(p for p, _ in spec.params) or "no arguments"
        raise ValueError(f"{name} takes {expected}; got {len(raw)} argument(s)")
    values: list[Any] = []
    for (pname, convert), text in zip(spec.params, raw, strict=False):
        try:
            values.append(convert(text))
        except ValueError as exc:
            raise ValueError(f"{name}: {pname}: {exc}") from None
    return spec, values


ANGLE_MODES = {"euler", "angle-control", "fpv"}


async def _send(
    url: str, spec: CliCommand, values: list[Any], timeout: float, rate: float, hold: float,
    capture: PacketCapture | None = None,
) -> tuple[Any, dict[str, Any]]:
    async with connect(url, command_timeout=timeout, connect_timeout=timeout, rate_hz=rate,
                       capture=capture) as gcu:  # fmt: skip
        feedback = await spec.call(gcu, values)
        # Control values only act while packets carry them: hold them for a while (angle
        # modes stop early once the camera's attitude matches the target).
        deadline = time.monotonic() + hold
        while time.monotonic() < deadline:
            if spec.angle_target and _arrived(gcu, values):
                break
            await asyncio.sleep(0.05)
        return feedback, {"attitude_deg": gcu.status.attitude._asdict(),
                          "mode": gcu.status.mode.name}  # fmt: skip


def _arrived(gcu: GcuClient, values: list[Any]) -> bool:
    pitch, yaw = float(values[1]), float(values[2])
    att = gcu.status.attitude
    return abs(att.pitch - pitch) < 0.5 and abs((att.yaw - yaw + 180) % 360 - 180) < 0.5


def run(args: argparse.Namespace) -> int:
    try:
        spec, values = parse_args(args.name, args.args)
        if not args.timeout > 0:
            raise ValueError(f"--timeout: {args.timeout!r} must be > 0")
        # validate the command's arguments before opening anything
        connect(args.url)
        capture = as_capture(args.capture)
    except (ValueError, CaptureUnavailable) as exc:
        print(f"gcu-async send: {exc}", file=sys.stderr)
        return EXIT_USAGE
    hold = args.hold if args.hold is not None else (3.0 if spec.holds else 0.0)
    if not 0 <= hold <= 3600:
        print(f"gcu-async send: --hold: {hold!r} is outside [0, 3600] s", file=sys.stderr)
        return EXIT_USAGE
    try:
        feedback, state = asyncio.run(interruptible(
            _send(args.url, spec, values, args.timeout, args.rate, hold, capture)))  # fmt: skip
    except (Interrupted, KeyboardInterrupt):  # KeyboardInterrupt: no loop signal handlers
        print(json.dumps({"ok": False, "error": "interrupted"}))
        return EXIT_INTERRUPTED
    except ValueError as exc:
        print(f"gcu-async send: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except CommandFailed as exc:
        out = {"ok": False, "error": str(exc), "opcode": exc.opcode, "status_raw": exc.status,
               "failed_cameras": int(exc.failed_cameras)}  # fmt: skip
        print(json.dumps(out))
        return EXIT_FAILED
    except (TimeoutError, LinkLost, GcuError, OSError) as exc:
        print(json.dumps({"ok": False, "error": str(exc) or type(exc).__name__}))
        return EXIT_FAILED
    if feedback is None:
        print(json.dumps({"ok": True, "skipped": True}))
        return EXIT_OK
    assert isinstance(feedback, Feedback)
    print(json.dumps({"ok": True, **feedback.as_dict(), **state}))
    return EXIT_OK
