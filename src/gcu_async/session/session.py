"""The command session as a sans-I/O state machine (the h11 / wsproto pattern).

Inputs: bytes received (:meth:`Session.receive`), the time (every call takes ``now``), API
calls (:meth:`Session.submit`, :meth:`Session.cancel`, :meth:`Session.set_aircraft`,
:meth:`Session.update_aircraft`, :meth:`Session.set_control`, :meth:`Session.open`,
:meth:`Session.close`) and transport news
(:meth:`Session.connection_lost`). Outputs: the packet to send now (:meth:`Session.poll`),
when to call :meth:`Session.poll` next (:meth:`Session.next_wakeup`) and events
(:meth:`Session.events`). No asyncio, no sockets, no clock of its own: a driver (the
asyncio :class:`~gcu_async.client.GcuClient`, or a virtual-time test harness) does the I/O.

The contract it keeps, with its assumptions, is in docs/client.md ("The session
contract"); the rules behind it live in :mod:`~gcu_async.session.pacing` (when a packet may
go), :mod:`~gcu_async.session.runs` (what a reply proves, when an opcode may start),
:mod:`~gcu_async.session.control` (which control values go out valid),
:mod:`~gcu_async.session.recording` (state-checked record toggles) and
:mod:`~gcu_async.session.feed` (which aircraft data goes out valid, GNSS time).
"""

from __future__ import annotations

import enum
import heapq
import logging
import math
import sys
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, fields, replace
from typing import TYPE_CHECKING, Any

from gcu_async._checks import check_bool, check_instance, check_int, check_positive, type_error
from gcu_async.errors import (
    CommandError,
    CommandFailed,
    CommandLinkLost,
    CommandTimeout,
    GcuError,
    Outcome,
)
from gcu_async.protocol.aircraft import AircraftState
from gcu_async.protocol.anomalies import Anomaly
from gcu_async.protocol.commands import AnomalousCommand, Command, NullCommand, command_code
from gcu_async.protocol.deframer import Deframer
from gcu_async.protocol.enums import (
    CameraFlags,
    ExecutionStatus,
    Opcode,
    opcode_name,
)
from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.gcu_frames import GcuMainFrame, GcuSubFrame
from gcu_async.protocol.host_frames import (
    CONTROL_ANGLE_RAW,
    CONTROL_RATE_RAW,
    ControlValues,
    HostMainFrame,
    HostSubFrame,
)
from gcu_async.protocol.packets import SUPPORTED_VERSIONS, GcuPacket, HostPacket, decode_gcu_packet
from gcu_async.session.config import SessionConfig, SessionOptions
from gcu_async.session.control import KIND, REPORTED, ControlKind, ControlState
from gcu_async.session.events import (
    Event,
    LinkDown,
    LinkUp,
    ResetLink,
    Restarted,
    TelemetrySample,
    TicketDone,
)
from gcu_async.session.feed import AircraftFeed
from gcu_async.session.health import HealthTracker, LinkHealth
from gcu_async.session.pacing import Pacer
from gcu_async.session.recording import RecordingBelief
from gcu_async.session.restart import ZOOM_SCALE, RestartWatch, StateChange
from gcu_async.session.runs import RunLedger
from gcu_async.session.tickets import Ticket, TicketState

if sys.version_info >= (3, 11):
    from typing import Unpack
elif TYPE_CHECKING:
    from typing_extensions import Unpack

log = logging.getLogger("gcu_async.session")

NULL = NullCommand()
_NULL_OPCODE = int(Opcode.NULL)
_RECORDING = int(CameraFlags.RECORDING)
FLAGGED_MAX = 64
"""Kinds of anomaly logged once each per session (a GCU sending junk cannot flood the log)."""
MIN_WAKE = 1e-4
"""Seconds; the smallest step :meth:`Session.next_wakeup` asks for while no packet may go
(a floor against float round-off, never a busy loop)."""


class SessionState(enum.Enum):
    """The session's lifecycle: one state, not a set of flags."""

    CLOSED = "closed"
    """Not open (never opened, or closed: it may be opened again)."""
    OPENING = "opening"
    """Open; the heartbeat runs; no reply yet."""
    UP = "up"
    """Replies arrive; commands are accepted."""
    DOWN = "down"
    """The link was lost; the heartbeat goes on; commands fail at once until replies return."""


