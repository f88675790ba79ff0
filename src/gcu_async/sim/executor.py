"""What each command does to the simulated pod, and the execution status it answers.

Statuses follow docs/protocol-notes.md §2 "Execution status per command" via
:func:`~gcu_async.protocol.feedback.failure_status`: 0x00 success; 0x01 failure (0x02 for palette
and the thermal commands; the failed-camera mask for zoom commands); calibration 0x02 while in
progress. A command the pod model does not support (Appendix 8) fails without effect.
Interpretations the simulator makes:

- a camera mask naming a camera the pod lacks fails (zoom: those cameras are the mask NN,
  the others still zoom); palette/thermal commands need camera 2 in the mask;
- gaze (at coordinates or at the image centre) fails when the host packet's INS data are
  invalid (byte 11 B0 = 0);
- centre fails in the modes the spec says ignore it; click-to-pan fails while tracking;
- tracking fails for an empty target box; an unknown opcode fails with 0x01;
- a command whose parameters V2.0.6 does not allow (an :class:`AnomalousCommand`: out of
  range, wrong length) does nothing and answers its failure status (zoom: the cameras it
  named, camera 1 when it named none).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

from gcu_async.protocol.command_base import Command
from gcu_async.protocol.command_decode import AnomalousCommand, UnknownCommand, command_code
from gcu_async.protocol.commands import (
    COMMAND_TYPES,
    AreaTemperature,
    Calibration,
    Centre,
    ClickToPan,
    DigitalZoom,
    FillLight,
    Focus,
    GazeAtCoordinates,
    GazeLock,
    ImageAutoFlip,
    Isotherm,
    NightVision,
    Osd,
    OsdCoordinates,
    Palette,
    PictureInPicture,
    Ranging,
    Record,
    SpotTemperature,
    TakePhoto,
    TargetDetection,
    TemperatureAlarm,
    TimeZone,
    Track,
    ZoomIn,
    ZoomOut,
    ZoomStop,
    ZoomTo,
)
from gcu_async.protocol.enums import Mode, NightVisionMode, Opcode, OsdCoordinateSource
from gcu_async.protocol.feedback import CALIBRATION_IN_PROGRESS, failure_status
from gcu_async.protocol.host_frames import HostMainFrame
from gcu_async.protocol.pods import supports
from gcu_async.protocol.units import GeoPosition
from gcu_async.sim.camera import THERMAL, cameras_in
from gcu_async.sim.firmware import DEFAULT_FIRMWARE, FIRMWARES, Firmware
from gcu_async.sim.profiles import PodProfile
from gcu_async.sim.state import SimState

SUCCESS = 0x00
FAILED = 0x01

MODE_OPCODES: dict[int, Mode] = {
    op: c.SCHEMA.mode.mode for op, c in COMMAND_TYPES.items() if c.SCHEMA.mode is not None
}
"""The mode each mode command enters (from the command schema)."""

Handler = Callable[["Executor", Any, HostMainFrame, float], int]
"""What a command does to the simulated pod: (executor, command, host main frame, now) →
the execution status byte."""
HANDLERS: dict[type[Command], Handler] = {}
"""The behaviour of each command class: the one place a command's simulation is written
(:func:`behaviour`); a mode command without parameters has :func:`_enter_mode` unless it
registers its own."""
_H = TypeVar("_H", bound=Handler)


def behaviour(*commands: type[Command]) -> Callable[[_H], _H]:
    """Register the decorated function as what ``commands`` do to the simulated pod."""

    def register(handler: _H) -> _H:
        for command in commands:
            HANDLERS[command] = handler
        return handler

    return register


def handler_for(command: type[Command]) -> Handler | None:
    """The behaviour of ``command`` (``None``: the simulator does not know it)."""
    handler = HANDLERS.get(command)
    if handler is None and command.SCHEMA.mode is not None and not command.SCHEMA.params:
        return _enter_mode
    return handler


class Executor:
    """Runs commands against a :class:`SimState` for one pod profile."""

    def __init__(self, state: SimState, profile: PodProfile, calibration_seconds: float,
                 firmware: Firmware = FIRMWARES[DEFAULT_FIRMWARE]) -> None:  # fmt: skip
        self.state = state
        self.profile = profile
        self.calibration_seconds = calibration_seconds
        self.firmware = firmware
        """The firmware's behaviours (the model keeps it current)."""

    def execute(self, command: Command, main: HostMainFrame, now: float) -> int:
        """Run ``command`` (carried by a host packet with main frame ``main``) at clock time
        ``now``; return the execution status byte."""
        opcode = command_code(command)
        if isinstance(command, UnknownCommand):
            return FAILED
        if isinstance(command, AnomalousCommand):
            named = command.params[0] if command.params else 0
            return failure_status(opcode, named or 1)
        if not supports(self.profile.model, opcode):
            return failure_status(opcode, int(getattr(command, "cameras", 1)))
        handler = handler_for(type(command))
        if handler is None:  # the null command (tests check every other command has one)
            return FAILED
        status = handler(self, command, main, now)
        if status == SUCCESS:
            self.state.accepted[opcode] = command
        return status

    def calibration_status(self, now: float) -> int:
        """0x02 while a calibration runs, 0x00 once it has finished."""
        until = self.state.calibration_until
        if until is not None and now < until:
            return CALIBRATION_IN_PROGRESS
        self.state.calibration_until = None
        return SUCCESS

    def has_cameras(self, mask: int) -> bool:
        """Every camera in ``mask`` exists on this pod."""
        return mask != 0 and not mask & ~self.state.camera.mask


