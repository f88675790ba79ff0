"""Host conformance: every way a host's packets deviate from V2.0.6, with a diagnosis.

Sans-I/O: feed :class:`HostConformance` the host packets a GCU receives, each with the time
it arrived (any clock in seconds), then read :meth:`HostConformance.report`. The report groups
what it found by field or command — how many packets, the first few examples (raw hex and
decoded), and a plain-language diagnosis where the pattern is recognisable. One module per
check:

- :mod:`~gcu_async.conformance.host_fields`: values outside their V2.0.6 range, the version
  byte, unknown opcodes and sub-frame headers; an aircraft yaw past a full turn that reads
  as a signed value of half a turn either way;
- :mod:`~gcu_async.conformance.host_velocity`: the aircraft velocity against the change of
  the GNSS position over time (a scale off by ≈10 is 0.1 m/s sent for 0.01 m/s);
- :mod:`~gcu_async.conformance.host_ins`: command packets whose main frame is all zero
  right after packets with INS valid, and the INS-valid flag dropping out for a few packets;
- :mod:`~gcu_async.conformance.host_runs`: one non-null opcode standing in consecutive
  packets for more than :data:`LONG_RUN_S` without the null command between (only the first
  packet of a run executes), and the same opcode repeated with other parameters;
- :mod:`~gcu_async.conformance.host_rate`: the packet rate below the document's 30 Hz and
  gaps longer than :data:`GAP_S`.

Memory is bounded: counters, a few examples per deviation, one open velocity window.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from gcu_async.conformance.findings import (
    EXAMPLES,
    ByKey,
    Deviation,
    Findings,
    deviation_lines,
    ordered,
)
from gcu_async.conformance.host_fields import FieldCheck, frame_anomalies
from gcu_async.conformance.host_ins import InsCheck
from gcu_async.conformance.host_rate import GAP_S, MIN_RATE_HZ, RateCheck
from gcu_async.conformance.host_runs import LONG_RUN_S, OpcodeRuns
from gcu_async.conformance.host_velocity import VelocityCheck
from gcu_async.errors import RemoteProtocolError
from gcu_async.protocol.anomalies import Anomaly
from gcu_async.protocol.host_frames import HostSubFrame
from gcu_async.protocol.packets import HostPacket, decode_host_packet


@dataclass(frozen=True)
class ConformanceReport(ByKey):
    """What :meth:`HostConformance.report` found."""

    packets: int
    undecodable: int
    duration: float
    deviations: tuple[Deviation, ...]
    notes: tuple[str, ...]
    """Measurements that are not deviations (rate, velocity check outcome)."""

    @property
    def rate(self) -> float:
        return (self.packets - 1) / self.duration if self.duration > 0 else 0.0

    def as_dict(self) -> dict[str, Any]:
        return {
            "protocol": "V2.0.6", "packets": self.packets, "undecodable": self.undecodable,
            "duration_s": round(self.duration, 3), "rate_hz": round(self.rate, 2),
            "conforms": not self.deviations,
            "deviations": [d.as_dict() for d in self.deviations], "notes": list(self.notes),
        }  # fmt: skip

    def text(self) -> str:
        """The report for a terminal: one block per deviation."""
        head = (f"Host conformance to V2.0.6: {self.packets} packets in {self.duration:.1f} s "
                f"({self.rate:.1f}/s)")  # fmt: skip
        if self.undecodable:
            head += f", {self.undecodable} undecodable"
        lines = [head]
        if not self.deviations:
            lines.append("  no deviation found" if self.packets else "  no host packet yet")
        lines += deviation_lines(self.deviations)
        lines.extend(f"  note: {n}" for n in self.notes)
        return "\n".join(lines)


class HostConformance:
    """Collects host packets and reports how they deviate from V2.0.6 (see the module)."""

    def __init__(self, *, examples: int = EXAMPLES) -> None:
        self._findings = f = Findings(examples)
        self.packets = 0
        self.undecodable = 0
        self._t0: float | None = None
        self._last_t = 0.0
        self._fields = FieldCheck(f)
        self._rate = RateCheck(f)
        self._runs = OpcodeRuns(f)
        self._ins = InsCheck(f)
        self._velocity = VelocityCheck(f.examples)

    def add(self, data: bytes, time: float) -> None:
        """One complete host packet as received (bytes) at ``time`` seconds."""
        try:
            packet = decode_host_packet(data)
        except RemoteProtocolError:
            self.undecodable += 1
            return
        self.add_packet(packet, time, raw=data)

    def add_packet(self, packet: HostPacket, time: float, *, raw: bytes = b"",
                   frame: tuple[Anomaly, ...] | None = None) -> None:  # fmt: skip
        """One decoded host packet (``raw``: its bytes, shown in the examples; ``frame``:
        its :func:`~gcu_async.conformance.host_fields.frame_anomalies` when the caller has
        them already)."""
        if self._t0 is None:
            self._t0 = time
        t = time - self._t0
        self._rate.add(time, t, raw)
        self._last_t = time
        self.packets += 1
        self._fields.add(packet, t, raw, frame_anomalies(packet) if frame is None else frame)
        self._runs.add(packet, t, raw)
        self._ins.add(packet, t, raw)
        if packet.main.ins_valid and isinstance(packet.sub, HostSubFrame):
            self._velocity.add(packet.main, packet.sub, t)

    def report(self) -> ConformanceReport:
        """Everything found so far (the open opcode run and velocity window included);
        nothing is reset."""
        total = self.packets
        devs = self._findings.copy(total)
        notes: list[str] = []
        duration = self._last_t - self._t0 if self._t0 is not None else 0.0
        self._fields.diagnose(devs, total)
        self._runs.report(self._findings, devs, total)
        self._ins.report(devs, duration)
        self._velocity.report(devs, notes)
        self._rate.report(devs, total, duration, notes)
        return ConformanceReport(total, self.undecodable, duration, ordered(devs), tuple(notes))


__all__ = ["GAP_S", "LONG_RUN_S", "MIN_RATE_HZ", "ConformanceReport", "HostConformance"]
