"""What the simulated GCU knows about the aircraft, from the host packets it receives."""

from __future__ import annotations

from dataclasses import dataclass

from gcu_async.protocol.host_frames import HostMainFrame, HostSubFrame
from gcu_async.protocol.units import Attitude, GeoPosition

DEFAULT_HEIGHT_M = 100.0
"""Simulator assumption: height above flat ground when the host sends no relative altitude."""


@dataclass
class AircraftState:
    """Aircraft attitude (host bytes 12–17) and GNSS position (host sub frame 38–60)."""

    attitude: Attitude = Attitude(0.0, 0.0, 0.0)
    """Last attitude received with the INS-valid flag (B0 of byte 11) set."""
    ins_valid: bool = False
    """B0 of byte 11 in the latest host packet."""
    position: GeoPosition | None = None
    """Last position from a host sub frame 0x01; ``None`` until one arrives."""
    relative_altitude: float = 0.0
    """Host sub frame bytes 57–60 (m above the take-off point, 0 = not sent)."""
    satellites: int = 0

    def update(self, main: HostMainFrame, sub: object) -> None:
        """Take the aircraft data of one host packet."""
        self.ins_valid = main.ins_valid
        if self.ins_valid:
            self.attitude = main.aircraft_attitude
        if isinstance(sub, HostSubFrame):
            self.position = sub.position
            self.relative_altitude = sub.relative_altitude
            self.satellites = sub.satellites

    @property
    def height(self) -> float:
        """Height above the (flat) ground: the relative altitude when sent, else
        :data:`DEFAULT_HEIGHT_M`."""
        return self.relative_altitude if self.relative_altitude > 0 else DEFAULT_HEIGHT_M
