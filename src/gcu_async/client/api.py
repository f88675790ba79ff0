"""One awaitable method per command of V2.0.6, typed and in engineering units.

A mixin over :meth:`GcuClient.execute`: each method builds the protocol core's command
(validating every argument before anything is sent) and awaits its feedback.
"""

from __future__ import annotations

import abc

from gcu_async.protocol import commands as c
from gcu_async.protocol.enums import CameraMask, NightVisionMode, OsdCoordinates
from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.gcu_frames import GcuSubFrame
from gcu_async.protocol.host_frames import ControlValues
from gcu_async.protocol.units import wrap_degrees_180

CAM1 = CameraMask.CAMERA_1
CAM2 = CameraMask.CAMERA_2


class CommandMethods(abc.ABC):
    """Command methods shared by :class:`GcuClient`."""

    _info: GcuSubFrame | None

    @abc.abstractmethod
    async def execute(self, command: c.Command, *, timeout: float | None = None) -> Feedback:
        """Send a command and await its feedback."""

    @abc.abstractmethod
    def set_control(self, control: ControlValues | None) -> None:
        """Set the control values."""

    def _main_zoom(self) -> float:
        zoom = self._info.camera1_zoom if self._info is not None else 1.0
        return zoom if zoom >= 1.0 else 1.0

    async def _mode(self, command: c.Command, control: ControlValues | None) -> Feedback:
        # Control values change meaning with the mode: send them invalid (rates 0, angles
        # held) until the GCU confirms the new mode, then the new values.
        self.set_control(None)
        feedback = await self.execute(command)
        self.set_control(control)
        return feedback

    # -- pod: modes ----------------------------------------------------------------------
    async def euler_control(
        self, *, roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0
    ) -> Feedback:
        """Euler-angle control mode (0x14) holding roll/pitch/yaw Euler angles in degrees
        (yaw may be given in [0, 360); it is sent as ±180)."""
        control = ControlValues.angles(roll, pitch, wrap_degrees_180(yaw))
        return await self._mode(c.EulerControl(), control)

    async def angle_control(
        self, *, roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0
    ) -> Feedback:
        """Angle-control mode (0x10): roll/pitch Euler angles, yaw relative to the aircraft."""
        return await self._mode(c.AngleControl(), ControlValues.angles(roll, pitch, yaw))

    async def fpv(self, *, roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0) -> Feedback:
        """FPV mode (0x1C): roll/pitch/yaw angles relative to the aircraft, degrees."""
        return await self._mode(c.Fpv(), ControlValues.angles(roll, pitch, yaw))

    async def pointing_lock(self, *, pitch_rate: float = 0.0, yaw_rate: float = 0.0) -> Feedback:
        """Pointing-lock mode (0x11) with pitch/yaw rates in °/s at the current zoom."""
        control = ControlValues.rates(0.0, pitch_rate, yaw_rate, zoom=self._main_zoom())
        return await self._mode(c.PointingLock(), control)

    async def pointing_follow(
        self, *, pitch_rate: float = 0.0, yaw_rate: float = 0.0
    ) -> Feedback:
        """Pointing-follow mode (0x12); yaw rate 0 follows the aircraft's heading."""
        control = ControlValues.rates(0.0, pitch_rate, yaw_rate, zoom=self._main_zoom())
        return await self._mode(c.PointingFollow(), control)

    async def top_down(self, *, yaw_rate: float = 0.0) -> Feedback:
        """Top-down mode (0x13): pitch −90°, yaw rate in °/s."""
        control = ControlValues.rates(0.0, 0.0, yaw_rate, zoom=self._main_zoom())
        return await self._mode(c.TopDown(), control)

    async def gaze_lock(self, *, pitch_rate: float = 0.0, yaw_rate: float = 0.0) -> Feedback:
        """Gaze (geographic target lock) at the image centre (0x16); needs valid INS data."""
        control = ControlValues.rates(0.0, pitch_rate, yaw_rate, zoom=self._main_zoom())
        return await self._mode(c.GazeLock(), control)

    async def gaze_at(self, latitude: float, longitude: float, altitude: float) -> Feedback:
        """Gaze at a coordinate (0x15): degrees, degrees, metres MSL; needs valid INS data."""
        command = c.GazeAtCoordinates(latitude=latitude, longitude=longitude, altitude=altitude)
        return await self._mode(command, None)

    def set_angles(self, *, roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0) -> None:
        """New target angles (degrees) for the angle-based modes, from the next packet on."""
        self.set_control(ControlValues.angles(roll, pitch, yaw))

    def set_rates(
        self, *, roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0
    ) -> None:
        """New angular rates (°/s at the current main-view zoom) for the rate-based modes."""
        self.set_control(ControlValues.rates(roll, pitch, yaw, zoom=self._main_zoom()))

    def release_control(self) -> None:
        """Send the control values invalid: rates 0, angles held."""
        self.set_control(None)

    # -- pod: other ----------------------------------------------------------------------
    async def calibrate(self, *, timeout: float = 15.0) -> Feedback:
        """Calibrate (0x01); keeps waiting while the GCU answers "in progress"."""
        return await self.execute(c.Calibration(), timeout=timeout)

    async def centre(self) -> Feedback:
        """Centre pitch and heading (0x03); control values are sent invalid meanwhile."""
        return await self.execute(c.Centre())

    async def track(
        self, box: c.ImageBox | tuple[float, float, float, float], *, cameras: int = CAM1
    ) -> Feedback:
        """Track the target in ``box`` (left, top, right, bottom as image fractions). The
        pod steers itself while tracking: control values are sent invalid from now on."""
        command = c.Track(True, c.ImageBox(*box), cameras)
        self.set_control(None)
        return await self.execute(command)

    async def stop_tracking(self, *, cameras: int = CAM1) -> Feedback:
        """Exit tracking (0x17 with TT = 0)."""
        return await self.execute(c.Track(False, cameras=cameras))

    async def click_to_pan(self, x: float, y: float, *, cameras: int = CAM1) -> Feedback:
        """Bring image point (x, y) (fractions) to the centre (0x1A). The pod ends in
        pointing-lock, where control values are rates: they are sent invalid (hold) from now
        on, so earlier angle targets are never read as rates."""
        command = c.ClickToPan(c.ImagePoint(x, y), cameras)
        self.set_control(None)
        return await self.execute(command)

    # -- camera --------------------------------------------------------------------------
    async def take_photo(self, *, cameras: int = CAM1) -> Feedback:
        """Take a photo (0x20)."""
        return await self.execute(c.TakePhoto(cameras))

    async def toggle_recording(self, *, cameras: int = CAM1) -> Feedback:
        """Start or stop recording (0x21, a toggle)."""
        return await self.execute(c.Record(cameras))

    async def start_recording(self, *, cameras: int = CAM1) -> Feedback | None:
        """Start recording unless the camera flags say it already records (then ``None``)."""
        if self._info is not None and self._info.recording:
            return None
        return await self.toggle_recording(cameras=cameras)

    async def stop_recording(self, *, cameras: int = CAM1) -> Feedback | None:
        """Stop recording if the camera flags say it records (else ``None``)."""
        if self._info is None or not self._info.recording:
            return None
        return await self.toggle_recording(cameras=cameras)

    async def zoom_in(self, *, cameras: int = CAM1) -> Feedback:
        """Start zooming in (0x22) until :meth:`zoom_stop`."""
        return await self.execute(c.ZoomIn(cameras))

    async def zoom_out(self, *, cameras: int = CAM1) -> Feedback:
        """Start zooming out (0x23) until :meth:`zoom_stop`."""
        return await self.execute(c.ZoomOut(cameras))

    async def zoom_stop(self, *, cameras: int = CAM1) -> Feedback:
        """Stop a continuous zoom (0x24)."""
        return await self.execute(c.ZoomStop(cameras))

    async def zoom_to(self, ratio: float, *, cameras: int = CAM1) -> Feedback:
        """Zoom to a ratio (0x25), e.g. ``10.0`` for 10×, 0.1× resolution."""
        return await self.execute(c.ZoomTo(ratio=ratio, cameras=cameras))

    async def zoom_to_fraction(self, fraction: float, *, cameras: int = CAM1) -> Feedback:
        """Zoom to a fraction (0, 1] of the maximum ratio (0x25, positive form)."""
        return await self.execute(c.ZoomTo(fraction=fraction, cameras=cameras))

    async def focus(self, *, cameras: int = CAM1) -> Feedback:
        """Trigger focus (0x26)."""
        return await self.execute(c.Focus(cameras))

    async def set_palette(self, palette: int = 0, *, cameras: int = CAM2) -> Feedback:
        """Thermal palette 1–10, or 0 to cycle (0x2A)."""
        return await self.execute(c.Palette(palette, cameras))

    async def set_night_vision(
        self, mode: NightVisionMode | int = NightVisionMode.ON, *, cameras: int = CAM1
    ) -> Feedback:
        """Night vision off / on / auto (0x2B)."""
        return await self.execute(c.NightVision(NightVisionMode(mode), cameras))

    async def area_temperature(
        self,
        enabled: bool = True,
        box: c.ImageBox | tuple[float, float, float, float] = (0.0, 0.0, 1.0, 1.0),
        *,
        cameras: int = CAM2,
    ) -> Feedback:
        """Area temperature measurement over ``box`` (0x30)."""
        return await self.execute(c.AreaTemperature(enabled, c.ImageBox(*box), cameras))

    async def temperature_alarm(
        self, enabled: bool = True, *, high: float = 0.0, low: float = 0.0, cameras: int = CAM2
    ) -> Feedback:
        """Temperature alarm with high/low thresholds in °C (0x31)."""
        return await self.execute(c.TemperatureAlarm(enabled, high, low, cameras))

    async def isotherm(
        self, enabled: bool = True, *, high: float = 0.0, low: float = 0.0, cameras: int = CAM2
    ) -> Feedback:
        """Isotherm between ``low`` and ``high`` °C (0x32)."""
        return await self.execute(c.Isotherm(enabled, high, low, cameras))

    async def spot_temperature(
        self, enabled: bool = True, x: float = 0.5, y: float = 0.5, *, cameras: int = CAM2
    ) -> Feedback:
        """Spot temperature at image point (x, y) (0x33)."""
        command = c.SpotTemperature(enabled, c.ImagePoint(x, y), cameras)
        return await self.execute(command)

    async def set_osd(self, enabled: bool = True) -> Feedback:
        """On-screen display on/off (0x73)."""
        return await self.execute(c.Osd(enabled))

    async def set_osd_coordinates(
        self, coordinates: OsdCoordinates | int = OsdCoordinates.AIRCRAFT
    ) -> Feedback:
        """OSD shows aircraft or target coordinates (0x06)."""
        return await self.execute(c.OsdCoordinatesCommand(OsdCoordinates(coordinates)))

    async def set_image_auto_flip(self, enabled: bool = True) -> Feedback:
        """Image auto-flip on/off (0x07)."""
        return await self.execute(c.ImageAutoFlip(enabled))

    async def set_time_zone(self, offset_hours: int) -> Feedback:
        """The pod's UTC offset in whole hours, −12 … +14 (0x08)."""
        return await self.execute(c.TimeZone(offset_hours))

    async def set_picture_in_picture(self, mode: int = 0) -> Feedback:
        """Picture-in-picture mode 1–4, or 0 to cycle (0x74)."""
        return await self.execute(c.PictureInPicture(mode))

    async def set_target_detection(self, enabled: bool = True) -> Feedback:
        """AI target detection on/off (0x75)."""
        return await self.execute(c.TargetDetection(enabled))

    async def set_digital_zoom(self, enabled: bool = True) -> Feedback:
        """Digital zoom on/off (0x76)."""
        return await self.execute(c.DigitalZoom(enabled))

    async def set_fill_light(self, brightness: int) -> Feedback:
        """Fill light brightness 0–255, 0 = off (0x80); on also turns night vision on."""
        return await self.execute(c.FillLight(brightness))

    async def set_ranging(self, enabled: bool = True) -> Feedback:
        """Continuous laser ranging on/off (0x81)."""
        return await self.execute(c.Ranging(enabled))
