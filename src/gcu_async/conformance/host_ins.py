"""Host check: the aircraft state going invalid and back.

Command packets whose main frame is all zero right after packets with INS valid (a host
that builds its command packets from an empty frame), and the INS-valid flag dropping out
for at most :data:`SHORT_DROPOUT` packets.
"""

from __future__ import annotations

from gcu_async.conformance.findings import Deviation, Findings
from gcu_async.protocol.command_decode import command_code
from gcu_async.protocol.enums import Opcode, opcode_name
from gcu_async.protocol.host_frames import HostMainFrame
from gcu_async.protocol.packets import HostPacket

SHORT_DROPOUT = 5
"""INS valid → invalid → valid within this many packets is a dropout, not a state change."""


class InsCheck:
    """INS-valid toggles and all-zero main frames."""

    def __init__(self, findings: Findings) -> None:
        self._f = findings
        self._previous: bool | None = None
        self._toggles = 0
        self._seen_valid = False
        self._invalid_run = 0
        self._invalid_run_zero = 0
        self._dropouts = 0
        self._zero_in_dropouts = 0

    def add(self, packet: HostPacket, t: float, raw: bytes) -> None:
        main = packet.main
        valid = main.ins_valid
        zero = _zero_main(main)
        opcode = command_code(packet.command)
        if zero and self._previous and opcode != Opcode.NULL:
            self._f.flag("main.all_zero", "packets carrying a command with an all-zero main "
                         "frame (control values, flags, attitude, acceleration, velocity) "
                         "right after INS-valid packets", t, raw,
                         f"command {opcode_name(opcode)}, main frame bytes 5–29 all zero "
                         "(INS invalid, control values invalid)")  # fmt: skip
        if self._previous is not None and valid is not self._previous:
            self._toggles += 1
            if valid and self._seen_valid and 0 < self._invalid_run <= SHORT_DROPOUT:
                self._dropouts += 1
                self._zero_in_dropouts += self._invalid_run_zero
                self._f.flag("ins_valid.toggles", "INS-valid flag dropping out for a few "
                             "packets", t, raw, f"INS valid again after {self._invalid_run} "
                             "invalid packet(s)")  # fmt: skip
        if valid:
            self._seen_valid = True
            self._invalid_run = self._invalid_run_zero = 0
        else:
            self._invalid_run += 1
            self._invalid_run_zero += zero
        self._previous = valid

    def report(self, devs: dict[str, Deviation], duration: float) -> None:
        d = devs.get("ins_valid.toggles")
        zero = devs.get("main.all_zero")
        minutes = duration / 60  # 0.0 for a duration too small to divide (5e-324 s)
        per_min = self._toggles / minutes if minutes > 0 else 0.0
        if d is not None:
            d.title = f"INS-valid flag toggles {self._toggles} times ({per_min:.1f} a minute)"
            d.diagnosis = (f"{self._dropouts} dropouts of at most {SHORT_DROPOUT} packets: the "
                           "aircraft state goes invalid and back")  # fmt: skip
            if self._zero_in_dropouts:
                d.diagnosis += (f"; {self._zero_in_dropouts} of the invalid packets have an "
                                "all-zero main frame (see main.all_zero)")  # fmt: skip
        if zero is not None:
            zero.diagnosis = ("the host builds its command packets from an empty main frame: "
                              "they say INS invalid and control values invalid, so the GCU "
                              "loses the aircraft state and the angle targets for those "
                              "packets")  # fmt: skip
            if d is not None:
                zero.diagnosis += f" (INS valid toggles {per_min:.1f} times a minute)"


def _zero_main(main: HostMainFrame) -> bool:
    """Bytes 5–29 all zero (the request code, byte 30, may be set)."""
    return not any(main[:-1])
