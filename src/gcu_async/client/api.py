"""One awaitable method per command of V2.0.6, typed and in engineering units.

A mixin over :meth:`GcuClient._submit`: each method checks its arguments, builds the
protocol core's command and awaits its feedback. The boundary (:mod:`gcu_async._checks`):
a flag is a ``bool``, a mask or count an ``int`` (an IntFlag/IntEnum member counts as its
value), a real number a finite ``int``/``float``, an enum one of its members or exact
values, a box an :class:`~gcu_async.protocol.ImageBox` or a plain 4-tuple. Nothing is
coerced, clipped or wrapped. A bad argument raises ``TypeError`` or
:class:`~gcu_async.errors.FieldRangeError` whose message starts with the parameter name as
the caller wrote it (``pitch_rate``, ``box.right``) and gives the allowed range and the
value; then nothing is sent and no state changes (tests/client/test_client_boundary.py).

The methods' names, parameters, defaults and ranges are those of the command catalogue
(:mod:`gcu_async.protocol.catalogue`, docs/architecture.md "One command catalogue");
tests/protocol/test_catalogue.py checks every method against its entry.
"""

from __future__ import annotations

import abc
from typing import Any, TypeVar

from gcu_async._checks import check_bool, check_int, check_positive, check_real, type_error
from gcu_async.protocol import commands as c
from gcu_async.protocol.catalogue import ALTITUDE_RANGE, RATE_LIMIT, TEMPERATURE_RANGE
from gcu_async.protocol.enums import CameraMask, NightVisionMode, OsdCoordinateSource
from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.gcu_frames import GcuSubFrame
from gcu_async.protocol.host_frames import ControlValues
from gcu_async.protocol.units import Attitude, check_member, check_tuple
from gcu_async.session import ControlKind

_NT = TypeVar("_NT", bound=tuple[Any, ...])

CAM1 = CameraMask.CAMERA_1
CAM2 = CameraMask.CAMERA_2


def _angle(name: str, value: object, low: float = -180.0, high: float = 180.0) -> float:
    return check_real(name, value, low, high, "deg")


def _cameras(value: object) -> int:
    return check_int("cameras", value, 1, 0xFF, "camera mask")


def _point(x: object, y: object) -> c.ImagePoint:
    return c.ImagePoint(check_real("x", x, 0.0, 1.0, "image fraction"),
                        check_real("y", y, 0.0, 1.0, "image fraction"))  # fmt: skip


def check_sequence(field: str, value: object, cls: type[_NT]) -> _NT:
    """``value`` as a ``cls`` (a NamedTuple of units): an instance, a plain tuple or a list
    (JSON gives lists) of the right length, and nothing else (a ``TypeError`` naming what
    is accepted). The elements are the caller's to check."""
    try:
        return check_tuple(field, tuple(value) if type(value) is list else value, cls)
    except TypeError:
        name = cls.__name__
        article = "an" if name[0] in "AEIOU" else "a"
        fields = ", ".join(cls._fields)  # type: ignore[attr-defined]
        raise type_error(field, f"{article} {name} or a tuple or list ({fields})",
                         value) from None  # fmt: skip


def _box(value: object) -> c.ImageBox:
    """An ImageBox, a plain 4-tuple or a list of 4, each edge a fraction checked under
    ``box.<edge>``."""
    box = check_sequence("box", value, c.ImageBox)
    return c.ImageBox(*(check_real(f"box.{f}", v, 0.0, 1.0, "image fraction")
                        for f, v in zip(c.ImageBox._fields, box, strict=True)))  # fmt: skip


