"""Camera-side state of the simulated pod: zoom, recording, display and thermal settings.

Everything here shows up in the GCU sub frame (bytes 59–66) or the pod status flags
(main frame bytes 6–7). The thermal scene is a simulator assumption: a fixed range of
temperatures (15–45 °C by default) against which the temperature alarm thresholds are
compared.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from gcu_async.protocol.enums import CameraFlags, NightVisionMode, ThermalFlags
from gcu_async.protocol.units import ImageBox, ImagePoint
from gcu_async.sim.profiles import PodProfile
from gcu_async.sim.zoom import ZoomDrive

VISIBLE, THERMAL = 1, 2
"""Camera numbers (bit 0 / bit 1 of a camera mask)."""
PALETTES = 10
PIP_MODES = 4
THERMAL_ZOOM_TRAVEL_SECONDS = 2.0


def cameras_in(mask: int) -> list[int]:
    """Camera numbers named by a camera mask (bit 0 = camera 1)."""
    return [bit + 1 for bit in range(8) if mask >> bit & 1]


@dataclass
class CameraState:
    """Settings and counters of the pod's cameras."""

    zoom: dict[int, ZoomDrive]
    """Camera number → its zoom drive (camera 2 only on thermal models)."""
    optical_max: float = 30.0
    digital_zoom_factor: float = 4.0
    recording: bool = False
    photos: dict[int, int] = field(default_factory=dict)
    """Camera number → photos taken."""
    focus_count: int = 0
    osd_on: bool = False
    osd_target_coordinates: bool = False
    auto_flip: bool = True
    digital_zoom: bool = False
    target_detection: bool = False
    pip_mode: int = 0
    time_zone: int = 0
    night_vision: NightVisionMode = NightVisionMode.OFF
    ambient_dark: bool = False
    """What night vision "auto" sees: the simulator's scene is in daylight unless set."""
    fill_light: int = 0
    """Fill light brightness 0–255 (0 = off)."""
    ranging: bool = False
    palette: int = 1
    area_temperature: ImageBox | None = None
    spot_temperature: ImagePoint | None = None
    temperature_alarm: tuple[float, float] | None = None
    """(high, low) thresholds in °C while the alarm is on."""
    isotherm: tuple[float, float] | None = None
    scene_temperature: tuple[float, float] = (15.0, 45.0)
    """(coldest, hottest) temperature in the simulated thermal image, °C."""

    @classmethod
    def for_profile(cls, profile: PodProfile) -> CameraState:
        zoom = {VISIBLE: ZoomDrive(maximum=profile.optical_zoom)}
        if profile.thermal_zoom is not None:
            speed = max(profile.thermal_zoom - 1.0, 1.0) / THERMAL_ZOOM_TRAVEL_SECONDS
            zoom[THERMAL] = ZoomDrive(maximum=profile.thermal_zoom, speed=speed)
        return cls(zoom, optical_max=profile.optical_zoom,
                   digital_zoom_factor=profile.digital_zoom_factor)  # fmt: skip

    @property
    def mask(self) -> int:
        """Camera mask of the cameras present."""
        bits = 0
        for number in self.zoom:
            bits |= 1 << (number - 1)
        return bits

    @property
    def main_zoom(self) -> float:
        """Zoom of the main view (camera 1), which scales the control rates
        (docs/protocol-notes.md §5 "Control values change meaning with the mode")."""
        return self.zoom[VISIBLE].value

    @property
    def night_vision_on(self) -> bool:
        return self.night_vision == NightVisionMode.ON or (
            self.night_vision == NightVisionMode.AUTO and self.ambient_dark
        )

    def set_digital_zoom(self, on: bool) -> None:
        """Digital zoom (``Opcode.DIGITAL_ZOOM``) extends camera 1's range by the digital factor."""
        self.digital_zoom = on
        factor = self.digital_zoom_factor if on else 1.0
        self.zoom[VISIBLE].set_maximum(self.optical_max * factor)

    def set_fill_light(self, brightness: int) -> None:
        """Fill light (``Opcode.FILL_LIGHT``): turning it on also turns night vision on; off
        leaves it."""
        self.fill_light = brightness
        if brightness > 0:
            self.night_vision = NightVisionMode.ON

    def cycle_pip(self, mode: int) -> None:
        """Picture in picture (``Opcode.PICTURE_IN_PICTURE``): mode 1 to :data:`PIP_MODES`, or 0
        to step to the next mode."""
        self.pip_mode = mode if mode else self.pip_mode % PIP_MODES + 1

    def cycle_palette(self, palette: int) -> None:
        """Thermal palette (``Opcode.PALETTE``): palette 1 to :data:`PALETTES`, or 0 to step to
        the next one."""
        self.palette = palette if palette else self.palette % PALETTES + 1

    def step(self, dt: float) -> None:
        for drive in self.zoom.values():
            drive.step(dt)

    def thermal_flags(self, radiometric: bool) -> int:
        """GCU sub frame byte 63."""
        flags = ThermalFlags(0)
        if radiometric:
            flags |= ThermalFlags.MEASUREMENT_AVAILABLE
        if self.area_temperature is not None:
            flags |= ThermalFlags.AREA_TEMPERATURE_ON
        if self.spot_temperature is not None:
            flags |= ThermalFlags.SPOT_TEMPERATURE_ON
        if self.isotherm is not None:
            flags |= ThermalFlags.ISOTHERM_ON
        if self.temperature_alarm is not None:
            flags |= ThermalFlags.TEMPERATURE_ALARM_ON
            high, low = self.temperature_alarm
            coldest, hottest = self.scene_temperature
            if hottest > high:
                flags |= ThermalFlags.HIGH_TEMPERATURE_ALARM
            if coldest < low:
                flags |= ThermalFlags.LOW_TEMPERATURE_ALARM
        return int(flags)

    def camera_flags(self) -> int:
        """GCU sub frame bytes 64–65, without the picture-in-picture bits."""
        flags = CameraFlags(0)
        if self.recording:
            flags |= CameraFlags.RECORDING
        if not self.auto_flip:
            flags |= CameraFlags.AUTO_FLIP_OFF
        if self.osd_target_coordinates:
            flags |= CameraFlags.OSD_TARGET_COORDINATES
        if self.osd_on:
            flags |= CameraFlags.OSD_ON
        if self.digital_zoom:
            flags |= CameraFlags.DIGITAL_ZOOM_ON
        if self.target_detection:
            flags |= CameraFlags.TARGET_DETECTION_ON
        return int(flags)
