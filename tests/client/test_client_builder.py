"""The command builder (gcu_async.protocol.builder) and the client composed around it.

- every catalogue entry has exactly one client method, one line naming what it sends: the
  entry's command class, or the builder function of the entry's own name when the method does
  more than call the class (test_catalogue.py checks the method's parameters against the
  entry: names, order, defaults, annotations);
- the builder and the client method give the same error (type and message) for every bad
  argument of every entry, and the same command for good ones: the method adds nothing;
- the arguments that depend on the GCU's state (Euler angles left out, rate limits at zoom,
  ``max_zoom``) follow the :class:`Context` given;
- ``gcu-async send`` checks its arguments with the builder, without an event loop;
- the client's public surface is the one before the parts were composed (pinned below);
- ``rate_hz`` and ``version`` are checked in one place, the session, and still refused at
  ``GcuClient(...)`` with the session's message.
"""

from __future__ import annotations

import asyncio
import inspect
import math
import warnings
from typing import Any

import pytest

from gcu_async import GcuClient, GcuSubFrame
from gcu_async.cli.send_commands import COMMANDS
from gcu_async.errors import CommandLinkLost, FieldRangeError
from gcu_async.protocol import Feedback, command_code
from gcu_async.protocol import commands as c
from gcu_async.protocol.builder import MAKERS, Context, Submission, angles, build, rates
from gcu_async.protocol.catalogue import BY_METHOD, CATALOGUE, CatalogueEntry, Kind, Parameter
from gcu_async.protocol.gcu_frames import GcuMainFrame
from gcu_async.protocol.host_frame_tables import ControlValues
from gcu_async.protocol.units import Attitude, ImageBox, ImagePoint
from gcu_async.session import Session
from gcu_async.transport.memory import MemoryTransport
from helpers.client import methods as client_methods
from helpers.protocol.catalogue_samples import required_samples

IDS = [e.method for e in CATALOGUE]
def good(entry: CatalogueEntry) -> dict[str, Any]:
    return required_samples(entry)


def bad_values(p: Parameter) -> list[object]:
    """Values ``p`` refuses: wrong types, and the first values outside each bound."""
    out: list[object] = ["1", object()]
    if p.kind is not Kind.SWITCH:
        out.append(True)
    if p.kind in (Kind.REAL, Kind.INTEGER, Kind.CAMERAS):
        assert p.low is not None and p.high is not None
        step = 1 if p.kind is not Kind.REAL else max(abs(p.low), abs(p.high), 1.0) * 1e-6
        out += [p.low - step, math.nan] + ([] if math.isinf(p.high) else [p.high + step])
        if p.low_open:
            out.append(p.low)
        if p.kind is not Kind.REAL:
            out.append(float(p.low))
    if p.kind is Kind.CHOICE:
        assert p.choices is not None
        out.append(max(p.choices) + 1)
    if p.kind is Kind.BOX:
        out += [(0.0, 0.0, 1.0), (0.0, 0.0, 1.5, 1.0), [0.0, -0.1, 1.0, 1.0], (0, 0, 1, "1")]
    if p.kind is Kind.SWITCH:
        out.append(1)
    return out


def outcome(call: Any) -> tuple[type[BaseException], str] | Submission:
    try:
        return call()
    except Exception as exc:
        return type(exc), str(exc)


async def through_client(entry: CatalogueEntry, **kwargs: Any) -> tuple[type[BaseException], str]:
    """What the client method raises for ``kwargs`` on a client that is not open: an
    argument error, else "not opened" (nothing can be sent)."""
    gcu = GcuClient(MemoryTransport())
    try:
        await getattr(gcu, entry.method)(**kwargs)
    except Exception as exc:
        return type(exc), str(exc)
    raise AssertionError(f"{entry.method} sent on a client that is not open")


# -- one client method per entry, one line each -------------------------------------------
def test_every_entry_has_exactly_one_client_method_sending_it() -> None:
    sent = client_methods.sent_names()
    assert set(sent) == set(BY_METHOD)
    for method, names in sent.items():
        expected = method if method in MAKERS else BY_METHOD[method].command.__name__
        assert names == [expected], f"{method} sends {names}"


