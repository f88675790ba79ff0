"""The asyncio driver of a :class:`~gcu_async.session.Session` over a transport: timers,
futures, the packet pump (the client's session + transport part).

It does I/O only: it hands received bytes and transport news to the session, sends the
packet the session asks for at the time it asks, and turns the session's events into
resolved futures, telemetry (:class:`~gcu_async.client.telemetry.Telemetry`) and link
events. Every rule (pacing, separation, matching, timeouts, control values, link health)
lives in the session (docs/session-contract.md, "The session contract").
"""

from __future__ import annotations

import asyncio
import enum
import logging
import math
import time
from collections.abc import Callable, Coroutine, Sequence
from typing import Any

from gcu_async._checks import check_instance
from gcu_async._lograte import LogLimiter
from gcu_async.client.causes import explain
from gcu_async.client.restore import restore, restored
from gcu_async.client.telemetry import Callbacks, Telemetry
from gcu_async.client.wirelog import WIRE_LOG, log_packet
from gcu_async.conformance import GcuConformance
from gcu_async.errors import (
    CommandFailed,
    CommandLinkLost,
    GcuError,
    LinkLost,
    Outcome,
    UnsupportedCommandError,
)
from gcu_async.protocol.builder import Context, Submission
from gcu_async.protocol.catalogue import NEEDS_INS
from gcu_async.protocol.command_base import Command
from gcu_async.protocol.command_decode import command_code
from gcu_async.protocol.enums import PodModel, opcode_name
from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.gcu_frames import GcuMainFrame
from gcu_async.protocol.pods import POD_NAMES, pod_name, supports
from gcu_async.session import (
    Event,
    LinkDown,
    LinkUp,
    ResetLink,
    Restarted,
    Session,
    TelemetrySample,
    Ticket,
    TicketDone,
    TicketState,
)
from gcu_async.transport.base import CLOCK_RESOLUTION, LinkEvent, LinkEventKind, Transport

log = logging.getLogger("gcu_async.client")


class ClientState(enum.Enum):
    """The client's lifecycle (reusable, not reentrant; docs/client.md, "Lifecycle")."""

    CLOSED = "closed"
    """Not opened yet, or closed: :meth:`~GcuClient.open` may open it."""
    OPENING = "opening"
    """:meth:`~GcuClient.open` runs (or, with ``wait=False``, its attempts run in the
    background): no reply from the GCU yet; commands fail at once (``NOT_SENT``)."""
    OPEN = "open"
    """The GCU answered; the link may go down and come back any number of times."""
    CLOSING = "closing"
    FAILED = "failed"
    """The client stopped by itself: its transport gave up restoring the link (opt-in
    bounds, or ``reconnect=False``) or, opened with ``wait=False``, ``open_timeout`` ran
    out (a ``GAVE_UP`` link event said so). Nothing runs; :meth:`~GcuClient.open` starts
    over, :meth:`~GcuClient.close` makes it ``CLOSED``."""


ENDED = frozenset({ClientState.CLOSED, ClientState.CLOSING, ClientState.FAILED})
"""States in which no telemetry comes."""
SEND_FAILED_WINDOW = 10.0
"""Seconds between two log lines of a send that keeps failing (the link is down: every
heartbeat's send fails, 50 a second)."""


def loop_keeps(clock: Callable[[], float], loop: asyncio.AbstractEventLoop) -> bool:
    """True when ``loop``'s time is ``clock`` itself (:func:`time.monotonic` on asyncio's own
    loops): a time on the clock is then a time on the loop."""
    return clock is time.monotonic and type(loop).time is asyncio.BaseEventLoop.time


