"""The asyncio driver of a :class:`~gcu_async.session.Session`: timers, futures, transport.

``GcuClient`` owns one transport and one sans-I/O session (composition). It does I/O only:
it hands received bytes and transport news to the session, sends the packet the session
asks for at the time it asks, and turns the session's events into resolved futures,
telemetry and link callbacks. Every rule (pacing, separation, matching, timeouts, control
values, link health) lives in the session (docs/client.md, "The session contract").
"""

from __future__ import annotations

import asyncio
import contextlib
import enum
import inspect
import logging
import math
import os
import random
import sys
import time
import warnings
from collections.abc import AsyncGenerator, Callable, Generator
from datetime import datetime
from typing import Any, Final

from gcu_async._checks import (
    check_bool,
    check_instance,
    check_int,
    check_positive,
    check_real,
    type_error,
)
from gcu_async._lifecycle import OpenClose
from gcu_async.capture.writer import PacketCapture
from gcu_async.client.api import CommandMethods, check_sequence
from gcu_async.client.telemetry import TelemetrySubscription
from gcu_async.client.waiting import WaitingMethods
from gcu_async.client.wirelog import WIRE_LOG, log_packet
from gcu_async.errors import (
    ClientStateError,
    CommandFailed,
    CommandLinkLost,
    GcuError,
    LikelyCause,
    LinkLost,
    Outcome,
    UnsupportedCommandError,
)
from gcu_async.protocol.aircraft import AircraftState
from gcu_async.protocol.catalogue import NEEDS_INS, YAW_INPUT_RANGE
from gcu_async.protocol.commands import ZOOM_RATIO_MAX, Command, ZoomTo, command_code
from gcu_async.protocol.enums import PodModel, opcode_name
from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.gcu_frames import GcuMainFrame, GcuSubFrame
from gcu_async.protocol.host_frames import MS_PER_WEEK, ControlValues
from gcu_async.protocol.packets import DEFAULT_VERSION
from gcu_async.protocol.pods import POD_NAMES, pod_name, supports
from gcu_async.protocol.units import (
    Attitude,
    GeoPosition,
    NorthEastUp,
    wrap_degrees_360,
)
from gcu_async.session import (
    ControlKind,
    LinkDown,
    LinkHealth,
    LinkUp,
    ResetLink,
    Session,
    SessionState,
    TelemetrySample,
    Ticket,
    TicketDone,
    TicketState,
)
from gcu_async.session.session import RATE_MAX_HZ, RATE_MIN_HZ
from gcu_async.transport.backoff import Backoff
from gcu_async.transport.base import LinkEvent, LinkEventKind, Transport
from gcu_async.transport.tap import with_capture

log = logging.getLogger("gcu_async.client")
_RESOLUTION = time.get_clock_info("monotonic").resolution

DEFAULT_REORDER_GUARD = 0.015
"""Seconds; the reordering guard on links that may reorder (UDP)."""
RATE_ADVISED = (30.0, 50.0)


class Keep(enum.Enum):
    """The type of :data:`KEEP`: "not given, keep the current value" (a default distinct
    from ``None``, which clears a value)."""

    KEEP = "KEEP"

    def __repr__(self) -> str:
        return "KEEP"


KEEP: Final = Keep.KEEP
"""Default of :meth:`GcuClient.update_aircraft`'s parameters: the field keeps its value."""

LinkCallback = Callable[[LinkEvent], None]
TelemetryCallback = Callable[[TelemetrySample], None]


OPEN_BACKOFF = Backoff(base=0.25, factor=2.0, cap=5.0, max_attempts=None, max_total=1e9)
"""Delays between the attempts of :meth:`GcuClient.open` with ``open_timeout``."""


class ClientState(enum.Enum):
    """The client's lifecycle (reusable, not reentrant)."""

    CLOSED = "closed"
    OPENING = "opening"
    OPEN = "open"
    CLOSING = "closing"


