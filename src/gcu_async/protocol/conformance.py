"""Host conformance: every way a host's packets deviate from V2.0.6, with a diagnosis.

Sans-I/O: feed :class:`HostConformance` the host packets a GCU receives, each with the time
it arrived (any clock in seconds), then read :meth:`HostConformance.report`. The report groups
what it found by field or command — how many packets, the first few examples (raw hex and
decoded), and a plain-language diagnosis where the pattern is recognisable:

- frame fields and command parameters outside their V2.0.6 range (the packet's
  :attr:`~gcu_async.protocol.HostPacket.anomalies`), the version byte, unknown opcodes and
  sub-frame headers; aircraft yaw ≥ 36000 that reads as a signed ±18000 value;
- the aircraft velocity against the change of the sub frame's GNSS position over time
  (a scale off by ≈10 is 0.1 m/s sent for 0.01 m/s);
- command packets whose main frame is all zero right after packets with INS valid, and the
  INS-valid flag dropping out for a few packets;
- one non-null opcode standing in consecutive packets for more than :data:`LONG_RUN_S`
  without the null command between (only the first packet of a run executes), and the same
  opcode repeated with other parameters (the repeat does not execute);
- the packet rate below the document's 30 Hz and gaps longer than :data:`GAP_S`.

Memory is bounded: counters, a few examples per deviation, one open velocity window.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from gcu_async._checks import check_int
from gcu_async.errors import RemoteProtocolError
from gcu_async.protocol.anomalies import Anomaly
from gcu_async.protocol.command_decode import AnomalousCommand, UnknownCommand, command_code
from gcu_async.protocol.enums import Opcode, opcode_name
from gcu_async.protocol.gcu_frames import UnknownSubFrame
from gcu_async.protocol.host_frames import AIRCRAFT_YAW, HostMainFrame, HostSubFrame
from gcu_async.protocol.layout import CRC_SIZE, OPCODE_OFFSET
from gcu_async.protocol.packets import HostPacket, decode_host_packet, version_anomalies

EXAMPLES = 3
"""Examples kept per deviation by default."""
MIN_RATE_HZ = 30.0
"""The document asks for 30–50 Hz; slower is a deviation (faster is not)."""
GAP_S = 0.5
"""A silence longer than this between two host packets is a gap (the host "must never stop
sending": the packets carry the aircraft state)."""
LONG_RUN_S = 1.0
"""A non-null opcode standing in consecutive packets longer than this is not a command being
repeated until its feedback arrives but a host that does not send the null command."""
SHORT_DROPOUT = 5
"""INS valid → invalid → valid within this many packets is a dropout, not a state change."""
VELOCITY_WINDOW_S = 1.0
MIN_SPEED_M_S = 0.5
"""The velocity check compares windows of at least :data:`VELOCITY_WINDOW_S` in which the
position moved at least this fast."""
MAX_SPEED_M_S = 300.0
"""Faster than this is a position jump (e.g. the first GNSS fix), not motion."""
MIN_VELOCITY_WINDOWS = 3
EARTH_RADIUS_M = 6_371_000.0
_YAW = AIRCRAFT_YAW.field
_U16_SPAN = AIRCRAFT_YAW.span
YAW_WRAP = AIRCRAFT_YAW.turn
"""The raw aircraft yaw one past the field's range: 360° (36000)."""
YAW_SIGNED_LOW = AIRCRAFT_YAW.signed_low
"""Raw aircraft yaw values from here to 65535 read as S16 −18000 … −1 (−180° … −0.01°)."""
_SIGNED_TEXT = f"±{YAW_WRAP // 2}"
_YAW_TEXT = f"U16 [0, {YAW_WRAP})"
FIXED_PARAMETER_OPCODES = frozenset({Opcode.TAKE_PHOTO, Opcode.RECORD, Opcode.FOCUS})
"""Commands whose parameter byte V2.0.6's table gives as the constant 0x01."""


def yaw_reading(raw: int) -> str:
    """What a raw aircraft yaw value outside its range most likely means, one sentence."""
    if YAW_SIGNED_LOW <= raw < _U16_SPAN:
        signed = raw - _U16_SPAN
        return (f"reads as S16 {signed} ({signed / _YAW.scale:.2f}°): looks like a signed "
                f"{_SIGNED_TEXT} value in the {_YAW_TEXT} field")  # fmt: skip
    if YAW_WRAP <= raw < YAW_SIGNED_LOW:
        return (f"{raw / _YAW.scale:.2f}° is past 360°: looks like an angle not wrapped into "
                "[0°, 360°)")  # fmt: skip
    return ""


def field_diagnosis(anomaly: Anomaly) -> str:
    """A diagnosis of one out-of-range frame value, or ``""`` when none is recognisable."""
    if anomaly.field == "aircraft_yaw_raw":
        return yaw_reading(anomaly.value)
    if anomaly.field == "version":
        return "V2.0.6 defines versions 1 and 2"
    return ""


def frame_anomalies(packet: HostPacket) -> tuple[Anomaly, ...]:
    """The main and sub frame's anomalies (:attr:`HostMainFrame.anomalies`,
    :attr:`HostSubFrame.anomalies`), quickly when there are none: a frame whose
    ``validate()`` passes has none (both read one range table)."""
    main, sub = packet.main, packet.sub
    found: tuple[Anomaly, ...] = ()
    try:
        main.validate()
    except (TypeError, ValueError):
        found = main.anomalies
    if isinstance(sub, HostSubFrame):
        try:
            sub.validate()
        except (TypeError, ValueError):
            found += sub.anomalies
    return found


@dataclass(frozen=True)
class Example:
    """One packet that shows a deviation."""

    time: float
    """Seconds since the first packet (NaN: the input had no times)."""
    raw_hex: str
    """The packet as received (empty when only the decoded packet was given)."""
    decoded: str
    """The values concerned, decoded."""

    def as_dict(self) -> dict[str, Any]:
        time = round(self.time, 3) if math.isfinite(self.time) else None
        return {"time_s": time, "raw_hex": self.raw_hex, "decoded": self.decoded}


@dataclass
class Deviation:
    """One kind of deviation: ``count`` of the ``total`` packets examined show it (gaps:
    of the intervals between packets; velocity: of the windows compared; the rate: 1 of 0,
    a property of the whole run)."""

    key: str
    """Stable name, e.g. ``main.aircraft_yaw_raw``, ``command.RECORD.cameras``,
    ``opcode.standing``, ``main.all_zero``, ``ins_valid.toggles``, ``velocity.scale``."""
    title: str
    count: int = 0
    total: int = 0
    examples: list[Example] = field(default_factory=list)
    diagnosis: str = ""

    def as_dict(self) -> dict[str, Any]:
        return {
            "key": self.key, "title": self.title, "count": self.count, "total": self.total,
            "diagnosis": self.diagnosis, "examples": [e.as_dict() for e in self.examples],
        }  # fmt: skip


@dataclass(frozen=True)
class ConformanceReport:
    """What :meth:`HostConformance.report` found."""

    packets: int
    undecodable: int
    duration: float
    deviations: tuple[Deviation, ...]
    notes: tuple[str, ...]
    """Measurements that are not deviations (rate, velocity check outcome)."""

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(d.key for d in self.deviations)

    def get(self, key: str) -> Deviation | None:
        return next((d for d in self.deviations if d.key == key), None)

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


def deviation_lines(deviations: tuple[Deviation, ...]) -> list[str]:
    """The text of each deviation: its key, title and share, diagnosis, examples."""
    lines: list[str] = []
    for d in deviations:
        share = f": {d.count} of {d.total} ({100 * d.count / d.total:.1f} %)" if d.total else ""
        lines.append(f"- {d.key}: {d.title}{share}")
        if d.diagnosis:
            lines.append(f"  diagnosis: {d.diagnosis}")
        for e in d.examples:
            when = f" t={e.time:.3f} s" if math.isfinite(e.time) else ""
            lines.append(f"  e.g.{when}: {e.decoded}")
            if e.raw_hex:
                lines.append(f"       {e.raw_hex}")
    return lines


class HostConformance:
    """Collects host packets and reports how they deviate from V2.0.6 (see the module)."""

    def __init__(self, *, examples: int = EXAMPLES) -> None:
        self._examples = check_int("examples", examples, 0, 100)
        self._devs: dict[str, Deviation] = {}
        self.packets = 0
        self.undecodable = 0
        self._t0: float | None = None
        self._last_t = 0.0
        # rate and gaps
        self._longest_gap = 0.0
        # opcodes
        self._nulls = 0
        self._run_opcode: int | None = None
        self._run_params = b""
        self._run_start = 0.0
        self._run_len = 0
        self._last_run_t = 0.0
        self._run_first: tuple[float, bytes, str] | None = None
        self._standing: dict[int, int] = {}
        self._longest_run: dict[int, tuple[int, float]] = {}
        # INS valid
        self._ins_prev: bool | None = None
        self._ins_toggles = 0
        self._seen_valid = False
        self._ins_invalid_run = 0
        self._dropouts = 0
        self._zero_frames_in_dropouts = 0
        self._invalid_run_zero = 0
        # velocity
        self._win: tuple[float, tuple[float, float, float], list[float], int] | None = None
        self._vel_dot = 0.0
        self._vel_sq = 0.0
        self._vel_windows = 0
        self._vel_examples: list[tuple[float, str]] = []
        # yaw
        self._yaw_signed = 0
        self._yaw_unwrapped = 0

    # -- input ------------------------------------------------------------------------------
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
        its :func:`frame_anomalies` when the caller has them already)."""
        if self._t0 is None:
            self._t0 = self._last_t = time
        t = time - self._t0
        gap = time - self._last_t
        if self.packets and gap > GAP_S:
            d = self._dev("rate.gaps", f"silences longer than {GAP_S:g} s between host packets")
            d.count += 1
            self._example(d, t, raw, f"no packet for {gap:.3f} s before this one")
        self._longest_gap = max(self._longest_gap, gap)
        self._last_t = time
        self.packets += 1
        main = packet.main
        if frame is None:
            frame = frame_anomalies(packet)
        anomalies = version_anomalies(packet.version) + frame
        if isinstance(packet.command, AnomalousCommand):
            anomalies += packet.command.anomalies
        for anomaly in anomalies:  # packet.anomalies, in its order
            self._anomaly(packet, anomaly, t, raw)
        if isinstance(packet.command, UnknownCommand):
            code = packet.command.code
            d = self._dev(f"opcode.unknown.0x{code:02X}", f"opcode 0x{code:02X}: not in V2.0.6")
            d.count += 1
            params = packet.command.params.hex(" ") or "-"
            self._example(d, t, raw, f"opcode 0x{code:02X} params {params}")
        if isinstance(packet.sub, UnknownSubFrame):
            d = self._dev("sub.header", "sub frame header other than 0x01 with data")
            d.count += 1
            self._example(d, t, raw, f"sub frame header 0x{packet.sub.header:02X}")
        self._opcode(packet, t, raw)
        self._ins(packet, t, raw)
        if main.ins_valid and isinstance(packet.sub, HostSubFrame):
            self._velocity(main, packet.sub, t)

    # -- the checks -------------------------------------------------------------------------
    def _dev(self, key: str, title: str) -> Deviation:
        d = self._devs.get(key)
        if d is None:
            d = self._devs[key] = Deviation(key, title)
        return d

    def _example(self, d: Deviation, t: float, raw: bytes, decoded: str) -> None:
        """Keep the first few examples that read differently."""
        if len(d.examples) < self._examples and all(e.decoded != decoded for e in d.examples):
            d.examples.append(Example(t, raw.hex(" "), decoded))

    def _anomaly(self, packet: HostPacket, a: Anomaly, t: float, raw: bytes) -> None:
        command = packet.command
        if a.field == "version":
            key, title = "version", "version byte other than 1 or 2"
        elif isinstance(command, AnomalousCommand) and a in command.anomalies:
            name = opcode_name(command.code)
            key = f"command.{name}.{a.field}"
            title = f"command 0x{command.code:02X} {name}: parameter {a.field} outside its range"
        else:
            part = "sub" if a.field in HostSubFrame._fields else "main"
            key, title = f"{part}.{a.field}", f"{a.field} outside its V2.0.6 range"
        d = self._dev(key, title)
        d.count += 1
        if a.field == "aircraft_yaw_raw":
            if a.value >= YAW_SIGNED_LOW:
                self._yaw_signed += 1
            else:
                self._yaw_unwrapped += 1
        detail = f" ({a.detail})" if a.detail else ""
        extra = field_diagnosis(a)
        self._example(d, t, raw, f"{a.field} = {a.value}, allowed {a.low}…{a.high} "
                      f"{a.unit}{detail}".rstrip() + (f"; {extra}" if extra else ""))  # fmt: skip

    def _opcode(self, packet: HostPacket, t: float, raw: bytes) -> None:
        opcode = command_code(packet.command)
        command = packet.command
        if opcode == Opcode.NULL:
            self._nulls += 1
            self._end_run()
            return
        if raw:
            params = raw[OPCODE_OFFSET + 1 : -CRC_SIZE]
        elif isinstance(command, (AnomalousCommand, UnknownCommand)):
            params = command.params
        else:
            params = command.encode_params()
        if opcode != self._run_opcode:
            self._end_run()
            self._run_opcode, self._run_params, self._run_start = opcode, params, t
            self._run_len = 1
            self._run_first = (t, raw, params.hex(" ") or "-")
            return
        self._run_len += 1
        self._last_run_t = t
        if params != self._run_params:
            name = opcode_name(opcode)
            d = self._dev(f"opcode.repeat_changed.{name}",
                          f"0x{opcode:02X} {name} again with other parameters, no null "
                          "between")  # fmt: skip
            d.count += 1
            d.diagnosis = ("the same opcode in consecutive packets executes once, so the "
                           "second command (its new parameters) never runs: send the null "
                           "command (0x00) between two commands of one opcode")  # fmt: skip
            before = self._run_params.hex(" ") or "-"
            self._example(d, t, raw, f"0x{opcode:02X} {name} params {params.hex(' ') or '-'} "
                          f"after {before}")  # fmt: skip
            self._run_params = params

    def _end_run(self) -> None:
        opcode = self._run_opcode
        if opcode is None:
            return
        duration = (self._last_run_t if self._run_len > 1 else self._run_start) - self._run_start
        if self._run_len > 1 and duration > LONG_RUN_S:
            self._standing[opcode] = self._standing.get(opcode, 0) + self._run_len
            longest = self._longest_run.get(opcode, (0, 0.0))
            if self._run_len > longest[0]:
                self._longest_run[opcode] = (self._run_len, duration)
            name = opcode_name(opcode)
            d = self._dev(f"opcode.standing.{name}",
                          f"0x{opcode:02X} {name} standing in consecutive packets for more "
                          f"than {LONG_RUN_S:g} s")  # fmt: skip
            if self._run_first is not None:
                ft, fraw, fparams = self._run_first
                self._example(d, ft, fraw, f"run of {self._run_len} packets ({duration:.2f} s) "
                              f"of 0x{opcode:02X} {name} params {fparams}")  # fmt: skip
        self._run_opcode = None
        self._run_len = 0
        self._last_run_t = 0.0

    def _ins(self, packet: HostPacket, t: float, raw: bytes) -> None:
        main = packet.main
        valid = main.ins_valid
        zero = _zero_main(main)
        if zero and self._ins_prev and command_code(packet.command) != Opcode.NULL:
            d = self._dev(
                "main.all_zero",
                "packets carrying a command with an all-zero main frame (control values, "
                "flags, attitude, acceleration, velocity) right after INS-valid packets",
            )
            d.count += 1
            name = opcode_name(command_code(packet.command))
            self._example(d, t, raw, f"command {name}, main frame bytes 5–29 all zero "
                          "(INS invalid, control values invalid)")  # fmt: skip
        if self._ins_prev is not None and valid is not self._ins_prev:
            self._ins_toggles += 1
            if valid and self._seen_valid and 0 < self._ins_invalid_run <= SHORT_DROPOUT:
                self._dropouts += 1
                self._zero_frames_in_dropouts += self._invalid_run_zero
                d = self._dev("ins_valid.toggles", "INS-valid flag dropping out for a few packets")
                d.count += 1
                self._example(d, t, raw, f"INS valid again after {self._ins_invalid_run} "
                              "invalid packet(s)")  # fmt: skip
        if valid:
            self._seen_valid = True
            self._ins_invalid_run = self._invalid_run_zero = 0
        else:
            self._ins_invalid_run += 1
            self._invalid_run_zero += zero
        self._ins_prev = valid

    def _velocity(self, main: HostMainFrame, sub: HostSubFrame, t: float) -> None:
        pos = (sub.latitude, sub.longitude, sub.altitude)
        v = main.velocity
        if self._win is None:
            self._win = (t, pos, [0.0, 0.0, 0.0], 0)
            return
        t0, p0, vsum, n = self._win
        vsum[0] += v.north
        vsum[1] += v.east
        vsum[2] += v.up
        n += 1
        if t - t0 < VELOCITY_WINDOW_S:
            self._win = (t0, p0, vsum, n)
            return
        dt = t - t0
        lat0 = math.radians(p0[0])
        k = math.pi / 180 * EARTH_RADIUS_M
        moved = ((pos[0] - p0[0]) * k / dt, (pos[1] - p0[1]) * k * math.cos(lat0) / dt,
                 (pos[2] - p0[2]) / dt)  # fmt: skip
        mean = tuple(s / n for s in vsum)
        self._win = (t, pos, [0.0, 0.0, 0.0], 0)
        speed = math.hypot(*moved)
        if not MIN_SPEED_M_S <= speed <= MAX_SPEED_M_S or not (p0[0] or p0[1]):
            return  # standing still, or a position jump (the first fix)
        self._vel_windows += 1
        self._vel_dot += sum(a * b for a, b in zip(moved, mean, strict=True))
        self._vel_sq += sum(b * b for b in mean)
        if len(self._vel_examples) < self._examples:
            self._vel_examples.append(
                (
                    t0,
                    f"{t0:.1f}–{t:.1f} s: position moved N/E/U "
                    + "/".join(f"{x:+.2f}" for x in moved)
                    + " m/s, velocity fields say "
                    + "/".join(f"{x:+.2f}" for x in mean)
                    + " m/s",
                )
            )

    # -- output -----------------------------------------------------------------------------
    def report(self) -> ConformanceReport:
        """Everything found so far (the open opcode run and velocity window included)."""
        saved = (self._run_opcode, self._run_params, self._run_start, self._run_len,
                 self._run_first, self._last_run_t, dict(self._standing),
                 dict(self._longest_run), self._devs)  # fmt: skip
        self._devs = {k: _copy(d) for k, d in self._devs.items()}
        self._end_run()
        devs = self._devs
        standing, longest = self._standing, self._longest_run
        (self._run_opcode, self._run_params, self._run_start, self._run_len, self._run_first,
         self._last_run_t, self._standing, self._longest_run, self._devs) = saved  # fmt: skip
        total = self.packets
        for d in devs.values():
            d.total = max(total - 1, 0) if d.key == "rate.gaps" else total  # gaps: intervals
        notes: list[str] = []
        duration = self._last_t - self._t0 if self._t0 is not None else 0.0
        self._diagnose(devs, total)
        self._standing_report(devs, total, standing, longest)
        self._ins_report(devs, duration)
        self._velocity_report(devs, notes)
        self._rate_report(devs, total, duration, notes)
        order = sorted(devs.values(), key=lambda d: (-d.count, d.key))
        return ConformanceReport(total, self.undecodable, duration, tuple(order), tuple(notes))

    def _diagnose(self, devs: dict[str, Deviation], total: int) -> None:
        yaw = devs.get("main.aircraft_yaw_raw")
        if yaw is not None:
            share = 100 * yaw.count / total
            if self._yaw_signed and not self._yaw_unwrapped:
                yaw.diagnosis = (f"aircraft yaw ≥ {YAW_WRAP} in {share:.0f} % of packets, every "
                                 f"one a signed S16 −{YAW_WRAP // 2}…−1 read as U16: looks "
                                 f"like a signed {_SIGNED_TEXT} value (headings west of north, "
                                 f"−180°…0°) in the {_YAW_TEXT} field")  # fmt: skip
            elif self._yaw_unwrapped and not self._yaw_signed:
                yaw.diagnosis = (f"aircraft yaw ≥ {YAW_WRAP} in {share:.0f} % of packets: looks "
                                 "like an angle not wrapped into [0°, 360°)")  # fmt: skip
            else:
                yaw.diagnosis = (f"aircraft yaw ≥ {YAW_WRAP} in {share:.0f} % of packets "
                                 f"({self._yaw_signed} read as signed S16 values)")  # fmt: skip
        if "version" in devs:
            devs["version"].diagnosis = "V2.0.6 defines versions 1 and 2"
        for key, d in devs.items():
            if not key.startswith("command."):
                continue
            name = key.split(".")[1]
            opcode = Opcode[name] if name in Opcode.__members__ else None
            if opcode in FIXED_PARAMETER_OPCODES and key.endswith(".cameras"):
                d.diagnosis = (f"V2.0.6 gives the parameter byte of {name} as 0x01; 0x00 selects "
                               "no camera when read as a camera mask")  # fmt: skip
                if opcode == Opcode.RECORD:
                    d.diagnosis += (": looks like start/stop in the parameter byte (0x01 "
                                    "start, 0x00 stop), as ArduPilot 4.7 sends it")  # fmt: skip
            elif not d.diagnosis:
                d.diagnosis = "command parameter outside its V2.0.6 range"

    def _standing_report(self, devs: dict[str, Deviation], total: int, standing: dict[int, int],
                         longest: dict[int, tuple[int, float]]) -> None:  # fmt: skip
        for opcode, count in standing.items():
            name = opcode_name(opcode)
            d = devs[f"opcode.standing.{name}"]
            d.count = count
            run, secs = longest[opcode]
            never = "the host never sends the null command (0x00); " if not self._nulls else ""
            d.diagnosis = (f"{never}0x{opcode:02X} {name} in {100 * count / total:.0f} % of "
                           f"packets, in runs up to {run} packets ({secs:.1f} s) where the "
                           "null command belongs: only the first packet of a run executes, "
                           f"and {name} runs again after every other command")  # fmt: skip

    def _ins_report(self, devs: dict[str, Deviation], duration: float) -> None:
        d = devs.get("ins_valid.toggles")
        zero = devs.get("main.all_zero")
        minutes = duration / 60  # 0.0 for a duration too small to divide (5e-324 s)
        per_min = self._ins_toggles / minutes if minutes > 0 else 0.0
        if d is not None:
            d.title = f"INS-valid flag toggles {self._ins_toggles} times ({per_min:.1f} a minute)"
            d.diagnosis = (f"{self._dropouts} dropouts of at most {SHORT_DROPOUT} packets: the "
                           "aircraft state goes invalid and back")  # fmt: skip
            if self._zero_frames_in_dropouts:
                d.diagnosis += (f"; {self._zero_frames_in_dropouts} of the invalid packets have an "
                                "all-zero main frame (see main.all_zero)")  # fmt: skip
        if zero is not None:
            zero.diagnosis = ("the host builds its command packets from an empty main frame: "
                              "they say INS invalid and control values invalid, so the GCU "
                              "loses the aircraft state and the angle targets for those "
                              "packets")  # fmt: skip
            if d is not None:
                zero.diagnosis += f" (INS valid toggles {per_min:.1f} times a minute)"

    def _velocity_report(self, devs: dict[str, Deviation], notes: list[str]) -> None:
        if self._vel_windows < MIN_VELOCITY_WINDOWS:
            notes.append(f"velocity scale not checked: {self._vel_windows} windows of "
                         f"{VELOCITY_WINDOW_S:g} s with the position moving ≥ {MIN_SPEED_M_S:g} "
                         f"m/s (needs {MIN_VELOCITY_WINDOWS})")  # fmt: skip
            return
        ratio = math.inf if self._vel_sq == 0 else self._vel_dot / self._vel_sq
        summary = (f"velocity × {ratio:.2f} matches the change of GNSS position over "
                   f"{self._vel_windows} windows of ≥ {VELOCITY_WINDOW_S:g} s")  # fmt: skip
        if 0.8 <= ratio <= 1.25:
            notes.append(summary + ": consistent")
            return
        d = devs["velocity.scale"] = Deviation(
            "velocity.scale", "velocity disagrees with the change of GNSS position",
            self._vel_windows, self._vel_windows,
            [Example(t, "", text) for t, text in self._vel_examples])  # fmt: skip
        guess = _scale_guess(ratio)
        d.diagnosis = f"the position changes {ratio:.2f}× as fast as the velocity fields say" + (
            f" (≈{guess[0]}): {guess[1]}"
            if guess
            else ": check the scale (0.01 m/s) and the axes (north, east, up)"
        )

    def _rate_report(self, devs: dict[str, Deviation], total: int, duration: float,
                     notes: list[str]) -> None:  # fmt: skip
        rate = (total - 1) / duration if duration > 0 else 0.0
        notes.append(f"{total} packets in {duration:.1f} s: {rate:.1f}/s, longest silence "
                     f"{self._longest_gap * 1000:.0f} ms")  # fmt: skip
        if duration >= 2.0 and rate < MIN_RATE_HZ:
            devs["rate.low"] = Deviation(
                "rate.low", f"packet rate below {MIN_RATE_HZ:g} Hz", 1, 0, [],
                f"{rate:.1f} packets/s: V2.0.6 asks for 30–50 Hz; the gimbal depends on the "
                "aircraft state they carry")  # fmt: skip
        gaps = devs.get("rate.gaps")
        if gaps is not None:
            gaps.diagnosis = (f"longest {self._longest_gap:.2f} s: the host must never stop "
                              "sending (V2.0.6: 30–50 Hz)")  # fmt: skip


def _scale_guess(ratio: float) -> tuple[str, str] | None:
    for factor, meaning in ((10, "the velocity looks like 0.1 m/s (dm/s) units: check the "
                                 "scale (0.01 m/s)"),
                            (100, "the velocity looks like m/s: check the scale (0.01 m/s)"),
                            (0.1, "the velocity looks like mm/s: check the scale (0.01 m/s)"),
                            (-1, "the velocity has the opposite sign: check the axes (up "
                                 "positive)")):  # fmt: skip
        if 0.8 <= ratio / factor <= 1.25:
            return (f"{factor:g}×", meaning)
    return None


def _zero_main(main: HostMainFrame) -> bool:
    """Bytes 5–29 all zero (the request code, byte 30, may be set)."""
    return not any(main[:-1])


def _copy(d: Deviation) -> Deviation:
    return Deviation(d.key, d.title, d.count, d.total, list(d.examples), d.diagnosis)


__all__ = [
    "EXAMPLES", "GAP_S", "LONG_RUN_S", "MIN_RATE_HZ", "ConformanceReport", "Deviation",
    "Example", "HostConformance", "deviation_lines", "field_diagnosis", "frame_anomalies",
    "yaw_reading",
]  # fmt: skip