@dataclass
class SessionStats:
    """Counters of one session (since it was created)."""

    submitted: int = 0
    succeeded: int = 0
    skipped: int = 0
    failed: int = 0
    not_sent: int = 0
    unknown: int = 0
    cancelled: int = 0
    late_feedback: int = 0
    """Replies to an earlier run of the same opcode as the command in flight (expected:
    the GCU answers every repeat of the previous command)."""
    separator_packets: int = 0
    """Null packets sent because the next command had to wait for proof of separation."""
    early_packets: int = 0
    """Commands sent before their heartbeat slot (the phase moved instead)."""
    aircraft_stale: int = 0
    """Episodes in which packets withheld aircraft data because it was older than
    ``aircraft_timeout`` (one per run of such packets; docs/client.md, "Aircraft data:
    what the packets claim")."""


class Session:
    """One host's session with one GCU. See the module docstring and docs/client.md.

    ``Session(config)`` takes a :class:`SessionConfig`; ``Session(**options)`` makes one from
    its fields (``Session(rate_hz=30, reorder_guard=0.015)``), which checks them all."""

    def __init__(self, config: SessionConfig | None = None, /,
                 **options: Unpack[SessionOptions]) -> None:  # fmt: skip
        if config is None:
            config = SessionConfig(**options)
        elif options:
            raise TypeError("Session: give a SessionConfig or its fields as options, not both")
        self.config = check_instance("config", config, SessionConfig)
        """The options (read-only: a new session takes new ones)."""
        self._pacer = Pacer(config.rate_hz, config.reorder_guard)
        self._ledger = RunLedger(config.reorder_guard, config.reply_window)
        self._control = ControlState()
        self._recording = RecordingBelief(config.record_settle)
        self._deframer = Deframer.for_gcu_packets()
        self._health = HealthTracker()
        self._restart = RestartWatch()
        self.stats = SessionStats()
        self.telemetry = True
        """Emit a :class:`TelemetrySample` event for every reply (a driver with no
        telemetry consumers turns this off)."""
        self._state = SessionState.CLOSED
        self._queue: deque[Ticket] = deque()
        self._deadlines: list[tuple[float, int, Ticket]] = []
        self._seq = 0
        """Tie-breaker of equal deadlines: the order they were queued in."""
        self._in_flight: Ticket | None = None
        self._kick = False
        self._events: list[Event] = []
        self._status: GcuMainFrame | None = None
        self._info: GcuSubFrame | None = None
        self._feedback: Feedback | None = None
        self.trace: Callable[[bytes], None] | None = None
        """Called with every whole packet received (before it is decoded), e.g. to log it."""
        self._feed = AircraftFeed(config.aircraft_timeout, config.name)
        self._last_encoded: tuple[object, object, object, bytes] = (None, None, None, b"")
        self._last_datagram = b""
        self._last_packet: GcuPacket | None = None
        """The last whole-packet datagram decoded, and its packet (decoding is a pure
        function of the bytes: a repeated datagram reuses it)."""
        self._silent_at = math.inf
        """When the link counts as lost if no reply comes first (set by every reply)."""
        self._flagged: set[tuple[str, str]] = set()
        """The kinds of anomaly (field, detail) already logged (:meth:`_flag`)."""

    # -- lifecycle -------------------------------------------------------------------------
    @property
    def state(self) -> SessionState:
        return self._state

    def open(self, now: float) -> None:
        """Start a session: the heartbeat begins with the next :meth:`poll`. Raises
        ``RuntimeError`` unless the session is closed."""
        if self._state is not SessionState.CLOSED:
            raise RuntimeError(f"session is already {self._state.value}")
        self._pacer.reset()
        self._ledger = RunLedger(self.config.reorder_guard, self.config.reply_window)
        self._control.reset()
        self._recording.reset()
        self._restart.reset()
        self._deframer.reset()
        self._status = self._info = None
        self._state = SessionState.OPENING

    def close(self, now: float, reason: str = "client closed") -> None:
        """End the session: every pending command ends (:class:`CommandLinkLost`); nothing
        more is sent. Idempotent."""
        if self._state is SessionState.CLOSED:
            return
        self._end_all(now, f"{self.config.name}: {reason}")
        self._state = SessionState.CLOSED

    # -- inputs ----------------------------------------------------------------------------
    def receive(self, data: bytes, now: float, *, datagram: bool = False,
                arrived_after: float | None = None) -> None:  # fmt: skip
        """Bytes from the GCU, in any chunking (``datagram``: exactly one datagram, whose
        leftovers are not joined with the next one's).

        ``arrived_after``: a time before which these bytes cannot have arrived (default
        ``now``). On links that may reorder, a driver whose event loop can lag must pass it
        (the time it last found the link with nothing to read), or the proofs drawn from
        reply timing assume replies are processed as they arrive."""
        if self._state is SessionState.CLOSED:
            return
        deframer = self._deframer
        if datagram and data == self._last_datagram and not deframer.buffered:
            packet = self._last_packet  # one memcmp: an idle GCU repeats its reply
            assert packet is not None
            self._on_reply(data, packet, now, arrived_after)
            return
        packets = deframer.feed(data)
        if datagram and deframer.buffered:
            packets += deframer.flush()  # a datagram's leftovers never join the next one
        for raw in packets:
            packet = decode_gcu_packet(raw)  # framed: header, length and CRC are right
            if datagram and raw is data and type(data) is bytes:  # whole, immutable: kept
                self._last_datagram, self._last_packet = data, packet
            self._on_reply(raw, packet, now, arrived_after)

    def connection_lost(self, now: float, reason: str) -> None:
        """The transport lost its connection (stream transports): no reply to anything sent
        so far can arrive any more; the link is down until replies return."""
        if self._state is SessionState.CLOSED:
            return
        self._ledger.connection_reset(now)
        self._deframer.reset()
        self._link_down(now, reason, reset=False)

    def submit(
        self,
        command: Command,
        now: float,
        *,
        timeout: float | None = None,
        queue_timeout: float | None = None,
        control: ControlValues | None = None,
        recording_target: bool | None = None,
    ) -> Ticket:
        """Queue ``command``; returns its :class:`Ticket` (its outcome arrives as a
        :class:`TicketDone` event).

        ``timeout`` (default ``command_timeout``) counts from its first packet;
        ``queue_timeout`` (default ``queue_timeout``) bounds the wait before it.
        ``control``: for a mode command, the values to send valid once the GCU confirmed
        it. ``recording_target`` (record commands only): send it only if the camera is not
        already in that state when its turn comes (else it ends ``SKIPPED``).
        Raises :class:`CommandLinkLost` (``NOT_SENT``) unless the link is up, TypeError /
        ValueError for bad arguments.
        """
        check_instance("command", command, Command, "a Command")
        if isinstance(command, AnomalousCommand):  # decoded, never sent: send is strict
            raise command.error()
        if isinstance(command, NullCommand):
            raise ValueError("command: the null command is the session's own separator")
        opcode = command_code(command)
        config = self.config
        timeout = config.command_timeout if timeout is None else check_positive("timeout", timeout)
        queue_timeout = (config.queue_timeout if queue_timeout is None
                         else check_positive("queue_timeout", queue_timeout))  # fmt: skip
        if control is not None:
            self._check_values(control, KIND.get(opcode), opcode)
        if recording_target is not None:
            check_bool("recording_target", recording_target)
            if opcode != Opcode.RECORD:
                raise ValueError(f"recording_target: only for RECORD, not {opcode_name(opcode)}")
        if self._state is not SessionState.UP:
            state = "closed" if self._state is SessionState.CLOSED else "down"
            raise CommandLinkLost(
                f"{opcode_name(opcode)}: {self.config.name}: link is {state}; not sent",
                outcome=Outcome.NOT_SENT, opcode=opcode, command=command,
            )  # fmt: skip
        ticket = Ticket(command, opcode, now, timeout, now + queue_timeout,
                        recording_target=recording_target)  # fmt: skip
        self.stats.submitted += 1
        self._queue.append(ticket)
        self._seq += 1
        heapq.heappush(self._deadlines, (ticket.queue_deadline, self._seq, ticket))
        self._control.submitted(ticket, control)
        if self._in_flight is None:
            self._kick = True
        self._advance_queue(now)
        return ticket

    def cancel(self, ticket: Ticket, now: float) -> None:
        """Withdraw a ticket (its caller gave up): ``NOT_SENT`` if it was still queued,
        ``UNKNOWN`` if it was in flight (it stops being repeated). No-op when done."""
        if ticket.done:
            return
        self.stats.cancelled += 1
        self._end(ticket, now, "cancelled by the caller", CommandError)

    def set_aircraft(self, state: AircraftState, now: float) -> None:
        """Replace the aircraft state carried by the packets from the next one on: every part
        it gives counts as measured at ``now`` (docs/client.md, "Aircraft data: what the
        packets claim")."""
        check_instance("state", state, AircraftState)
        self._feed.set(state, now, _AIRCRAFT_FIELDS)

    def update_aircraft(self, changes: Mapping[str, Any], now: float) -> AircraftState:
        """Change the named fields of the aircraft state (the others keep their value and
        the time they were given); the parts named count as measured at ``now``. Raises
        ``TypeError``/``ValueError`` (nothing changes) for an unknown field or a bad value;
        returns the new state."""
        if not isinstance(changes, Mapping):
            raise type_error("changes", "a mapping of AircraftState fields", changes)
        unknown = sorted(str(k) for k in changes if k not in _AIRCRAFT_FIELDS)
        if unknown:
            raise TypeError(f"changes: {', '.join(unknown)}: not AircraftState fields "
                            f"({', '.join(_AIRCRAFT_FIELDS)})")  # fmt: skip
        state = replace(self._feed.state, **changes)  # validates
        self._feed.set(state, now, changes)
        return state

    @property
    def aircraft(self) -> AircraftState:
        """The aircraft state as last given (see :meth:`ins_valid` for what goes out)."""
        return self._feed.state

    def ins_valid(self, now: float) -> bool:
        """True if a packet sent at ``now`` would set the INS-valid bit: attitude,
        acceleration and velocity all given, each within ``aircraft_timeout``."""
        return self._feed.ins_valid(now)

    def set_control(self, values: ControlValues | None,
                    kind: ControlKind | None = None) -> int | None:  # fmt: skip
        """New control values for the current mode: the last mode command pending, else the
        confirmed one (``None``: send them invalid). ``kind`` (if given) must be what that
        mode reads. Returns the mode's opcode (None: no mode known, values released).
        Raises ``ValueError``/``TypeError`` (nothing changes) for values out of range or when
        no mode takes values."""
        if values is not None:
            opcode, _ = self._control.target()
            self._check_values(values, KIND.get(opcode) if opcode is not None else None, opcode)
        return self._control.set_values(values, kind)

    # -- outputs ---------------------------------------------------------------------------
    def events(self) -> Sequence[Event]:
        """Every event since the last call, in order."""
        events = self._events
        if not events:
            return ()
        self._events = []
        return events

    def poll(self, now: float) -> bytes | None:
        """Run due timers; return the host packet to send now, if one is due."""
        if self._state is SessionState.CLOSED:
            return None
        self._timers(now)
        pacer = self._pacer
        if pacer.late:
            pacer.settle(now)
        when, start = self._gate(now)
        if now < when:
            return None
        self._kick = False
        early = now < pacer.next_slot
        ticket = self._in_flight
        if start is not None:
            self._queue.popleft()
            start.state = TicketState.SENT
            start.first_sent = now
            if start.opcode == Opcode.RECORD:
                belief = self._recording.value(now)
                start.expect_recording = None if belief is None else not belief
            self._in_flight = ticket = start
        command, opcode = (NULL, _NULL_OPCODE) if ticket is None else (ticket.command,
                                                                        ticket.opcode)
        run = self._ledger.sent(opcode, now)
        if ticket is not None:
            ticket.run = run
            ticket.packets += 1
        elif self._queue:
            self.stats.separator_packets += 1
        if early:
            self.stats.early_packets += 1
        pacer.record(now, opcode, early=early)
        self._health.packets_sent += 1
        if self._feed.check(now):
            self.stats.aircraft_stale += 1
        values = None if self._control.values is None else self._valid_values(now)
        main, sub = self._feed.frames(values, now)
        return self._encode(main, sub, command)

    def next_wakeup(self, now: float) -> float:
        """When :meth:`poll` must be called next (``inf`` when closed): when the gate lets
        the next packet go, or a timer is due, whichever comes first.

        ``now`` itself when a packet may go now, or when the last packet went out late
        (:attr:`~gcu_async.session.pacing.Pacer.late`): the driver then polls
        at its next turn, which on a busy event loop is the next iteration, late enough for
        the next slot."""
        if self._state is SessionState.CLOSED:
            return math.inf
        when = self._gate(now)[0]
        if when <= now or self._pacer.late:
            return now  # poll(now) sends (after its timers), or settles the late packet
        timer = self._timers_due_at(now)
        if timer <= now:
            return now  # poll(now) fires it
        if timer < when:
            when = timer
        return when if when > now + MIN_WAKE else now + MIN_WAKE

    def _gate(self, now: float) -> tuple[float, Ticket | None]:
        """The one gate of sending, read by :meth:`poll` (a packet goes iff ``now`` has
        reached it) and :meth:`next_wakeup` (it wakes the driver then): the earliest time
        the next packet may go, and the queued ticket it would start (``None``: the command
        in flight or a null packet).

        A packet goes on its heartbeat slot, or early (before it) to start a command that
        was just queued (``_kick``) once the early window is open; never before the rate
        bound and the edge guard allow (:mod:`~gcu_async.session.pacing`). A kick that
        cannot start its command early now (nothing may start, or the early window is not
        open) is spent: the command goes on a slot."""
        pacer = self._pacer
        opcode, start, t = _NULL_OPCODE, None, self._in_flight
        if t is not None:  # it repeats until its feedback
            opcode = t.opcode
        elif self._queue:  # the head starts once a reply proved it may, and its state is known
            head = self._queue[0]
            if self._ledger.may_start(head.opcode) and (
                head.recording_target is None or self._recording.value(now) is not None
            ):
                opcode, start = head.opcode, head
        gate = pacer.open_at(opcode)
        when = pacer.next_slot
        if gate > when:
            when = gate
        if self._kick and now < pacer.next_slot:
            early = pacer.early_open_at()
            if start is None or now < early:
                self._kick = False  # early only to start a command, once per window
            else:
                if gate > early:
                    early = gate
                if early < when:
                    when = early
        return when, start

    def _timers_due_at(self, now: float) -> float:
        """When the earliest timer :meth:`_timers` fires is due: the link's silence, the
        command in flight's timeout, a queued command's deadline, the recording belief of a
        state-checked head settling (``inf``: none)."""
        when = self._silent_at if self._state is SessionState.UP else math.inf
        t = self._in_flight
        if t is not None and t.first_sent is not None and t.first_sent + t.timeout < when:
            when = t.first_sent + t.timeout
        deadlines = self._deadlines
        while deadlines and deadlines[0][2].state is not TicketState.QUEUED:
            heapq.heappop(deadlines)
        if deadlines and deadlines[0][0] < when:
            when = deadlines[0][0]
        if self._queue and self._queue[0].recording_target is not None:
            settle = self._recording.settles_at()  # the head waits for the belief to settle
            if now < settle < when:
                when = settle
        return when

    # -- observations ----------------------------------------------------------------------
    @property
    def status(self) -> GcuMainFrame | None:
        """The latest main frame (None before the first reply)."""
        return self._status

    @property
    def info(self) -> GcuSubFrame | None:
        """The latest sub frame (None before the first)."""
        return self._info

    @property
    def latest(self) -> TelemetrySample | None:
        """The latest reply as a telemetry sample (None before the first)."""
        status, feedback, at = self._status, self._feedback, self._health.last_reply
        if status is None or feedback is None or at is None:
            return None
        return TelemetrySample(status, self._info, feedback, at)

    @property
    def pending(self) -> int:
        """Commands queued or in flight."""
        return len(self._queue) + (self._in_flight is not None)

    @property
    def control(self) -> ControlValues | None:
        """The values given for the current mode (whether or not they go out valid now)."""
        return self._control.target_values()

    @property
    def control_mode(self) -> int | None:
        """Opcode of the mode command the GCU confirmed last (None: no mode is known)."""
        return self._control.confirmed

    def control_valid(self, now: float) -> ControlValues | None:
        """The control values the next packet would carry valid (None: invalid)."""
        return self._valid_values(now)

    def recording(self, now: float) -> bool | None:
        """Whether the camera records, as far as the session can tell (None: not known)."""
        return self._recording.value(now)

    def link_health(self, now: float) -> LinkHealth:
        h, d, r = self._health, self._deframer.stats, self._ledger.stats
        return LinkHealth(
            up=self._state is SessionState.UP,
            reply_rate=h.reply_rate(now),
            last_reply_age=None if h.last_reply is None else now - h.last_reply,
            packets_sent=h.packets_sent,
            packets_received=h.packets_received,
            send_errors=h.send_errors,
            crc_errors=d.crc_errors,
            length_errors=d.length_errors,
            bytes_discarded=d.bytes_discarded,
            other_versions=h.other_versions,
            unmatched_feedback=r.unmatched,
            ambiguous_feedback=r.ambiguous,
            lost_count=h.lost_count,
            restored_count=h.restored_count,
            restarted_count=h.restarted_count,
        )

    def send_failed(self) -> None:
        """The driver could not hand the last packet to the transport (counted)."""
        self._health.send_errors += 1

    # -- internals: replies ----------------------------------------------------------------
    def _other_version(self, version: int) -> None:
        """A reply of a version V2.0.6 does not define: decoded with its layout, counted;
        the first one of the session is logged as a warning."""
        self._health.other_versions += 1
        if self._health.other_versions == 1:
            log.warning("%s: reply of protocol version %d (V2.0.6 defines 1 and 2): decoded "
                        "with the V2.0.6 layout; further ones are only counted "
                        "(link_health().other_versions)", self.config.name, version)  # fmt: skip

    def _flag(self, anomalies: tuple[Anomaly, ...]) -> None:
        """Log each kind of value outside V2.0.6 (field and reading) the first time a reply
        carries it: a firmware deviation is said once, not per packet; every reply keeps its
        own in its ``anomalies``."""
        for anomaly in anomalies:
            key = (anomaly.field, anomaly.detail)
            if key in self._flagged or len(self._flagged) >= FLAGGED_MAX:
                continue
            self._flagged.add(key)
            log.warning("%s: the GCU sends a value outside V2.0.6, %s; said once, each reply "
                        "keeps it in its anomalies (docs/protocol-notes.md, \"What real pods "
                        "do\")", self.config.name, anomaly)  # fmt: skip

    def _on_reply(self, raw: bytes, packet: GcuPacket, now: float,
                  earliest: float | None) -> None:  # fmt: skip
        """One reply (``raw``: its bytes) that arrived in ``[earliest, now]``."""
        if self.trace is not None:
            self.trace(raw)
        if packet.version not in SUPPORTED_VERSIONS:
            self._other_version(packet.version)
        main, feedback = packet.main, packet.feedback
        sub = packet.sub if type(packet.sub) is GcuSubFrame else None
        self._health.on_reply(now)
        if main is not self._status and (main.anomalies or feedback.anomalies):
            self._flag(main.anomalies + feedback.anomalies)  # a new frame: an idle GCU repeats
        # the first instant the silence since this reply exceeds silence_timeout
        self._silent_at = math.nextafter(now + self.config.silence_timeout, math.inf)
        self._status = main
        self._feedback = feedback
        if sub is not None:
            if sub is not self._info:
                self._restart.zoom_seen(self._info, sub, now)
            self._info = sub
            recording = self._recording
            flag = bool(sub.camera_flags_raw & _RECORDING)
            if flag is not recording.observed:
                recording.observe(flag, now)
        if self._state is not SessionState.UP:
            restored = self._state is SessionState.DOWN
            if restored:
                self._health.restored_count += 1
            self._state = SessionState.UP
            self._events.append(LinkUp(restored, "replies resumed" if restored else "first reply"))
        if self._restart.pending:
            changes = self._restart.compare(main, sub)
            if changes:
                self._restarted(changes)
        run = self._ledger.identify(feedback.opcode, now, earliest)
        ticket = self._in_flight
        if run is not None and ticket is not None and run.opcode == ticket.opcode:
            if run is not ticket.run:
                self.stats.late_feedback += 1
            else:
                result = feedback.result
                if result is ExecutionStatus.IN_PROGRESS:
                    ticket.progress.append(feedback)
                elif result is ExecutionStatus.SUCCESS:
                    ticket.feedback = feedback
                    self._finish(ticket, TicketState.SUCCEEDED, now)
                else:
                    ticket.feedback = feedback
                    error = CommandFailed(
                        feedback.opcode, feedback.status, feedback.failed_cameras,
                        command=ticket.command, name=feedback.command,
                    )  # fmt: skip
                    self._finish(ticket, TicketState.FAILED, now, error)
        elif run is not None and ticket is None and run.opcode != Opcode.NULL:
            self.stats.late_feedback += 1
        if self.telemetry:
            self._events.append(TelemetrySample(main, self._info, feedback, now))
        if self._queue:
            self._advance_queue(now)

    # -- internals: timers and the queue ---------------------------------------------------
    def _timers(self, now: float) -> None:
        if self._state is SessionState.UP and now >= self._silent_at:
            self._link_down(now, f"no reply for {self.config.silence_timeout:g} s", reset=True)
        if not self._deadlines and self._in_flight is None:
            return
        t = self._in_flight
        if t is not None and t.first_sent is not None and now >= t.first_sent + t.timeout:
            progress = " (last status: in progress)" if t.progress else ""
            message = (
                f"{opcode_name(t.opcode)}: no feedback within {t.timeout:g} s of its first "
                f"packet{progress}; outcome unknown (it may have executed)"
            )
            self._finish(t, TicketState.UNKNOWN, now, CommandTimeout(
                message, outcome=Outcome.UNKNOWN, opcode=t.opcode, command=t.command))  # fmt: skip
        deadlines = self._deadlines
        while deadlines and (deadlines[0][0] <= now
                             or deadlines[0][2].state is not TicketState.QUEUED):  # fmt: skip
            _, _, ticket = heapq.heappop(deadlines)
            if ticket.state is TicketState.QUEUED:
                queued = now - ticket.submitted_at
                message = (f"{opcode_name(ticket.opcode)}: not sent: still queued after "
                           f"{queued:.3g} s (queue_timeout)")  # fmt: skip
                self._queue.remove(ticket)
                self._finish(ticket, TicketState.NOT_SENT, now, CommandTimeout(
                    message, outcome=Outcome.NOT_SENT, opcode=ticket.opcode,
                    command=ticket.command))  # fmt: skip
        self._advance_queue(now)

    def _advance_queue(self, now: float) -> None:
        """End state-checked record commands at the head whose target state holds."""
        queue = self._queue
        while self._in_flight is None and queue and queue[0].recording_target is not None:
            head = queue[0]
            if self._recording.value(now) is not head.recording_target:
                return
            queue.popleft()
            self._finish(head, TicketState.SKIPPED, now)

    def _restarted(self, changes: tuple[StateChange, ...]) -> None:
        """The GCU restarted: the event, with what a driver needs to restore the host's
        mode (the mode command it confirmed last, if the GCU was in that mode before the
        loss and the mode changed) and camera 1's zoom (if it changed)."""
        self._health.restarted_count += 1
        before, control = self._restart.compared, self._control
        assert before is not None
        aspects = {change.aspect for change in changes}
        mode = None
        if ("mode" in aspects and control.command is not None and control.confirmed in KIND
                and REPORTED[control.confirmed] == before.mode_raw):  # fmt: skip
            mode = control.command
        zoom = None
        if "zoom" in aspects and before.zoom_raw is not None:
            zoom = before.zoom_raw / ZOOM_SCALE
        self._events.append(Restarted(changes, mode, control.values if mode else None, zoom))

    def _link_down(self, now: float, reason: str, *, reset: bool) -> None:
        up = self._state is SessionState.UP
        if up:
            self._health.lost_count += 1
        was = self._state
        self._state = SessionState.DOWN
        self._end_all(now, f"{self.config.name}: {reason}")
        if up:
            self._restart.lost(self._status, self._info, self._health.last_reply)
        if was is not SessionState.DOWN:
            self._events.append(LinkDown(reason))
            if reset:
                self._events.append(ResetLink(reason))

    def _end_all(self, now: float, reason: str) -> None:
        for ticket in [*([self._in_flight] if self._in_flight else []), *self._queue]:
            self._end(ticket, now, reason, CommandLinkLost)

    def _end(self, ticket: Ticket, now: float, reason: str, cls: type[CommandError]) -> None:
        """End a pending ticket from outside: ``UNKNOWN`` if it was sent, else ``NOT_SENT``."""
        sent = ticket.state is TicketState.SENT
        state = TicketState.UNKNOWN if sent else TicketState.NOT_SENT
        outcome = Outcome.UNKNOWN if sent else Outcome.NOT_SENT
        what = ("outcome unknown (it may have executed)" if sent
                else "not sent (it did not execute)")  # fmt: skip
        message = f"{opcode_name(ticket.opcode)}: {reason}; {what}"
        error = cls(message, outcome=outcome, opcode=ticket.opcode, command=ticket.command)
        if not sent:
            self._queue.remove(ticket)
        self._finish(ticket, state, now, error)

    def _finish(self, ticket: Ticket, state: TicketState, now: float,
                error: GcuError | None = None) -> None:  # fmt: skip
        ticket.state = state
        ticket.error = error
        ticket.finished_at = now
        if ticket is self._in_flight:
            self._in_flight = None
        self._control.finished(ticket)
        self._restart.finished(ticket.opcode, ticket.command, state, now)
        if ticket.opcode == Opcode.RECORD:
            if state is TicketState.SUCCEEDED:
                self._recording.toggled(ticket.expect_recording, now)
            elif state is TicketState.UNKNOWN:
                self._recording.uncertain(now)
        s = self.stats
        if state is TicketState.SUCCEEDED:
            s.succeeded += 1
        elif state is TicketState.SKIPPED:
            s.skipped += 1
        elif state is TicketState.FAILED:
            s.failed += 1
        elif state is TicketState.NOT_SENT:
            s.not_sent += 1
        else:
            s.unknown += 1
        self._events.append(TicketDone(ticket))

    # -- internals: packets ----------------------------------------------------------------
    def _valid_values(self, now: float) -> ControlValues | None:
        control = self._control
        if control.values is None:
            return None
        status = self._status
        reported = status.mode_raw if status is not None else None
        silent = self._health.silent_for(now) > self.config.control_silence
        return control.valid(reported, silent)

    def _encode(self, main: HostMainFrame, sub: HostSubFrame | None, command: Command) -> bytes:
        """The packet's bytes; the previous packet's are reused when it had the very same
        (immutable) parts, as every heartbeat of an idle session has."""
        last = self._last_encoded
        if last[0] is main and last[1] is sub and last[2] is command:
            return last[3]
        data = HostPacket(main, sub, command, self.config.version).encode()
        self._last_encoded = (main, sub, command, data)
        return data

    @staticmethod
    def _check_values(values: ControlValues, kind: ControlKind | None,
                      opcode: int | None) -> None:  # fmt: skip
        """Control values must fit the wire and, when the mode is known, its kind: angles
        ±18000 (0.01°), rates ±1500 (0.1 °/s ÷ zoom)."""
        ControlValues.check(values)
        limit = CONTROL_RATE_RAW if kind is ControlKind.RATES else CONTROL_ANGLE_RAW
        for field, raw in zip(("roll_raw", "pitch_raw", "yaw_raw"), values, strict=True):
            check_int(f"control.{field}", raw, -limit, limit)
        if kind is ControlKind.NONE and opcode is not None:
            raise ValueError(f"control: {opcode_name(opcode)} takes no control values")


_AIRCRAFT_FIELDS = tuple(f.name for f in fields(AircraftState))

__all__ = ["Session", "SessionState", "SessionStats"]
