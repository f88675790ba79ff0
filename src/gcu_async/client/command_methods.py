"""The client's command methods: one per catalogue entry, each naming what it sends.

:class:`GcuCommands` is a base of :class:`~gcu_async.client.GcuClient`: the methods live here,
apart from the client's lifecycle, telemetry and waits, and reach the client only through
its driver. A method that only sends its command calls the command class
(:mod:`gcu_async.protocol.commands`), which checks the arguments; a method that does more
(control values, the GCU's context, a box as a list, recording intent) calls the builder's
function of the same name (:mod:`gcu_async.protocol.builder`). Either way a reader and a type
checker follow each argument from the method to the wire, and the command table's
``gcu-async send`` and docs tables list the opcode each method sends.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Concatenate, ParamSpec

from gcu_async.protocol import builder
from gcu_async.protocol import commands as c
from gcu_async.protocol.builder import Context, Submission
from gcu_async.protocol.command_base import Command
from gcu_async.protocol.enums import CameraMask, NightVisionMode, OsdCoordinateSource
from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.units import ImageBox

if TYPE_CHECKING:
    from gcu_async.client.driver import Driver

__all__ = ["GcuCommands"]

CAM1 = CameraMask.CAMERA_1
CAM2 = CameraMask.CAMERA_2

_P = ParamSpec("_P")


class GcuCommands:
    """The command methods of :class:`~gcu_async.client.GcuClient` (docs/client.md,
    "Commands")."""

    _driver: Driver

    async def _run(self, command: Command, /) -> Feedback:
        """Run ``command`` and return its success feedback."""
        return await self._driver.run(Submission(command))

    async def _build(self, make: Callable[Concatenate[Context, _P], Submission], /,
                     *args: _P.args, **kwargs: _P.kwargs) -> Feedback:  # fmt: skip
        """Run what builder function ``make`` makes of the arguments and the GCU's context."""
        return await self._driver.run(make(self._driver.context(), *args, **kwargs))

    async def _send(self, make: Callable[Concatenate[Context, _P], Submission], /,
                    *args: _P.args, **kwargs: _P.kwargs) -> Feedback | None:  # fmt: skip
        """Like :meth:`_build`, for a command the session may skip (``None``)."""
        return await self._driver.submit(make(self._driver.context(), *args, **kwargs))

    # -- pod modes ------------------------------------------------------------------------
    async def enter_euler_control(
        self, *, roll: float | None = None, pitch: float | None = None,
        yaw: float | None = None,
    ) -> Feedback:  # fmt: skip
        """Euler-angle control mode holding roll/pitch/yaw Euler angles in degrees;
        an angle left out keeps the camera's current one (``status.attitude``), so
        ``enter_euler_control(pitch=-45)`` does not swing the yaw. ``yaw`` may be given in
        [-180, 360): [180, 360) is sent as its −180…0 equivalent. The angles go out valid
        once the GCU confirmed the mode; :meth:`reach_attitude` also waits until the camera
        is there."""
        return await self._build(builder.enter_euler_control, roll=roll, pitch=pitch, yaw=yaw)

    async def enter_angle_control(
        self, *, roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0
    ) -> Feedback:
        """Angle-control mode: roll/pitch Euler angles, yaw relative to the aircraft
        (degrees, up to :data:`~gcu_async.protocol.commands.ANGLE_LIMIT` either way)."""
        return await self._build(builder.enter_angle_control, roll=roll, pitch=pitch, yaw=yaw)

    async def enter_fpv(
        self, *, roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0
    ) -> Feedback:
        """FPV mode: roll/pitch/yaw angles relative to the aircraft, degrees (up to
        :data:`~gcu_async.protocol.commands.ANGLE_LIMIT` either way)."""
        return await self._build(builder.enter_fpv, roll=roll, pitch=pitch, yaw=yaw)

    async def enter_pointing_lock(
        self, *, pitch_rate: float = 0.0, yaw_rate: float = 0.0
    ) -> Feedback:
        """Pointing-lock mode with pitch/yaw rates in °/s at the current zoom
        (at most 150 / zoom °/s)."""
        return await self._build(builder.enter_pointing_lock, pitch_rate=pitch_rate,
                                 yaw_rate=yaw_rate)  # fmt: skip

    async def enter_pointing_follow(
        self, *, pitch_rate: float = 0.0, yaw_rate: float = 0.0
    ) -> Feedback:
        """Pointing-follow mode; yaw rate 0 follows the aircraft's heading."""
        return await self._build(builder.enter_pointing_follow, pitch_rate=pitch_rate,
                                 yaw_rate=yaw_rate)  # fmt: skip

    async def enter_top_down(self, *, yaw_rate: float = 0.0) -> Feedback:
        """Top-down mode: pitch −90°, yaw rate in °/s."""
        return await self._build(builder.enter_top_down, yaw_rate=yaw_rate)

    async def enter_gaze_lock(self, *, pitch_rate: float = 0.0, yaw_rate: float = 0.0) -> Feedback:
        """Gaze (geographic target lock) at the image centre; needs valid INS data."""
        return await self._build(builder.enter_gaze_lock, pitch_rate=pitch_rate, yaw_rate=yaw_rate)

    async def gaze_at(self, latitude: float, longitude: float, altitude: float) -> Feedback:
        """Gaze at a coordinate: degrees, degrees, metres MSL; needs valid INS data.
        Control values stay invalid (the pod locks the point) until :meth:`set_rates`."""
        return await self._run(c.GazeAtCoordinates(latitude=latitude, longitude=longitude,
                                                 altitude=altitude))  # fmt: skip

    # -- pod, other ----------------------------------------------------------------------
    async def calibrate(self, *, timeout: float = 15.0) -> Feedback:
        """Calibrate; keeps waiting while the GCU answers "in progress", up to
        ``timeout`` seconds (a finite real number > 0)."""
        return await self._build(builder.calibrate, timeout=timeout)

    async def centre(self) -> Feedback:
        """Centre pitch and heading. Control values go out invalid while it runs and
        are cleared afterwards (they would steer away from the centre)."""
        return await self._run(c.Centre())

    async def track(
        self, box: ImageBox | tuple[float, float, float, float] | list[float], *,
        cameras: int = CAM1,
    ) -> Feedback:  # fmt: skip
        """Track the target in ``box`` (left, top, right, bottom as image fractions; an
        ImageBox, a tuple or a list of four). The pod steers itself while tracking: control
        values go out invalid."""
        return await self._build(builder.track, box=box, cameras=cameras)

    async def stop_tracking(self, *, cameras: int = CAM1) -> Feedback:
        """Exit tracking (the track command with TT = 0); control values stay invalid until
        a mode command is confirmed."""
        return await self._build(builder.stop_tracking, cameras=cameras)

    async def click_to_pan(self, x: float, y: float, *, cameras: int = CAM1) -> Feedback:
        """Bring image point (x, y) (fractions) to the centre. The pod ends in
        pointing-lock; control values stay invalid until a mode command is confirmed."""
        return await self._build(builder.click_to_pan, x=x, y=y, cameras=cameras)

    # -- camera --------------------------------------------------------------------------
    async def take_photo(self, *, cameras: int = CAM1) -> Feedback:
        """Take a photo."""
        return await self._run(c.TakePhoto(cameras=cameras))

    async def toggle_recording(self, *, cameras: int = CAM1) -> Feedback:
        """Start or stop recording (a toggle), unconditionally."""
        return await self._run(c.Record(cameras=cameras))

    async def start_recording(self, *, cameras: int = CAM1) -> Feedback | None:
        """Start recording unless the camera already records (then ``None``, nothing sent).
        Record commands run one at a time and the state is checked when this one's turn
        comes, so concurrent calls start recording once (docs/client.md, "Recording")."""
        return await self._send(builder.start_recording, cameras=cameras)

    async def stop_recording(self, *, cameras: int = CAM1) -> Feedback | None:
        """Stop recording if the camera records (else ``None``, nothing sent)."""
        return await self._send(builder.stop_recording, cameras=cameras)

    async def zoom_in(self, *, cameras: int = CAM1) -> Feedback:
        """Start zooming in until :meth:`stop_zoom`."""
        return await self._run(c.ZoomIn(cameras=cameras))

    async def zoom_out(self, *, cameras: int = CAM1) -> Feedback:
        """Start zooming out until :meth:`stop_zoom`."""
        return await self._run(c.ZoomOut(cameras=cameras))

    async def stop_zoom(self, *, cameras: int = CAM1) -> Feedback:
        """Stop a continuous zoom."""
        return await self._run(c.ZoomStop(cameras=cameras))

    async def zoom_to(self, ratio: float, *, cameras: int = CAM1) -> Feedback:
        """Zoom to a ratio, e.g. ``10.0`` for 10×, 0.1× resolution, at most the largest the
        command carries and :attr:`max_zoom` when the client was given it (the GCU itself
        answers success and stops at its limit)."""
        return await self._build(builder.zoom_to, ratio=ratio, cameras=cameras)

    async def zoom_to_fraction(self, fraction: float, *, cameras: int = CAM1) -> Feedback:
        """Zoom to a fraction (0, 1] of the maximum ratio (zoom-to's positive form;
        resolution 1/10000)."""
        return await self._build(builder.zoom_to_fraction, fraction=fraction, cameras=cameras)

    async def focus(self, *, cameras: int = CAM1) -> Feedback:
        """Trigger focus."""
        return await self._run(c.Focus(cameras=cameras))

    async def set_palette(self, palette: int = 0, *, cameras: int = CAM2) -> Feedback:
        """Thermal palette 1–10, or 0 to cycle."""
        return await self._run(c.Palette(palette=palette, cameras=cameras))

    async def set_night_vision(
        self, mode: NightVisionMode | int = NightVisionMode.ON, *, cameras: int = CAM1
    ) -> Feedback:
        """Night vision off / on / auto."""
        return await self._run(c.NightVision(mode=mode, cameras=cameras))

    async def set_area_temperature(
        self,
        enabled: bool = True,
        box: ImageBox | tuple[float, float, float, float] | list[float] = (0.0, 0.0, 1.0, 1.0),
        *,
        cameras: int = CAM2,
    ) -> Feedback:
        """Area temperature measurement over ``box``."""
        return await self._build(builder.set_area_temperature, enabled=enabled, box=box,
                                 cameras=cameras)  # fmt: skip

    async def set_temperature_alarm(
        self, enabled: bool = True, *, high: float = 0.0, low: float = 0.0, cameras: int = CAM2
    ) -> Feedback:
        """Temperature alarm with high/low thresholds in °C."""
        return await self._run(c.TemperatureAlarm(enabled=enabled, high=high, low=low,
                                                cameras=cameras))  # fmt: skip

    async def set_isotherm(
        self, enabled: bool = True, *, high: float = 0.0, low: float = 0.0, cameras: int = CAM2
    ) -> Feedback:
        """Isotherm between ``low`` and ``high`` °C."""
        return await self._run(c.Isotherm(enabled=enabled, high=high, low=low, cameras=cameras))

    async def set_spot_temperature(
        self, enabled: bool = True, x: float = 0.5, y: float = 0.5, *, cameras: int = CAM2
    ) -> Feedback:
        """Spot temperature at image point (x, y)."""
        return await self._build(builder.set_spot_temperature, enabled=enabled, x=x, y=y,
                                 cameras=cameras)  # fmt: skip

    async def set_osd(self, enabled: bool = True) -> Feedback:
        """On-screen display on/off."""
        return await self._run(c.Osd(enabled=enabled))

    async def set_osd_coordinates(
        self, coordinates: OsdCoordinateSource | int = OsdCoordinateSource.AIRCRAFT
    ) -> Feedback:
        """OSD shows aircraft or target coordinates."""
        return await self._run(c.OsdCoordinates(coordinates=coordinates))

    async def set_image_auto_flip(self, enabled: bool = True) -> Feedback:
        """Image auto-flip on/off."""
        return await self._run(c.ImageAutoFlip(enabled=enabled))

    async def set_time_zone(self, offset_hours: int) -> Feedback:
        """The pod's UTC offset in whole hours (a real time zone's)."""
        return await self._run(c.TimeZone(offset_hours=offset_hours))

    async def set_picture_in_picture(self, mode: int = 0) -> Feedback:
        """Picture-in-picture mode 1–4, or 0 to cycle."""
        return await self._run(c.PictureInPicture(mode=mode))

    async def set_target_detection(self, enabled: bool = True) -> Feedback:
        """AI target detection on/off."""
        return await self._run(c.TargetDetection(enabled=enabled))

    async def set_digital_zoom(self, enabled: bool = True) -> Feedback:
        """Digital zoom on/off."""
        return await self._run(c.DigitalZoom(enabled=enabled))

    async def set_fill_light(self, brightness: int) -> Feedback:
        """Fill light brightness 0–255, 0 = off; on also turns night vision on."""
        return await self._run(c.FillLight(brightness=brightness))

    async def set_ranging(self, enabled: bool = True) -> Feedback:
        """Continuous laser ranging on/off."""
        return await self._run(c.Ranging(enabled=enabled))
