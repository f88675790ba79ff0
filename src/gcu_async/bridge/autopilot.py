"""The autopilot side: its MAVLink stream → the aircraft state the GCU's heartbeat carries.

Messages from the autopilot (this system id, component ``MAV_COMP_ID_AUTOPILOT1`` by
default) go through :class:`gcu_async.mavlink.MavlinkAircraftState`; the parts each message
gives are handed to :meth:`GcuClient.update_aircraft`, so each ages on its own and the
client's stale-feed rule (``aircraft_timeout``, docs/client.md, "Aircraft data: what the
packets claim") withdraws what stops arriving. AUTOPILOT_STATE_FOR_GIMBAL_DEVICE gives the
attitude and velocity for autopilots that send it. GLOBAL_POSITION_INT (altitude minus
relative altitude) or HOME_POSITION give the home altitude (ROI heights, ground point);
SYSTEM_TIME gives UTC for the geotags.
"""

from __future__ import annotations

import math
from typing import Any

from gcu_async.bridge._mavlink import mavlink
from gcu_async.bridge.geometry import euler_from_quaternion
from gcu_async.mavlink import MavlinkAircraftState
from gcu_async.protocol.units import Attitude, NorthEastUp, wrap_degrees_180, wrap_degrees_360


def gimbal_device_state_changes(msg: Any) -> dict[str, Any]:
    """AUTOPILOT_STATE_FOR_GIMBAL_DEVICE → ``update_aircraft`` keyword arguments: attitude
    from the quaternion (degrees, roll wrapped signed, yaw to a compass heading:
    :func:`~gcu_async.protocol.units.wrap_degrees_180` and ``wrap_degrees_360``) and velocity from
    vx/vy/vz (m/s NED → north/east/up), each only when finite."""
    changes: dict[str, Any] = {}
    q = list(msg.q)
    if all(math.isfinite(c) for c in q) and any(q):
        att = euler_from_quaternion(q)
        changes["attitude"] = Attitude(wrap_degrees_180(round(att.roll, 2)), att.pitch,
                                       wrap_degrees_360(round(att.yaw, 2)))  # fmt: skip
    if all(math.isfinite(v) for v in (msg.vx, msg.vy, msg.vz)):
        changes["velocity"] = NorthEastUp(float(msg.vx), float(msg.vy), -float(msg.vz))
    return changes


class AutopilotFeed:
    """Filters the autopilot's messages and turns them into aircraft updates.

    ``update(msg, now)`` returns the keyword arguments for ``update_aircraft`` (``None``
    when the message gives none). ``now`` is a monotonic time in seconds."""

    def __init__(self, system_id: int,
                 component_id: int = mavlink.MAV_COMP_ID_AUTOPILOT1) -> None:  # fmt: skip
        self.system_id = system_id
        self.component_id = component_id
        self.mapper = MavlinkAircraftState()
        self.home_altitude: float | None = None
        """Metres MSL (HOME_POSITION, else GLOBAL_POSITION_INT alt − relative_alt)."""
        self._home_from_message = False
        self._utc: tuple[int, float] | None = None
        self.position_at: float | None = None
        """When the last GLOBAL_POSITION_INT arrived (monotonic seconds)."""
        self.last_seen: float | None = None

    def accepts(self, msg: Any) -> bool:
        """Is ``msg`` from the autopilot?"""
        return bool(msg.get_srcSystem() == self.system_id
                    and msg.get_srcComponent() == self.component_id)  # fmt: skip

    def update(self, msg: Any, now: float) -> dict[str, Any] | None:
        """Take one autopilot message; raises what the mapping raises (FieldRangeError,
        ValueError) and then changes nothing."""
        self.last_seen = now
        kind = msg.get_type()
        if kind == "HOME_POSITION":
            self.home_altitude = msg.altitude / 1000
            self._home_from_message = True
            return None
        if kind == "AUTOPILOT_STATE_FOR_GIMBAL_DEVICE":
            return gimbal_device_state_changes(msg) or None
        if not self.mapper.update(msg):
            return None
        if kind == "GLOBAL_POSITION_INT":
            self.position_at = now
            if not self._home_from_message:
                self.home_altitude = (msg.alt - msg.relative_alt) / 1000
        elif kind == "SYSTEM_TIME":
            self._utc = (int(msg.time_unix_usec), now)
        return self.mapper.changes

    def utc_usec(self, now: float) -> int:
        """UTC now in µs since 1970 from the last SYSTEM_TIME (0 when none came)."""
        if self._utc is None:
            return 0
        usec, at = self._utc
        return usec + max(0, round((now - at) * 1e6))

    def position_current(self, now: float, timeout: float) -> bool:
        """A GLOBAL_POSITION_INT arrived within ``timeout`` seconds."""
        return self.position_at is not None and now - self.position_at <= timeout