@pytest.mark.parametrize("entry", CATALOGUE, ids=IDS)
def test_the_method_is_one_line_of_delegation(entry: CatalogueEntry) -> None:
    source = inspect.getsource(getattr(GcuClient, entry.method))
    body = source.split('"""')[-1].strip().splitlines()
    assert body[0].startswith(("return await self._run(", "return await self._build(",
                               "return await self._send("))  # fmt: skip
    assert len([line for line in body if "# fmt: skip" not in line or line is body[-1]]) <= 2


def test_the_one_line_check_can_fail() -> None:
    """A method that does more than delegate is caught: execute names no command."""
    assert "execute" not in client_methods.sent_names()
    assert client_methods.SENDS.findall("self._build(builder.zoom_to, ratio=ratio)") == [
        "zoom_to"]
    assert client_methods.SENDS.findall("self._run(c.TakePhoto(cameras=cameras))") == [
        "TakePhoto"]


# -- builder == client method --------------------------------------------------------------
@pytest.mark.parametrize("entry", CATALOGUE, ids=IDS)
async def test_bad_arguments_raise_the_same_error_both_ways(entry: CatalogueEntry) -> None:
    checked = 0
    for p in entry.parameters:
        for value in bad_values(p):
            kwargs = {**good(entry), p.name: value}
            expected = outcome(lambda kw=kwargs: build(entry, **kw))
            assert isinstance(expected, tuple), (entry.method, p.name, value)
            assert expected[0] in (TypeError, FieldRangeError), expected
            assert expected[1].startswith(f"{p.name}"), expected
            assert await through_client(entry, **kwargs) == expected, (p.name, value)
            checked += 1
    assert checked >= 3 * len(entry.parameters)


@pytest.mark.parametrize("entry", CATALOGUE, ids=IDS)
async def test_good_arguments_build_and_the_client_only_refuses_to_send(
    entry: CatalogueEntry,
) -> None:
    submission = build(entry, **good(entry))
    assert type(submission.command) is entry.command
    error, message = await through_client(entry, **good(entry))
    assert error is CommandLinkLost and "not opened" in message


@pytest.mark.parametrize("entry", [e for e in CATALOGUE if e.method not in MAKERS],
                         ids=lambda e: e.method)  # fmt: skip
