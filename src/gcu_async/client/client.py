"""The asyncio session: heartbeat, command exchange, telemetry and link health.

``GcuClient`` owns one transport and the protocol core (composition): every host packet is
built from the latest aircraft state, the current control values and the command the
:class:`CommandScheduler` picks; every reply updates status/info, link health, telemetry and
the waiting command.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
import warnings
from collections.abc import AsyncGenerator, Callable
from dataclasses import replace
from datetime import datetime
from types import TracebackType
from typing import Any

from gcu_async.client.api import CommandMethods
from gcu_async.client.health import HealthTracker, LinkHealth
from gcu_async.client.scheduler import CommandScheduler, Ticket
from gcu_async.client.telemetry import TelemetrySample, TelemetrySubscription
from gcu_async.errors import (
    CommandFailed,
    CommandTimeout,
    GcuError,
    LinkLost,
    RemoteProtocolError,
    UnsupportedCommandError,
)
from gcu_async.protocol.aircraft import AircraftState
from gcu_async.protocol.commands import Command, command_code
from gcu_async.protocol.deframer import Deframer
from gcu_async.protocol.enums import ExecutionStatus, PodModel, SubFrameRequest, opcode_name
from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.gcu_frames import GcuMainFrame, GcuSubFrame
from gcu_async.protocol.host_frames import ControlValues, HostMainFrame, HostSubFrame
from gcu_async.protocol.packets import DEFAULT_VERSION, HostPacket, decode_gcu_packet
from gcu_async.protocol.pods import POD_NAMES, pod_name, supports
from gcu_async.protocol.units import Attitude, GeoPosition, NorthEastUp
from gcu_async.transport.base import LinkEvent, LinkEventKind, Transport

log = logging.getLogger("gcu_async.client")

RATE_MAX_HZ = 200.0
DEFAULT_REORDER_GUARD = 0.015
"""Seconds; the reordering guard on links that may reorder (UDP)."""
RATE_ADVISED = (30.0, 50.0)
_UNSET: Any = object()

LinkCallback = Callable[[LinkEvent], None]
TelemetryCallback = Callable[[TelemetrySample], None]


class GcuClient(CommandMethods):
    """An asyncio session with one GCU.

    ``async with GcuClient(transport) as gcu:`` opens the transport, starts the heartbeat
    (``rate_hz`` host packets per second), waits up to ``connect_timeout`` for the first
    reply, and on exit stops every task and closes the transport.

    Args:
        transport: any :class:`~gcu_async.transport.Transport` (not yet opened).
        rate_hz: heartbeat rate; the protocol advises 30–50 Hz (warned outside), must be in
            (0, 200].
        command_timeout: default seconds a command may take, from the call to its feedback.
        connect_timeout: seconds to wait for the first reply when opening.
        silence_timeout: seconds without a reply after which the link counts as lost.
        check_support: refuse commands the pod model does not support (Appendix 8) once the
            model is known, raising :class:`UnsupportedCommandError` without sending.
        reorder_guard: seconds between the last packet of a finished command and the next
            packet (see :mod:`gcu_async.client.scheduler`); must exceed the link's worst
            reordering delay. Default: 0 on ordered transports (TCP, serial), 15 ms on UDP.
        version: protocol version byte to send (2; some field devices expect 1).
        clock: monotonic time source (seconds).
    """

    def __init__(
        self,
        transport: Transport,
        *,
        rate_hz: float = 50.0,
        command_timeout: float = 2.0,
        connect_timeout: float = 3.0,
        silence_timeout: float = 1.0,
        check_support: bool = False,
        reorder_guard: float | None = None,
        version: int = DEFAULT_VERSION,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        if not 0 < rate_hz <= RATE_MAX_HZ:
            raise ValueError(f"rate_hz: {rate_hz!r} is outside the allowed range (0, 200] Hz")
        if not RATE_ADVISED[0] <= rate_hz <= RATE_ADVISED[1]:
            warnings.warn(
                f"rate_hz={rate_hz:g}: the protocol advises 30-50 Hz host packets",
                stacklevel=2,
            )
        for name, value in (
            ("command_timeout", command_timeout),
            ("connect_timeout", connect_timeout),
        ):
            if not value > 0:
                raise ValueError(f"{name}: {value!r} must be > 0 seconds")
        if version not in (1, 2):
            raise ValueError(f"version: {version!r} is not one of 1, 2")
        self.transport = transport
        self.rate_hz = float(rate_hz)
        self.command_timeout = command_timeout
        self.connect_timeout = connect_timeout
        self.check_support = check_support
        self.version = version
        self._clock = clock
        if reorder_guard is None:
            reorder_guard = 0.0 if transport.ordered else DEFAULT_REORDER_GUARD
        self._scheduler = CommandScheduler(reorder_guard)
        self._deferred: asyncio.TimerHandle | None = None
        self._deframer = Deframer.for_gcu_packets()
        self._health = HealthTracker(silence_timeout)
        self._aircraft = AircraftState()
        self._control: ControlValues | None = None
        self._main_valid = self._main_invalid = HostMainFrame()
        self._sub: HostSubFrame | None = None
        self._rebuild_frames()
        self._status: GcuMainFrame | None = None
        self._info: GcuSubFrame | None = None
        self._futures: dict[Ticket, asyncio.Future[Feedback]] = {}
        self._timers: dict[Ticket, asyncio.TimerHandle] = {}
        self._subscriptions: set[TelemetrySubscription] = set()
        self._telemetry_callbacks: list[TelemetryCallback] = []
        self._link_callbacks: list[LinkCallback] = []
        self._tasks: list[asyncio.Task[None]] = []
        self._first_reply: asyncio.Event | None = None
        self._open = False
        self._closing = False
        self.telemetry_dropped = 0
        self.heartbeat_ticks = 0
        self.heartbeat_late = 0

    # -- lifecycle ---------------------------------------------------------------------
    async def __aenter__(self) -> GcuClient:
        await self.open()
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        await self.close()

    async def open(self) -> None:
        """Open the transport, start the heartbeat, wait for the first reply."""
        if self._open:
            raise RuntimeError("GcuClient is already open")
        self._first_reply = asyncio.Event()
        self.transport.set_handlers(self._on_data, self._on_link_event)
        await self.transport.open()
        self._open = True
        self._closing = False
        self._tasks.append(asyncio.create_task(self._heartbeat(), name="gcu-heartbeat"))
        try:
            await asyncio.wait_for(self._first_reply.wait(), self.connect_timeout)
        except asyncio.TimeoutError:
            await self.close()
            raise LinkLost(
                f"{self.transport.url}: no reply from the GCU within {self.connect_timeout:g} s"
            ) from None
        except BaseException:
            await self.close()
            raise

    async def close(self) -> None:
        """Stop the heartbeat, fail waiting commands with :class:`LinkLost`, close the
        transport. Idempotent."""
        if not self._open:
            return
        self._closing = True
        if self._deferred is not None:
            self._deferred.cancel()
            self._deferred = None
        tasks, self._tasks = self._tasks, []
        for task in tasks:
            task.cancel()
        for task in tasks:
            with contextlib.suppress(asyncio.CancelledError):
                await task
        self._fail_all(LinkLost("client closed"))
        for sub in self._subscriptions:
            sub.close()
        self._open = False
        await self.transport.close()

    # -- aircraft state and control values ------------------------------------------------
    @property
    def aircraft(self) -> AircraftState:
        """The aircraft state sent in every packet."""
        return self._aircraft

    def update_aircraft(
        self,
        *,
        attitude: Attitude | tuple[float, float, float] | None = _UNSET,
        acceleration: NorthEastUp | tuple[float, float, float] | None = _UNSET,
        velocity: NorthEastUp | tuple[float, float, float] | None = _UNSET,
        position: GeoPosition | tuple[float, float, float] | None = _UNSET,
        relative_altitude: float = _UNSET,
        satellites: int = _UNSET,
        gnss_time: datetime | None = None,
        gnss_week: int = _UNSET,
        gnss_ms: int = _UNSET,
    ) -> AircraftState:
        """Update the aircraft state carried by the heartbeat; fields not given keep their
        value, ``None`` clears one. Units: degrees (attitude, yaw in [0, 360)), m/s² north/
        east/up without gravity, m/s north/east/up, (latitude °, longitude °, altitude m MSL),
        metres. ``gnss_time`` (aware UTC) sets week + ms with leap seconds applied.

        Raises :class:`FieldRangeError` (nothing changes) for any out-of-range value.
        """
        changes: dict[str, Any] = {}
        if attitude is not _UNSET:
            changes["attitude"] = None if attitude is None else Attitude(*attitude)
        if acceleration is not _UNSET:
            changes["acceleration"] = None if acceleration is None else NorthEastUp(*acceleration)
        if velocity is not _UNSET:
            changes["velocity"] = None if velocity is None else NorthEastUp(*velocity)
        if position is not _UNSET:
            changes["position"] = None if position is None else GeoPosition(*position)
        for name, value in (
            ("relative_altitude", relative_altitude),
            ("satellites", satellites),
            ("gnss_week", gnss_week),
            ("gnss_ms", gnss_ms),
        ):
            if value is not _UNSET:
                changes[name] = value
        if gnss_time is not None:
            changes["gnss_week"], changes["gnss_ms"] = AircraftState.gnss_from_utc(gnss_time)
        state = replace(self._aircraft, **changes)  # validates
        self._aircraft = state
        self._rebuild_frames()
        return state

    def set_aircraft(self, state: AircraftState) -> None:
        """Replace the whole aircraft state."""
        self._aircraft = state
        self._rebuild_frames()

    @property
    def control(self) -> ControlValues | None:
        """Control values sent (``None``: sent invalid — rates 0, angles held)."""
        return self._control

    def set_control(self, control: ControlValues | None) -> None:
        """Set the raw control values (their meaning depends on the mode, NOTES §5)."""
        self._control = control
        self._rebuild_frames()

    def _rebuild_frames(self) -> None:
        request = SubFrameRequest.STANDARD
        self._main_invalid = self._aircraft.main_frame(None, request)
        self._main_valid = (
            self._aircraft.main_frame(self._control, request)
            if self._control is not None
            else self._main_invalid
        )
        self._sub = self._aircraft.sub_frame()

    # -- telemetry -----------------------------------------------------------------------
    @property
    def status(self) -> GcuMainFrame:
        """The latest main frame (mode, pod status, angles, rates)."""
        if self._status is None:
            raise GcuError("no reply from the GCU yet")
        return self._status

    @property
    def info(self) -> GcuSubFrame:
        """The latest sub frame (pod model, versions, zoom, ranging, flags)."""
        if self._info is None:
            raise GcuError("no reply with a sub frame from the GCU yet")
        return self._info

    @property
    def pod_model(self) -> PodModel | None:
        """The pod model once a sub frame arrived, else ``None``."""
        return None if self._info is None else self._info.pod_model

    @property
    def link(self) -> LinkHealth:
        """A snapshot of the link's health."""
        h, now, d = self._health, self._clock(), self._deframer.stats
        return LinkHealth(
            up=h.up,
            reply_rate=h.reply_rate(now),
            last_reply_age=None if h.last_reply is None else now - h.last_reply,
            packets_sent=h.packets_sent,
            packets_received=h.packets_received,
            send_errors=h.send_errors,
            crc_errors=d.crc_errors,
            length_errors=d.length_errors,
            bytes_discarded=d.bytes_discarded,
            decode_errors=h.decode_errors,
            unmatched_feedback=self._scheduler.stats.unmatched_feedback,
            lost_count=h.lost_count,
            restored_count=h.restored_count,
        )

    @property
    def scheduler(self) -> CommandScheduler:
        """The command scheduler (for its statistics)."""
        return self._scheduler

    async def telemetry(self, maxsize: int = 1) -> AsyncGenerator[TelemetrySample, None]:
        """Iterate over replies as they arrive. The queue holds ``maxsize`` samples; when
        the consumer falls behind the oldest are dropped (counted in
        ``telemetry_dropped``). Ends when the client closes."""
        sub = TelemetrySubscription(maxsize)
        self._subscriptions.add(sub)
        if self._closing or not self._open:
            sub.close()
        try:
            while (sample := await sub.get()) is not None:
                yield sample
        finally:
            self._subscriptions.discard(sub)

    def on_telemetry(self, callback: TelemetryCallback) -> Callable[[], None]:
        """Call ``callback(sample)`` for every reply; returns a function that unsubscribes."""
        self._telemetry_callbacks.append(callback)
        return lambda: self._telemetry_callbacks.remove(callback)

    def on_link_change(self, callback: LinkCallback) -> Callable[[], None]:
        """Call ``callback(LinkEvent)`` when the link is lost or restored."""
        self._link_callbacks.append(callback)
        return lambda: self._link_callbacks.remove(callback)

    # -- commands ------------------------------------------------------------------------
    async def execute(self, command: Command, *, timeout: float | None = None) -> Feedback:
        """Send ``command`` and wait for its feedback.

        Returns the success feedback. Raises :class:`CommandFailed` on a failure status,
        :class:`CommandTimeout` (a ``TimeoutError``) after ``timeout`` seconds (default
        ``command_timeout``), :class:`LinkLost` (a ``ConnectionError``) at once if the link is
        or goes down, :class:`UnsupportedCommandError` with ``check_support``.
        """
        if timeout is None:
            timeout = self.command_timeout
        elif not timeout > 0:
            raise ValueError(f"timeout: {timeout!r} must be > 0 seconds")
        if not isinstance(command, Command):
            raise TypeError(f"command: expected a Command, got {type(command).__name__}")
        self._check_link()
        self._check_support(command)
        loop = asyncio.get_running_loop()
        ticket = Ticket(command, deadline=self._clock() + timeout)
        future: asyncio.Future[Feedback] = loop.create_future()
        self._futures[ticket] = future
        self._timers[ticket] = loop.call_later(timeout, self._on_timeout, ticket, timeout)
        idle = self._scheduler.in_flight is None
        self._scheduler.submit(ticket)
        if idle:
            self._send_packet()  # goes out at once, not at the next tick
        try:
            return await future
        except asyncio.CancelledError:
            self._scheduler.cancel(ticket)
            raise
        finally:
            self._futures.pop(ticket, None)
            timer = self._timers.pop(ticket, None)
            if timer is not None:
                timer.cancel()

    def _check_link(self) -> None:
        if not self._open or self._closing:
            raise LinkLost("client is not open")
        if not self._health.up:
            raise LinkLost(f"{self.transport.url}: link is down")

    def _check_support(self, command: Command) -> None:
        model = self.pod_model
        if not self.check_support or model is None or model not in POD_NAMES:
            return
        if not supports(model, command_code(command)):
            raise UnsupportedCommandError(opcode_name(command_code(command)), pod_name(model))

    def _on_timeout(self, ticket: Ticket, timeout: float) -> None:
        self._timers.pop(ticket, None)
        if self._scheduler.time_out(ticket):
            name = opcode_name(ticket.opcode)
            progress = " (last status: in progress)" if ticket.progress else ""
            self._resolve(
                ticket,
                error=CommandTimeout(f"{name}: no feedback within {timeout:g} s{progress}"),
            )
            self._send_packet()  # the next queued command goes out now

    def _resolve(
        self, ticket: Ticket, *, result: Feedback | None = None, error: BaseException | None = None
    ) -> None:
        future = self._futures.get(ticket)
        if future is None or future.done():
            return
        if error is not None:
            future.set_exception(error)
        else:
            assert result is not None
            future.set_result(result)

    def _fail_all(self, error: LinkLost) -> None:
        for ticket in self._scheduler.drain():
            self._resolve(ticket, error=LinkLost(str(error)))

    # -- packets out ---------------------------------------------------------------------
    _last_encoded: tuple[object, object, object, int, bytes] = (None, None, None, -1, b"")

    def _encode(self, main: HostMainFrame, command: Command) -> bytes:
        """The packet's bytes; the previous packet's are reused when it had the very same
        (immutable) parts, as every heartbeat of an idle session has."""
        sub, version, last = self._sub, self.version, self._last_encoded
        if last[0] is main and last[1] is sub and last[2] is command and last[3] == version:
            return last[4]
        data = HostPacket(main, sub, command, version).encode()
        self._last_encoded = (main, sub, command, version, data)
        return data

    def _send_packet(self) -> None:
        if not self._open or self._closing or not self.transport.connected:
            return
        now = self._clock()
        hold = self._scheduler.hold_until
        if now < hold:  # reordering guard: send this packet a little later
            if self._deferred is None:
                loop = asyncio.get_running_loop()
                self._deferred = loop.call_later(hold - now, self._send_deferred)
            return
        command = self._scheduler.next_command(now)
        main = self._main_invalid if self._scheduler.control_blocked else self._main_valid
        data = self._encode(main, command)
        try:
            self.transport.send(data)
        except (LinkLost, OSError) as exc:
            self._health.send_errors += 1
            log.debug("send failed: %s", exc)
            return
        self._health.packets_sent += 1

    def _send_deferred(self) -> None:
        self._deferred = None
        self._send_packet()

    async def _heartbeat(self) -> None:
        """Send a packet every period on monotonic deadlines; never stops on errors."""
        period = 1.0 / self.rate_hz
        clock = self._clock
        deadline = clock()
        while True:
            now = clock()
            try:
                self._tick(now)
            except Exception:  # the heartbeat must never stop
                log.exception("heartbeat tick failed")
            self.heartbeat_ticks += 1
            deadline += period
            now = clock()
            if deadline < now:  # fell behind: skip the missed slots, don't burst
                self.heartbeat_late += 1
                deadline = now
            await asyncio.sleep(deadline - now)

    def _tick(self, now: float) -> None:
        if self._health.silent(now):
            self._link_down(f"no reply for {self._health.silence_timeout:g} s")
        self._send_packet()

    # -- packets in ----------------------------------------------------------------------
    def _on_data(self, data: bytes) -> None:
        for raw in self._deframer.feed(data):
            try:
                packet = decode_gcu_packet(raw)
            except RemoteProtocolError as exc:
                self._health.decode_errors += 1
                log.debug("undecodable reply: %s", exc)
                continue
            self._on_packet(packet.main, packet.sub, packet.feedback)

    def _on_packet(self, main: GcuMainFrame, sub: object, feedback: Feedback) -> None:
        now = self._clock()
        self._status = main
        if isinstance(sub, GcuSubFrame):
            self._info = sub
        if self._health.on_reply(now):
            if self._health.lost_count:
                self._health.restored_count += 1
                self._emit_link(LinkEvent(LinkEventKind.RESTORED, "replies resumed"))
            if self._first_reply is not None:
                self._first_reply.set()
        scheduler = self._scheduler
        unmatched = scheduler.stats.unmatched_feedback
        ticket = scheduler.on_feedback(feedback, now)
        if ticket is not None:
            if feedback.result is ExecutionStatus.SUCCESS:
                self._resolve(ticket, result=feedback)
            else:
                cams = int(feedback.failed_cameras)
                error = CommandFailed(feedback.opcode, feedback.status, cams)
                self._resolve(ticket, error=error)
        elif scheduler.stats.unmatched_feedback != unmatched:
            log.debug("unmatched feedback %s (in flight: %s)", feedback, scheduler.in_flight)
        if (
            (ticket is not None or feedback.opcode == 0)
            and scheduler.in_flight is None
            and scheduler.pending
            and not scheduler.waiting_for_null_ack
        ):
            self._send_packet()  # the next command goes out at once, not at the next tick
        if not self._subscriptions and not self._telemetry_callbacks:
            return
        sample = TelemetrySample(main, self._info, feedback, now)
        for sub_queue in self._subscriptions:
            before = sub_queue.dropped
            sub_queue.put(sample)
            self.telemetry_dropped += sub_queue.dropped - before
        for callback in list(self._telemetry_callbacks):
            try:
                callback(sample)
            except Exception:
                log.exception("telemetry callback failed")

    # -- link ----------------------------------------------------------------------------
    def _on_link_event(self, event: LinkEvent) -> None:
        if event.kind is LinkEventKind.LOST:
            self._deframer.reset()
            self._link_down(event.detail or "transport lost")
        elif event.kind is LinkEventKind.PEER:
            self._emit_link(event)

    def _link_down(self, reason: str) -> None:
        if not self._health.up:
            self._fail_all(LinkLost(f"{self.transport.url}: {reason}"))
            return
        self._health.up = False
        self._health.lost_count += 1
        log.warning("link to %s lost: %s", self.transport.url, reason)
        self._fail_all(LinkLost(f"{self.transport.url}: {reason}"))
        self._emit_link(LinkEvent(LinkEventKind.LOST, reason))

    def _emit_link(self, event: LinkEvent) -> None:
        for callback in list(self._link_callbacks):
            try:
                callback(event)
            except Exception:
                log.exception("link callback failed")
