"""The asyncio driver of a :class:`~gcu_async.session.Session` over a transport: timers,
futures, the packet pump (the client's session + transport part).

It does I/O only: it hands received bytes and transport news to the session, sends the
packet the session asks for at the time it asks, and turns the session's events into
resolved futures, telemetry (:class:`~gcu_async.client.telemetry.Telemetry`) and link
events. Every rule (pacing, separation, matching, timeouts, control values, link health)
lives in the session (docs/client.md, "The session contract").
"""

from __future__ import annotations

import asyncio
import enum
import logging
import math
from collections.abc import Callable, Sequence

from gcu_async._checks import check_instance
from gcu_async.client.telemetry import Callbacks, Telemetry
from gcu_async.client.wirelog import WIRE_LOG, log_packet
from gcu_async.errors import (
    CommandFailed,
    CommandLinkLost,
    GcuError,
    LikelyCause,
    LinkLost,
    Outcome,
    UnsupportedCommandError,
)
from gcu_async.protocol.builder import Context, Submission
from gcu_async.protocol.catalogue import NEEDS_INS
from gcu_async.protocol.commands import Command, ZoomTo, command_code
from gcu_async.protocol.enums import PodModel, opcode_name
from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.gcu_frames import GcuMainFrame
from gcu_async.protocol.pods import POD_NAMES, pod_name, supports
from gcu_async.session import (
    Event,
    LinkDown,
    LinkUp,
    ResetLink,
    Session,
    TelemetrySample,
    Ticket,
    TicketDone,
    TicketState,
)
from gcu_async.transport.arrival import ArrivalBound, arrival_bound, loop_keeps
from gcu_async.transport.base import LinkEvent, LinkEventKind, Transport

log = logging.getLogger("gcu_async.client")


class ClientState(enum.Enum):
    """The client's lifecycle (reusable, not reentrant)."""

    CLOSED = "closed"
    OPENING = "opening"
    OPEN = "open"
    CLOSING = "closing"


ENDED = frozenset({ClientState.CLOSED, ClientState.CLOSING})
"""States in which no telemetry comes."""


