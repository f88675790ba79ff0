"""Zoom of one camera moving over time within its range (sans-I/O)."""

from __future__ import annotations

import math
from dataclasses import dataclass

FULL_TRAVEL_SECONDS = 4.0
"""Simulator assumption: a continuous zoom crosses the optical range in about 4 s."""


@dataclass
class ZoomDrive:
    """Current ratio of one camera and where it is heading (``target=None``: standing)."""

    maximum: float
    minimum: float = 1.0
    value: float = 1.0
    target: float | None = None
    speed: float = 0.0
    """Ratio change per second; 0 → derived from the range and :data:`FULL_TRAVEL_SECONDS`."""

    def __post_init__(self) -> None:
        if self.speed <= 0:
            self.speed = max(self.maximum - self.minimum, 1.0) / FULL_TRAVEL_SECONDS

    @property
    def moving(self) -> bool:
        return self.target is not None

    def clamp(self, ratio: float) -> float:
        return min(max(ratio, self.minimum), self.maximum)

    def zoom_in(self) -> None:
        """Zoom in continuously (until :meth:`stop` or the maximum)."""
        self.target = self.maximum

    def zoom_out(self) -> None:
        """Zoom out continuously (until :meth:`stop` or the minimum)."""
        self.target = self.minimum

    def stop(self) -> None:
        self.target = None

    def zoom_to(self, ratio: float) -> None:
        """Head for ``ratio``, clamped into the range (the spec: "the maximum is what the
        pod can reach")."""
        self.target = self.clamp(ratio)

    def zoom_to_fraction(self, fraction: float) -> None:
        """Zoom to (``Opcode.ZOOM_TO``), positive values: fraction × maximum, never below the
        minimum (so with a 30× camera 1 → 1×, 5000 → 15×, 10000 → 30×, as the spec's example
        says)."""
        self.zoom_to(fraction * self.maximum)

    def set_maximum(self, maximum: float) -> None:
        """Change the range (digital zoom on/off); a ratio beyond it moves back in."""
        self.maximum = maximum
        if self.target is not None:
            self.target = self.clamp(self.target)
        if self.value > maximum:
            self.target = maximum

    def step(self, dt: float) -> None:
        """Advance ``dt`` seconds."""
        if self.target is None or dt <= 0:
            return
        diff = self.target - self.value
        travel = self.speed * dt
        if abs(diff) <= travel:
            self.value = self.target
            self.target = None
        else:
            self.value += math.copysign(travel, diff)
