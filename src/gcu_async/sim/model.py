"""The sans-I/O GCU model: host packets in, GCU packets out, with a pod behind them.

``SimulatorModel.receive(bytes)`` takes raw bytes in any chunking and returns the encoded replies;
``handle(HostPacket)`` answers one decoded packet. Time comes from an injectable clock; on every
packet the model first advances its physics to ``clock.now()``, then runs the command (the
same-opcode rule applies, docs/protocol-notes.md §4 "The same-opcode rule"), then takes the packet's
control values, and answers with main frame, the requested sub frame and the feedback
(docs/protocol-notes.md §2 "Execution status per command").
"""

from __future__ import annotations

import logging
import random
from collections import Counter
from dataclasses import dataclass, field
from typing import NamedTuple

from gcu_async._checks import check_bool
from gcu_async.conformance import HostConformance, field_diagnosis, frame_anomalies
from gcu_async.errors import ProtocolErrorReason, RemoteProtocolError
from gcu_async.protocol.anomalies import Anomaly
from gcu_async.protocol.command_base import Command
from gcu_async.protocol.command_decode import AnomalousCommand, command_code
from gcu_async.protocol.deframer import Deframer
from gcu_async.protocol.enums import Mode, Opcode, PodModel, SubFrameRequest, opcode_name
from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.packets import (
    DEFAULT_VERSION,
    SUPPORTED_VERSIONS,
    GcuPacket,
    HostPacket,
    decode_host_packet,
)
from gcu_async.sim.aircraft import ReceivedAircraft, aircraft_yaw
from gcu_async.sim.camera import CameraState
from gcu_async.sim.clock import Clock, MonotonicClock
from gcu_async.sim.executor import Executor
from gcu_async.sim.firmware import DEFAULT_FIRMWARE, Firmware, firmware_for
from gcu_async.sim.memo import ReplyMemo, at_rest
from gcu_async.sim.motion import DEFAULT_MAX_RATE, Gimbal
from gcu_async.sim.profiles import PodProfile, profile_for
from gcu_async.sim.rangefinder import Rangefinder
from gcu_async.sim.report import main_frame, sub_frame
from gcu_async.sim.state import SimState
from gcu_async.sim.tolerance import tolerated

log = logging.getLogger("gcu_async.sim")

DEFAULT_POD = "D-90Pro(TA)"
"""Default pod: thermal (radiometric) + AI core, supports nearly every command."""
CALIBRATION_SECONDS = 3.0


@dataclass
class ModelStats:
    """Counters of one model."""

    received: int = 0
    """CRC-valid host packets handed to the model."""
    answered: int = 0
    """Packets answered: every CRC-valid host packet is (docs/client.md, "Liberal receive,
    strict send")."""
    malformed: int = 0
    """Packets handed to :meth:`SimulatorModel.handle_bytes` with a wrong header, too short
    (:class:`~gcu_async.errors.ProtocolErrorReason` ``HEADER`` / ``SHORT``): no answer."""
    anomalous: int = 0
    """Answered packets whose command had parameters V2.0.6 does not allow (an
    :class:`~gcu_async.protocol.AnomalousCommand`): not executed, answered with its failure
    status — except a null command with parameter bytes, still the separator (no status),
    and the ones counted in :attr:`tolerated`."""
    tolerated: int = 0
    """Anomalous commands executed anyway, as field-tested hosts need (photo, record and
    focus with parameter byte 0x00: docs/protocol-notes.md §14 "Photo, record and focus
    with parameter byte 0x00")."""
    frame_anomalies: int = 0
    """Packets with a main- or sub-frame field outside its V2.0.6 range (or reserved flag
    bits set); each field's first one is logged as a warning with a diagnosis."""
    anomalies_by_field: dict[str, int] = field(default_factory=dict)
    """Frame field name → packets in which it was out of range."""
    other_versions: int = 0
    """Answered packets with a version byte other than 1 or 2 (decoded with the V2.0.6
    layout; the first one is logged as a warning)."""
    crc_errors: int = 0
    length_errors: int = 0
    bytes_discarded: int = 0
    """Bytes that belonged to no valid packet (garbage, bad CRC/length)."""
    repeated: int = 0
    """Packets whose opcode repeated the previous one: answered, not executed
    (docs/protocol-notes.md §4 "The same-opcode rule")."""


class ExecutionRecord(NamedTuple):
    """One command the model acted upon (see ``SimulatorModel(record_executions=True)``)."""

    time: float
    """The model clock's time when it ran."""
    command: Command
    """The typed command as decoded from the host packet, parameters included."""
    status: int
    """The execution status byte it answered."""