class Driver:
    """One session driven over one transport on the running event loop."""

    def __init__(self, session: Session, transport: Transport, clock: Callable[[], float],
                 telemetry: Telemetry, links: Callbacks[LinkEvent], *, check_support: bool,
                 max_zoom: float | None, restore: bool = False,
                 conformance: GcuConformance | None = None) -> None:  # fmt: skip
        self.session = session
        self.transport = transport
        self._clock = clock
        self.telemetry = telemetry
        self.links = links
        self.check_support = check_support
        self.max_zoom = max_zoom
        self.restore = restore
        """Restore the mode and zoom after a GCU restart (:mod:`~gcu_async.client.restore`)."""
        self.conformance = conformance
        """Fed every packet sent and every reply (the ``conformance`` option), else None."""
        self.state = ClientState.CLOSED
        self.failure: str | None = None
        """Why the client is ``FAILED`` (None in every other state)."""
        self._timer: asyncio.TimerHandle | None = None
        self._timer_at = math.inf
        self._futures: dict[Ticket, asyncio.Future[Feedback | None]] = {}
        self._needs_ins: dict[Ticket, bool] = {}
        """Pending commands that need INS data: True once a packet went out while one was
        pending with INS invalid."""
        self._first_reply: asyncio.Future[LinkLost | None] | None = None
        """Resolved by the first reply of an open attempt (None), or by what ends the
        attempt first (a :class:`LinkLost`: the client closed, the transport gave up)."""
        self._run = 0
        """Counts :meth:`begin`: an attempt of an earlier open() knows it is stale."""
        self._tasks: set[asyncio.Task[None]] = set()
        """Work the driver started (a restore, a shutdown after GAVE_UP); cancelled when the
        client closes."""
        self._logs = LogLimiter(log, burst=1, window=SEND_FAILED_WINDOW, clock=clock,
                                name=transport.url)  # fmt: skip
        self._loop: asyncio.AbstractEventLoop | None = None
        self.closed_event: asyncio.Event | None = None
        """Set once the client closes or fails (None before it was first opened)."""
        self._datagram = transport.datagram
        self._arrived_after: float | None = None
        """Replies delivered from now on arrived after this (links that reorder: the
        session's ``arrived_after``); None: the link never reorders, or cannot tell."""
        self._timer_when = 0.0
        """Event-loop time the pending timer is due."""
        self._loop_clock = False
        """The event loop's time is ``clock`` (``time.monotonic`` on asyncio's own loops):
        the heartbeat timer bounds reply arrival for free (:meth:`_on_timer`); otherwise
        the link is read before each send (:meth:`_pump`)."""

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

    def not_open(self) -> str:
        """Why nothing can be done right now: the client is not open, or it failed."""
        if self.state is ClientState.FAILED:
            return f"the client failed ({self.failure}); open it again"
        return "the client is not open"

    @property
    def url(self) -> str:
        """The transport's URL."""
        return self.transport.url

    def emit(self, event: LinkEvent) -> None:
        """Hand ``event`` to the link-event subscribers."""
        self.links.emit(event)

    def context(self) -> Context:
        """What the command builder needs of the GCU's latest reports."""
        session = self.session
        return Context.of(session.status, session.info, self.max_zoom)

    def closed(self) -> asyncio.Event | None:
        """Set once the client closes or fails; None while it is closed."""
        return None if self.state is ClientState.CLOSED else self.closed_event

    # -- lifecycle -------------------------------------------------------------------------
    def begin(self) -> None:
        """An open() starts: ``OPENING``, a new closed event (it spans every attempt)."""
        self.state = ClientState.OPENING
        self.failure = None
        self._loop = asyncio.get_running_loop()
        self.closed_event = asyncio.Event()
        self._run += 1

    def _opening(self, run: int) -> bool:
        return run == self._run and self.state is ClientState.OPENING

    async def open_once(self, connect_timeout: float) -> None:
        """One attempt of an open (the client is ``OPENING``): open the transport, start
        the heartbeat, wait for the first reply, which makes it ``OPEN``. :class:`LinkLost`
        if it fails, with the attempt's transport and session closed again (still
        ``OPENING``)."""
        run = self._run
        loop = asyncio.get_running_loop()
        self._first_reply = first = loop.create_future()
        self.transport.set_handlers(self._on_data, self._on_link_event)
        log.debug("%s: opening the transport", self.transport.url)
        try:
            await self.transport.open()
        except BaseException:
            self._first_reply = None
            raise
        if not self._opening(run):  # closed while the transport opened
            self._first_reply = None
            await self.transport.close()
            raise LinkLost(f"{self.transport.url}: closed while opening")
        self.session.open(self._clock())
        self._loop_clock = loop_keeps(self._clock, loop)
        self._arrived_after = self._arrival_start()
        self._pump()
        try:
            # asyncio.wait, not wait_for: a first reply handled in the very loop iteration in
            # which the timeout fires counts (wait_for could raise TimeoutError with the client
            # already OPEN); and a cancelled open leaves `first` alone
            await asyncio.wait({first}, timeout=connect_timeout)
        except BaseException:
            self._first_reply = None
            await self.stop_attempt("open interrupted")
            raise
        self._first_reply = None
        if not first.done():
            await self.stop_attempt("no reply")
            raise LinkLost(
                f"{self.transport.url}: no reply from the GCU within {connect_timeout:g} s")
        failure = first.result()
        if failure is None and run == self._run and self.state is ClientState.OPEN:
            return  # the first reply made it OPEN (_handle)
        await self.stop_attempt("open failed")
        raise failure or LinkLost(f"{self.transport.url}: closed while opening")

    async def stop_attempt(self, reason: str) -> None:
        """End an open attempt: the session, the heartbeat and the transport (the client
        stays as it is)."""
        self.session.close(self._clock(), reason)
        self._dispatch()
        if self._timer is not None:
            self._timer.cancel()
            self._timer, self._timer_at = None, math.inf
        await self.transport.close()

    async def shutdown(self, reason: str, end: ClientState = ClientState.CLOSED) -> None:
        """End pending commands, stop the heartbeat, end the telemetry iterators and the
        waits, close the transport; then ``end`` (``CLOSED``, or ``FAILED`` with
        ``reason`` as :attr:`failure`). Idempotent."""
        if self.state is ClientState.CLOSING:  # another shutdown runs: let it finish
            assert self.closed_event is not None
            await self.closed_event.wait()
        if self.state in (ClientState.CLOSED, ClientState.FAILED):
            if end is ClientState.CLOSED:
                self.state, self.failure = ClientState.CLOSED, None
            return
        first = self._first_reply
        if first is not None and not first.done():  # an open attempt waits: end it now
            first.set_result(LinkLost(f"{self.transport.url}: {reason} while opening"))
        self.state = ClientState.CLOSING
        current = asyncio.current_task()
        for task in list(self._tasks):
            if task is not current:
                task.cancel()
        try:
            await self.stop_attempt(reason)
            self.telemetry.close()
        finally:
            self.state = end
            self.failure = reason if end is ClientState.FAILED else None
            self._logs.flush()
            if end is ClientState.FAILED:
                log.error("%s: the client failed: %s", self.transport.url, reason)
            else:
                log.info("closed %s (%s)", self.transport.url, reason)
            if self.closed_event is not None:
                self.closed_event.set()

    async def fail(self, reason: str) -> None:
        """Stop for good (``FAILED``) after a ``GAVE_UP``: the transport will not restore the
        link, or the open attempts ran out of ``open_timeout``."""
        await self.shutdown(reason, ClientState.FAILED)

    def spawn(self, work: Coroutine[Any, Any, None], name: str) -> asyncio.Task[None]:
        """Run ``work`` in a task the driver cancels when the client closes."""
        task = asyncio.get_running_loop().create_task(work, name=f"{name} {self.transport.url}")
        self._tasks.add(task)
        task.add_done_callback(self._task_done)
        return task

    def _task_done(self, task: asyncio.Task[None]) -> None:
        self._tasks.discard(task)
        if not task.cancelled() and task.exception() is not None:
            log.error("%s: %s failed", self.transport.url, task.get_name(),
                      exc_info=task.exception())  # fmt: skip

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
        ticket, future = self.enqueue(submission, queue_timeout=queue_timeout)
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

    def enqueue(self, submission: Submission, *, queue_timeout: float | None = None
                ) -> tuple[Ticket, asyncio.Future[Feedback | None]]:  # fmt: skip
        """Submit a command now (synchronously): its ticket and the future of its outcome.
        Raises what :meth:`Session.submit` raises, and :class:`CommandLinkLost` unless the
        client is open."""
        command = submission.command
        check_instance("command", command, Command, "a Command")
        if self.state is not ClientState.OPEN:
            opcode = command_code(command)
            if self.closed_event is None:
                hint = ("not opened: use `async with connect(url) as gcu:` (or `await "
                        "gcu.open()`) first")  # fmt: skip
            elif self.state is ClientState.OPENING:
                hint = "client is opening (no reply from the GCU yet)"
            elif self.state is ClientState.FAILED:
                hint = f"client failed ({self.failure}; open it again)"
            else:
                hint = f"client is {self.state.value}"
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
        return ticket, future

    def _check_support(self, command: Command) -> None:
        model = self.pod_model
        if not self.check_support or model is None or model not in POD_NAMES:
            return
        if not supports(model, command_code(command)):
            raise UnsupportedCommandError(opcode_name(command_code(command)), pod_name(model))

    # -- the pump: the only place packets are sent -----------------------------------------
    def _arrival_start(self) -> float | None:
        """The first bound of reply arrival (docs/session-contract.md, "Assumptions", A4):
        ``None`` on a link that never reorders, or one that cannot be read on demand (the
        transport's :meth:`~gcu_async.transport.Transport.caught_up`: the session then
        assumes a responsive loop, logged); else now."""
        if self.transport.ordered:
            return None
        now = self._clock()
        if self.transport.caught_up():
            return now
        log.info("%s cannot be read on demand: reply timing assumes a responsive event loop "
                 "(docs/session-contract.md, \"Assumptions\", A4)",
                 self.transport.url)  # fmt: skip
        return None

    def _on_timer(self) -> None:
        # a reply not delivered yet arrived after this iteration's poll of the OS (the
        # transport reads what the poll may have left first): no later than the timer's due
        if (self._arrived_after is not None and self._loop_clock
                and self.transport.caught_up(self._timer_when)):  # fmt: skip
            self._arrived_after = self._timer_when - CLOCK_RESOLUTION
        self._timer, self._timer_at = None, math.inf
        self._pump()

    def _pump(self) -> None:
        if self._timer is not None:  # called early (a command): this run replaces the timer
            self._timer.cancel()
            self._timer, self._timer_at = None, math.inf
        session = self.session
        try:
            if self._arrived_after is not None and not self._loop_clock:  # replies first
                now = self._clock()
                if self.transport.caught_up():
                    self._arrived_after = now
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
                    if self.conformance is not None:
                        self.conformance.add_host(data, now)
                except (LinkLost, OSError) as exc:
                    session.send_failed()  # every heartbeat while the link is down
                    self._logs.log(logging.DEBUG, "send failed", "send failed: %s", exc)
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
        session = self.session
        session.receive(data, self._clock(), datagram=self._datagram,
                        arrived_after=self._arrived_after)  # fmt: skip
        events = session.events()
        if events:
            self._handle(events)
        if self._timer is None:  # a reply never brings the next wake-up forward
            self._schedule()

    def _on_link_event(self, event: LinkEvent) -> None:
        kind = event.kind
        if kind is LinkEventKind.LOST:
            self.session.connection_lost(self._clock(), event.detail or "transport lost")
            self._dispatch()
            self._schedule()
        elif kind is LinkEventKind.PEER:
            log.info("%s", event.detail)
            self.links.emit(event)
        elif kind is LinkEventKind.ERROR:
            log.warning("%s (the client keeps sending; the link is up once the GCU answers)",
                        event.detail)  # fmt: skip
            self.links.emit(event)
        elif kind is LinkEventKind.GAVE_UP:
            first = self._first_reply
            if self.state is ClientState.OPEN:
                self.links.emit(event)
                self.spawn(self.fail(event.detail), "gcu_async fail")
            elif first is not None and not first.done():  # it ends this open attempt
                first.set_result(LinkLost(event.detail))
        # RESTORED: the link counts as up with the next reply (the session's LinkUp)

    # -- events ----------------------------------------------------------------------------
    def _dispatch(self) -> None:
        events = self.session.events()
        if events:
            self._handle(events)

    def _handle(self, events: Sequence[Event]) -> None:
        for event in events:
            if isinstance(event, TelemetrySample):
                if self.conformance is not None:
                    self.conformance.add_reply(event.status, event.info, event.feedback,
                                               event.received_at)  # fmt: skip
                self.telemetry.publish(event)
            elif isinstance(event, TicketDone):
                self._resolve(event.ticket)
            elif isinstance(event, LinkUp):
                first = self._first_reply
                if first is not None and not first.done():
                    first.set_result(None)
                    self.state = ClientState.OPEN  # commands are accepted from this reply on
                self._logs.flush()
                if event.restored:
                    log.info("link to %s restored", self.transport.url)
                    self.links.emit(LinkEvent(LinkEventKind.RESTORED, event.reason))
                else:
                    log.info("link to %s up", self.transport.url)
                    self.links.emit(LinkEvent(LinkEventKind.UP, event.reason))
            elif isinstance(event, LinkDown):
                log.warning("link to %s lost: %s", self.transport.url, event.reason)
                self.links.emit(LinkEvent(LinkEventKind.LOST, event.reason))
            elif isinstance(event, Restarted):
                self._restarted(event)
            elif isinstance(event, ResetLink):
                reset = getattr(self.transport, "reset", None)
                if reset is not None:
                    reset(event.reason)

    def _restarted(self, event: Restarted) -> None:
        """The GCU restarted: restore what it lost first (so that commands the
        application sends on hearing of it come after), then say so."""
        restoring = self.restore and (event.mode is not None or event.zoom is not None)
        detail = f"the GCU restarted: {event.reason}"
        if restoring:
            self.spawn(restore(self, event), "gcu_async restore")
            detail += "; restoring " + " and ".join(restored(event))
        log.warning("%s: %s", self.transport.url, detail)
        self.links.emit(LinkEvent(LinkEventKind.RESTARTED, detail))

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
                explain(ticket.error, ticket.command, self.pod_model, ins_invalid=ins_invalid,
                        max_zoom=self.max_zoom,
                        aircraft_timeout=self.session.config.aircraft_timeout)  # fmt: skip
            future.set_exception(ticket.error)
