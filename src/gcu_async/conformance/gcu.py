"""GCU conformance: what a GCU's replies do outside V2.0.6, with counts and examples.

Sans-I/O, the mirror of the host's report (:class:`~gcu_async.conformance.host.
HostConformance`). Feed :class:`GcuConformance` each reply the host received and, when you
have them, the opcodes of the host packets it sent, each with its time (seconds on any
clock, or ``None`` when unknown); read :meth:`GcuConformance.report`. It finds:

- frame fields outside their V2.0.6 range (the frames' :attr:`anomalies`), by reading: a
  camera yaw sent as a signed S16 (:mod:`~gcu_async.protocol.headings`), with the spread of
  the raw values that tells a signed pod from a U16 one; version bytes, unknown modes, pod
  codes and sub-frame headers; status bytes a command never answers;
- replies to a command without an execution status (72 bytes), and what the null command's
  replies carry;
- the camera's absolute roll, pitch or yaw staying zero in every reply while the relative
  angle of its axis moved (a GCU that does not fill the field);
- the mode byte not taking the mode of a mode command the GCU confirmed, within
  :data:`MODE_SETTLE_S`;
- with the host's opcodes: the time from a command's first packet to its feedback, commands
  no feedback answered, feedback for commands never sent, and how repeats are answered
  (:mod:`~gcu_async.conformance.runs`);
- the pod's identity (model, hardware and firmware versions, protocol version) and the
  reply rate, as notes.

Memory is bounded: counters, a few examples per deviation, the latest values.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from gcu_async.conformance.findings import (
    EXAMPLES,
    ByKey,
    Deviation,
    Example,
    Findings,
    deviation_lines,
    ordered,
    when,
)
from gcu_async.conformance.runs import FEEDBACK_GRACE_S, CommandRuns
from gcu_async.errors import RemoteProtocolError
from gcu_async.protocol.anomalies import Anomaly
from gcu_async.protocol.commands import COMMAND_TYPES, MODE_COMMANDS
from gcu_async.protocol.enums import Mode, Opcode, opcode_name
from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.gcu_frame_tables import CAMERA_YAW
from gcu_async.protocol.gcu_frames import GcuMainFrame, GcuSubFrame, UnknownSubFrame
from gcu_async.protocol.layout import OPCODE_OFFSET
from gcu_async.protocol.packets import (
    BASE_LENGTH,
    HOST_HEADER,
    SUPPORTED_VERSIONS,
    GcuPacket,
    decode_gcu_packet,
)
from gcu_async.protocol.pods import POD_NAMES, pod_name

MODE_SETTLE_S = 1.0
"""After the GCU confirmed a mode command, its mode byte shows the mode within this long."""
MODE_SETTLE_REPLIES = 50
"""… or within this many replies when no times are given."""
STUCK_MOVE_DEG = 10.0
"""An absolute angle that stays 0 in every reply while its axis's relative angle moved at
least this much is not filled in."""
MODE_OF: dict[int, Mode] = {
    int(op): mode for op in MODE_COMMANDS
    if (spec := COMMAND_TYPES[op].SCHEMA.mode) is not None and (mode := spec.mode) is not None
}  # fmt: skip
"""The mode each mode command enters (the command schema's)."""
STUCK_AXES = (("yaw_raw", "relative_z_raw", "yaw"), ("pitch_raw", "relative_x_raw", "pitch"),
              ("roll_raw", "relative_y_raw", "roll"))  # fmt: skip
"""(absolute field, the relative angle of its axis, name): Appendix 4's axes (pitch = −X,
roll = +Y, yaw = +Z)."""
_HALF, _TURN, _SIGNED_LOW = CAMERA_YAW.turn // 2, CAMERA_YAW.turn, CAMERA_YAW.signed_low
_BANDS = (f"0-{_HALF - 1}", f"{_HALF}-{_TURN - 1}", f"{_TURN}-{_SIGNED_LOW - 1}",
          f"{_SIGNED_LOW}-{CAMERA_YAW.span - 1}")  # fmt: skip
"""The raw camera yaw in four bands, split at half a turn, a full turn and the lowest
negative S16 a signed pod sends: what a signed pod sends (first and last), what only a U16
pod sends (second), what neither explains (third)."""
_DEG = CAMERA_YAW.field.scale
_SIGNED_DEG = f"±{_HALF / _DEG:g}°"
_TURN_DEG = f"{_TURN / _DEG:g}°"
_U16_OFF = CAMERA_YAW.span - _TURN
"""How far a signed heading read as U16 lands past the heading it means, raw steps."""
_AXES = tuple((GcuMainFrame._fields.index(f), GcuMainFrame._fields.index(r), f, r)
              for f, r, _ in STUCK_AXES)  # fmt: skip


@dataclass(frozen=True)
class GcuReport(ByKey):
    """What :meth:`GcuConformance.report` found."""

    replies: int
    host_packets: int
    undecodable: int
    duration: float | None
    """Seconds from the first to the last reply (``None``: no times given)."""
    identity: dict[str, Any]
    """The pod as its sub frames describe it (empty before one came)."""
    deviations: tuple[Deviation, ...]
    notes: tuple[str, ...]
    latency: dict[str, Any]

    @property
    def rate(self) -> float:
        d = self.duration
        return (self.replies - 1) / d if d else 0.0

    def as_dict(self) -> dict[str, Any]:
        return {
            "protocol": "V2.0.6", "side": "gcu", "replies": self.replies,
            "host_packets": self.host_packets, "undecodable": self.undecodable,
            "duration_s": None if self.duration is None else round(self.duration, 3),
            "rate_hz": round(self.rate, 2), "identity": self.identity,
            "conforms": not self.deviations,
            "deviations": [d.as_dict() for d in self.deviations],
            "feedback_latency": self.latency, "notes": list(self.notes),
        }  # fmt: skip

    def text(self) -> str:
        """The report for a terminal or a file: one block per deviation."""
        head = f"GCU conformance to V2.0.6: {self.replies} replies"
        if self.host_packets:
            head += f" to {self.host_packets} host packets"
        if self.duration is not None:
            head += f" in {self.duration:.1f} s ({self.rate:.1f}/s)"
        if self.undecodable:
            head += f", {self.undecodable} undecodable"
        lines = [head]
        if self.identity:
            i = self.identity
            lines.append(f"  pod: {i['pod_model']} (code {i['pod_code']}), hardware "
                         f"{i['hardware_version']:g}, firmware {i['firmware_version']:g}, "
                         f"protocol version {i['version']}")  # fmt: skip
        if not self.deviations:
            lines.append("  no deviation found" if self.replies else "  no reply yet")
        lines += deviation_lines(self.deviations)
        lines.extend(f"  note: {n}" for n in self.notes)
        return "\n".join(lines)


class GcuConformance:
    """Collects GCU replies (and the host's opcodes) and reports how the GCU deviates from
    V2.0.6 (see the module). Per reply it does a few comparisons; text is only made for the
    first :data:`~gcu_async.conformance.findings.EXAMPLES` examples of each deviation."""

    def __init__(self, *, examples: int = EXAMPLES) -> None:
        self._findings = Findings(examples)
        self._examples = self._findings.examples
        self._flag = self._findings.flag
        self.replies = 0
        self.undecodable = 0
        self._t0: float | None = None
        self._last_t: float | None = None
        self._timed = True
        self._longest_gap = 0.0
        self._runs = CommandRuns(self._examples)
        self._bands = [0, 0, 0, 0]
        self._band_low = [_TURN * 2] * 4
        self._band_high = [-1] * 4
        self._moved = {rel: [0, 0] for _, rel, _ in STUCK_AXES}
        """Relative angle → [lowest, highest] raw seen."""
        self._nonzero = dict.fromkeys((f for f, _, _ in STUCK_AXES), False)
        self._first_raw = b""
        self._first_main: GcuMainFrame | None = None
        self._last_sub: object = None
        self._sub_frame: GcuSubFrame | None = None
        self._identity: tuple[int, int, int, int] | None = None
        self._identities = 0
        self._version = 0
        self._faults = 0
        self._pod_status = 0
        self._mode_wait: tuple[Mode, float | None, int, int] | None = None
        """(mode, confirmed at, reply count then, opcode) of a confirmed mode command."""
        self._mode_latency: float | None = None
        self._null_replies = [0, 0]
        """Replies to the null command [without, with] a status byte."""
        self._command_replies = [0, 0]

    # -- input --------------------------------------------------------------------------------
    def add(self, data: bytes, time: float | None = None) -> None:
        """One complete GCU reply as received (bytes)."""
        try:
            packet = decode_gcu_packet(data)
        except RemoteProtocolError:
            self.undecodable += 1
            return
        self.add_reply(packet.main, packet.sub, packet.feedback, time, version=packet.version,
                       raw=data)  # fmt: skip

    def add_packet(self, packet: GcuPacket, time: float | None = None, *,
                   raw: bytes = b"") -> None:  # fmt: skip
        """One decoded reply (``raw``: its bytes, shown in the examples)."""
        self.add_reply(packet.main, packet.sub, packet.feedback, time, version=packet.version,
                       raw=raw)  # fmt: skip

    def host_sent(self, opcode: int, time: float | None = None) -> None:
        """One host packet went out carrying ``opcode`` (byte 69), at ``time``."""
        self._runs.sent(opcode, self._time(time))

    def add_host(self, data: bytes, time: float | None = None) -> None:
        """One host packet as sent (bytes): its opcode counts (:meth:`host_sent`)."""
        if len(data) >= BASE_LENGTH and data[:2] == HOST_HEADER:
            self.host_sent(data[OPCODE_OFFSET], time)

    def add_reply(self, main: GcuMainFrame, sub: GcuSubFrame | UnknownSubFrame | None,
                  feedback: Feedback, time: float | None = None, *, version: int = 2,
                  raw: bytes = b"") -> None:  # fmt: skip
        """One reply in parts: what a client's telemetry sample holds (``sub`` may be the
        latest sub frame: the same object twice counts once)."""
        t = self._time(time)
        self.replies += 1
        if t is not None:
            last = self._last_t
            if last is not None and t - last > self._longest_gap:
                self._longest_gap = t - last
            self._last_t = t
        if self._first_main is None:
            self._first_main, self._first_raw = main, raw
        if version not in SUPPORTED_VERSIONS:
            self._flag("version", "version byte other than 1 or 2", t, raw,
                       f"version {version}")  # fmt: skip
        self._version = version
        yaw = main.yaw_raw
        band = 0 if yaw < _HALF else 1 if yaw < _TURN else 2 if yaw < _SIGNED_LOW else 3
        self._bands[band] += 1
        if yaw < self._band_low[band]:
            self._band_low[band] = yaw
        if yaw > self._band_high[band]:
            self._band_high[band] = yaw
        if yaw >= _TURN:  # a signed pod: every other reply; the other fields on the fast path
            self._yaw(main, yaw, t, raw)
            found = main._replace(yaw_raw=0).anomalies
        else:
            found = main.anomalies
        if found:
            for a in found:
                self._main_anomaly(a, t, raw)
        if main.mode_raw not in Mode._value2member_map_:
            self._flag("main.mode_raw", "mode byte V2.0.6 does not define", t, raw,
                       f"mode 0x{main.mode_raw:02X}")  # fmt: skip
        self._axes(main)
        self._pod_status |= main.pod_status_raw
        if sub is not self._last_sub:
            self._last_sub = sub
            self._sub(sub, t, raw)
        self._feedback(main, feedback, t, raw)

    # -- the checks ---------------------------------------------------------------------------
    def _time(self, time: float | None) -> float | None:
        """Seconds since the first time given (``None`` once any input had none)."""
        if time is None:
            self._timed = False
            return None
        if self._t0 is None:
            self._t0 = time
        return time - self._t0 if self._timed else None

    def _yaw(self, main: GcuMainFrame, yaw: int, t: float | None, raw: bytes) -> None:
        if yaw >= _SIGNED_LOW:
            d = self._findings.dev("main.yaw_raw.signed", "camera yaw sent as a signed S16 "
                                   f"({_SIGNED_DEG}) in the U16 [0, {_TURN}) field")  # fmt: skip
            reading = f"S16 {CAMERA_YAW.signed(yaw)}"
        else:
            d = self._findings.dev("main.yaw_raw.past_turn", f"camera yaw {_TURN}…"
                                   f"{_SIGNED_LOW - 1}: neither U16 nor signed S16")  # fmt: skip
            reading = f"past {_TURN_DEG}"
        d.count += 1
        if len(d.examples) < self._examples:  # the text only for an example
            self._findings.example(d, t, raw, f"yaw_raw = {yaw}: {reading}, heading "
                                   f"{CAMERA_YAW.degrees(yaw):.2f}°, relative yaw "
                                   f"{main.relative_angles.z:.2f}°")  # fmt: skip

    def _main_anomaly(self, a: Anomaly, t: float | None, raw: bytes) -> None:
        detail = f" ({a.detail})" if a.detail else ""
        self._flag(f"main.{a.field}", f"{a.field} outside its V2.0.6 range", t, raw,
                   f"{a.field} = {a.value}, allowed {a.low}…{a.high} {a.unit}{detail}".rstrip())

    def _axes(self, main: GcuMainFrame) -> None:
        moved, nonzero, first = self._moved, self._nonzero, self.replies == 1
        for i_field, i_rel, field, rel in _AXES:
            r = main[i_rel]
            span = moved[rel]
            if first:
                span[0] = span[1] = r
            elif r < span[0]:
                span[0] = r
            elif r > span[1]:
                span[1] = r
            if main[i_field] and not nonzero[field]:
                nonzero[field] = True

    def _sub(self, sub: object, t: float | None, raw: bytes) -> None:
        if isinstance(sub, UnknownSubFrame):
            self._flag("sub.header", "sub frame header other than 0x01", t, raw,
                       f"sub frame header 0x{sub.header:02X}")  # fmt: skip
            return
        if not isinstance(sub, GcuSubFrame):
            return
        for a in sub.anomalies:  # V2.0.6 gives none: a later revision may
            self._flag(f"sub.{a.field}", f"{a.field} outside its V2.0.6 range", t, raw, str(a))
        if sub.pod_code not in POD_NAMES:
            self._flag("sub.pod_code", "pod code not in Appendix 7", t, raw,
                       f"pod code {sub.pod_code}")  # fmt: skip
        self._faults |= sub.fault_raw
        ident = (sub.pod_code, sub.hardware_version_raw, sub.firmware_version_raw, self._version)
        if ident != self._identity:
            self._identity = ident
            self._identities += 1
            self._sub_frame = sub

    def _feedback(self, main: GcuMainFrame, fb: Feedback, t: float | None, raw: bytes) -> None:
        opcode, status = fb.opcode, fb.status
        lengths = self._null_replies if opcode == Opcode.NULL else self._command_replies
        lengths[status is not None] += 1
        if status is None and opcode != Opcode.NULL:
            self._flag("feedback.no_status", "feedback to a command without an execution "
                       "status (72 bytes)", t, raw, f"feedback 0x{opcode:02X} "
                       f"{opcode_name(opcode)}, no status byte")  # fmt: skip
        if status is not None:
            for a in fb.anomalies:
                key = f"feedback.{opcode_name(opcode)}.{a.field.replace(' ', '_')}"
                self._flag(key, f"feedback 0x{opcode:02X} {opcode_name(opcode)}: {a.field} "
                           "V2.0.6 does not define", t, raw, str(a))  # fmt: skip
        self._runs.reply(opcode, t)
        wait = self._mode_wait
        if wait is not None:
            mode, since, count, op = wait
            if main.mode_raw == mode:
                self._mode_wait = None
                if since is not None and t is not None:
                    self._mode_latency = max(self._mode_latency or 0.0, t - since)
            elif (t - since > MODE_SETTLE_S if t is not None and since is not None
                  else self.replies - count > MODE_SETTLE_REPLIES):  # fmt: skip
                self._mode_wait = None
                self._flag("mode.not_followed", "mode byte not taking the mode of a mode "
                           "command the GCU confirmed", t, raw, f"0x{op:02X} {opcode_name(op)} "
                           f"confirmed, mode byte still 0x{main.mode_raw:02X}, not "
                           f"0x{int(mode):02X} {mode.name}")  # fmt: skip
        if (status == 0 and opcode in MODE_OF and main.mode_raw != MODE_OF[opcode]
                and (wait is None or wait[3] != opcode)):  # fmt: skip
            self._mode_wait = (MODE_OF[opcode], t, self.replies, opcode)

    # -- output -------------------------------------------------------------------------------
    def report(self) -> GcuReport:
        """Everything found so far (nothing is reset)."""
        devs = self._findings.copy(self.replies)
        notes: list[str] = []
        self._yaw_report(devs)
        self._stuck_report(devs)
        self._runs_report(devs, notes)
        self._reply_notes(notes)
        if "version" in devs:
            devs["version"].diagnosis = "V2.0.6 defines versions 1 and 2"
        if "mode.not_followed" in devs:
            devs["mode.not_followed"].diagnosis = (
                "a client that waits for the mode byte to confirm a mode (gcu_async sends "
                "control values only then) waits in vain; V2.0.6: the mode byte is the pod's "
                "working mode")  # fmt: skip
        if "feedback.no_status" in devs:
            devs["feedback.no_status"].diagnosis = ("V2.0.6 answers a command with its "
                                                    "execution status in byte 70")  # fmt: skip
        duration = self._last_t if self._timed and self._last_t is not None else None
        latency = self._runs.latency.as_dict()
        return GcuReport(self.replies, self._runs.host_packets, self.undecodable, duration,
                         self._identity_dict(), ordered(devs), tuple(notes), latency)  # fmt: skip

    def _identity_dict(self) -> dict[str, Any]:
        sub = self._sub_frame
        if sub is None:
            return {}
        return {"pod_model": pod_name(sub.pod_code), "pod_code": sub.pod_code,
                "hardware_version": sub.hardware_version,
                "hardware_version_raw": sub.hardware_version_raw,
                "firmware_version": sub.firmware_version,
                "firmware_version_raw": sub.firmware_version_raw, "version": self._version,
                "changes": self._identities - 1}  # fmt: skip

    def _band_text(self) -> str:
        return ", ".join(f"{name}: {n} ({self._band_low[i]}…{self._band_high[i]})" if n
                         else f"{name}: 0" for i, (name, n) in enumerate(zip(_BANDS, self._bands,
                                                                         strict=True)))  # fmt: skip

    def _yaw_report(self, devs: dict[str, Deviation]) -> None:
        signed, past = devs.get("main.yaw_raw.signed"), devs.get("main.yaw_raw.past_turn")
        u16_high = self._bands[1]
        spread = f"raw camera yaw by band: {self._band_text()}"
        if signed is not None:
            if not u16_high:
                signed.diagnosis = (
                    f"no camera yaw in the U16-only band {_HALF}…{_TURN - 1}: the pod sends its "
                    f"yaw as a signed S16 ±{_HALF} (−{_HALF / _DEG:g}°…{_HALF / _DEG:g}°) "
                    f"({spread}). gcu_async shows it as the heading it means, in "
                    f"[0°, {_TURN_DEG}); a host reading the field as U16 "
                    f"puts headings west of north {_U16_OFF / _DEG:g}° off "
                    f"({CAMERA_YAW.span / _DEG:g}° − {_TURN_DEG})")  # fmt: skip
            else:
                signed.diagnosis = (f"some camera yaws read only as signed S16, others only "
                                    f"as U16: a mixed or changing encoding ({spread})")
        if past is not None:
            past.diagnosis = (f"neither reading explains these: shown as an angle past "
                              f"{_TURN_DEG} and wrapped ({spread})")  # fmt: skip

    def _stuck_report(self, devs: dict[str, Deviation]) -> None:
        for field, rel, name in STUCK_AXES:
            low, high = self._moved[rel]
            moved = (high - low) / 100
            if self._nonzero[field] or moved < STUCK_MOVE_DEG:
                continue
            at = when(0.0 if self._timed else None)
            example = [Example(at, self._first_raw.hex(" "), f"{field} = 0 from the first "
                               f"reply on, {rel} {low}…{high}")]  # fmt: skip
            devs[f"main.{field}.zero"] = Deviation(
                f"main.{field}.zero", f"camera absolute {name} 0 in every reply while the "
                f"relative angle of its axis moved {moved:.2f}°", self.replies, self.replies,
                example, f"a GCU that does not fill {field} (an emulator may leave it zero), "
                "or a camera held exactly there in a mode that locks the axis")  # fmt: skip

    def _runs_report(self, devs: dict[str, Deviation], notes: list[str]) -> None:
        runs = self._runs
        if not runs.host_packets:
            notes.append("no host packets given: feedback timing and the same-opcode rule not "
                         "observed")  # fmt: skip
            return
        missing = runs.pending_missing(self._last_t)
        if missing:
            devs["feedback.missing"] = Deviation(
                "feedback.missing", "commands no reply answered with their feedback", missing,
                0, [Example(when(t), "", text) for t, text in runs.missing_examples],
                f"no reply carried the command's opcode within {FEEDBACK_GRACE_S:g} s of the "
                "host moving on (V2.0.6: the GCU answers every command with its feedback)")
        if runs.unsolicited:
            devs["feedback.unsolicited"] = Deviation(
                "feedback.unsolicited", "feedback for an opcode the host never sent",
                runs.unsolicited, self.replies,
                [Example(when(t), "", text) for t, text in runs.unsolicited_examples])
        notes.append(runs.latency.text() if self._timed else "no times given: feedback "
                     "latency not measured")  # fmt: skip
        if runs.run_replies:
            notes.append(f"while a command stood in consecutive host packets, "
                         f"{runs.run_feedback} of {runs.run_replies} replies carried its "
                         "feedback (the same-opcode rule: repeats are answered, not "
                         "executed)")  # fmt: skip
        if runs.again:
            notes.append(f"an opcode sent again after null packets: {runs.again} times, "
                         f"answered {runs.again_answered} (V2.0.6: it runs again)")

    def _reply_notes(self, notes: list[str]) -> None:
        n0, n1 = self._null_replies
        c0, c1 = self._command_replies
        if n0 or n1:
            notes.append(f"replies to the null command: {n0} of 72 bytes (no status), {n1} "
                         "with a status byte")  # fmt: skip
        if c0 or c1:
            notes.append(f"replies to commands: {c1} with a status byte, {c0} without")
        if self._mode_latency is not None:
            notes.append(f"mode byte took a confirmed mode within {self._mode_latency * 1000:.0f}"
                         " ms")  # fmt: skip
        if self._timed and self.replies > 1:
            notes.append(f"longest silence between replies {self._longest_gap * 1000:.0f} ms")
        flags = []
        if self._pod_status:
            flags.append(f"pod status bits seen 0x{self._pod_status:04X}")
        if self._faults:
            flags.append(f"fault bits seen 0x{self._faults:04X}")
        if flags:
            notes.append(", ".join(flags))
        if self._identities > 1:
            notes.append(f"the pod's identity changed {self._identities - 1} times (another pod "
                         "or firmware answered)")  # fmt: skip


__all__ = ["MODE_SETTLE_S", "STUCK_MOVE_DEG", "GcuConformance", "GcuReport"]