class SimulatorModel:
    """A simulated GCU with a pod of model ``pod`` (Appendix 7 code or name).

    ``executions`` counts, per opcode, how often a command was acted upon (successfully or
    not) — a repeated opcode without a null command in between does not count again. The
    null command is never counted. With ``record_executions=True``, ``execution_log`` lists
    the same executions one by one, in order, as :class:`ExecutionRecord` (time, command,
    status), so a test can tell two commands of one opcode apart by their parameters; it
    stays empty otherwise (it grows by one record per execution: clear it in long runs).
    ``state`` is the live :class:`SimState`. ``firmware`` (a name of
    :data:`~gcu_async.sim.firmware.FIRMWARES` or a :class:`~gcu_async.sim.firmware.Firmware`)
    says how the replies are filled: ``"v2.0.6"``, the document, by default.

    ``reply_memo`` (default on; settable): a request repeated while the pod is at rest (an
    idle host's heartbeat) is answered from a memo of the last reply, every counter and the
    conformance report kept as the full path keeps them (:mod:`gcu_async.sim.memo` says when
    exactly); off, every packet takes the full path. The replies are the same either way.
    """

    def __init__(
        self,
        pod: PodModel | int | str = DEFAULT_POD,
        *,
        clock: Clock | None = None,
        seed: int = 0,
        max_zoom: float | None = None,
        thermal_max_zoom: float | None = None,
        calibration_seconds: float = CALIBRATION_SECONDS,
        max_slew_rate: float = DEFAULT_MAX_RATE,
        initial_mode: Mode = Mode.POINTING_FOLLOW,
        protocol_version: int = DEFAULT_VERSION,
        record_executions: bool = False,
        firmware: Firmware | str = DEFAULT_FIRMWARE,
        reply_memo: bool = True,
    ) -> None:
        if not calibration_seconds >= 0:
            raise ValueError(f"calibration_seconds: {calibration_seconds!r} must be >= 0")
        if not max_slew_rate > 0:
            raise ValueError(f"max_slew_rate: {max_slew_rate!r} must be > 0 deg/s")
        if initial_mode not in (set(Mode) - {Mode.UNKNOWN}):
            raise ValueError(f"initial_mode: {initial_mode!r} is not a pod working mode")
        self.profile: PodProfile = profile_for(
            pod, max_zoom=max_zoom, thermal_max_zoom=thermal_max_zoom
        )
        self.clock: Clock = clock if clock is not None else MonotonicClock()
        self.rng = random.Random(seed)
        self.protocol_version = protocol_version
        aircraft = ReceivedAircraft()
        self.state = SimState(
            aircraft=aircraft,
            gimbal=Gimbal(aircraft, mode=initial_mode, max_rate=max_slew_rate),
            camera=CameraState.for_profile(self.profile),
            rangefinder=Rangefinder(),
        )
        self.executor = Executor(self.state, self.profile, calibration_seconds,
                                 firmware_for(firmware))  # fmt: skip
        self.executions: Counter[int] = Counter()
        self.record_executions = check_bool("record_executions", record_executions)
        self.execution_log: list[ExecutionRecord] = []
        self.stats = ModelStats()
        self.last_opcode: int | None = None
        """Opcode of the last packet handled (the same-opcode rule compares with it)."""
        self._last_feedback = Feedback(Opcode.NULL)
        self._time = self.clock.now()
        self._deframer = Deframer.for_host_packets()
        self.conformance = HostConformance()
        """Every host packet handled, checked against V2.0.6 (:meth:`HostConformance.report`)."""
        self._raw = b""
        self.reply_memo = check_bool("reply_memo", reply_memo)
        """Answer a request repeated at rest from the memo (:mod:`gcu_async.sim.memo`)."""
        self._memo: ReplyMemo | None = None
        self._handled: tuple[tuple[Anomaly, ...], bool] = ((), False)
        """What :meth:`handle` found in its last packet: the frame anomalies, and whether
        it ran no command (the null command or a repeated opcode other than calibration)."""

    @property
    def firmware(self) -> Firmware:
        """How the replies are filled and commands answered (:mod:`~gcu_async.sim.firmware`);
        settable while the model runs (a name or a :class:`~gcu_async.sim.firmware.Firmware`):
        the next reply follows it."""
        return self.executor.firmware

    @firmware.setter
    def firmware(self, firmware: Firmware | str) -> None:
        self.executor.firmware = firmware_for(firmware)

    # -- bytes in, bytes out ------------------------------------------------------------------
    def receive(self, data: bytes | bytearray | memoryview) -> list[bytes]:
        """Feed raw bytes (any chunking); return the encoded reply to every complete valid
        packet. Garbage and bad packets are counted in :attr:`stats` and not answered."""
        return [
            reply
            for packet in self.split(data, self._deframer)
            if (reply := self.handle_bytes(packet)) is not None
        ]

    def split(self, data: bytes | bytearray | memoryview, deframer: Deframer, *,
              end: bool = False) -> list[bytes]:  # fmt: skip
        """Deframe ``data`` with ``deframer`` (one per stream or datagram), adding what it
        discards to :attr:`stats`; return the CRC-valid packets. ``end``: the stream ends
        here (a datagram): what is still pending is settled (:meth:`Deframer.flush`)."""
        before = deframer.stats
        crc, length, discarded = before.crc_errors, before.length_errors, before.bytes_discarded
        packets = deframer.feed(data)
        if end:
            packets += deframer.flush()
        after = deframer.stats
        self.stats.crc_errors += after.crc_errors - crc
        self.stats.length_errors += after.length_errors - length
        self.stats.bytes_discarded += after.bytes_discarded - discarded
        return packets

    def discard(self, deframer: Deframer) -> None:
        """Drop what ``deframer`` still buffers (end of a datagram or connection), counted."""
        before = deframer.stats.bytes_discarded
        deframer.reset()
        self.stats.bytes_discarded += deframer.stats.bytes_discarded - before

    def handle_bytes(self, packet: bytes) -> bytes | None:
        """Answer one complete packet; ``None`` (counted by reason) only when its header,
        length or CRC is wrong: any CRC-valid host packet is answered."""
        reply = self.replay(packet)
        if reply is not None:
            return reply
        try:
            decoded = decode_host_packet(packet)
        except RemoteProtocolError as exc:
            stats = self.stats
            if exc.reason is ProtocolErrorReason.CRC:
                stats.crc_errors += 1
            elif exc.reason is ProtocolErrorReason.LENGTH:
                stats.length_errors += 1
            else:
                stats.malformed += 1
            stats.bytes_discarded += len(packet)
            log.debug("ignored a malformed packet: %s", exc)
            return None
        self._raw = packet  # for the conformance report's examples; handle() keeps its shape
        try:
            reply = self.encode(self.handle(decoded))
        finally:
            self._raw = b""
        frame, ran_none = self._handled
        if ran_none and self.reply_memo and self._plain() and at_rest(self.state):
            self._memo = ReplyMemo(
                bytes(packet), decoded, reply, frame=frame,
                repeated=command_code(decoded.command) != Opcode.NULL,
                anomalous=isinstance(decoded.command, AnomalousCommand),
                other_version=decoded.version not in SUPPORTED_VERSIONS,
                state=self.state, executor=self.executor, model=self._memo_key(),
            )  # fmt: skip
        return reply

    def replay(self, packet: bytes | bytearray | memoryview) -> bytes | None:
        """The memo's reply to ``packet``, counted as the full path counts it, if ``packet``
        is the memo's request and the state is the one its reply was made in; else ``None``,
        nothing done (:mod:`gcu_async.sim.memo`). :meth:`handle_bytes` tries it first; a
        server's exchange calls it for a datagram, which it then need not deframe."""
        memo = self._memo
        if (memo is None or packet != memo.request or not self.reply_memo or not self._plain()
                or not memo.holds(self.state, self.executor, self._memo_key())):  # fmt: skip
            return None
        now = self.clock.now()
        stats = self.stats
        stats.received += 1
        decoded = memo.packet
        if memo.other_version:
            self._other_version(decoded.version)
        self.conformance.add_packet(decoded, now, raw=memo.request, frame=memo.frame)
        if memo.frame:
            self._frame_anomalies(memo.frame)
        self.state.aircraft.count(memo.ins_valid)
        if now > self._time:  # advance(now): nothing moves at rest
            self._time = now
        if memo.anomalous:
            stats.anomalous += 1
        if memo.repeated:
            stats.repeated += 1
        stats.answered += 1
        return memo.reply

    def _plain(self) -> bool:
        """None of the methods the memo stands for is overridden (an override sees every
        packet)."""
        cls = type(self)
        return (cls.handle, cls.handle_bytes, cls.encode) == _OWN and vars(self).keys().isdisjoint(
            _OWN_NAMES
        )

    def _memo_key(self) -> tuple[object, ...]:
        """The model's own attributes a reply depends on (besides its state's)."""
        return (self.state, self.executor, self.profile, self.protocol_version,
                self.last_opcode, self._last_feedback)  # fmt: skip

    def encode(self, reply: GcuPacket) -> bytes:
        """The wire bytes of a reply :meth:`handle` made, with this firmware's deviations from
        V2.0.6 (``GcuPacket.encode()`` alone refuses them)."""
        return reply.encode(deviations=self.firmware.deviations)

    # -- the GCU ------------------------------------------------------------------------------
    def handle(self, packet: HostPacket) -> GcuPacket:
        """Answer one host packet: advance time, run its command, take its control values.
        (Applications and tests override it to watch packets: its signature stays this.)"""
        raw, self._raw = self._raw, b""
        now = self.clock.now()
        self.stats.received += 1
        if packet.version not in SUPPORTED_VERSIONS:
            self._other_version(packet.version)
        found = frame_anomalies(packet)
        self.conformance.add_packet(packet, now, raw=raw, frame=found)
        if found:
            self._frame_anomalies(found)
        main = packet.main
        self.state.aircraft.update(main, packet.sub)
        self.advance(now)
        opcode = command_code(packet.command)
        if isinstance(packet.command, AnomalousCommand):
            self.stats.anomalous += 1
        ran_none = opcode != Opcode.CALIBRATION
        if opcode == Opcode.NULL:  # with parameter bytes too (flagged): still the separator
            feedback = Feedback(Opcode.NULL)
        elif opcode == self.last_opcode:
            self.stats.repeated += 1
            feedback = self._last_feedback
            if opcode == Opcode.CALIBRATION:
                feedback = Feedback(opcode, self.executor.calibration_status(now))
        else:
            ran_none = False
            run = packet.command
            if isinstance(run, AnomalousCommand):
                instead = tolerated(run)
                if instead is None:
                    log.info("not executed: %s", run.error())
                else:
                    self.stats.tolerated += 1
                    log.info("executed as %s although %s", instead, run.error())
                    run = instead
            status = self.executor.execute(run, main, now)
            self.executions[opcode] += 1
            if self.record_executions:
                self.execution_log.append(ExecutionRecord(now, packet.command, status))
            feedback = Feedback(opcode, status)
            self._last_feedback = feedback
            if log.isEnabledFor(logging.INFO):
                params = (packet.command.params if isinstance(packet.command, AnomalousCommand)
                          else packet.command.encode_params())  # fmt: skip
                log.info("executed %s %s -> status 0x%02X", opcode_name(opcode),
                         params.hex(" ") or "-", status)  # fmt: skip
        self.last_opcode = opcode
        cam = self.state.camera
        self.state.gimbal.control_input(main.control, main.control_valid, cam.main_zoom)
        self.state.rangefinder.measure(self.state.attitude, self.state.aircraft, self.rng)
        self.stats.answered += 1
        self._handled = (found, ran_none)
        standard = main.subframe_request == SubFrameRequest.STANDARD
        return GcuPacket(
            main_frame(self.state, self.firmware),
            sub_frame(self.state, self.profile, self.firmware) if standard else None,
            feedback,
            self.protocol_version,
        )

    def _frame_anomalies(self, anomalies: tuple[Anomaly, ...]) -> None:
        """Count out-of-range frame fields; warn about each field's first one only."""
        self.stats.frame_anomalies += 1
        counts = self.stats.anomalies_by_field
        for a in anomalies:
            seen = counts.get(a.field, 0)
            counts[a.field] = seen + 1
            if not seen:
                diagnosis = field_diagnosis(a)
                using = (f"; the simulator uses {aircraft_yaw(a.value):.2f}°"
                         if a.field == "aircraft_yaw_raw" else "")  # fmt: skip
                log.warning("host packet field out of range: %s%s%s; further ones are only "
                            "counted (stats.anomalies_by_field)", a,
                            f" — {diagnosis}" if diagnosis else "", using)  # fmt: skip

    def _other_version(self, version: int) -> None:
        """Count a packet of another version; warn about the first one only."""
        self.stats.other_versions += 1
        if self.stats.other_versions == 1:
            log.warning("host packet of protocol version %d (V2.0.6 defines 1 and 2): decoded "
                        "and answered with the V2.0.6 layout; further ones are only counted "
                        "(stats.other_versions)", version)  # fmt: skip

    def advance(self, now: float | None = None) -> None:
        """Move the physics (angles, zoom, calibration) forward to ``now`` (default: the
        clock's time). Time never runs backwards."""
        now = self.clock.now() if now is None else now
        dt = now - self._time
        if dt <= 0:
            return
        self._time = now
        cam = self.state.camera
        self.state.gimbal.step(dt, cam.main_zoom)
        cam.step(dt)
        if self.state.calibration_until is not None:
            self.executor.calibration_status(now)

    def __repr__(self) -> str:
        return (f"<SimulatorModel {self.profile.name} firmware={self.firmware.name} "
                f"mode={self.state.mode.name} "
                f"answered={self.stats.answered}>")  # fmt: skip


_OWN = (SimulatorModel.handle, SimulatorModel.handle_bytes, SimulatorModel.encode)
_OWN_NAMES = ("handle", "handle_bytes", "encode")
