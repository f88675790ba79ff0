"""Host check: the null command between commands (the same-opcode rule).

Only the first packet of a run of one opcode executes (docs/protocol-notes.md §4). A
non-null opcode standing in consecutive packets for more than :data:`LONG_RUN_S` is not a
command repeated until its feedback arrives but a host that never sends the null command;
the same opcode again with other parameters, no null between, is a command that never runs.
"""

from __future__ import annotations

from gcu_async.conformance.findings import Deviation, Findings
from gcu_async.protocol.command_decode import AnomalousCommand, UnknownCommand, command_code
from gcu_async.protocol.enums import Opcode, opcode_name
from gcu_async.protocol.layout import CRC_SIZE, OPCODE_OFFSET
from gcu_async.protocol.packets import HostPacket

LONG_RUN_S = 1.0
"""A non-null opcode standing in consecutive packets longer than this is not a command being
repeated until its feedback arrives but a host that does not send the null command."""

Tally = dict[int, int]
Longest = dict[int, tuple[int, float]]


class OpcodeRuns:
    """Runs of one opcode: the standing ones, and repeats with other parameters."""

    def __init__(self, findings: Findings) -> None:
        self._f = findings
        self._nulls = 0
        self._opcode: int | None = None
        self._params = b""
        self._start = 0.0
        self._length = 0
        self._last = 0.0
        self._first: tuple[float, bytes, str] = (0.0, b"", "")
        self._standing: Tally = {}
        """Opcode → packets in its standing runs (those that ended)."""
        self._longest: Longest = {}
        """Opcode → (packets, seconds) of its longest standing run."""

    def add(self, packet: HostPacket, t: float, raw: bytes) -> None:
        command = packet.command
        opcode = command_code(command)
        if opcode == Opcode.NULL:
            self._nulls += 1
            self._end()
            return
        if raw:
            params = raw[OPCODE_OFFSET + 1 : -CRC_SIZE]
        elif isinstance(command, (AnomalousCommand, UnknownCommand)):
            params = command.params
        else:
            params = command.encode_params()
        if opcode != self._opcode:
            self._end()
            self._opcode, self._params, self._start = opcode, params, t
            self._length = 1
            self._first = (t, raw, params.hex(" ") or "-")
            return
        self._length += 1
        self._last = t
        if params != self._params:
            name = opcode_name(opcode)
            d = self._f.dev(f"opcode.repeat_changed.{name}",
                            f"0x{opcode:02X} {name} again with other parameters, no null "
                            "between")  # fmt: skip
            d.count += 1
            d.diagnosis = ("the same opcode in consecutive packets executes once, so the "
                           "second command (its new parameters) never runs: send the null "
                           "command (0x00) between two commands of one opcode")  # fmt: skip
            before = self._params.hex(" ") or "-"
            self._f.example(d, t, raw, f"0x{opcode:02X} {name} params "
                            f"{params.hex(' ') or '-'} after {before}")  # fmt: skip
            self._params = params

    def _end(self) -> None:
        """The run ends: counted if it stood."""
        self._count(self._f, self._standing, self._longest)
        self._opcode = None
        self._length = 0
        self._last = 0.0

    def _count(self, findings: Findings, standing: Tally, longest: Longest) -> None:
        """Count the current run in ``standing``, ``longest`` and ``findings`` if it stood
        (its own state is left as it is)."""
        opcode = self._opcode
        if opcode is None or self._length < 2:
            return
        duration = self._last - self._start
        if duration <= LONG_RUN_S:
            return
        standing[opcode] = standing.get(opcode, 0) + self._length
        if self._length > longest.get(opcode, (0, 0.0))[0]:
            longest[opcode] = (self._length, duration)
        name = opcode_name(opcode)
        d = findings.dev(f"opcode.standing.{name}", f"0x{opcode:02X} {name} standing in "
                         f"consecutive packets for more than {LONG_RUN_S:g} s")  # fmt: skip
        ft, fraw, fparams = self._first
        findings.example(d, ft, fraw, f"run of {self._length} packets ({duration:.2f} s) of "
                         f"0x{opcode:02X} {name} params {fparams}")  # fmt: skip

    def report(self, findings: Findings, devs: dict[str, Deviation], total: int) -> None:
        """Into ``devs`` (``findings``' copy, before it was copied): the run still going on
        counted as if it ended now, and each standing opcode's diagnosis."""
        standing, longest = dict(self._standing), dict(self._longest)
        self._count(Findings(findings.examples, devs), standing, longest)
        for opcode, count in standing.items():
            name = opcode_name(opcode)
            d = devs[f"opcode.standing.{name}"]
            d.count = count
            d.total = total
            run, secs = longest[opcode]
            never = "the host never sends the null command (0x00); " if not self._nulls else ""
            d.diagnosis = (f"{never}0x{opcode:02X} {name} in {100 * count / total:.0f} % of "
                           f"packets, in runs up to {run} packets ({secs:.1f} s) where the "
                           "null command belongs: only the first packet of a run executes, "
                           f"and {name} runs again after every other command")  # fmt: skip
