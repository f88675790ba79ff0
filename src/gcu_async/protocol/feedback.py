"""Command feedback of a GCU packet: the opcode (byte 69) and execution status (byte 70).

The status is read per command (docs/protocol-notes.md §2 "Execution status per command"): 0x00 is
success everywhere; calibration answers 0x02 while in progress; zoom commands answer a camera mask
naming the failed cameras; any other non-zero value is a failure (0x01 for most commands, 0x02 for
palette/thermal).
"""

from __future__ import annotations

from typing import Any, NamedTuple

from gcu_async._checks import check_int
from gcu_async.protocol.enums import CameraMask, ExecutionStatus, Opcode, opcode_name

ZOOM_OPCODES = frozenset({Opcode.ZOOM_IN, Opcode.ZOOM_OUT, Opcode.ZOOM_STOP, Opcode.ZOOM_TO})
THERMAL_OPCODES = frozenset({
    Opcode.PALETTE, Opcode.AREA_TEMPERATURE, Opcode.TEMPERATURE_ALARM, Opcode.ISOTHERM,
    Opcode.SPOT_TEMPERATURE,
})  # fmt: skip
CALIBRATION_IN_PROGRESS = 0x02


def failure_status(opcode: int, failed_cameras: int = CameraMask.CAMERA_1) -> int:
    """The status byte a GCU sends when ``opcode`` (an ``int`` 0–255) fails (for the
    simulator and tests). For zoom commands it is ``failed_cameras``, the mask of the
    failed cameras; it must not be empty (0x00 would read as success), so it is an ``int``
    1–255 for every opcode."""
    check_int("opcode", opcode, 0, 0xFF)
    mask = check_int("failed_cameras", failed_cameras, 1, 0xFF, "camera mask")
    if opcode in ZOOM_OPCODES:
        return mask
    return 0x02 if opcode in THERMAL_OPCODES else 0x01


def read_status(opcode: int, status: int | None) -> ExecutionStatus:
    """Meaning of ``status`` for a feedback to ``opcode``."""
    if status is None:
        return ExecutionStatus.NONE
    if status == 0:
        return ExecutionStatus.SUCCESS
    if opcode == Opcode.CALIBRATION and status == CALIBRATION_IN_PROGRESS:
        return ExecutionStatus.IN_PROGRESS
    return ExecutionStatus.FAILED


class Feedback(NamedTuple):
    """Bytes 69..S-3 of a GCU packet."""

    opcode: int
    """Byte 69: opcode of the command this answers."""
    status: int | None = None
    """Byte 70: raw execution status, ``None`` when the packet carries none (S = 72)."""

    @property
    def command(self) -> str:
        """Protocol name of the opcode."""
        return opcode_name(self.opcode)

    @property
    def result(self) -> ExecutionStatus:
        return read_status(self.opcode, self.status)

    @property
    def succeeded(self) -> bool:
        return self.status == 0

    @property
    def failed_cameras(self) -> CameraMask:
        """Cameras that failed (zoom commands); empty otherwise."""
        if self.opcode in ZOOM_OPCODES and self.status:
            return CameraMask(self.status)
        return CameraMask(0)

    def as_dict(self) -> dict[str, Any]:
        return {
            "command": self.command,
            "opcode": self.opcode,
            "status": self.result.name,
            "status_raw": self.status,
            "failed_cameras": int(self.failed_cameras),
        }