# -- pod commands ---------------------------------------------------------------------


@behaviour(Calibration)
def _calibration(ex: Executor, command: Command, main: HostMainFrame, now: float) -> int:
    ex.state.calibration_until = now + ex.calibration_seconds
    return ex.calibration_status(now)


@behaviour(Centre)
def _centre(ex: Executor, command: Command, main: HostMainFrame, now: float) -> int:
    return SUCCESS if ex.state.gimbal.centre() or ex.firmware.centre_ignored_ok else FAILED


def _enter_mode(ex: Executor, command: Command, main: HostMainFrame, now: float) -> int:
    ex.state.gimbal.enter_mode(MODE_OPCODES[command_code(command)])
    return SUCCESS


@behaviour(GazeAtCoordinates)
def _gaze_at(ex: Executor, command: GazeAtCoordinates, main: HostMainFrame, now: float) -> int:
    if not main.ins_valid:
        return FAILED
    target = GeoPosition(command.latitude, command.longitude, command.altitude)
    ex.state.gimbal.gaze_at(target)
    return SUCCESS


@behaviour(GazeLock)
def _gaze_lock(ex: Executor, command: Command, main: HostMainFrame, now: float) -> int:
    if not main.ins_valid:
        return FAILED
    ex.state.gimbal.gaze_at(None)
    return SUCCESS


@behaviour(Track)
def _track(ex: Executor, command: Track, main: HostMainFrame, now: float) -> int:
    gimbal = ex.state.gimbal
    if not command.enter:
        gimbal.stop_track()
        return SUCCESS
    if not ex.has_cameras(command.cameras):
        return FAILED
    ok = gimbal.start_track(command.box, ex.state.camera.main_zoom)
    return SUCCESS if ok else FAILED


@behaviour(ClickToPan)
def _click_to_pan(ex: Executor, command: ClickToPan, main: HostMainFrame, now: float) -> int:
    gimbal = ex.state.gimbal
    if gimbal.mode == Mode.TRACK or not ex.has_cameras(command.cameras):
        return FAILED
    gimbal.click_to_pan(command.point, ex.state.camera.main_zoom)
    return SUCCESS


# -- camera commands --------------------------------------------------------------------


@behaviour(OsdCoordinates)
def _osd_coordinates(ex: Executor, command: OsdCoordinates, main: HostMainFrame,
                     now: float) -> int:  # fmt: skip
    ex.state.camera.osd_target_coordinates = command.coordinates == OsdCoordinateSource.TARGET
    return SUCCESS


@behaviour(ImageAutoFlip)
def _auto_flip(ex: Executor, command: ImageAutoFlip, main: HostMainFrame, now: float) -> int:
    ex.state.camera.auto_flip = command.enabled
    return SUCCESS


@behaviour(TimeZone)
def _time_zone(ex: Executor, command: TimeZone, main: HostMainFrame, now: float) -> int:
    ex.state.camera.time_zone = command.offset_hours
    return SUCCESS


@behaviour(TakePhoto)
def _photo(ex: Executor, command: Any, main: HostMainFrame, now: float) -> int:
    if not ex.has_cameras(command.cameras):
        return FAILED
    photos = ex.state.camera.photos
    for number in cameras_in(command.cameras):
        photos[number] = photos.get(number, 0) + 1
    return SUCCESS


