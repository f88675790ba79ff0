"""What the bridge knows at one instant: a snapshot the pure mapping functions read.

The asyncio part builds one :class:`GcuView` per message it answers or streams (from the
client, the autopilot feed and the bridge's own bookkeeping); everything that turns it into
MAVLink is a pure function of it, tested without sockets.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from gcu_async.protocol.aircraft import AircraftState
from gcu_async.protocol.enums import Mode, PodModel
from gcu_async.protocol.gcu_frames import GcuMainFrame, GcuSubFrame
from gcu_async.protocol.pods import POD_NAMES, supports


@dataclass(frozen=True)
class Control:
    """Who controls the gimbal manager (MAV_CMD_DO_GIMBAL_MANAGER_CONFIGURE): (system id,
    component id) of the primary and secondary controller, (0, 0) for none."""

    primary: tuple[int, int] = (0, 0)
    secondary: tuple[int, int] = (0, 0)

    def allows(self, source: tuple[int, int]) -> bool:
        """Anyone may steer while nobody took control; then only the two controllers."""
        if self.primary == (0, 0) and self.secondary == (0, 0):
            return True
        return source in (self.primary, self.secondary)


@dataclass(frozen=True)
class GcuView:
    """A snapshot of the GCU (via the client), the aircraft (via the autopilot feed) and
    the bridge's own state, at ``time_boot_ms`` (ms since the bridge started)."""

    time_boot_ms: int = 0
    link_up: bool = False
    """Replies from the GCU are arriving."""
    status: GcuMainFrame | None = None
    """The latest GCU main frame (mode, angles, rates, pod status)."""
    info: GcuSubFrame | None = None
    """The latest GCU sub frame (pod model, versions, zoom, ranging, faults, flags)."""
    ins_valid: bool = False
    """The host packets currently mark the aircraft's INS data valid (so the GCU's absolute
    yaw is earth-referenced)."""
    aircraft: AircraftState = field(default_factory=AircraftState)
    """The aircraft state the autopilot feed gave."""
    position_current: bool = False
    """The aircraft position is current (within the feed's ``aircraft_timeout``)."""
    home_altitude: float | None = None
    """Metres MSL of the home (take-off) point: position altitude minus relative altitude
    from the autopilot, ``None`` until both are known."""
    utc_usec: int = 0
    """UTC now, µs since 1970, from the autopilot's SYSTEM_TIME (0: unknown)."""
    recording: bool | None = None
    """The GCU's record flag (``None``: not known yet)."""
    recording_since_ms: int | None = None
    """``time_boot_ms`` at which the bridge saw recording start."""
    images_captured: int = 0
    """Successful photos taken through the bridge."""
    control: Control = field(default_factory=Control)
    bridge_mode: Mode | None = None
    """The mode the bridge's last confirmed mode command set (``None``: none yet)."""
    pending_mode: Mode | None = None
    """The mode of a mode command the bridge has sent and not yet seen answered."""
    tracking_mode: int = 0
    """CAMERA_TRACKING_MODE of the last tracking command the GCU accepted (0: none)."""
    tracking_box: tuple[float, float, float, float] | None = None
    """The box (left, top, right, bottom fractions) the last accepted track started with."""
    camera_mode: int = 0
    """CAMERA_MODE last set with MAV_CMD_SET_CAMERA_MODE (0: image); reported as video
    while recording."""

    @property
    def mode(self) -> Mode | None:
        """The pod's working mode as last reported."""
        return None if self.status is None else self.status.mode

    @property
    def pod_model(self) -> PodModel | None:
        """The pod model once known and listed in Appendix 7."""
        if self.info is None:
            return None
        model = self.info.pod_model
        return model if model in POD_NAMES else None

    def supports(self, opcode: int) -> bool:
        """Does the pod support ``opcode`` (Appendix 8)? True while the model is unknown:
        the GCU then answers for itself."""
        model = self.pod_model
        return model is None or supports(model, opcode)

    def in_mode(self, mode: Mode) -> bool:
        """The pod reports ``mode`` and it is the one the bridge's last mode command set, or
        a command for ``mode`` is pending (new control values then belong to it)."""
        return self.pending_mode is mode or (self.mode is mode and self.bridge_mode is mode)