class CommandMethods(abc.ABC):
    """Command methods shared by :class:`GcuClient`."""

    @property
    @abc.abstractmethod
    def _info(self) -> GcuSubFrame | None:
        """The latest sub frame."""

    @abc.abstractmethod
    async def _submit(
        self,
        command: c.Command,
        *,
        timeout: float | None = None,
        queue_timeout: float | None = None,
        control: ControlValues | None = None,
        recording_target: bool | None = None,
    ) -> Feedback | None:
        """Submit a command and await its outcome."""

    @abc.abstractmethod
    def _set_control(self, control: ControlValues | None, kind: ControlKind) -> None:
        """New control values of ``kind`` for the current mode."""

    @abc.abstractmethod
    def _current_attitude(self) -> Attitude:
        """The camera's latest reported attitude (zeros before the first reply)."""

    async def _run(self, command: c.Command, *, timeout: float | None = None,
                   control: ControlValues | None = None) -> Feedback:  # fmt: skip
        result = await self._submit(command, timeout=timeout, control=control)
        assert result is not None  # only state-checked record commands are ever skipped
        return result

    @property
    def max_zoom(self) -> float | None:
        """Camera 1's largest zoom ratio, as given to the client (``None``: not known; the
        protocol reports no limit)."""
        return None

    def _main_zoom(self) -> float:
        info = self._info
        zoom = info.camera1_zoom if info is not None else 1.0
        return zoom if zoom >= 1.0 else 1.0

    def _rates(self, **rates: object) -> ControlValues:
        """Control values for three rates given as ``name=value`` (roll, pitch, yaw in that
        order), each checked under the name the caller used."""
        zoom = self._main_zoom()
        limit = RATE_LIMIT / zoom
        unit = f"deg/s at zoom {zoom:g}x"
        r, p, y = (check_real(name, v, -limit, limit, unit) for name, v in rates.items())
        return ControlValues.rates(r, p, y, zoom=zoom)

    # -- pod: modes ------------------------------------------------------------------------
    async def enter_euler_control(
        self, *, roll: float | None = None, pitch: float | None = None,
        yaw: float | None = None,
    ) -> Feedback:  # fmt: skip
        """Euler-angle control mode (0x14) holding roll/pitch/yaw Euler angles in degrees;
        an angle left out keeps the camera's current one (``status.attitude``), so
        ``enter_euler_control(pitch=-45)`` does not swing the yaw. ``yaw`` may be given in
        [-180, 360): [180, 360) is sent as its −180…0 equivalent. The angles go out valid
        once the GCU confirmed the mode; :meth:`reach_attitude` also waits until the camera
        is there."""
        current = self._current_attitude()
        roll = current.roll if roll is None else roll
        pitch = current.pitch if pitch is None else pitch
        yaw = current.yaw if yaw is None else yaw
        y = check_real("yaw", yaw, -180.0, 360.0, "deg", high_open=True)
        values = ControlValues.angles(_angle("roll", roll), _angle("pitch", pitch),
                                      y - 360.0 if y >= 180.0 else y)  # fmt: skip
        return await self._run(c.EulerControl(), control=values)

    async def enter_angle_control(
        self, *, roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0
    ) -> Feedback:
        """Angle-control mode (0x10): roll/pitch Euler angles, yaw relative to the aircraft
        (degrees, ±180)."""
        values = ControlValues.angles(_angle("roll", roll), _angle("pitch", pitch),
                                      _angle("yaw", yaw))  # fmt: skip
        return await self._run(c.AngleControl(), control=values)

    async def enter_fpv(
        self, *, roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0
    ) -> Feedback:
        """FPV mode (0x1C): roll/pitch/yaw angles relative to the aircraft, degrees (±180)."""
        values = ControlValues.angles(_angle("roll", roll), _angle("pitch", pitch),
                                      _angle("yaw", yaw))  # fmt: skip
        return await self._run(c.Fpv(), control=values)

    async def enter_pointing_lock(
        self, *, pitch_rate: float = 0.0, yaw_rate: float = 0.0
    ) -> Feedback:
        """Pointing-lock mode (0x11) with pitch/yaw rates in °/s at the current zoom
        (at most 150 / zoom °/s)."""
        values = self._rates(roll_rate=0.0, pitch_rate=pitch_rate, yaw_rate=yaw_rate)
        return await self._run(c.PointingLock(), control=values)

    async def enter_pointing_follow(
        self, *, pitch_rate: float = 0.0, yaw_rate: float = 0.0
    ) -> Feedback:
        """Pointing-follow mode (0x12); yaw rate 0 follows the aircraft's heading."""
        values = self._rates(roll_rate=0.0, pitch_rate=pitch_rate, yaw_rate=yaw_rate)
        return await self._run(c.PointingFollow(), control=values)

    async def enter_top_down(self, *, yaw_rate: float = 0.0) -> Feedback:
        """Top-down mode (0x13): pitch −90°, yaw rate in °/s."""
        values = self._rates(roll_rate=0.0, pitch_rate=0.0, yaw_rate=yaw_rate)
        return await self._run(c.TopDown(), control=values)

    async def enter_gaze_lock(self, *, pitch_rate: float = 0.0, yaw_rate: float = 0.0) -> Feedback:
        """Gaze (geographic target lock) at the image centre (0x16); needs valid INS data."""
        values = self._rates(roll_rate=0.0, pitch_rate=pitch_rate, yaw_rate=yaw_rate)
        return await self._run(c.GazeLock(), control=values)

    async def gaze_at(self, latitude: float, longitude: float, altitude: float) -> Feedback:
        """Gaze at a coordinate (0x15): degrees, degrees, metres MSL; needs valid INS data.
        Control values stay invalid (the pod locks the point) until :meth:`set_rates`."""
        command = c.GazeAtCoordinates(
            latitude=check_real("latitude", latitude, -90.0, 90.0, "deg"),
            longitude=check_real("longitude", longitude, -180.0, 180.0, "deg"),
            altitude=check_real("altitude", altitude, *ALTITUDE_RANGE, "m"),
        )
        return await self._run(command)

    def set_angles(self, *, roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0) -> None:
        """New target angles (degrees, ±180) for the current angle-based mode (Euler, angle
        control, FPV). Raises ``ValueError`` if the current mode does not take angles."""
        values = ControlValues.angles(_angle("roll", roll), _angle("pitch", pitch),
                                      _angle("yaw", yaw))  # fmt: skip
        self._set_control(values, ControlKind.ANGLES)

    def set_rates(self, *, roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0) -> None:
        """New angular rates (°/s at the current main-view zoom) for the current rate-based
        mode. Raises ``ValueError`` if the current mode does not take rates."""
        values = self._rates(roll=roll, pitch=pitch, yaw=yaw)
        self._set_control(values, ControlKind.RATES)

    def release_control(self) -> None:
        """Send the control values invalid from now on: rates 0, angles held."""
        self._set_control(None, ControlKind.NONE)

    # -- pod: other ------------------------------------------------------------------------
    async def calibrate(self, *, timeout: float = 15.0) -> Feedback:
        """Calibrate (0x01); keeps waiting while the GCU answers "in progress", up to
        ``timeout`` seconds (a finite real number > 0)."""
        return await self._run(c.Calibration(), timeout=check_positive("timeout", timeout))

    async def centre(self) -> Feedback:
        """Centre pitch and heading (0x03). Control values go out invalid while it runs and
        are cleared afterwards (they would steer away from the centre)."""
        return await self._run(c.Centre())

    async def track(
        self, box: c.ImageBox | tuple[float, float, float, float] | list[float], *,
        cameras: int = CAM1,
    ) -> Feedback:  # fmt: skip
        """Track the target in ``box`` (left, top, right, bottom as image fractions; an
        ImageBox, a tuple or a list of four). The pod steers itself while tracking: control
        values go out invalid."""
        return await self._run(c.Track(True, _box(box), _cameras(cameras)))

    async def stop_tracking(self, *, cameras: int = CAM1) -> Feedback:
        """Exit tracking (0x17 with TT = 0); control values stay invalid until a mode
        command is confirmed."""
        return await self._run(c.Track(False, cameras=_cameras(cameras)))

    async def click_to_pan(self, x: float, y: float, *, cameras: int = CAM1) -> Feedback:
        """Bring image point (x, y) (fractions) to the centre (0x1A). The pod ends in
        pointing-lock; control values stay invalid until a mode command is confirmed."""
        return await self._run(c.ClickToPan(_point(x, y), _cameras(cameras)))

    # -- camera ----------------------------------------------------------------------------
    async def take_photo(self, *, cameras: int = CAM1) -> Feedback:
        """Take a photo (0x20)."""
        return await self._run(c.TakePhoto(_cameras(cameras)))

    async def toggle_recording(self, *, cameras: int = CAM1) -> Feedback:
        """Start or stop recording (0x21, a toggle), unconditionally."""
        return await self._run(c.Record(_cameras(cameras)))

    async def start_recording(self, *, cameras: int = CAM1) -> Feedback | None:
        """Start recording unless the camera already records (then ``None``, nothing sent).
        Record commands run one at a time and the state is checked when this one's turn
        comes, so concurrent calls start recording once (docs/client.md, "Recording")."""
        return await self._submit(c.Record(_cameras(cameras)), recording_target=True)

    async def stop_recording(self, *, cameras: int = CAM1) -> Feedback | None:
        """Stop recording if the camera records (else ``None``, nothing sent)."""
        return await self._submit(c.Record(_cameras(cameras)), recording_target=False)

    async def zoom_in(self, *, cameras: int = CAM1) -> Feedback:
        """Start zooming in (0x22) until :meth:`stop_zoom`."""
        return await self._run(c.ZoomIn(_cameras(cameras)))

    async def zoom_out(self, *, cameras: int = CAM1) -> Feedback:
        """Start zooming out (0x23) until :meth:`stop_zoom`."""
        return await self._run(c.ZoomOut(_cameras(cameras)))

    async def stop_zoom(self, *, cameras: int = CAM1) -> Feedback:
        """Stop a continuous zoom (0x24)."""
        return await self._run(c.ZoomStop(_cameras(cameras)))

    async def zoom_to(self, ratio: float, *, cameras: int = CAM1) -> Feedback:
        """Zoom to a ratio (0x25), e.g. ``10.0`` for 10×, 0.1× resolution, 1 … 3276.8, and
        at most :attr:`max_zoom` when the client was given it (the GCU itself answers
        success and stops at its limit)."""
        r = check_zoom_ratio(ratio, self.max_zoom)
        return await self._run(c.ZoomTo(ratio=r, cameras=_cameras(cameras)))

    async def zoom_to_fraction(self, fraction: float, *, cameras: int = CAM1) -> Feedback:
        """Zoom to a fraction (0, 1] of the maximum ratio (0x25, positive form; resolution
        1/10000)."""
        f = check_real("fraction", fraction, 1e-4, 1.0, "of maximum ratio")
        return await self._run(c.ZoomTo(fraction=f, cameras=_cameras(cameras)))

    async def focus(self, *, cameras: int = CAM1) -> Feedback:
        """Trigger focus (0x26)."""
        return await self._run(c.Focus(_cameras(cameras)))

    async def set_palette(self, palette: int = 0, *, cameras: int = CAM2) -> Feedback:
        """Thermal palette 1–10, or 0 to cycle (0x2A)."""
        return await self._run(c.Palette(check_int("palette", palette, 0, 10), _cameras(cameras)))

    async def set_night_vision(
        self, mode: NightVisionMode | int = NightVisionMode.ON, *, cameras: int = CAM1
    ) -> Feedback:
        """Night vision off / on / auto (0x2B)."""
        command = c.NightVision(check_member("mode", mode, NightVisionMode), _cameras(cameras))
        return await self._run(command)

    async def set_area_temperature(
        self,
        enabled: bool = True,
        box: c.ImageBox | tuple[float, float, float, float] | list[float] = (0.0, 0.0, 1.0, 1.0),
        *,
        cameras: int = CAM2,
    ) -> Feedback:
        """Area temperature measurement over ``box`` (0x30)."""
        command = c.AreaTemperature(check_bool("enabled", enabled), _box(box), _cameras(cameras))
        return await self._run(command)

    async def set_temperature_alarm(
        self, enabled: bool = True, *, high: float = 0.0, low: float = 0.0, cameras: int = CAM2
    ) -> Feedback:
        """Temperature alarm with high/low thresholds in °C (0x31)."""
        command = c.TemperatureAlarm(check_bool("enabled", enabled), _temp("high", high),
                                     _temp("low", low), _cameras(cameras))  # fmt: skip
        return await self._run(command)

    async def set_isotherm(
        self, enabled: bool = True, *, high: float = 0.0, low: float = 0.0, cameras: int = CAM2
    ) -> Feedback:
        """Isotherm between ``low`` and ``high`` °C (0x32)."""
        command = c.Isotherm(check_bool("enabled", enabled), _temp("high", high),
                             _temp("low", low), _cameras(cameras))  # fmt: skip
        return await self._run(command)

    async def set_spot_temperature(
        self, enabled: bool = True, x: float = 0.5, y: float = 0.5, *, cameras: int = CAM2
    ) -> Feedback:
        """Spot temperature at image point (x, y) (0x33)."""
        command = c.SpotTemperature(check_bool("enabled", enabled), _point(x, y),
                                    _cameras(cameras))  # fmt: skip
        return await self._run(command)

    async def set_osd(self, enabled: bool = True) -> Feedback:
        """On-screen display on/off (0x73)."""
        return await self._run(c.Osd(check_bool("enabled", enabled)))

    async def set_osd_coordinates(
        self, coordinates: OsdCoordinateSource | int = OsdCoordinateSource.AIRCRAFT
    ) -> Feedback:
        """OSD shows aircraft or target coordinates (0x06)."""
        value = check_member("coordinates", coordinates, OsdCoordinateSource)
        return await self._run(c.OsdCoordinates(value))

    async def set_image_auto_flip(self, enabled: bool = True) -> Feedback:
        """Image auto-flip on/off (0x07)."""
        return await self._run(c.ImageAutoFlip(check_bool("enabled", enabled)))

    async def set_time_zone(self, offset_hours: int) -> Feedback:
        """The pod's UTC offset in whole hours, −12 … +14 (0x08)."""
        return await self._run(c.TimeZone(check_int("offset_hours", offset_hours, -12, 14, "h")))

    async def set_picture_in_picture(self, mode: int = 0) -> Feedback:
        """Picture-in-picture mode 1–4, or 0 to cycle (0x74)."""
        return await self._run(c.PictureInPicture(check_int("mode", mode, 0, 4)))

    async def set_target_detection(self, enabled: bool = True) -> Feedback:
        """AI target detection on/off (0x75)."""
        return await self._run(c.TargetDetection(check_bool("enabled", enabled)))

    async def set_digital_zoom(self, enabled: bool = True) -> Feedback:
        """Digital zoom on/off (0x76)."""
        return await self._run(c.DigitalZoom(check_bool("enabled", enabled)))

    async def set_fill_light(self, brightness: int) -> Feedback:
        """Fill light brightness 0–255, 0 = off (0x80); on also turns night vision on."""
        return await self._run(c.FillLight(check_int("brightness", brightness, 0, 255)))

    async def set_ranging(self, enabled: bool = True) -> Feedback:
        """Continuous laser ranging on/off (0x81)."""
        return await self._run(c.Ranging(check_bool("enabled", enabled)))


def check_zoom_ratio(ratio: object, max_zoom: float | None) -> float:
    """``ratio`` checked against what the field carries and the pod's limit if known."""
    if max_zoom is None:
        return check_real("ratio", ratio, 1.0, c.ZOOM_RATIO_MAX, "x")
    return check_real("ratio", ratio, 1.0, max_zoom, "x",
                      detail=f"camera 1's maximum zoom is {max_zoom:g}x (max_zoom)")  # fmt: skip


def _temp(name: str, value: object) -> float:
    return check_real(name, value, *TEMPERATURE_RANGE, "degC")
