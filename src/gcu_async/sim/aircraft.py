"""What the simulated GCU knows about the aircraft, from the host packets it receives."""

from __future__ import annotations

from dataclasses import dataclass

from gcu_async.protocol.host_frame_tables import AIRCRAFT_YAW
from gcu_async.protocol.host_frames import HostMainFrame, HostSubFrame
from gcu_async.protocol.units import Attitude, GeoPosition, NorthEastUp

DEFAULT_HEIGHT_M = 100.0
"""Simulator assumption: height above flat ground when the host sends no relative altitude."""


def aircraft_yaw(raw: int) -> float:
    """Host bytes 16–17 (U16, 0.01°, below a full turn) as the simulator uses them, a
    heading in degrees from 0 up to (excluding) a full turn.

    Out-of-range values are flagged by the decoder and read as the host most likely meant
    them (docs/protocol-notes.md §15, an aircraft yaw outside its range; the rule of
    :mod:`~gcu_async.protocol.headings`): from the field's
    :attr:`~gcu_async.protocol.headings.HeadingRule.signed_low` to the top of U16 as a signed
    S16 (what a host writing a signed value of half a turn either way sends for headings west
    of north), from a full turn up to there as an angle past a full turn (wrapped).
    """
    return AIRCRAFT_YAW.degrees(raw)


@dataclass
class ReceivedAircraft:
    """Aircraft attitude, acceleration, velocity (host bytes 11–29) and GNSS data (host sub
    frame 38–60), as the host packets report them."""

    attitude: Attitude = Attitude(0.0, 0.0, 0.0)
    """Last attitude received with the INS-valid flag (B0 of byte 11) set (yaw read by
    :func:`aircraft_yaw`)."""
    acceleration: NorthEastUp = NorthEastUp(0.0, 0.0, 0.0)
    """Last acceleration (N/E/U, gravity excluded) received with INS valid."""
    velocity: NorthEastUp = NorthEastUp(0.0, 0.0, 0.0)
    """Last velocity (N/E/U) received with INS valid."""
    ins_valid: bool = False
    """B0 of byte 11 in the latest host packet."""
    packets: int = 0
    """Host packets taken."""
    ins_valid_packets: int = 0
    """Host packets that had INS valid."""
    ins_changes: int = 0
    """Times the INS-valid flag changed from one host packet to the next."""
    has_sub_frame: bool = False
    """The latest host packet carried a sub frame 0x01 (position, GNSS time)."""
    position: GeoPosition | None = None
    """Last position from a host sub frame 0x01; ``None`` until one arrives."""
    relative_altitude: float = 0.0
    """Host sub frame bytes 57–60 (m above the take-off point, 0 = not sent)."""
    satellites: int = 0
    gnss_week: int = 0
    """Host sub frame bytes 55–56 of the last sub frame."""
    gnss_ms: int = 0
    """Host sub frame bytes 51–54 of the last sub frame."""

    def update(self, main: HostMainFrame, sub: object) -> None:
        """Take the aircraft data of one host packet."""
        valid = main.ins_valid
        self.count(valid)
        self.ins_valid = valid
        if valid:
            self.attitude = Attitude(
                main.aircraft_roll_raw / 100,
                main.aircraft_pitch_raw / 100,
                aircraft_yaw(main.aircraft_yaw_raw),
            )
            self.acceleration = main.acceleration
            self.velocity = main.velocity
        self.has_sub_frame = isinstance(sub, HostSubFrame)
        if isinstance(sub, HostSubFrame):
            self.position = sub.position
            self.relative_altitude = sub.relative_altitude
            self.satellites = sub.satellites
            self.gnss_week = sub.gnss_week
            self.gnss_ms = sub.gnss_ms

    def count(self, valid: bool) -> None:
        """Count one host packet with INS valid ``valid`` (the counters :meth:`update`
        keeps: a packet repeated while the model is at rest is counted so, its data being
        what this object holds already)."""
        if self.packets and valid is not self.ins_valid:
            self.ins_changes += 1
        self.packets += 1
        if valid:
            self.ins_valid_packets += 1

    @property
    def height(self) -> float:
        """Height above the (flat) ground: the relative altitude when sent, else
        :data:`DEFAULT_HEIGHT_M`."""
        return self.relative_altitude if self.relative_altitude > 0 else DEFAULT_HEIGHT_M