class GcuClient(CommandMethods, WaitingMethods, OpenClose):
    """An asyncio session with one GCU.

    ``async with GcuClient(transport) as gcu:`` opens the transport, starts the heartbeat,
    waits up to ``connect_timeout`` for the first reply and, on exit, ends pending commands,
    stops the heartbeat and closes the transport. A closed client can be opened again;
    opening one that is open (or opening) raises :class:`ClientStateError` (a
    ``RuntimeError``) naming its state. ``gcu = await connect(url)`` opens it too (then close
    it yourself: ``await gcu.close()``).

    Args:
        transport: any :class:`~gcu_async.transport.Transport` (not yet opened).
        rate_hz: heartbeat rate, [2, 200] packets per second; the protocol advises 30–50 Hz
            (a warning outside). Host packets never exceed ``rate_hz`` + 1 in any second.
        command_timeout: default seconds a command may take on the wire, from its first
            packet to its feedback (:class:`CommandTimeout`, outcome ``UNKNOWN``).
        queue_timeout: default seconds a command may wait before its first packet
            (:class:`CommandTimeout`, outcome ``NOT_SENT``).
        connect_timeout: seconds to wait for the first reply when opening.
        open_timeout: keep retrying :meth:`open` (backoff 0.25–5 s, full jitter) until this
            many seconds have passed, e.g. to start before the GCU is powered; each failed
            attempt is a ``RETRYING`` link event. ``None`` (default): one attempt.
        silence_timeout: seconds without a reply after which the link counts as lost (more
            than the heartbeat period).
        check_support: refuse commands the pod model does not support (Appendix 8) once the
            model is known, raising :class:`UnsupportedCommandError` without sending.
        reorder_guard: seconds between the last packet of one opcode and the first of the
            next; must exceed how much more the link may delay one packet than another.
            Default: 0 on ordered transports (TCP, serial), 15 ms otherwise (UDP).
        aircraft_timeout: seconds an aircraft part given with :meth:`update_aircraft` or
            :meth:`set_aircraft` stays current, (0, 10]; after it the packets stop claiming
            it (INS-valid cleared, no sub frame) until the next update (docs/client.md,
            "Aircraft data: what the packets claim").
        version: protocol version byte to send (2; some field devices expect 1).
        clock: monotonic time source (seconds).
        capture: write every packet exchanged to this pcapng file (a path or a
            :class:`~gcu_async.capture.PacketCapture`; needs the ``capture`` extra).
        max_zoom: camera 1's largest zoom ratio (the pod's datasheet: the protocol reports
            no limit). Given, :meth:`zoom_to` and :meth:`reach_zoom` refuse a larger ratio
            before sending; ``None`` (default): only the field's range, 1–3276.8.
    """

    def __init__(
        self,
        transport: Transport,
        *,
        rate_hz: float = 50.0,
        command_timeout: float = 2.0,
        queue_timeout: float = 30.0,
        connect_timeout: float = 3.0,
        open_timeout: float | None = None,
        silence_timeout: float = 1.0,
        check_support: bool = False,
        reorder_guard: float | None = None,
        aircraft_timeout: float = 1.0,
        version: int = DEFAULT_VERSION,
        clock: Callable[[], float] = time.monotonic,
        capture: PacketCapture | str | os.PathLike[str] | None = None,
        max_zoom: float | None = None,
    ) -> None:
        if not isinstance(transport, Transport):
            raise type_error("transport", "a Transport", transport)
        transport = with_capture(transport, capture)
        rate = check_real("rate_hz", rate_hz, RATE_MIN_HZ, RATE_MAX_HZ, "Hz")
        if reorder_guard is None:
            reorder_guard = 0.0 if transport.ordered else DEFAULT_REORDER_GUARD
        if not callable(clock):
            raise type_error("clock", "a callable returning seconds", clock)
        reading = clock()
        if isinstance(reading, bool) or not isinstance(reading, (int, float)):
            raise type_error("clock", f"a callable returning seconds (it returned {reading!r})",
                             clock)  # fmt: skip
        if not math.isfinite(reading):
            raise ValueError(f"clock: {clock!r} returned {reading!r}, not finite seconds")
        self.transport = transport
        self.session = Session(
            rate_hz=rate_hz, reorder_guard=reorder_guard, command_timeout=command_timeout,
            queue_timeout=queue_timeout, silence_timeout=silence_timeout,
            aircraft_timeout=aircraft_timeout, version=check_int("version", version, 1, 2),
            name=transport.url,
        )  # fmt: skip
        self.connect_timeout = check_positive("connect_timeout", connect_timeout)
        self.open_timeout = (None if open_timeout is None
                             else check_positive("open_timeout", open_timeout))  # fmt: skip
        self._open_abort: asyncio.Event | None = None
        self._between_attempts = False
        self._rng = random.Random()
        self.check_support = check_bool("check_support", check_support)
        self._max_zoom = (None if max_zoom is None
                          else check_real("max_zoom", max_zoom, 1.0, ZOOM_RATIO_MAX, "x"))
        if not RATE_ADVISED[0] <= rate <= RATE_ADVISED[1]:
            warnings.warn(f"rate_hz={rate:g}: the protocol advises 30-50 Hz host packets",
                          stacklevel=_caller_stacklevel())  # fmt: skip
        self._clock = clock
        self._state = ClientState.CLOSED
        self._timer: asyncio.TimerHandle | None = None
        self._timer_at = math.inf
        self._futures: dict[Ticket, asyncio.Future[Feedback | None]] = {}
        self._needs_ins: dict[Ticket, bool] = {}
        """Pending commands that need INS data: True once a packet went out while one was
        pending with INS invalid."""
        self._subscriptions: set[TelemetrySubscription] = set()
        self._telemetry_callbacks: list[TelemetryCallback] = []
        self._link_callbacks: list[LinkCallback] = []
        self._first_reply: asyncio.Future[None] | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._closed_event: asyncio.Event | None = None
        self._datagram = transport.datagram
        self._rx_bound: float | None = None
        """Replies delivered from now on arrived after this time (links that reorder); None:
        the transport cannot tell (see :meth:`_arrival_bound`)."""
        self._bound_from_loop = False
        self._timer_when = 0.0
        """Event-loop time the pending timer is due."""
        self.telemetry_dropped = 0
        self.session.telemetry = False

    # -- configuration (read-only views of the session's) ----------------------------------
    @property
    def rate_hz(self) -> float:
        return self.session.rate_hz

    @property
    def reorder_guard(self) -> float:
        return self.session.reorder_guard

    @property
    def command_timeout(self) -> float:
        return self.session.command_timeout

    @property
    def queue_timeout(self) -> float:
        return self.session.queue_timeout

    @property
    def version(self) -> int:
        return self.session.version

    @property
    def state(self) -> ClientState:
        return self._state

    @property
    def max_zoom(self) -> float | None:
        """Camera 1's largest zoom ratio as given (``max_zoom=``), ``None`` if not known."""
        return self._max_zoom

    def __await__(self) -> Generator[Any, None, GcuClient]:
        """``gcu = await connect(url)``: open the client and return it (close it yourself;
        ``async with connect(url) as gcu:`` does both)."""
        yield from self.open().__await__()
        return self

    # -- lifecycle -------------------------------------------------------------------------
    async def open(self) -> None:
        """Open the transport, start the heartbeat, wait for the first reply.

        Raises :class:`LinkLost` if the transport cannot open or no reply comes within
        ``connect_timeout`` (everything is closed again), ``RuntimeError`` if the client is
        not closed. With ``open_timeout``, failed attempts are retried with backoff until
        that many seconds have passed (docs/client.md, "Lifecycle"); :meth:`close` stops
        the retries (``LinkLost``)."""
        if self._state is not ClientState.CLOSED:
            raise ClientStateError(
                f"GcuClient is {self._state.value}: a client is reusable but not reentrant "
                "(close it before opening it again; `async with` does both)",
                state=self._state.value,
            )
        if self.open_timeout is None:
            await self._open_once()
            return
        loop = asyncio.get_running_loop()
        deadline = loop.time() + self.open_timeout
        self._open_abort = abort = asyncio.Event()
        attempts = 0
        try:
            while True:
                try:
                    await self._open_once()
                    return
                except LinkLost as exc:
                    attempts += 1
                    delay = OPEN_BACKOFF.delay(attempts - 1, self._rng)
                    if abort.is_set():
                        raise LinkLost(f"{self.transport.url}: closed while opening") from exc
                    delay = min(delay, deadline - loop.time())  # the last try at the end
                    if delay <= 0:
                        raise LinkLost(
                            f"{self.transport.url}: no GCU within open_timeout "
                            f"{self.open_timeout:g} s ({attempts} attempts; last: {exc})"
                        ) from exc
                    log.info("%s: attempt %d failed (%s); next in %.2f s",
                             self.transport.url, attempts, exc, delay)  # fmt: skip
                    self._emit_link(LinkEvent(
                        LinkEventKind.RETRYING,
                        f"attempt {attempts} failed: {exc}; next in {delay:.2f} s"))  # fmt: skip
                    self._state = ClientState.OPENING  # not reentrant while it waits
                    self._between_attempts = True
                    try:
                        with contextlib.suppress(asyncio.TimeoutError):
                            await asyncio.wait_for(abort.wait(), delay)
                    finally:
                        self._between_attempts = False
                        self._state = ClientState.CLOSED
                    if abort.is_set():
                        raise LinkLost(f"{self.transport.url}: closed while opening") from exc
        finally:
            self._open_abort = None

    async def _open_once(self) -> None:
        self._state = ClientState.OPENING
        self._loop = loop = asyncio.get_running_loop()
        self._closed_event = asyncio.Event()
        self._first_reply = loop.create_future()
        self.transport.set_handlers(self._on_data, self._on_link_event)
        log.info("opening %s", self.transport.url)
        try:
            await self.transport.open()
        except BaseException:
            self._state = ClientState.CLOSED
            raise
        self.session.open(self._clock())
        self._arrival_bound(loop)
        self._pump()
        try:
            await asyncio.wait_for(asyncio.shield(self._first_reply), self.connect_timeout)
        except asyncio.TimeoutError:
            await self._shutdown("no reply")
            raise LinkLost(
                f"{self.transport.url}: no reply from the GCU within {self.connect_timeout:g} s"
            ) from None
        except BaseException:
            await self._shutdown("open interrupted")
            raise
        self._state = ClientState.OPEN
        log.info("link to %s up", self.transport.url)

    async def close(self) -> None:
        """End pending commands (:class:`CommandLinkLost`), stop the heartbeat, end the
        telemetry iterators and close the transport. Idempotent."""
        if self._open_abort is not None:  # open() is retrying: stop it
            self._open_abort.set()
        if self._state in (ClientState.CLOSED, ClientState.CLOSING):
            return
        if self._between_attempts:
            return  # open() waits between attempts: nothing is open
        await self._shutdown("client closed")

    async def _shutdown(self, reason: str) -> None:
        self._state = ClientState.CLOSING
        try:
            self.session.close(self._clock(), reason)
            self._dispatch()
            if self._timer is not None:
                self._timer.cancel()
                self._timer, self._timer_at = None, math.inf
            for sub in self._subscriptions:
                sub.close()
            await self.transport.close()
        finally:
            self._state = ClientState.CLOSED
            log.info("closed %s (%s)", self.transport.url, reason)
            if self._closed_event is not None:
                self._closed_event.set()

    # -- aircraft state and control values -------------------------------------------------
    @property
    def aircraft(self) -> AircraftState:
        """The aircraft state as last given (what goes out: :attr:`ins_valid`)."""
        return self.session.aircraft

    @property
    def aircraft_timeout(self) -> float:
        return self.session.aircraft_timeout

    @property
    def ins_valid(self) -> bool:
        """True if the next packet sets the INS-valid bit: attitude, acceleration and
        velocity all given, each within ``aircraft_timeout`` (docs/client.md, "Aircraft
        data: what the packets claim")."""
        return self.session.ins_valid(self._clock())

    def update_aircraft(
        self,
        *,
        attitude: Attitude | tuple[float, float, float] | Keep | None = KEEP,
        acceleration: NorthEastUp | tuple[float, float, float] | Keep | None = KEEP,
        velocity: NorthEastUp | tuple[float, float, float] | Keep | None = KEEP,
        position: GeoPosition | tuple[float, float, float] | Keep | None = KEEP,
        relative_altitude: float | Keep = KEEP,
        satellites: int | Keep = KEEP,
        gnss_time: datetime | None = None,
        gnss_week: int | Keep = KEEP,
        gnss_ms: int | Keep = KEEP,
    ) -> AircraftState:
        """Update the aircraft state carried by the heartbeat; fields not given (default
        :data:`KEEP`) keep their value, ``None`` clears one. A triple is a NamedTuple, a
        tuple or a list of three. Units: degrees (attitude; yaw in [-180, 360), MAVLink's
        ±180° or compass 0–360°, sent as its 0–360° equivalent), m/s² north/east/up without
        gravity, m/s north/east/up, (latitude °,
        longitude °, altitude m MSL), metres. ``gnss_time`` (aware UTC) sets week + ms with
        leap seconds applied.

        The parts given count as measured now: INS-valid goes out only while attitude,
        acceleration and velocity have all been given within ``aircraft_timeout``, the sub
        frame only while the position has; GNSS time advances with the clock between
        updates (docs/client.md, "Aircraft data: what the packets claim").

        Raises ``TypeError`` or :class:`FieldRangeError` (nothing changes) for a bad value.
        """
        changes: dict[str, Any] = {}
        for name, value in (("attitude", attitude), ("acceleration", acceleration),
                            ("velocity", velocity), ("position", position)):  # fmt: skip
            if value is not KEEP:
                changes[name] = None if value is None else _triple(name, value)
        if relative_altitude is not KEEP:
            changes["relative_altitude"] = check_real(
                "relative_altitude", relative_altitude, *S32_MM, "m")
        for name, scalar, high in (("satellites", satellites, 255),
                                   ("gnss_week", gnss_week, GNSS_WEEK_MAX),
                                   ("gnss_ms", gnss_ms, MS_PER_WEEK - 1)):  # fmt: skip
            if scalar is not KEEP:
                changes[name] = check_int(name, scalar, 0, high)
        if gnss_time is not None:
            check_instance("gnss_time", gnss_time, datetime)
            if gnss_week is not KEEP or gnss_ms is not KEEP:
                raise ValueError("gnss_time: give either gnss_time or gnss_week/gnss_ms, "
                                 "not both")  # fmt: skip
            week, ms = AircraftState.gnss_from_utc(gnss_time)
            if week > GNSS_WEEK_MAX:
                raise ValueError(f"gnss_time: {gnss_time.isoformat()} is after the last GNSS "
                                 f"week the packet carries ({GNSS_WEEK_MAX})")  # fmt: skip
            changes["gnss_week"], changes["gnss_ms"] = week, ms
        return self.session.update_aircraft(changes, self._clock())

    def set_aircraft(self, state: AircraftState) -> None:
        """Replace the whole aircraft state (an :class:`AircraftState`); every part it gives
        counts as measured now (see :meth:`update_aircraft`)."""
        self.session.set_aircraft(state, self._clock())

    @property
    def control(self) -> ControlValues | None:
        """The control values given for the current mode (``None``: none, sent invalid).
        Whether they go out valid right now: :attr:`control_valid`."""
        return self.session.control

    @property
    def control_valid(self) -> bool:
        """True if the next packet carries the control values valid (docs/client.md,
        "Control values")."""
        return self.session.control_valid(self._clock()) is not None

    def set_control(self, control: ControlValues | None) -> None:
        """Raw control values for the current mode (their meaning depends on the mode,
        docs/protocol-notes.md §5 "Control values change meaning with the mode"); ``None`` sends
        them invalid (rates 0, angles held). Raises ``ValueError`` (nothing changes) when no mode
        takes values or a value is out of range."""
        self.session.set_control(control)

    def _set_control(self, control: ControlValues | None, kind: ControlKind) -> None:
        self.session.set_control(control, kind)

    # -- telemetry -------------------------------------------------------------------------
    @property
    def status(self) -> GcuMainFrame:
        """The latest main frame (mode, pod status, angles, rates)."""
        status = self.session.status
        if status is None:
            raise GcuError("no reply from the GCU yet")
        return status

    @property
    def info(self) -> GcuSubFrame:
        """The latest sub frame (pod model, versions, zoom, ranging, flags)."""
        info = self.session.info
        if info is None:
            raise GcuError("no reply with a sub frame from the GCU yet")
        return info

    @property
    def _info(self) -> GcuSubFrame | None:
        return self.session.info

    @property
    def pod_model(self) -> PodModel | None:
        """The pod model once a sub frame arrived, else ``None``."""
        info = self.session.info
        return None if info is None else info.pod_model

    @property
    def recording(self) -> bool | None:
        """Whether the camera records, as far as the client can tell (``None``: not known
        yet)."""
        return self.session.recording(self._clock())

    @property
    def link(self) -> LinkHealth:
        """A snapshot of the link's health."""
        return self.session.link_health(self._clock())

    async def telemetry(self, maxsize: int = 1) -> AsyncGenerator[TelemetrySample, None]:
        """Iterate over replies as they arrive. The queue holds ``maxsize`` samples; when
        the consumer falls behind the oldest are dropped (counted in
        ``telemetry_dropped``). Ends when the client closes."""
        sub = TelemetrySubscription(check_int("maxsize", maxsize, 1, sys.maxsize))
        self._subscriptions.add(sub)
        self._consumers_changed()
        if self._state in (ClientState.CLOSED, ClientState.CLOSING):
            sub.close()
        try:
            while (sample := await sub.get()) is not None:
                yield sample
        finally:
            self._subscriptions.discard(sub)
            self._consumers_changed()

    def on_telemetry(self, callback: TelemetryCallback) -> Callable[[], None]:
        """Call ``callback(sample)`` for every reply; returns a function that unsubscribes."""
        _check_callback(callback)
        self._telemetry_callbacks.append(callback)
        self._consumers_changed()
        return _unsubscriber(self._telemetry_callbacks, callback, self._consumers_changed)

    def _current_attitude(self) -> Attitude:
        status = self.session.status
        return status.attitude if status is not None else Attitude(0.0, 0.0, 0.0)

    def _latest(self) -> TelemetrySample | None:
        return self.session.latest

    def _link_up(self) -> bool:
        return self.session.state is SessionState.UP

    def _closed(self) -> asyncio.Event | None:
        return None if self._state is ClientState.CLOSED else self._closed_event

    def on_link_change(self, callback: LinkCallback) -> Callable[[], None]:
        """Call ``callback(LinkEvent)`` when the link is lost or restored, when the OS
        reports an error on it (:attr:`~gcu_async.transport.LinkEventKind.ERROR`: once per
        episode), when a new peer answers, and when :meth:`open` retries."""
        _check_callback(callback)
        self._link_callbacks.append(callback)
        return _unsubscriber(self._link_callbacks, callback, None)

    def _consumers_changed(self) -> None:
        """Telemetry samples are built only while someone consumes them."""
        self.session.telemetry = bool(self._subscriptions or self._telemetry_callbacks)

    # -- commands --------------------------------------------------------------------------
    async def execute(
        self, command: Command, *, timeout: float | None = None,
        queue_timeout: float | None = None,
    ) -> Feedback:  # fmt: skip
        """Send ``command`` and wait for its feedback.

        Returns the success feedback. Raises :class:`CommandFailed` on a failure status;
        :class:`CommandTimeout` (a ``TimeoutError``) after ``timeout`` seconds on the wire
        (default ``command_timeout``; outcome ``UNKNOWN``) or ``queue_timeout`` seconds
        before its first packet (outcome ``NOT_SENT``); :class:`CommandLinkLost` (a
        ``ConnectionError``) at once if the link is or goes down; and
        :class:`UnsupportedCommandError` with ``check_support``. Cancelling the awaiting task
        withdraws the command (it may have executed if it was already sent).
        """
        result = await self._submit(command, timeout=timeout, queue_timeout=queue_timeout)
        assert result is not None  # only state-checked record commands are ever skipped
        return result

    async def _submit(
        self,
        command: Command,
        *,
        timeout: float | None = None,
        queue_timeout: float | None = None,
        control: ControlValues | None = None,
        recording_target: bool | None = None,
    ) -> Feedback | None:
        check_instance("command", command, Command, "a Command")
        if self._state is not ClientState.OPEN:
            opcode = command_code(command)
            hint = ("not opened: use `async with connect(url) as gcu:` (or `await "
                    "gcu.open()`) first" if self._closed_event is None
                    else f"client is {self._state.value}")  # fmt: skip
            raise CommandLinkLost(f"{opcode_name(opcode)}: {hint}; not sent",
                                  outcome=Outcome.NOT_SENT, opcode=opcode,
                                  command=command)  # fmt: skip
        self._check_support(command)
        loop = asyncio.get_running_loop()
        ticket = self.session.submit(
            command, self._clock(), timeout=timeout, queue_timeout=queue_timeout,
            control=control, recording_target=recording_target,
        )  # fmt: skip
        future: asyncio.Future[Feedback | None] = loop.create_future()
        self._futures[ticket] = future
        if ticket.opcode in NEEDS_INS:
            self._needs_ins[ticket] = False
        self._pump()  # goes out now if the rate allows: the heartbeat's phase moves
        try:
            return await future
        except asyncio.CancelledError:
            self._futures.pop(ticket, None)
            self._needs_ins.pop(ticket, None)
            if not ticket.done:
                self.session.cancel(ticket, self._clock())
                self._dispatch()
                self._schedule()
            raise

    def _check_support(self, command: Command) -> None:
        model = self.pod_model
        if not self.check_support or model is None or model not in POD_NAMES:
            return
        if not supports(model, command_code(command)):
            raise UnsupportedCommandError(opcode_name(command_code(command)), pod_name(model))

    # -- the pump: the only place packets are sent -----------------------------------------
    def _arrival_bound(self, loop: asyncio.AbstractEventLoop) -> None:
        """Choose how replies get a lower bound on their arrival (links that reorder; docs/
        client.md, "The session contract", A4). Best, for free: on a draining transport whose
        loop keeps this client's time (the default clock), a reply not delivered by the time
        a timer runs arrived after that loop iteration's poll returned, which was no earlier
        than the timer was due. Else: read the link empty before each send
        (``read_pending``). Else none: the session assumes a responsive loop."""
        self._rx_bound = None
        self._bound_from_loop = False
        transport = self.transport
        if transport.ordered:
            return
        now = self._clock()
        if (transport.drains and self._clock is time.monotonic
                and type(loop).time is asyncio.BaseEventLoop.time):  # fmt: skip
            self._bound_from_loop = True
            self._rx_bound = now
        elif transport.read_pending():
            self._rx_bound = now
        else:
            log.info("%s cannot be read on demand: reply timing assumes a responsive event "
                     "loop (docs/client.md, \"The session contract\")", transport.url)

    def _on_timer(self) -> None:
        if self._bound_from_loop and not self.transport.backlog:
            # this iteration's poll returned at >= when - resolution (asyncio runs I/O
            # callbacks before timers): later deliveries arrived after it
            self._rx_bound = self._timer_when - _RESOLUTION
        self._timer, self._timer_at = None, math.inf
        self._pump()

    def _pump(self) -> None:
        if self._timer is not None:  # called early (a command): this run replaces the timer
            self._timer.cancel()
            self._timer, self._timer_at = None, math.inf
        session = self.session
        try:
            if self._rx_bound is not None and not self._bound_from_loop:
                now = self._clock()  # read what waits first: replies before sends
                if self.transport.read_pending():
                    self._rx_bound = now
            wire = WIRE_LOG.isEnabledFor(logging.DEBUG)  # the level may change at run time
            session.trace = self._trace if wire else None
            now = self._clock()
            data = session.poll(now)
            if data is not None and self._needs_ins and not session.ins_valid(now):
                for ticket in self._needs_ins:  # they went out with INS invalid
                    self._needs_ins[ticket] = True
            if data is not None:
                if wire:
                    log_packet(self.transport.url, True, data)
                try:
                    self.transport.send(data)
                except (LinkLost, OSError) as exc:
                    session.send_failed()
                    log.debug("send failed: %s", exc)
            self._dispatch()
        except Exception:  # the heartbeat must never stop
            log.exception("gcu_async: heartbeat step failed")
        self._schedule()

    def _schedule(self) -> None:
        if self._state is ClientState.CLOSED:
            return
        now = self._clock()
        when = self.session.next_wakeup(now)
        if when == math.inf or when >= self._timer_at:
            return
        if self._timer is not None:
            self._timer.cancel()
        loop = self._loop
        assert loop is not None
        self._timer_when = loop.time() + (when - now)
        self._timer = loop.call_at(self._timer_when, self._on_timer)
        self._timer_at = when

    # -- input from the transport ----------------------------------------------------------
    def _trace(self, packet: bytes) -> None:
        log_packet(self.transport.url, False, packet)

    def _on_data(self, data: bytes) -> None:
        self.session.receive(data, self._clock(), datagram=self._datagram,
                             arrived_after=self._rx_bound)  # fmt: skip
        self._dispatch()
        if self._timer is None:  # a reply never brings the next wake-up forward
            self._schedule()

    def _on_link_event(self, event: LinkEvent) -> None:
        if event.kind is LinkEventKind.LOST:
            self.session.connection_lost(self._clock(), event.detail or "transport lost")
            self._dispatch()
            self._schedule()
        elif event.kind is LinkEventKind.PEER:
            self._emit_link(event)
        elif event.kind is LinkEventKind.ERROR:
            log.warning("%s (the link stays open; link health decides whether it is up)",
                        event.detail)  # fmt: skip
            self._emit_link(event)

    # -- events ----------------------------------------------------------------------------
    def _dispatch(self) -> None:
        events = self.session.events()
        if not events:
            return
        for event in events:
            if isinstance(event, TelemetrySample):
                self._telemetry(event)
            elif isinstance(event, TicketDone):
                self._resolve(event.ticket)
            elif isinstance(event, LinkUp):
                first = self._first_reply
                if first is not None and not first.done():
                    first.set_result(None)
                if event.restored:
                    log.warning("link to %s restored", self.transport.url)
                    self._emit_link(LinkEvent(LinkEventKind.RESTORED, event.reason))
            elif isinstance(event, LinkDown):
                log.warning("link to %s lost: %s", self.transport.url, event.reason)
                self._emit_link(LinkEvent(LinkEventKind.LOST, event.reason))
            elif isinstance(event, ResetLink):
                reset = getattr(self.transport, "reset", None)
                if reset is not None:
                    reset(event.reason)

    def _resolve(self, ticket: Ticket) -> None:
        future = self._futures.pop(ticket, None)
        ins_invalid = self._needs_ins.pop(ticket, False)
        if future is None or future.done():
            return
        if ticket.state is TicketState.SUCCEEDED:
            future.set_result(ticket.feedback)
        elif ticket.state is TicketState.SKIPPED:
            future.set_result(None)
        else:
            assert ticket.error is not None
            if isinstance(ticket.error, CommandFailed):
                self._explain(ticket.error, ticket.command, ins_invalid)
            future.set_exception(ticket.error)

    def _explain(self, error: CommandFailed, command: Command, ins_invalid: bool) -> None:
        """Add what the client knows that explains a failure (docs/client.md, "Why a
        command failed"): the pod model's Appendix 8 row, INS sent invalid, the zoom limit."""
        opcode = command_code(command)
        name = opcode_name(opcode)
        model = self.pod_model
        if model is not None and model in POD_NAMES and not supports(model, opcode):
            error.explain(LikelyCause.NOT_SUPPORTED,
                          f"protocol Appendix 8: the {pod_name(model)} does not support "
                          f"{name}")  # fmt: skip
        elif ins_invalid:
            error.explain(LikelyCause.INS_INVALID,
                          f"{name} needs valid INS data and the host packets carried INS "
                          "invalid: give the aircraft's attitude, acceleration and velocity "
                          "with update_aircraft(), at most aircraft_timeout "
                          f"({self.aircraft_timeout:g} s) apart")  # fmt: skip
        elif (isinstance(command, ZoomTo) and command.ratio is not None
              and self._max_zoom is not None and command.ratio > self._max_zoom):  # fmt: skip
            error.explain(LikelyCause.ZOOM_LIMIT,
                          f"{command.ratio:g}x is beyond camera 1's maximum zoom "
                          f"{self._max_zoom:g}x")  # fmt: skip

    def _telemetry(self, sample: TelemetrySample) -> None:
        if not self._subscriptions and not self._telemetry_callbacks:
            return
        for sub in self._subscriptions:
            before = sub.dropped
            sub.put(sample)
            self.telemetry_dropped += sub.dropped - before
        for callback in list(self._telemetry_callbacks):
            try:
                callback(sample)
            except Exception:
                log.exception("telemetry callback failed")

    def _emit_link(self, event: LinkEvent) -> None:
        for callback in list(self._link_callbacks):
            try:
                callback(event)
            except Exception:
                log.exception("link callback failed")


