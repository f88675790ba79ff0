"""What each command does to the simulated pod, and the execution status it answers.

Statuses follow docs/protocol-notes.md §2 "Execution status per command" via
:func:`~gcu_async.protocol.feedback.failure_status`: 0x00 success; 0x01 failure (0x02 for palette
and the thermal commands; the failed-camera mask for zoom commands); calibration 0x02 while in
progress. A command the pod model does not support (Appendix 8) fails without effect.
Interpretations the simulator makes:

- a camera mask naming a camera the pod lacks fails (zoom: those cameras are the mask NN,
  the others still zoom); palette/thermal commands need camera 2 in the mask;
- gaze (0x15, 0x16) fails when the host packet's INS data are invalid (byte 11 B0 = 0);
- centre fails in the modes the spec says ignore it; click-to-pan fails while tracking;
- tracking fails for an empty target box; an unknown opcode fails with 0x01;
- a command whose parameters V2.0.6 does not allow (an :class:`AnomalousCommand`: out of
  range, wrong length) does nothing and answers its failure status (zoom: the cameras it
  named, camera 1 when it named none).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from gcu_async.protocol.commands import (
    AnomalousCommand,
    AreaTemperature,
    ClickToPan,
    Command,
    DigitalZoom,
    FillLight,
    GazeAtCoordinates,
    ImageAutoFlip,
    Isotherm,
    NightVision,
    Osd,
    OsdCoordinates,
    Palette,
    PictureInPicture,
    Ranging,
    SpotTemperature,
    TargetDetection,
    TemperatureAlarm,
    TimeZone,
    Track,
    UnknownCommand,
    ZoomTo,
    command_code,
)
from gcu_async.protocol.enums import Mode, Opcode, OsdCoordinateSource
from gcu_async.protocol.feedback import CALIBRATION_IN_PROGRESS, failure_status
from gcu_async.protocol.host_frames import HostMainFrame
from gcu_async.protocol.pods import supports
from gcu_async.protocol.units import GeoPosition
from gcu_async.sim.camera import THERMAL, cameras_in
from gcu_async.sim.profiles import PodProfile
from gcu_async.sim.state import SimState

SUCCESS = 0x00
FAILED = 0x01

MODE_OPCODES: dict[int, Mode] = {
    Opcode.ANGLE_CONTROL: Mode.ANGLE_CONTROL,
    Opcode.POINTING_LOCK: Mode.POINTING_LOCK,
    Opcode.POINTING_FOLLOW: Mode.POINTING_FOLLOW,
    Opcode.TOP_DOWN: Mode.TOP_DOWN,
    Opcode.EULER_CONTROL: Mode.EULER_CONTROL,
    Opcode.FPV: Mode.FPV,
}


class Executor:
    """Runs commands against a :class:`SimState` for one pod profile."""

    def __init__(self, state: SimState, profile: PodProfile, calibration_seconds: float) -> None:
        self.state = state
        self.profile = profile
        self.calibration_seconds = calibration_seconds
        self._handlers: dict[int, Callable[[Any, HostMainFrame, float], int]] = {
            Opcode.CALIBRATION: self._calibration,
            Opcode.CENTRE: self._centre,
            Opcode.GAZE_AT_COORDINATES: self._gaze_at,
            Opcode.GAZE_LOCK: self._gaze_lock,
            Opcode.TRACK: self._track,
            Opcode.CLICK_TO_PAN: self._click_to_pan,
            Opcode.OSD_COORDINATES: self._osd_coordinates,
            Opcode.IMAGE_AUTO_FLIP: self._auto_flip,
            Opcode.TIME_ZONE: self._time_zone,
            Opcode.TAKE_PHOTO: self._photo,
            Opcode.RECORD: self._record,
            Opcode.ZOOM_IN: self._zoom,
            Opcode.ZOOM_OUT: self._zoom,
            Opcode.ZOOM_STOP: self._zoom,
            Opcode.ZOOM_TO: self._zoom,
            Opcode.FOCUS: self._focus,
            Opcode.PALETTE: self._palette,
            Opcode.NIGHT_VISION: self._night_vision,
            Opcode.AREA_TEMPERATURE: self._thermal,
            Opcode.TEMPERATURE_ALARM: self._thermal,
            Opcode.ISOTHERM: self._thermal,
            Opcode.SPOT_TEMPERATURE: self._thermal,
            Opcode.OSD: self._osd,
            Opcode.PICTURE_IN_PICTURE: self._pip,
            Opcode.TARGET_DETECTION: self._target_detection,
            Opcode.DIGITAL_ZOOM: self._digital_zoom,
            Opcode.FILL_LIGHT: self._fill_light,
            Opcode.RANGING: self._ranging,
        }
        for opcode in MODE_OPCODES:
            self._handlers[opcode] = self._mode

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
        handler = self._handlers.get(opcode)
        if handler is None:  # pragma: no cover - every defined non-null opcode has one
            return FAILED
        return handler(command, main, now)

    def calibration_status(self, now: float) -> int:
        """0x02 while a calibration runs, 0x00 once it has finished."""
        until = self.state.calibration_until
        if until is not None and now < until:
            return CALIBRATION_IN_PROGRESS
        self.state.calibration_until = None
        return SUCCESS

    # -- pod commands ---------------------------------------------------------------------
    def _calibration(self, command: Command, main: HostMainFrame, now: float) -> int:
        self.state.calibration_until = now + self.calibration_seconds
        return self.calibration_status(now)

    def _centre(self, command: Command, main: HostMainFrame, now: float) -> int:
        return SUCCESS if self.state.gimbal.centre() else FAILED

    def _mode(self, command: Command, main: HostMainFrame, now: float) -> int:
        self.state.gimbal.enter_mode(MODE_OPCODES[command_code(command)])
        return SUCCESS

    def _gaze_at(self, command: GazeAtCoordinates, main: HostMainFrame, now: float) -> int:
        if not main.ins_valid:
            return FAILED
        target = GeoPosition(command.latitude, command.longitude, command.altitude)
        self.state.gimbal.gaze_at(target)
        return SUCCESS

    def _gaze_lock(self, command: Command, main: HostMainFrame, now: float) -> int:
        if not main.ins_valid:
            return FAILED
        self.state.gimbal.gaze_at(None)
        return SUCCESS

    def _track(self, command: Track, main: HostMainFrame, now: float) -> int:
        gimbal = self.state.gimbal
        if not command.enter:
            gimbal.stop_track()
            return SUCCESS
        if not self._has(command.cameras):
            return FAILED
        ok = gimbal.start_track(command.box, self.state.camera.main_zoom)
        return SUCCESS if ok else FAILED

    def _click_to_pan(self, command: ClickToPan, main: HostMainFrame, now: float) -> int:
        gimbal = self.state.gimbal
        if gimbal.mode == Mode.TRACK or not self._has(command.cameras):
            return FAILED
        gimbal.click_to_pan(command.point, self.state.camera.main_zoom)
        return SUCCESS

    # -- camera commands --------------------------------------------------------------------
    def _has(self, mask: int) -> bool:
        """Every camera in ``mask`` exists on this pod."""
        return mask != 0 and not mask & ~self.state.camera.mask

    def _osd_coordinates(self, command: OsdCoordinates, main: HostMainFrame,
                         now: float) -> int:  # fmt: skip
        self.state.camera.osd_target_coordinates = command.coordinates == OsdCoordinateSource.TARGET
        return SUCCESS

    def _auto_flip(self, command: ImageAutoFlip, main: HostMainFrame, now: float) -> int:
        self.state.camera.auto_flip = command.enabled
        return SUCCESS

    def _time_zone(self, command: TimeZone, main: HostMainFrame, now: float) -> int:
        self.state.camera.time_zone = command.offset_hours
        return SUCCESS

    def _photo(self, command: Any, main: HostMainFrame, now: float) -> int:
        if not self._has(command.cameras):
            return FAILED
        photos = self.state.camera.photos
        for number in cameras_in(command.cameras):
            photos[number] = photos.get(number, 0) + 1
        return SUCCESS

    def _record(self, command: Any, main: HostMainFrame, now: float) -> int:
        if not self._has(command.cameras):
            return FAILED
        self.state.camera.recording = not self.state.camera.recording
        return SUCCESS

    def _focus(self, command: Any, main: HostMainFrame, now: float) -> int:
        if not self._has(command.cameras):
            return FAILED
        self.state.camera.focus_count += 1
        return SUCCESS

    def _zoom(self, command: Any, main: HostMainFrame, now: float) -> int:
        mask = int(command.cameras)
        drives = self.state.camera.zoom
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

    def _palette(self, command: Palette, main: HostMainFrame, now: float) -> int:
        if not command.cameras & (1 << (THERMAL - 1)) or not self._has(command.cameras):
            return failure_status(Opcode.PALETTE)
        self.state.camera.cycle_palette(command.palette)
        return SUCCESS

    def _night_vision(self, command: NightVision, main: HostMainFrame, now: float) -> int:
        if not self._has(command.cameras):
            return FAILED
        self.state.camera.night_vision = command.mode
        return SUCCESS

    def _thermal(self, command: Any, main: HostMainFrame, now: float) -> int:
        cam = self.state.camera
        opcode = command_code(command)
        if not command.cameras & (1 << (THERMAL - 1)) or not self._has(command.cameras):
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

    def _osd(self, command: Osd, main: HostMainFrame, now: float) -> int:
        self.state.camera.osd_on = command.enabled
        return SUCCESS

    def _pip(self, command: PictureInPicture, main: HostMainFrame, now: float) -> int:
        self.state.camera.cycle_pip(command.mode)
        return SUCCESS

    def _target_detection(self, command: TargetDetection, main: HostMainFrame,
                          now: float) -> int:  # fmt: skip
        self.state.camera.target_detection = command.enabled
        return SUCCESS

    def _digital_zoom(self, command: DigitalZoom, main: HostMainFrame, now: float) -> int:
        self.state.camera.set_digital_zoom(command.enabled)
        return SUCCESS

    def _fill_light(self, command: FillLight, main: HostMainFrame, now: float) -> int:
        self.state.camera.set_fill_light(command.brightness)
        return SUCCESS

    def _ranging(self, command: Ranging, main: HostMainFrame, now: float) -> int:
        self.state.rangefinder.on = command.enabled
        return SUCCESS
