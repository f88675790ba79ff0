"""The command session as a sans-I/O state machine (the h11 / wsproto pattern).

Inputs: bytes received (:meth:`Session.receive`), the time (every call takes ``now``), API
calls (:meth:`Session.submit`, :meth:`Session.cancel`, :meth:`Session.set_aircraft`,
:meth:`Session.update_aircraft`, :meth:`Session.set_control`, :meth:`Session.open`,
:meth:`Session.close`) and transport news
(:meth:`Session.connection_lost`). Outputs: the packet to send now (:meth:`Session.poll`),
when to call :meth:`Session.poll` next (:meth:`Session.next_wakeup`) and events
(:meth:`Session.events`). No asyncio, no sockets, no clock of its own: a driver (the
asyncio :class:`~gcu_async.client.GcuClient`, or a virtual-time test harness) does the I/O.

The contract it keeps, with its assumptions, is in docs/session-contract.md ("The session
contract"); the rules behind it live in :mod:`~gcu_async.session.pacing` (when a packet may
go), :mod:`~gcu_async.session.runs` (what a reply proves, when an opcode may start),
:mod:`~gcu_async.session.control` (which control values go out valid),
:mod:`~gcu_async.session.recording` (state-checked record toggles) and
:mod:`~gcu_async.session.feed` (which aircraft data goes out valid, GNSS time).
"""

from __future__ import annotations

import heapq
import math
import sys
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

from gcu_async._checks import check_instance
from gcu_async.errors import (
    CommandError,
    CommandLinkLost,
    GcuError,
    Outcome,
)
from gcu_async.protocol.aircraft import AircraftState
from gcu_async.protocol.command_base import Command
from gcu_async.protocol.commands import NullCommand
from gcu_async.protocol.deframer import Deframer
from gcu_async.protocol.enums import CameraFlags, Opcode, opcode_name
from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.gcu_frames import GcuMainFrame, GcuSubFrame
from gcu_async.protocol.host_frame_tables import ControlValues
from gcu_async.protocol.host_frames import HostMainFrame, HostSubFrame
from gcu_async.protocol.packets import SUPPORTED_VERSIONS, GcuPacket, HostPacket, decode_gcu_packet
from gcu_async.session.config import SessionConfig, SessionOptions
from gcu_async.session.control import KIND, ControlKind, ControlState, check_values
from gcu_async.session.deviations import DeviationLog
from gcu_async.session.events import (
    Event,
    LinkDown,
    LinkUp,
    ResetLink,
    Restarted,
    TelemetrySample,
    TicketDone,
)
from gcu_async.session.feed import AIRCRAFT_FIELDS, AircraftFeed
from gcu_async.session.health import HealthTracker, LinkHealth
from gcu_async.session.pacing import Pacer
from gcu_async.session.recording import RecordingBelief
from gcu_async.session.restart import RestartWatch, StateChange
from gcu_async.session.runs import RunLedger
from gcu_async.session.state import SessionState, SessionStats
from gcu_async.session.tickets import Ticket, TicketState

if sys.version_info >= (3, 11):
    from typing import Unpack
elif TYPE_CHECKING:
    from typing_extensions import Unpack

NULL = NullCommand()
_NULL_OPCODE = int(Opcode.NULL)
_RECORDING = int(CameraFlags.RECORDING)
MIN_WAKE = 1e-4
"""Seconds; the smallest step :meth:`Session.next_wakeup` asks for while no packet may go
(a floor against float round-off, never a busy loop)."""


class Session:
    """One host's session with one GCU. See the module docstring and docs/session-contract.md.

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
        self._deviations = DeviationLog(config.name)

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
        config = self.config
        ticket = Ticket.new(command, now, config.command_timeout if timeout is None else timeout,
                            config.queue_timeout if queue_timeout is None else queue_timeout,
                            recording_target)  # fmt: skip
        opcode = ticket.opcode
        if control is not None:
            check_values(control, KIND.get(opcode), opcode)
        if self._state is not SessionState.UP:
            state = "closed" if self._state is SessionState.CLOSED else "down"
            raise CommandLinkLost(f"{opcode_name(opcode)}: {config.name}: link is {state}; not "
                                  "sent", outcome=Outcome.NOT_SENT, opcode=opcode,
                                  command=command)  # fmt: skip
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
        self._feed.set(state, now, AIRCRAFT_FIELDS)

    def update_aircraft(self, changes: Mapping[str, Any], now: float) -> AircraftState:
        """Change the named fields of the aircraft state (the others keep their value and
        the time they were given); the parts named count as measured at ``now``. Raises
        ``TypeError``/``ValueError`` (nothing changes) for an unknown field or a bad value;
        returns the new state."""
        return self._feed.update(changes, now)

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
            check_values(values, KIND.get(opcode) if opcode is not None else None, opcode)
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
            start.start(now, self._recording.value(now))
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
        return self._health.snapshot(now, self._state is SessionState.UP,
                                     self._deframer.stats, self._ledger.stats)  # fmt: skip

    def send_failed(self) -> None:
        """The driver could not hand the last packet to the transport (counted)."""
        self._health.send_errors += 1

    # -- internals: replies ----------------------------------------------------------------
    def _on_reply(self, raw: bytes, packet: GcuPacket, now: float,
                  earliest: float | None) -> None:  # fmt: skip
        """One reply (``raw``: its bytes) that arrived in ``[earliest, now]``."""
        if self.trace is not None:
            self.trace(raw)
        if packet.version not in SUPPORTED_VERSIONS:  # decoded with the V2.0.6 layout
            self._health.other_versions += 1
            self._deviations.other_version(packet.version, self._health.other_versions)
        main, feedback = packet.main, packet.feedback
        sub = packet.sub if type(packet.sub) is GcuSubFrame else None
        self._health.on_reply(now)
        if main is not self._status and (main.anomalies or feedback.anomalies):
            self._deviations.flag(main.anomalies + feedback.anomalies)  # an idle GCU repeats
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
                ended = ticket.answered(feedback)
                if ended is not None:
                    self._finish(ticket, ended[0], now, ended[1])
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
            self._finish(t, TicketState.UNKNOWN, now, t.timeout_error(now))
        deadlines = self._deadlines
        while deadlines and (deadlines[0][0] <= now
                             or deadlines[0][2].state is not TicketState.QUEUED):  # fmt: skip
            _, _, ticket = heapq.heappop(deadlines)
            if ticket.state is TicketState.QUEUED:
                self._queue.remove(ticket)
                self._finish(ticket, TicketState.NOT_SENT, now, ticket.timeout_error(now))
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
        """The GCU restarted: the event, with what a driver needs to restore."""
        self._health.restarted_count += 1
        self._events.append(Restarted(changes, *self._restart.to_restore(changes, self._control)))

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
        error = ticket.end_error(reason, cls)
        if ticket.state is TicketState.SENT:
            self._finish(ticket, TicketState.UNKNOWN, now, error)
        else:
            self._queue.remove(ticket)
            self._finish(ticket, TicketState.NOT_SENT, now, error)

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
        self.stats.ended(state)
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

__all__ = ["Session"]