class Driver:
    """One session driven over one transport on the running event loop."""

    def __init__(self, session: Session, transport: Transport, clock: Callable[[], float],
                 telemetry: Telemetry, links: Callbacks[LinkEvent], *, check_support: bool,
                 max_zoom: float | None) -> None:  # fmt: skip
        self.session = session
        self.transport = transport
        self._clock = clock
        self.telemetry = telemetry
        self.links = links
        self.check_support = check_support
        self.max_zoom = max_zoom
        self.state = ClientState.CLOSED
        self._timer: asyncio.TimerHandle | None = None
        self._timer_at = math.inf
        self._futures: dict[Ticket, asyncio.Future[Feedback | None]] = {}
        self._needs_ins: dict[Ticket, bool] = {}
        """Pending commands that need INS data: True once a packet went out while one was
        pending with INS invalid."""
        self._first_reply: asyncio.Future[None] | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self.closed_event: asyncio.Event | None = None
        """Set once the client closes (None before it was first opened)."""
        self._datagram = transport.datagram
        self._bound: ArrivalBound | None = None
        """Replies delivered from now on arrived after ``_bound.value`` (links that reorder);
        None: the link never reorders, or cannot tell (:func:`arrival_bound`)."""
        self._timer_when = 0.0
        """Event-loop time the pending timer is due."""
        self._loop_clock = False
        """The event loop's time is ``clock`` (:func:`loop_keeps`)."""

    @property
    def pod_model(self) -> PodModel | None:
        info = self.session.info
        return None if info is None else info.pod_model

    def status(self) -> GcuMainFrame:
        """The latest main frame (:class:`GcuError` before the first reply)."""
        status = self.session.status
        if status is None:
            raise GcuError("no reply from the GCU yet")
        return status

    def context(self) -> Context:
        """What the command builder needs of the GCU's latest reports."""
        session = self.session
        return Context.of(session.status, session.info, self.max_zoom)

    def closed(self) -> asyncio.Event | None:
        """Set once the client closes; None while it is not open."""
        return None if self.state is ClientState.CLOSED else self.closed_event

    # -- lifecycle -------------------------------------------------------------------------
    async def open_once(self, connect_timeout: float) -> None:
        """Open the transport, start the heartbeat, wait for the first reply (one attempt)."""
        self.state = ClientState.OPENING
        self._loop = loop = asyncio.get_running_loop()
        self.closed_event = asyncio.Event()
        self._first_reply = loop.create_future()
        self.transport.set_handlers(self._on_data, self._on_link_event)
        log.info("opening %s", self.transport.url)
        try:
            await self.transport.open()
        except BaseException:
            self.state = ClientState.CLOSED
            raise
        self.session.open(self._clock())
        self._bound = arrival_bound(self.transport, self._clock, loop)
        self._loop_clock = loop_keeps(self._clock, loop)
        self._pump()
        try:
            await asyncio.wait_for(asyncio.shield(self._first_reply), connect_timeout)
        except asyncio.TimeoutError:
            await self.shutdown("no reply")
            raise LinkLost(
                f"{self.transport.url}: no reply from the GCU within {connect_timeout:g} s"
            ) from None
        except BaseException:
            await self.shutdown("open interrupted")
            raise
        self.state = ClientState.OPEN
        log.info("link to %s up", self.transport.url)

    async def shutdown(self, reason: str) -> None:
        """End pending commands, stop the heartbeat, end the telemetry iterators, close the
        transport."""
        self.state = ClientState.CLOSING
        try:
            self.session.close(self._clock(), reason)
            self._dispatch()
            if self._timer is not None:
                self._timer.cancel()
                self._timer, self._timer_at = None, math.inf
            self.telemetry.close()
            await self.transport.close()
        finally:
            self.state = ClientState.CLOSED
            log.info("closed %s (%s)", self.transport.url, reason)
            if self.closed_event is not None:
                self.closed_event.set()

    # -- commands --------------------------------------------------------------------------
    async def run(self, submission: Submission, *, queue_timeout: float | None = None) -> Feedback:
        """:meth:`submit` a command that is never skipped: its success feedback."""
        result = await self.submit(submission, queue_timeout=queue_timeout)
        assert result is not None  # only state-checked record commands are ever skipped
        return result

    async def submit(self, submission: Submission, *,
                     queue_timeout: float | None = None) -> Feedback | None:  # fmt: skip
        """Submit a command and await its outcome (``None``: a state-checked record command
        the camera's state made unnecessary)."""
        command = submission.command
        check_instance("command", command, Command, "a Command")
        if self.state is not ClientState.OPEN:
            opcode = command_code(command)
            hint = ("not opened: use `async with connect(url) as gcu:` (or `await "
                    "gcu.open()`) first" if self.closed_event is None
                    else f"client is {self.state.value}")  # fmt: skip
            raise CommandLinkLost(f"{opcode_name(opcode)}: {hint}; not sent",
                                  outcome=Outcome.NOT_SENT, opcode=opcode,
                                  command=command)  # fmt: skip
        self._check_support(command)
        loop = asyncio.get_running_loop()
        ticket = self.session.submit(
            command, self._clock(), timeout=submission.timeout, queue_timeout=queue_timeout,
            control=submission.control, recording_target=submission.recording_target,
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
    def _on_timer(self) -> None:
        bound = self._bound
        if bound is not None:
            bound.timer_ran(self._timer_when)
        self._timer, self._timer_at = None, math.inf
        self._pump()

    def _pump(self) -> None:
        if self._timer is not None:  # called early (a command): this run replaces the timer
            self._timer.cancel()
            self._timer, self._timer_at = None, math.inf
        session = self.session
        try:
            bound = self._bound
            if bound is not None and not bound.from_loop:  # replies before sends
                bound.before_send()
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
            events = session.events()
            if events:
                self._handle(events)
        except Exception:  # the heartbeat must never stop
            log.exception("gcu_async: heartbeat step failed")
        self._schedule()

    def _schedule(self) -> None:
        if self.state is ClientState.CLOSED:
            return
        now = self._clock()
        when = self.session.next_wakeup(now)
        if when == math.inf or when >= self._timer_at:
            return
        if self._timer is not None:
            self._timer.cancel()
        loop = self._loop
        assert loop is not None
        # the loop's own clock needs no conversion (the usual case: time.monotonic)
        self._timer_when = when if self._loop_clock else loop.time() + (when - now)
        self._timer = loop.call_at(self._timer_when, self._on_timer)
        self._timer_at = when

    # -- input from the transport ----------------------------------------------------------
    def _trace(self, packet: bytes) -> None:
        log_packet(self.transport.url, False, packet)

    def _on_data(self, data: bytes) -> None:
        bound, session = self._bound, self.session
        session.receive(data, self._clock(), datagram=self._datagram,
                        arrived_after=None if bound is None else bound.value)  # fmt: skip
        events = session.events()
        if events:
            self._handle(events)
        if self._timer is None:  # a reply never brings the next wake-up forward
            self._schedule()

    def _on_link_event(self, event: LinkEvent) -> None:
        if event.kind is LinkEventKind.LOST:
            self.session.connection_lost(self._clock(), event.detail or "transport lost")
            self._dispatch()
            self._schedule()
        elif event.kind is LinkEventKind.PEER:
            self.links.emit(event)
        elif event.kind is LinkEventKind.ERROR:
            log.warning("%s (the link stays open; link health decides whether it is up)",
                        event.detail)  # fmt: skip
            self.links.emit(event)

    # -- events ----------------------------------------------------------------------------
    def _dispatch(self) -> None:
        events = self.session.events()
        if events:
            self._handle(events)

    def _handle(self, events: Sequence[Event]) -> None:
        for event in events:
            if isinstance(event, TelemetrySample):
                self.telemetry.publish(event)
            elif isinstance(event, TicketDone):
                self._resolve(event.ticket)
            elif isinstance(event, LinkUp):
                first = self._first_reply
                if first is not None and not first.done():
                    first.set_result(None)
                if event.restored:
                    log.warning("link to %s restored", self.transport.url)
                    self.links.emit(LinkEvent(LinkEventKind.RESTORED, event.reason))
            elif isinstance(event, LinkDown):
                log.warning("link to %s lost: %s", self.transport.url, event.reason)
                self.links.emit(LinkEvent(LinkEventKind.LOST, event.reason))
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
                          f"({self.session.aircraft_timeout:g} s) apart")  # fmt: skip
        elif (isinstance(command, ZoomTo) and command.ratio is not None
              and self.max_zoom is not None and command.ratio > self.max_zoom):  # fmt: skip
            error.explain(LikelyCause.ZOOM_LIMIT,
                          f"{command.ratio:g}x is beyond camera 1's maximum zoom "
                          f"{self.max_zoom:g}x")  # fmt: skip
