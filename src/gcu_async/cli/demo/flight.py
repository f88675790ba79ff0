"""The aircraft the demo feeds to the GCU: a level, coordinated turn."""

from __future__ import annotations

import asyncio
import math
import time
from dataclasses import dataclass
from datetime import datetime, timezone
from typing import Any

from gcu_async.client.client import GcuClient
from gcu_async.protocol.units import GeoPosition, wrap_degrees_360


@dataclass(frozen=True)
class FlightPath:
    """A level, coordinated right turn at constant speed (what the demo tells the GCU)."""

    start: GeoPosition = GeoPosition(22.5760, 113.9400, 150.0)
    heading: float = 30.0
    """Degrees at t = 0."""
    turn_rate: float = 3.0
    """Degrees per second (positive: to the right)."""
    speed: float = 12.0
    """Ground speed, m/s."""
    height: float = 120.0
    """Metres above the take-off point (sent as the relative altitude)."""
    pitch: float = 2.0

    def heading_at(self, t: float) -> float:
        return wrap_degrees_360(self.heading + self.turn_rate * t)

    def state_at(self, t: float) -> dict[str, Any]:
        """Keyword arguments for :meth:`GcuClient.update_aircraft` at ``t`` seconds."""
        w = math.radians(self.turn_rate)
        h0, h = math.radians(self.heading), math.radians(self.heading + self.turn_rate * t)
        v = self.speed
        north = v * t * math.cos(h0) if w == 0 else v / w * (math.sin(h) - math.sin(h0))
        east = v * t * math.sin(h0) if w == 0 else v / w * (math.cos(h0) - math.cos(h))
        lat, lon, alt = self.start
        bank = math.degrees(math.atan2(v * w, 9.80665))
        return {
            "attitude": (bank, self.pitch, self.heading_at(t)),
            "velocity": (v * math.cos(h), v * math.sin(h), 0.0),
            "acceleration": (-v * w * math.sin(h), v * w * math.cos(h), 0.0),  # centripetal
            "position": (
                lat + north / 111_320.0,
                lon + east / (111_320.0 * math.cos(math.radians(lat))),
                alt,
            ),
            "relative_altitude": self.height,
            "satellites": 18,
            "gnss_time": datetime.now(timezone.utc),
        }


async def fly(gcu: GcuClient, path: FlightPath, started: float, period: float = 0.1) -> None:
    """Keep the client's aircraft state on ``path`` (until cancelled)."""
    while True:
        gcu.update_aircraft(**path.state_at(time.monotonic() - started))
        await asyncio.sleep(period)