async def test_a_plain_command_gets_each_value_in_its_field_of_the_same_name(
    entry: CatalogueEntry, monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A method without a builder function calls its class with its arguments by name, as
    ``build`` does: each value lands in the field of the same name (a swap in the method's
    body shows), and the method submits exactly what ``build`` makes."""
    distinct = {p.name: p for p in entry.parameters}
    given = {name: _non_default(p, i) for i, (name, p) in enumerate(distinct.items())}
    submission = build(entry, **given)
    for name in distinct:
        assert getattr(submission.command, name) == given[name], (entry.method, name)
    gcu = GcuClient(MemoryTransport())
    submitted: list[Submission] = []

    async def run(made: Submission, **options: Any) -> Feedback:
        submitted.append(made)
        return Feedback(command_code(made.command), 0)

    monkeypatch.setattr(gcu._driver, "run", run)
    await getattr(gcu, entry.method)(**given)
    assert submitted == [submission]


def _non_default(p: Parameter, i: int) -> object:
    """A valid value other than the default, different for each position ``i`` (so a swap
    of two fields of the same kind and range shows)."""
    if p.kind is Kind.SWITCH:
        return p.default is not True
    if p.kind is Kind.CHOICE:
        assert p.choices is not None
        return next(m for m in p.choices if m != p.default)
    if p.kind in (Kind.INTEGER, Kind.CAMERAS):
        assert p.high is not None
        value = int(p.high) - i
        return value if value != p.default else value - 1
    if p.kind is Kind.BOX:
        return (0.1, 0.2, 0.7, 0.8)
    assert p.low is not None and p.high is not None
    # decreasing with i: a high threshold (before its low) stays above it
    return p.low + (min(p.high, p.low + 100.0) - p.low) * (0.77 - 0.1 * i)


def test_missing_and_unknown_arguments_are_type_errors() -> None:
    with pytest.raises(TypeError, match=r"^zoom_to\(\) missing required argument: 'ratio'$"):
        build("zoom_to")
    with pytest.raises(TypeError, match=r"^zoom_to\(\) got an unexpected argument 'speed'$"):
        build("zoom_to", ratio=2.0, speed=1)
    with pytest.raises(KeyError):
        build("defog")


# -- what each entry builds ----------------------------------------------------------------
def test_submissions_carry_control_recording_intent_and_timeout() -> None:
    assert build("calibrate") == Submission(c.Calibration(), timeout=15.0)
    assert build("calibrate", timeout=3) == Submission(c.Calibration(), timeout=3.0)
    assert build("start_recording").recording_target is True
    assert build("stop_recording", cameras=3) == Submission(c.Record(3), recording_target=False)
    assert build("toggle_recording").recording_target is None
    assert build("track", box=[0.1, 0.2, 0.3, 0.4]).command == c.Track(
        True, ImageBox(0.1, 0.2, 0.3, 0.4))
    assert build("stop_tracking", cameras=2).command == c.Track(False, cameras=2)
    assert build("set_spot_temperature", enabled=False, x=0.25).command == c.SpotTemperature(
        False, ImagePoint(0.25, 0.5))
    assert build("zoom_to_fraction", fraction=0.5).command == c.ZoomTo(fraction=0.5)
    assert build("gaze_at", **good(BY_METHOD["gaze_at"])).control is None
    assert build("enter_fpv", yaw=-10).control == ControlValues.angles(0.0, 0.0, -10.0)


def test_euler_angles_left_out_keep_the_current_attitude_and_yaw_wraps() -> None:
    here = Context(attitude=Attitude(1.0, -30.0, 120.0))
    assert build("enter_euler_control", here, pitch=-45).control == ControlValues.angles(
        1.0, -45.0, 120.0)
    assert build("enter_euler_control", yaw=270.0).control == ControlValues.angles(
        0.0, 0.0, -90.0)
    with pytest.raises(FieldRangeError, match=r"^yaw: 360\.0 .*\[-180, 360\) deg"):
        build("enter_euler_control", yaw=360.0)


def test_euler_angles_are_checked_yaw_first() -> None:
    """With several bad angles the yaw is named, then the roll (the order the method always
    checked them in)."""
    with pytest.raises(FieldRangeError, match=r"^yaw: "):
        build("enter_euler_control", roll=999.0, pitch=999.0, yaw=999.0)
    with pytest.raises(FieldRangeError, match=r"^roll: "):
        build("enter_euler_control", roll=999.0, pitch=999.0)


def test_rate_limits_are_divided_by_the_zoom() -> None:
    assert build("enter_pointing_lock", pitch_rate=150.0).control == ControlValues.rates(
        0.0, 150.0, 0.0)
    zoomed = Context(zoom=10.0)
    assert build("enter_top_down", zoomed, yaw_rate=15.0).control == ControlValues.rates(
        0.0, 0.0, 15.0, zoom=10.0)
    with pytest.raises(FieldRangeError, match=r"^yaw_rate: 15\.1 .*deg/s at zoom 10x"):
        build("enter_top_down", zoomed, yaw_rate=15.1)
    assert rates(zoomed, roll=-15.0, pitch=0.0, yaw=1.0) == ControlValues.rates(
        -15.0, 0.0, 1.0, zoom=10.0)
    with pytest.raises(FieldRangeError, match=r"^roll: "):
        rates(zoomed, roll=-15.5, pitch=0.0, yaw=0.0)
    with pytest.raises(FieldRangeError, match=r"^pitch: 181"):
        angles(0.0, 181, 0.0)


def test_max_zoom_caps_the_ratio() -> None:
    assert build("zoom_to", ratio=3000.0).command == c.ZoomTo(ratio=3000.0)
    with pytest.raises(FieldRangeError, match=r"^ratio: 31\.0 .*camera 1's maximum zoom is 30x"):
        build("zoom_to", Context(max_zoom=30.0), ratio=31.0)
    assert build("zoom_to_fraction", Context(max_zoom=30.0), fraction=1.0)


def test_context_of_the_reports() -> None:
    assert Context.of(None, None) == Context()
    status = GcuMainFrame.build(attitude=(5.0, -10.0, 20.0))
    info = GcuSubFrame.build(camera1_zoom=4.0)
    assert Context.of(status, info, 30.0) == Context(status.attitude, 4.0, 30.0)
    assert Context.of(None, GcuSubFrame.build(camera1_zoom=0.0)).zoom == 1.0  # not reported


# -- the CLI checks with the builder -------------------------------------------------------
async def test_send_checks_its_arguments_inside_a_running_loop() -> None:
    """No fake client and no event loop of its own: the check is the builder's."""
    spec = COMMANDS["zoom-to"]
    spec.check([10.0])
    with pytest.raises(FieldRangeError, match=r"^ratio: 0\.5"):
        spec.check([0.5])
    with pytest.raises(FieldRangeError, match=r"^cameras: 0 "):
        spec.check([2.0], cameras=0)
    with pytest.raises(FieldRangeError, match=r"^box\.right: 1\.5"):
        COMMANDS["track"].check([0.0, 0.0, 1.5, 1.0])


# -- the client's surface --------------------------------------------------------------------
SURFACE = {
    "__aenter__": "await (self: '_T') -> '_T'",
    "__aexit__": (
        "await (self, exc_type: 'type[BaseException] | None', exc: 'BaseException | None', "
        "tb: 'TracebackType | None') -> 'None'"
    ),
    "__await__": "call (self) -> 'Generator[Any, None, GcuClient]'",
    "__init__": (
        "call (self, transport: 'Transport', *, rate_hz: 'float' = 50.0, "
        "command_timeout: 'float' = 2.0, queue_timeout: 'float' = 30.0, "
        "connect_timeout: 'float' = 3.0, open_timeout: 'float | None' = None, "
        "wait: 'bool' = True, restore: 'bool' = False, "
        "silence_timeout: 'float' = 1.0, check_support: 'bool' = False, "
        "reorder_guard: 'float | None' = None, aircraft_timeout: 'float' = 1.0, "
        "version: 'int' = 2, clock: 'Callable[[], float]' = <built-in function monotonic>, "
        "capture: 'PacketCapture | str | os.PathLike[str] | None' = None, "
        "max_zoom: 'float | None' = None, conformance: 'bool' = False) -> 'None'"
    ),
    "aircraft": "property",
    "aircraft_timeout": "property",
    "calibrate": "await (self, *, timeout: 'float' = 15.0) -> 'Feedback'",
    "centre": "await (self) -> 'Feedback'",
    "click_to_pan": (
        "await (self, x: 'float', y: 'float', *, "
        "cameras: 'int' = <CameraMask.CAMERA_1: 1>) -> 'Feedback'"
    ),
    "close": "await (self) -> 'None'",
    "command_timeout": "property",
    "conformance": "property",
    "conformance_report": "call (self) -> 'GcuReport'",
    "control": "property",
    "control_valid": "property",
    "enter_angle_control": (
        "await (self, *, roll: 'float' = 0.0, pitch: 'float' = 0.0, "
        "yaw: 'float' = 0.0) -> 'Feedback'"
    ),
    "enter_euler_control": (
        "await (self, *, roll: 'float | None' = None, pitch: 'float | None' = None, "
        "yaw: 'float | None' = None) -> 'Feedback'"
    ),
    "enter_fpv": (
        "await (self, *, roll: 'float' = 0.0, pitch: 'float' = 0.0, "
        "yaw: 'float' = 0.0) -> 'Feedback'"
    ),
    "enter_gaze_lock": (
        "await (self, *, pitch_rate: 'float' = 0.0, yaw_rate: 'float' = 0.0) -> 'Feedback'"
    ),
    "enter_pointing_follow": (
        "await (self, *, pitch_rate: 'float' = 0.0, yaw_rate: 'float' = 0.0) -> 'Feedback'"
    ),
    "enter_pointing_lock": (
        "await (self, *, pitch_rate: 'float' = 0.0, yaw_rate: 'float' = 0.0) -> 'Feedback'"
    ),
    "enter_top_down": "await (self, *, yaw_rate: 'float' = 0.0) -> 'Feedback'",
    "execute": (
        "await (self, command: 'Command', *, timeout: 'float | None' = None, "
        "queue_timeout: 'float | None' = None) -> 'Feedback'"
    ),
    "focus": "await (self, *, cameras: 'int' = <CameraMask.CAMERA_1: 1>) -> 'Feedback'",
    "gaze_at": (
        "await (self, latitude: 'float', longitude: 'float', altitude: 'float') -> 'Feedback'"
    ),
    "failure": "property",
    "info": "property",
    "ins_valid": "property",
    "link": "property",
    "link_events": "async for (self) -> 'AsyncGenerator[LinkEvent, None]'",
    "max_zoom": "property",
    "on_link_change": "call (self, callback: 'LinkCallback') -> 'Callable[[], None]'",
    "on_telemetry": "call (self, callback: 'TelemetryCallback') -> 'Callable[[], None]'",
    "open": "await (self) -> 'None'",
    "pod_model": "property",
    "queue_timeout": "property",
    "rate_hz": "property",
    "reach_attitude": (
        "await (self, *, roll: 'float | None' = None, pitch: 'float | None' = None, "
        "yaw: 'float | None' = None, tolerance: 'float' = 0.5, "
        "timeout: 'float' = 10.0) -> 'TelemetrySample'"
    ),
    "reach_zoom": (
        "await (self, ratio: 'float', *, tolerance: 'float' = 0.05, "
        "timeout: 'float' = 10.0) -> 'TelemetrySample'"
    ),
    "recording": "property",
    "release_control": "call (self) -> 'None'",
    "reorder_guard": "property",
    "set_aircraft": "call (self, state: 'AircraftState') -> 'None'",
    "set_angles": (
        "call (self, *, roll: 'float' = 0.0, pitch: 'float' = 0.0, yaw: 'float' = 0.0) -> 'None'"
    ),
    "set_area_temperature": (
        "await (self, enabled: 'bool' = True, box: 'ImageBox | tuple[float, float, float, "
        "float] | list[float]' = (0.0, 0.0, 1.0, 1.0), *, "
        "cameras: 'int' = <CameraMask.CAMERA_2: 2>) -> 'Feedback'"
    ),
    "set_control": "call (self, control: 'ControlValues | None') -> 'None'",
    "set_digital_zoom": "await (self, enabled: 'bool' = True) -> 'Feedback'",
    "set_fill_light": "await (self, brightness: 'int') -> 'Feedback'",
    "set_image_auto_flip": "await (self, enabled: 'bool' = True) -> 'Feedback'",
    "set_isotherm": (
        "await (self, enabled: 'bool' = True, *, high: 'float' = 0.0, low: 'float' = 0.0, "
        "cameras: 'int' = <CameraMask.CAMERA_2: 2>) -> 'Feedback'"
    ),
    "set_night_vision": (
        "await (self, mode: 'NightVisionMode | int' = <NightVisionMode.ON: 1>, *, "
        "cameras: 'int' = <CameraMask.CAMERA_1: 1>) -> 'Feedback'"
    ),
    "set_osd": "await (self, enabled: 'bool' = True) -> 'Feedback'",
    "set_osd_coordinates": (
        "await (self, coordinates: 'OsdCoordinateSource | int' = "
        "<OsdCoordinateSource.AIRCRAFT: 0>) -> 'Feedback'"
    ),
    "set_palette": (
        "await (self, palette: 'int' = 0, *, "
        "cameras: 'int' = <CameraMask.CAMERA_2: 2>) -> 'Feedback'"
    ),
    "set_picture_in_picture": "await (self, mode: 'int' = 0) -> 'Feedback'",
    "set_ranging": "await (self, enabled: 'bool' = True) -> 'Feedback'",
    "set_rates": (
        "call (self, *, roll: 'float' = 0.0, pitch: 'float' = 0.0, yaw: 'float' = 0.0) -> 'None'"
    ),
    "set_spot_temperature": (
        "await (self, enabled: 'bool' = True, x: 'float' = 0.5, y: 'float' = 0.5, *, "
        "cameras: 'int' = <CameraMask.CAMERA_2: 2>) -> 'Feedback'"
    ),
    "set_target_detection": "await (self, enabled: 'bool' = True) -> 'Feedback'",
    "set_temperature_alarm": (
        "await (self, enabled: 'bool' = True, *, high: 'float' = 0.0, low: 'float' = 0.0, "
        "cameras: 'int' = <CameraMask.CAMERA_2: 2>) -> 'Feedback'"
    ),
    "set_time_zone": "await (self, offset_hours: 'int') -> 'Feedback'",
    "start_recording": (
        "await (self, *, cameras: 'int' = <CameraMask.CAMERA_1: 1>) -> 'Feedback | None'"
    ),
    "restore": "property",
    "state": "property",
    "status": "property",
    "stop_recording": (
        "await (self, *, cameras: 'int' = <CameraMask.CAMERA_1: 1>) -> 'Feedback | None'"
    ),
    "stop_tracking": "await (self, *, cameras: 'int' = <CameraMask.CAMERA_1: 1>) -> 'Feedback'",
    "stop_zoom": "await (self, *, cameras: 'int' = <CameraMask.CAMERA_1: 1>) -> 'Feedback'",
    "take_photo": "await (self, *, cameras: 'int' = <CameraMask.CAMERA_1: 1>) -> 'Feedback'",
    "telemetry": (
        "async for (self, maxsize: 'int' = 1) -> 'AsyncGenerator[TelemetrySample, None]'"
    ),
    "toggle_recording": (
        "await (self, *, cameras: 'int' = <CameraMask.CAMERA_1: 1>) -> 'Feedback'"
    ),
    "track": (
        "await (self, box: 'ImageBox | tuple[float, float, float, float] | list[float]', *, "
        "cameras: 'int' = <CameraMask.CAMERA_1: 1>) -> 'Feedback'"
    ),
    "update_aircraft": (
        "call (self, *, attitude: 'Attitude | tuple[float, float, float] | Keep | None' = KEEP, "
        "acceleration: 'NorthEastUp | tuple[float, float, float] | Keep | None' = KEEP, "
        "velocity: 'NorthEastUp | tuple[float, float, float] | Keep | None' = KEEP, "
        "position: 'GeoPosition | tuple[float, float, float] | Keep | None' = KEEP, "
        "relative_altitude: 'float | Keep' = KEEP, satellites: 'int | Keep' = KEEP, "
        "gnss_time: 'datetime | None' = None, gnss_week: 'int | Keep' = KEEP, "
        "gnss_ms: 'int | Keep' = KEEP) -> 'AircraftState'"
    ),
    "version": "property",
    "wait_attitude": (
        "await (self, *, roll: 'float | None' = None, pitch: 'float | None' = None, "
        "yaw: 'float | None' = None, tolerance: 'float' = 0.5, "
        "timeout: 'float' = 10.0) -> 'TelemetrySample'"
    ),
    "wait_for": (
        "await (self, predicate: 'Predicate', *, timeout: 'float' = 10.0, "
        "what: 'str' = 'the condition') -> 'TelemetrySample'"
    ),
    "wait_link": "await (self, up: 'bool' = True, *, timeout: 'float' = 10.0) -> 'None'",
    "wait_zoom": (
        "await (self, ratio: 'float', *, tolerance: 'float' = 0.05, "
        "timeout: 'float' = 10.0) -> 'TelemetrySample'"
    ),
    "zoom_in": "await (self, *, cameras: 'int' = <CameraMask.CAMERA_1: 1>) -> 'Feedback'",
    "zoom_out": "await (self, *, cameras: 'int' = <CameraMask.CAMERA_1: 1>) -> 'Feedback'",
    "zoom_to": (
        "await (self, ratio: 'float', *, cameras: 'int' = <CameraMask.CAMERA_1: 1>) -> 'Feedback'"
    ),
    "zoom_to_fraction": (
        "await (self, fraction: 'float', *, "
        "cameras: 'int' = <CameraMask.CAMERA_1: 1>) -> 'Feedback'"
    ),
}
"""GcuClient's public members before the command methods, the waits and the driver became
composed parts: kind (``await``, ``async for``, a plain ``call``, a property) and
signature."""


def _surface() -> dict[str, str]:
    out = {}
    for name in dir(GcuClient):
        if name.startswith("_") and name not in ("__init__", "__aenter__", "__aexit__",
                                                  "__await__"):  # fmt: skip
            continue
        member = inspect.getattr_static(GcuClient, name)
        if isinstance(member, property):
            out[name] = "property"
            continue
        kind = ("async for" if inspect.isasyncgenfunction(member) else
                "await" if inspect.iscoroutinefunction(member) else "call")  # fmt: skip
        out[name] = f"{kind} {inspect.signature(member)}"
        assert name.startswith("_") or inspect.getdoc(member), f"{name} has no docstring"
    return out


def test_the_public_surface_is_unchanged() -> None:
    surface = _surface()
    # options kept as attributes, now views of the parts that use them
    assert surface.pop("check_support") == surface.pop("telemetry_dropped") == "property"
    # a command method added since is checked against its catalogue entry (test_catalogue.py)
    added = surface.keys() - SURFACE.keys()
    assert added <= BY_METHOD.keys(), sorted(added - BY_METHOD.keys())
    assert {k: v for k, v in surface.items() if k not in added} == SURFACE


def test_the_option_attributes_stay_readable_and_writable() -> None:
    gcu = GcuClient(MemoryTransport(), check_support=True, connect_timeout=2.5)
    assert gcu.check_support is True and gcu.connect_timeout == 2.5
    assert gcu.open_timeout is None and gcu.telemetry_dropped == 0
    assert isinstance(gcu.session, Session) and isinstance(gcu.transport, MemoryTransport)
    gcu.check_support = False
    gcu.telemetry_dropped = 0
    assert gcu.check_support is False
    with pytest.raises(TypeError, match=r"^check_support: expected a bool"):
        gcu.check_support = 1  # type: ignore[assignment]


# -- options checked once --------------------------------------------------------------------
@pytest.mark.parametrize(("option", "value", "error"), [
    *(("rate_hz", v, ValueError) for v in (0, -1, 1.5, 1.9, 200.5, 500.0, math.inf, math.nan)),
    ("rate_hz", True, TypeError), ("rate_hz", "50", TypeError),
    ("version", 3, ValueError), ("version", 0, ValueError),
    ("version", 2.0, TypeError), ("version", None, TypeError),
])  # fmt: skip
def test_rate_and_version_are_refused_at_construction_with_the_sessions_message(
    option: str, value: object, error: type[Exception]
) -> None:
    with pytest.raises(error) as session_error:
        Session(**{option: value})  # type: ignore[arg-type]
    with pytest.raises(type(session_error.value)) as client_error:
        GcuClient(MemoryTransport(), **{option: value})
    assert str(client_error.value) == str(session_error.value)
    assert str(client_error.value).startswith(f"{option}: ")


def test_the_session_is_the_one_place_rate_and_version_are_checked(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Widen the session's rate range: the client follows (it keeps no copy of its own)."""
    import gcu_async.session.config as config_module

    with pytest.raises(ValueError, match=r"^rate_hz: 250"):
        GcuClient(MemoryTransport(), rate_hz=250.0)
    monkeypatch.setattr(config_module, "RATE_MAX_HZ", 300.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # outside the advised 30-50 Hz
        assert GcuClient(MemoryTransport(), rate_hz=250.0).rate_hz == 250.0


def test_a_run_of_the_loop_is_not_needed_to_build() -> None:
    """The builder is sans-I/O: no loop is running here and none is started."""
    with pytest.raises(RuntimeError):
        asyncio.get_running_loop()
    assert build("take_photo").command == c.TakePhoto()