@behaviour(Record)
def _record(ex: Executor, command: Any, main: HostMainFrame, now: float) -> int:
    if not ex.has_cameras(command.cameras):
        return FAILED
    ex.state.camera.recording = not ex.state.camera.recording
    return SUCCESS


@behaviour(Focus)
def _focus(ex: Executor, command: Any, main: HostMainFrame, now: float) -> int:
    if not ex.has_cameras(command.cameras):
        return FAILED
    ex.state.camera.focus_count += 1
    return SUCCESS


@behaviour(ZoomIn, ZoomOut, ZoomStop, ZoomTo)
def _zoom(ex: Executor, command: Any, main: HostMainFrame, now: float) -> int:
    mask = int(command.cameras)
    drives = ex.state.camera.zoom
    failed = 0
    opcode = command_code(command)
    for number in cameras_in(mask):
        drive = drives.get(number)
        if drive is None:
            failed |= 1 << (number - 1)
        elif opcode == Opcode.ZOOM_IN:
            drive.zoom_in()
        elif opcode == Opcode.ZOOM_OUT:
            drive.zoom_out()
        elif opcode == Opcode.ZOOM_STOP:
            drive.stop()
        elif isinstance(command, ZoomTo) and command.ratio is not None:
            drive.zoom_to(command.ratio)
        elif isinstance(command, ZoomTo) and command.fraction is not None:
            drive.zoom_to_fraction(command.fraction)
    return failed


@behaviour(Palette)
def _palette(ex: Executor, command: Palette, main: HostMainFrame, now: float) -> int:
    if not command.cameras & (1 << (THERMAL - 1)) or not ex.has_cameras(command.cameras):
        return failure_status(Opcode.PALETTE)
    ex.state.camera.cycle_palette(command.palette)
    return SUCCESS


@behaviour(NightVision)
def _night_vision(ex: Executor, command: NightVision, main: HostMainFrame, now: float) -> int:
    if not ex.has_cameras(command.cameras):
        return FAILED
    ex.state.camera.night_vision = NightVisionMode(command.mode)  # stored as its member
    return SUCCESS


@behaviour(AreaTemperature, TemperatureAlarm, Isotherm, SpotTemperature)
def _thermal(ex: Executor, command: Any, main: HostMainFrame, now: float) -> int:
    cam = ex.state.camera
    opcode = command_code(command)
    if not command.cameras & (1 << (THERMAL - 1)) or not ex.has_cameras(command.cameras):
        return failure_status(opcode)
    if isinstance(command, AreaTemperature):
        cam.area_temperature = command.box if command.enabled else None
    elif isinstance(command, SpotTemperature):
        cam.spot_temperature = command.point if command.enabled else None
    elif isinstance(command, TemperatureAlarm):
        cam.temperature_alarm = (command.high, command.low) if command.enabled else None
    elif isinstance(command, Isotherm):
        cam.isotherm = (command.high, command.low) if command.enabled else None
    return SUCCESS


@behaviour(Osd)
def _osd(ex: Executor, command: Osd, main: HostMainFrame, now: float) -> int:
    ex.state.camera.osd_on = command.enabled
    return SUCCESS


@behaviour(PictureInPicture)
def _pip(ex: Executor, command: PictureInPicture, main: HostMainFrame, now: float) -> int:
    ex.state.camera.cycle_pip(command.mode)
    return SUCCESS


@behaviour(TargetDetection)
def _target_detection(ex: Executor, command: TargetDetection, main: HostMainFrame,
                      now: float) -> int:  # fmt: skip
    ex.state.camera.target_detection = command.enabled
    return SUCCESS


@behaviour(DigitalZoom)
def _digital_zoom(ex: Executor, command: DigitalZoom, main: HostMainFrame, now: float) -> int:
    ex.state.camera.set_digital_zoom(command.enabled)
    return SUCCESS


@behaviour(FillLight)
def _fill_light(ex: Executor, command: FillLight, main: HostMainFrame, now: float) -> int:
    ex.state.camera.set_fill_light(command.brightness)
    return SUCCESS


@behaviour(Ranging)
def _ranging(ex: Executor, command: Ranging, main: HostMainFrame, now: float) -> int:
    ex.state.rangefinder.on = command.enabled
    return SUCCESS
