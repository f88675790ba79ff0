"""Command feedback of a GCU packet: the opcode (byte 69) and execution status (byte 70).

The status is read per command (docs/protocol-notes.md §2 "Execution status per command"): 0x00 is
success everywhere; calibration answers 0x02 while in progress; zoom commands answer a camera mask
naming the failed cameras; any other non-zero value is a failure (0x01 for most commands, 0x02 for
palette/thermal).
A status byte a command does not answer, and status bytes beyond the one V2.0.6 defines (kept
in ``extra_status``), are flagged in :attr:`Feedback.anomalies` (docs/client.md, "Liberal
receive, strict send").
"""

from __future__ import annotations

from typing import Any, NamedTuple

from gcu_async._checks import check_int
from gcu_async.protocol.anomalies import Anomaly
from gcu_async.protocol.command_fields import CAMERA_MASK
from gcu_async.protocol.command_schema import StatusRule
from gcu_async.protocol.commands import COMMAND_TYPES
from gcu_async.protocol.enums import CameraMask, ExecutionStatus
from gcu_async.protocol.opcodes import Opcode, opcode_name


def _ruled(rule: StatusRule) -> frozenset[Opcode]:
    return frozenset(c.OPCODE for c in COMMAND_TYPES.values() if c.SCHEMA.status is rule)


ZOOM_OPCODES = _ruled(StatusRule.ZOOM)
"""Commands whose failure status is the mask of the failed cameras (their schema says so)."""
THERMAL_OPCODES = _ruled(StatusRule.THERMAL)
"""Commands that answer 0x02 on failure."""
CALIBRATION_IN_PROGRESS = 0x02


def failure_status(opcode: int, failed_cameras: int = CameraMask.CAMERA_1) -> int:
    """The status byte a GCU sends when ``opcode`` (an ``int`` 0–255) fails (for the
    simulator and tests). For zoom commands it is ``failed_cameras``, the mask of the
    failed cameras; it must not be empty (0x00 would read as success), so it is an ``int``
    within the camera mask's range
    (:data:`~gcu_async.protocol.command_fields.CAMERA_MASK`) for every opcode."""
    check_int("opcode", opcode, 0, 0xFF)
    mask = check_int("failed_cameras", failed_cameras, CAMERA_MASK.raw_low, CAMERA_MASK.raw_high,
                     "camera mask")  # fmt: skip
    if opcode in ZOOM_OPCODES:
        return mask
    return 0x02 if opcode in THERMAL_OPCODES else 0x01


_RULES: dict[int, StatusRule] = {op: c.SCHEMA.status for op, c in COMMAND_TYPES.items()}


def status_anomalies(opcode: int, status: int | None) -> tuple[Anomaly, ...]:
    """The status byte as an anomaly when ``opcode`` (a V2.0.6 command) never answers it
    (docs/protocol-notes.md §2 "Execution status per command"): failure is 0x01, 0x02 for
    palette and thermal commands, a camera mask for zoom; calibration adds 0x02."""
    rule = _RULES.get(opcode)
    if status is None or status == 0 or rule is None or rule is StatusRule.ZOOM:
        return ()
    if rule is StatusRule.THERMAL:
        if status == 0x02:
            return ()
        return (Anomaly("status", status, 0, 2, "", "0x00 = success, 0x02 = failure"),)
    calibration = rule is StatusRule.CALIBRATION
    if status == 0x01 or (calibration and status == CALIBRATION_IN_PROGRESS):
        return ()
    if calibration:
        return (Anomaly("status", status, 0, 2, "",
                        "0x00 = success, 0x01 = failure, 0x02 = in progress"),)  # fmt: skip
    return (Anomaly("status", status, 0, 1, "", "0x00 = success, 0x01 = failure"),)


def read_status(opcode: int, status: int | None) -> ExecutionStatus:
    """Meaning of ``status`` for a feedback to ``opcode``."""
    if status is None:
        return ExecutionStatus.NONE
    if status == 0:
        return ExecutionStatus.SUCCESS
    if status == CALIBRATION_IN_PROGRESS and _RULES.get(opcode) is StatusRule.CALIBRATION:
        return ExecutionStatus.IN_PROGRESS
    return ExecutionStatus.FAILED


class Feedback(NamedTuple):
    """Bytes 69..S-3 of a GCU packet."""

    opcode: int
    """Byte 69: opcode of the command this answers."""
    status: int | None = None
    """Byte 70: raw execution status, ``None`` when the packet carries none (S = 72)."""
    extra_status: bytes = b""
    """Bytes 71..S-3 of a reply longer than V2.0.6 defines (kept as received, flagged)."""

    @property
    def anomalies(self) -> tuple[Anomaly, ...]:
        """What V2.0.6 does not expect here: a status byte this command never answers,
        status bytes beyond the one it defines (docs/client.md, "Liberal receive, strict
        send")."""
        found = status_anomalies(self.opcode, self.status)
        if self.extra_status:
            n = 1 + len(self.extra_status)
            extra = self.extra_status.hex(" ")
            found += (Anomaly("status length", n, 1, 1, "bytes",
                              f"V2.0.6 defines one status byte; extra {extra}"),)  # fmt: skip
        return found

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
            **({"extra_status_hex": self.extra_status.hex(" ")} if self.extra_status else {}),
        }