S16_CENTI = (-327.68, 327.67)
"""m/s² or m/s: an S16 field in units of 0.01."""
S32_MM = (-2147483.648, 2147483.647)
"""Metres: an S32 field in millimetres."""
GNSS_WEEK_MAX = 32767
AIRCRAFT_TUPLES: dict[str, tuple[type[Any], str, tuple[tuple[float, float, bool], ...]]] = {
    "attitude": (Attitude, "deg", ((-180.0, 180.0, True), (-90.0, 90.0, False),
                                   (*YAW_INPUT_RANGE, True))),
    "acceleration": (NorthEastUp, "m/s^2", ((*S16_CENTI, False),) * 3),
    "velocity": (NorthEastUp, "m/s", ((*S16_CENTI, False),) * 3),
    "position": (GeoPosition, "deg, deg, m", ((-90.0, 90.0, False), (-180.0, 180.0, False),
                                              (*S32_MM, False))),
}  # fmt: skip
"""The aircraft fields given as triples: type, unit, (low, high, high open) per element (the
ranges of host bytes 12–29 and the sub frame; docs/protocol-notes.md §10 "Aircraft
acceleration excludes gravity")."""


def _triple(name: str, value: object) -> Any:
    """``value`` (a NamedTuple of the field's type, a plain 3-tuple or a list of three)
    checked element by element under the caller's names (``attitude.pitch``); the
    attitude's yaw goes out as its [0, 360) equivalent."""
    kind, unit, ranges = AIRCRAFT_TUPLES[name]
    elements: tuple[Any, ...] = check_sequence(name, value, kind)
    units = unit.split(", ") if ", " in unit else [unit] * 3
    fields: tuple[str, ...] = kind._fields
    checked = [check_real(f"{name}.{field}", v, low, high, u, high_open=open_)
               for field, v, (low, high, open_), u in
               zip(fields, elements, ranges, units, strict=True)]  # fmt: skip
    if kind is Attitude:
        checked[2] = wrap_degrees_360(checked[2])
    return kind(*checked)


