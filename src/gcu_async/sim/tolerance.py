"""Host deviations the simulated GCU executes anyway, as field-tested hosts need.

Decoding stays liberal and strict about what it flags (the packet keeps its
:class:`~gcu_async.protocol.AnomalousCommand` and counts in ``stats.anomalous``); this module
only decides what the simulator *runs* for one: docs/protocol-notes.md §14 "Photo, record
and focus with parameter byte 0x00".
"""

from __future__ import annotations

from gcu_async.conformance.host_fields import FIXED_PARAMETER_OPCODES
from gcu_async.protocol.command_base import Command
from gcu_async.protocol.command_decode import AnomalousCommand
from gcu_async.protocol.enums import CameraMask

DOCUMENT_VALUE = CameraMask.CAMERA_1
"""The parameter byte V2.0.6's table gives photo, record and focus (0x01)."""


def tolerated(command: Command) -> Command | None:
    """The command the simulator executes for ``command``: photo, record or focus
    (:data:`~gcu_async.conformance.host_fields.FIXED_PARAMETER_OPCODES`) with the single
    parameter byte 0x00 runs as with the document's 0x01;
    ``None`` for every other anomalous command (not executed)."""
    if (
        isinstance(command, AnomalousCommand)
        and command.code in FIXED_PARAMETER_OPCODES
        and command.params == b"\x00"
    ):
        run: Command = command.command_type(DOCUMENT_VALUE)  # type: ignore[call-arg]
        return run
    return None
