"""What the simulator assumes about each pod model beyond the spec.

The protocol gives model codes (Appendix 7) and the command support matrix (Appendix 8) but
no zoom ranges, fields of view or versions. The values here are **simulator assumptions**,
chosen to be plausible and overridable: D-series pods get a 30× optical zoom camera, Z-series
pods 10×; the thermal camera (camera 2, on models that support the palette command) zooms
1–8× digitally; digital zoom on the visible camera multiplies its range by 4.
"""

from __future__ import annotations

from dataclasses import dataclass

from gcu_async.protocol.enums import PodModel
from gcu_async.protocol.pods import is_radiometric, is_thermal, pod_name, resolve_pod_model

D_SERIES_OPTICAL_ZOOM = 30.0
Z_SERIES_OPTICAL_ZOOM = 10.0
THERMAL_MAX_ZOOM = 8.0
DIGITAL_ZOOM_FACTOR = 4.0
HORIZONTAL_FOV_DEG = 60.0
"""Horizontal field of view of camera 1 at 1× (divided by the zoom ratio)."""
ASPECT = 16 / 9


@dataclass(frozen=True)
class PodProfile:
    """A simulated pod: model, cameras and their zoom ranges."""

    model: PodModel
    optical_zoom: float
    """Maximum optical zoom of camera 1 (visible / zoom camera)."""
    thermal_zoom: float | None
    """Maximum zoom of camera 2 (thermal); ``None`` on models without a thermal camera."""
    radiometric: bool
    """Measures temperature (area/spot/alarm/isotherm commands)."""
    hardware_version: float = 3.1
    firmware_version: float = 5.0
    digital_zoom_factor: float = DIGITAL_ZOOM_FACTOR

    @property
    def name(self) -> str:
        return pod_name(self.model)

    @property
    def thermal(self) -> bool:
        return self.thermal_zoom is not None

    @property
    def camera_mask(self) -> int:
        """Bit mask of the cameras this pod has (bit 0 camera 1, bit 1 camera 2)."""
        return 0b11 if self.thermal else 0b01


def profile_for(
    pod: PodModel | int | str,
    *,
    max_zoom: float | None = None,
    thermal_max_zoom: float | None = None,
) -> PodProfile:
    """The profile of ``pod`` (an Appendix 7 code or name), with optional zoom overrides.

    Raises ``ValueError`` for an unknown model or a maximum zoom below 1×.
    """
    model = resolve_pod_model(pod)
    default = D_SERIES_OPTICAL_ZOOM if pod_name(model).startswith("D-") else Z_SERIES_OPTICAL_ZOOM
    optical = default if max_zoom is None else max_zoom
    if not 1.0 <= optical <= 3276.0:
        raise ValueError(f"max_zoom: {optical!r} is outside the allowed range [1, 3276] x")
    thermal: float | None = None
    if is_thermal(model):
        thermal = THERMAL_MAX_ZOOM if thermal_max_zoom is None else thermal_max_zoom
        if not 1.0 <= thermal <= 3276.0:
            raise ValueError(
                f"thermal_max_zoom: {thermal!r} is outside the allowed range [1, 3276] x"
            )
    return PodProfile(model, float(optical), thermal, is_radiometric(model))