def _caller_stacklevel() -> int:
    """The ``stacklevel`` of a warning that names the first caller outside gcu_async.client
    (the user's ``connect(…)`` or ``GcuClient(…)`` line)."""
    frame = sys._getframe(1)
    level = 1
    while frame is not None and frame.f_globals.get("__name__", "").startswith(
            "gcu_async.client"):  # fmt: skip
        frame, level = frame.f_back, level + 1  # type: ignore[assignment]
    return level


def _check_callback(callback: object) -> None:
    """A callable that takes one positional argument (the sample or the event)."""
    if not callable(callback):
        raise type_error("callback", "a callable taking one argument", callback)
    try:
        signature = inspect.signature(callback)
    except (TypeError, ValueError):  # some builtins have none: trust them
        return
    try:
        signature.bind(None)
    except TypeError:
        raise type_error("callback", f"a callable taking one argument (not {signature})",
                         callback) from None  # fmt: skip


def _unsubscriber(callbacks: list[Any], callback: Any,
                  then: Callable[[], None] | None) -> Callable[[], None]:  # fmt: skip
    """A function that removes ``callback`` once (and calls ``then``); calling it again does
    nothing."""

    def unsubscribe() -> None:
        if callback in callbacks:
            callbacks.remove(callback)
            if then is not None:
                then()

    return unsubscribe
