"""The simulated laser rangefinder: distance to flat ground along the line of sight.

Simulator assumptions: flat ground at the aircraft's height (see
:attr:`ReceivedAircraft.height`), a 3 km maximum range, ±0.2 m uniform noise from the model's
seeded random generator. Off: distance 0. On without a hit: −1 m (raw −10), as the spec
says the device reports. Distance *and* target coordinates valid (pod status B7) needs a
hit and a known aircraft position.
"""

from __future__ import annotations

import random
from dataclasses import dataclass

from gcu_async.protocol.units import Attitude, GeoPosition, offset_position
from gcu_async.sim.aircraft import ReceivedAircraft
from gcu_async.sim.geometry import ground_hit

MAX_RANGE_M = 3_000.0
NOISE_M = 0.2
NO_HIT_M = -1.0


@dataclass
class Rangefinder:
    on: bool = False
    distance: float = 0.0
    position: GeoPosition | None = None
    noise: float = NOISE_M

    @property
    def valid(self) -> bool:
        """Distance and target coordinates valid (pod status B7)."""
        return self.on and self.distance > 0 and self.position is not None

    @property
    def steady(self) -> bool:
        """The next :meth:`measure` at the same attitude draws no noise and finds what the
        last one found: off, or on with nothing hit."""
        return not self.on or (self.distance == NO_HIT_M and self.position is None)

    def measure(self, attitude: Attitude, aircraft: ReceivedAircraft, rng: random.Random) -> None:
        """Take a reading for the camera's current ``attitude``."""
        self.position = None
        if not self.on:
            self.distance = 0.0
            return
        sight = ground_hit(attitude.pitch, attitude.yaw, aircraft.height, MAX_RANGE_M)
        if sight is None:
            self.distance = NO_HIT_M
            return
        self.distance = max(sight.distance + rng.uniform(-self.noise, self.noise), 0.1)
        if aircraft.position is not None:
            self.position = offset_position(aircraft.position, sight.north, sight.east, sight.up)
