"""Everything the simulated GCU knows, in one readable object (``SimulatorModel.state``)."""

from __future__ import annotations

from dataclasses import dataclass, field

from gcu_async.protocol.command_base import Command
from gcu_async.protocol.enums import Mode
from gcu_async.protocol.units import Attitude, AxisAngles
from gcu_async.sim.aircraft import ReceivedAircraft
from gcu_async.sim.camera import CameraState
from gcu_async.sim.motion import PITCH, ROLL, YAW, Gimbal
from gcu_async.sim.rangefinder import Rangefinder


@dataclass
class SimState:
    """The pod's state: gimbal, cameras, rangefinder, what it knows of the aircraft.

    Mutable on purpose: tests and users may set e.g. ``camera.ambient_dark``,
    ``camera.scene_temperature``, ``faults`` or ``inverted`` to stage a situation.
    """

    aircraft: ReceivedAircraft
    gimbal: Gimbal
    camera: CameraState
    rangefinder: Rangefinder
    faults: int = 0
    """GCU sub frame bytes 41–42 (see :class:`~gcu_async.protocol.enums.FaultFlags`)."""
    inverted: bool = False
    """Pod status B12: powered on upside down."""
    calibration_until: float | None = None
    """Clock time at which a running calibration completes."""
    accepted: dict[int, Command] = field(default_factory=dict)
    """The last command of each opcode the pod executed with success: what a setting no
    frame reports (e.g. a time zone before the sub frame shows it) was set to."""

    @property
    def mode(self) -> Mode:
        return self.gimbal.mode

    @property
    def relative(self) -> Attitude:
        """Camera roll/pitch/yaw relative to the aircraft, degrees."""
        r = self.gimbal.relative
        return Attitude(r[ROLL], r[PITCH], r[YAW])

    @property
    def relative_axes(self) -> AxisAngles:
        """The relative angles as the GCU reports them (main frame bytes 12–17):
        X = −pitch, Y = roll, Z = yaw (simulator reading of Appendix 2 and 4)."""
        r = self.gimbal.relative
        return AxisAngles(-r[PITCH], r[ROLL], r[YAW])

    @property
    def attitude(self) -> Attitude:
        """Camera absolute roll/pitch/yaw: relative angles plus the aircraft attitude."""
        return self.gimbal.absolute()

    @property
    def zoom(self) -> dict[int, float]:
        """Camera number → current zoom ratio."""
        return {n: drive.value for n, drive in self.camera.zoom.items()}

    @property
    def recording(self) -> bool:
        return self.camera.recording

    @property
    def calibrating(self) -> bool:
        return self.calibration_until is not None
