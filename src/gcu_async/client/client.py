"""The client: one GCU over one transport, as composed parts (docs/client.md, "How the
client is built").

``GcuClient`` is the public face. It owns a :class:`~gcu_async.client.driver.Driver` (the
sans-I/O session driven over the transport: timers, futures, the packet pump), a
:class:`~gcu_async.client.telemetry.Telemetry` fan-out and the link-event callbacks, and a
:class:`~gcu_async.client.waiting.Waiting` part; none of them reaches into another through
abstract hooks. Its command methods come from its base
:class:`~gcu_async.client.command_methods.GcuCommands`, one line each naming what it sends.
Every rule (pacing, separation, matching, timeouts, control values, link health) lives in the
session (docs/session-contract.md, "The session contract").
"""

from __future__ import annotations

import contextlib
import enum
import math
import os
import sys
import time
import warnings
from collections.abc import AsyncGenerator, Callable, Generator
from datetime import datetime
from typing import Any, Final

from gcu_async._checks import (
    check_bool,
    check_int,
    check_positive,
    check_real,
    type_error,
)
from gcu_async._lifecycle import OpenClose
from gcu_async.capture.writer import PacketCapture
from gcu_async.client.command_methods import GcuCommands
from gcu_async.client.driver import ENDED, ClientState, Driver
from gcu_async.client.opening import Opener
from gcu_async.client.telemetry import Callbacks, Telemetry
from gcu_async.client.waiting import (
    ANGLE_TOLERANCE,
    WAIT_TIMEOUT,
    ZOOM_TOLERANCE,
    Predicate,
    Waiting,
)
from gcu_async.conformance import GcuConformance, GcuReport
from gcu_async.protocol.aircraft import AircraftState, aircraft_update
from gcu_async.protocol.builder import Submission, angles, rates
from gcu_async.protocol.command_base import Command
from gcu_async.protocol.commands import ZOOM_RATIO_MAX
from gcu_async.protocol.enums import PodModel
from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.gcu_frames import GcuMainFrame, GcuSubFrame
from gcu_async.protocol.host_frame_tables import ControlValues
from gcu_async.protocol.packets import DEFAULT_VERSION
from gcu_async.protocol.units import Attitude, GeoPosition, NorthEastUp
from gcu_async.session import ControlKind, LinkHealth, Session, SessionConfig, TelemetrySample
from gcu_async.transport.base import LinkEvent, Transport
from gcu_async.transport.tap import with_capture

__all__ = ["KEEP", "ClientState", "GcuClient", "Keep"]


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


class GcuClient(GcuCommands, OpenClose):
    """An asyncio session with one GCU.

    ``async with GcuClient(transport) as gcu:`` opens the transport, starts the heartbeat,
    waits up to ``connect_timeout`` for the first reply and, on exit, ends pending commands,
    stops the heartbeat and closes the transport. With ``wait=False`` it returns at once and
    brings the link up in the background. Once open, the client keeps the link up through
    outages of any length by itself (docs/client.md, "Lifecycle"). A closed (or failed)
    client can be opened again; opening one that is open (or opening) raises
    :class:`ClientStateError` (a ``RuntimeError``) naming its state. ``gcu = await
    connect(url)`` opens it too (then close it yourself: ``await gcu.close()``).

    Args:
        transport: any :class:`~gcu_async.transport.Transport` (not yet opened).
        rate_hz: heartbeat rate, [2, 200] packets per second; the protocol advises 30–50 Hz
            (a warning outside). Host packets never exceed ``rate_hz`` + 1 in any second.
        command_timeout: default seconds a command may take on the wire, from its first
            packet to its feedback (:class:`CommandTimeout`, outcome ``UNKNOWN``).
        queue_timeout: default seconds a command may wait before its first packet
            (:class:`CommandTimeout`, outcome ``NOT_SENT``).
        connect_timeout: seconds an open attempt waits for the first reply.
        open_timeout: keep retrying the open attempts (backoff 0.25–5 s, full jitter) until
            this many seconds have passed (``math.inf``: until closed), e.g. to start
            before the GCU is powered; each failed attempt is a ``RETRYING`` link event.
            ``None`` (default): one attempt with ``wait=True``, no limit with
            ``wait=False``.
        wait: ``True`` (default): :meth:`open` returns once the GCU answered, or raises.
            ``False``: :meth:`open` returns at once (``state`` ``OPENING``) and the attempts
            run in the background until the GCU answers (``UP`` link event, ``state``
            ``OPEN``), the client is closed, or ``open_timeout`` runs out (``GAVE_UP``,
            ``state`` ``FAILED``). Commands fail at once (``NOT_SENT``) until then.
        restore: after the GCU restarted (a ``RESTARTED`` link event), re-apply the mode it
            had confirmed last, with its control values, and camera 1's zoom
            (docs/client.md, "GCU restarts"). Default ``False``: only report it.
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
            before sending; ``None`` (default): only the field's range, 1 to
            :data:`~gcu_async.protocol.commands.ZOOM_RATIO_MAX`.
        conformance: collect the GCU conformance report (:meth:`conformance_report`): every reply
            and host packet is analysed (a few µs each, bounded memory). Default ``False``.
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
        wait: bool = True,
        restore: bool = False,
        silence_timeout: float = 1.0,
        check_support: bool = False,
        reorder_guard: float | None = None,
        aircraft_timeout: float = 1.0,
        version: int = DEFAULT_VERSION,
        clock: Callable[[], float] = time.monotonic,
        capture: PacketCapture | str | os.PathLike[str] | None = None,
        max_zoom: float | None = None,
        conformance: bool = False,
    ) -> None:
        if not isinstance(transport, Transport):
            raise type_error("transport", "a Transport", transport)
        transport = with_capture(transport, capture)
        if reorder_guard is None:
            reorder_guard = 0.0 if transport.ordered else DEFAULT_REORDER_GUARD
        config = SessionConfig(  # it checks its options (the one place they are checked)
            rate_hz=rate_hz, reorder_guard=reorder_guard, command_timeout=command_timeout,
            queue_timeout=queue_timeout, silence_timeout=silence_timeout,
            aircraft_timeout=aircraft_timeout, version=version, name=transport.url,
        )  # fmt: skip
        session = Session(config)
        if not callable(clock):
            raise type_error("clock", "a callable returning seconds", clock)
        reading = clock()
        if isinstance(reading, bool) or not isinstance(reading, (int, float)):
            raise type_error("clock", f"a callable returning seconds (it returned {reading!r})",
                             clock)  # fmt: skip
        if not math.isfinite(reading):
            raise ValueError(f"clock: {clock!r} returned {reading!r}, not finite seconds")
        self.transport = transport
        self.session = session
        self.connect_timeout = check_positive("connect_timeout", connect_timeout)
        self.open_timeout = (open_timeout if open_timeout is None or open_timeout == math.inf
                             else check_positive("open_timeout", open_timeout))  # fmt: skip
        self.wait = check_bool("wait", wait)
        """Whether :meth:`open` waits for the GCU's first reply (the ``wait`` option)."""
        restore = check_bool("restore", restore)
        check_support = check_bool("check_support", check_support)
        max_zoom = (None if max_zoom is None
                    else check_real("max_zoom", max_zoom, 1.0, ZOOM_RATIO_MAX, "x"))
        rate = config.rate_hz
        if not RATE_ADVISED[0] <= rate <= RATE_ADVISED[1]:
            warnings.warn(f"rate_hz={rate:g}: the protocol advises 30-50 Hz host packets",
                          stacklevel=_caller_stacklevel())  # fmt: skip
        self._clock = clock
        self._telemetry = Telemetry(self._consumed)
        self._links: Callbacks[LinkEvent] = Callbacks("link")
        report = GcuConformance() if check_bool("conformance", conformance) else None
        self._driver = Driver(session, transport, clock, self._telemetry, self._links,
                              check_support=check_support, max_zoom=max_zoom,
                              restore=restore, conformance=report)  # fmt: skip
        session.telemetry = report is not None  # the report is fed from telemetry samples
        self._opener = Opener(self._driver, self._links, clock)
        self._waiting = Waiting(self._driver, self._telemetry, self._links)

    def _consumed(self, consumed: bool) -> None:
        """Telemetry samples are built only while someone consumes them (a subscriber, or
        the conformance report)."""
        self.session.telemetry = consumed or self._driver.conformance is not None

    @property
    def check_support(self) -> bool:
        """Refuse commands the pod model does not support (the ``check_support`` option)."""
        return self._driver.check_support

    @check_support.setter
    def check_support(self, value: bool) -> None:
        self._driver.check_support = check_bool("check_support", value)

    @property
    def restore(self) -> bool:
        """Restore the mode and zoom after a GCU restart (the ``restore`` option)."""
        return self._driver.restore

    @restore.setter
    def restore(self, value: bool) -> None:
        self._driver.restore = check_bool("restore", value)

    @property
    def failure(self) -> str | None:
        """Why the client is :attr:`~ClientState.FAILED` (the ``GAVE_UP`` event's detail);
        ``None`` in every other state."""
        return self._driver.failure

    @property
    def telemetry_dropped(self) -> int:
        """Samples dropped so far by telemetry iterators that fell behind, all together."""
        return self._telemetry.dropped

    @telemetry_dropped.setter
    def telemetry_dropped(self, value: int) -> None:
        self._telemetry.dropped = check_int("telemetry_dropped", value, 0)

    # -- configuration (read-only views of the session's) ----------------------------------
    @property
    def rate_hz(self) -> float:
        return self.session.config.rate_hz

    @property
    def reorder_guard(self) -> float:
        return self.session.config.reorder_guard

    @property
    def command_timeout(self) -> float:
        return self.session.config.command_timeout

    @property
    def queue_timeout(self) -> float:
        return self.session.config.queue_timeout

    @property
    def version(self) -> int:
        return self.session.config.version

    @property
    def state(self) -> ClientState:
        return self._driver.state

    @property
    def max_zoom(self) -> float | None:
        """Camera 1's largest zoom ratio as given (``max_zoom=``), ``None`` if not known."""
        return self._driver.max_zoom

    def __await__(self) -> Generator[Any, None, GcuClient]:
        """``gcu = await connect(url)``: open the client and return it (close it yourself;
        ``async with connect(url) as gcu:`` does both)."""
        yield from self.open().__await__()
        return self

    # -- lifecycle -------------------------------------------------------------------------
    async def open(self) -> None:
        """Open the transport, start the heartbeat, wait for the first reply.

        Raises :class:`LinkLost` if the transport cannot open or no reply comes within
        ``connect_timeout`` (everything is closed again), ``RuntimeError`` unless the client
        is closed or failed. With ``open_timeout``, failed attempts are retried with
        backoff until that many seconds have passed; :meth:`close` stops them
        (``LinkLost``). With ``wait=False`` it returns at once and the attempts run in the
        background (docs/client.md, "Lifecycle")."""
        await self._opener.open(self.connect_timeout, self.open_timeout, self.wait)

    async def close(self) -> None:
        """End pending commands (:class:`CommandLinkLost`), stop the heartbeat and the
        background attempts, end the telemetry iterators and the waits, close the
        transport. Idempotent; a failed client becomes closed."""
        await self._opener.stop()
        await self._driver.shutdown("client closed")

    @property
    def aircraft(self) -> AircraftState:
        """The aircraft state as last given (what goes out: :attr:`ins_valid`)."""
        return self.session.aircraft

    @property
    def aircraft_timeout(self) -> float:
        return self.session.config.aircraft_timeout

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
        tuple or a list of three. Units: degrees (attitude; yaw in
        :data:`~gcu_async.protocol.units.YAW_INPUT_RANGE`, MAVLink's signed or a compass
        heading, sent as its compass equivalent), m/s² north/east/up without
        gravity, m/s north/east/up, (latitude °,
        longitude °, altitude m MSL), metres. ``gnss_time`` (aware UTC) sets week + ms with
        leap seconds applied.

        The parts given count as measured now: INS-valid goes out only while attitude,
        acceleration and velocity have all been given within ``aircraft_timeout``, the sub
        frame only while the position has; GNSS time advances with the clock between
        updates (docs/client.md, "Aircraft data: what the packets claim").

        Raises ``TypeError`` or :class:`FieldRangeError` (nothing changes) for a bad value.
        """
        arguments = {"attitude": attitude, "acceleration": acceleration, "velocity": velocity,
                     "position": position, "relative_altitude": relative_altitude,
                     "satellites": satellites, "gnss_week": gnss_week, "gnss_ms": gnss_ms}
        given: dict[str, object] = {k: v for k, v in arguments.items() if v is not KEEP}
        if gnss_time is not None:
            given["gnss_time"] = gnss_time
        changes = aircraft_update(given)
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
        """True if the next packet carries the control values valid (docs/client.md, "Modes
        and control values")."""
        return self.session.control_valid(self._clock()) is not None

    def set_control(self, control: ControlValues | None) -> None:
        """Raw control values for the current mode (their meaning depends on the mode,
        docs/protocol-notes.md §5 "Control values change meaning with the mode"); ``None`` sends
        them invalid (rates 0, angles held). Raises ``ValueError`` (nothing changes) when no mode
        takes values or a value is out of range."""
        self.session.set_control(control)

    def set_angles(self, *, roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0) -> None:
        """New target angles (degrees, up to :data:`~gcu_async.protocol.commands.ANGLE_LIMIT`
        either way) for the current angle-based mode (Euler, angle control, FPV). Raises
        ``ValueError`` if the current mode does not take angles."""
        self.session.set_control(angles(roll, pitch, yaw), ControlKind.ANGLES)

    def set_rates(self, *, roll: float = 0.0, pitch: float = 0.0, yaw: float = 0.0) -> None:
        """New angular rates (°/s at the current main-view zoom) for the current rate-based
        mode. Raises ``ValueError`` if the current mode does not take rates."""
        values = rates(self._driver.context(), roll=roll, pitch=pitch, yaw=yaw)
        self.session.set_control(values, ControlKind.RATES)

    def release_control(self) -> None:
        """Send the control values invalid from now on: rates 0, angles held."""
        self.session.set_control(None, ControlKind.NONE)

    # -- telemetry -------------------------------------------------------------------------
    @property
    def status(self) -> GcuMainFrame | None:
        """The latest main frame (mode, pod status, angles, rates); ``None`` before the
        first reply. While the link is down it is the last one received (``link.up``
        says whether it is current)."""
        return self.session.status

    @property
    def info(self) -> GcuSubFrame | None:
        """The latest sub frame (pod model, versions, zoom, ranging, flags); ``None`` before
        the first reply that carried one."""
        return self.session.info

    @property
    def pod_model(self) -> PodModel | None:
        """The pod model once a sub frame arrived, else ``None``."""
        return self._driver.pod_model

    @property
    def recording(self) -> bool | None:
        """Whether the camera records, as far as the client can tell (``None``: not known
        yet)."""
        return self.session.recording(self._clock())

    @property
    def link(self) -> LinkHealth:
        """A snapshot of the link's health."""
        return self.session.link_health(self._clock())

    @property
    def conformance(self) -> bool:
        """Whether the client collects the GCU conformance report (the ``conformance``
        option; :meth:`conformance_report`)."""
        return self._driver.conformance is not None

    def conformance_report(self) -> GcuReport:
        """The GCU conformance report so far: everything the GCU's replies did outside
        V2.0.6, with counts and examples (docs/conformance.md). Needs the client built with
        ``conformance=True`` (``ValueError`` otherwise); it covers every reply since."""
        report = self._driver.conformance
        if report is None:
            raise ValueError("conformance: the client was built with conformance=False; "
                             "pass conformance=True to collect the GCU conformance report")
        return report.report()

    async def telemetry(self, maxsize: int = 1) -> AsyncGenerator[TelemetrySample, None]:
        """Iterate over replies as they arrive. The queue holds ``maxsize`` samples; when
        the consumer falls behind the oldest are dropped (counted in
        ``telemetry_dropped``). Ends when the client closes or fails; an iterator started
        before the first reply (``wait=False``) waits for it."""
        samples = self._telemetry.samples(check_int("maxsize", maxsize, 1, sys.maxsize),
                                          self._driver.state in ENDED)  # fmt: skip
        async with contextlib.aclosing(samples):
            async for sample in samples:
                yield sample

    def on_telemetry(self, callback: TelemetryCallback) -> Callable[[], None]:
        """Call ``callback(sample)`` for every reply; returns a function that unsubscribes."""
        return self._telemetry.callbacks.add(callback)

    def on_link_change(self, callback: LinkCallback) -> Callable[[], None]:
        """Call ``callback(LinkEvent)`` when the link comes up, is lost or restored, when the
        GCU restarted, when the transport gave up, when the OS reports an error on it
        (:attr:`~gcu_async.transport.LinkEventKind.ERROR`: once per episode), when a new
        peer answers, and when an open attempt failed
        (:class:`~gcu_async.transport.LinkEventKind` lists them)."""
        return self._links.add(callback)

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
        return await self._driver.run(Submission(command, timeout=timeout),
                                      queue_timeout=queue_timeout)  # fmt: skip

    # -- waiting for the physical world (docs/client.md, "Waiting for the gimbal, the zoom
    # and the link") ----------------------------------------------------------------------
    async def wait_for(self, predicate: Predicate, *, timeout: float = WAIT_TIMEOUT,
                       what: str = "the condition") -> TelemetrySample:  # fmt: skip
        """Return the first telemetry sample for which ``predicate(sample)`` is true — the
        latest reply already, if it qualifies and the link is up. ``what`` names the
        condition in the error.

        Raises :class:`~gcu_async.errors.WaitTimeout` after ``timeout`` seconds (the last
        sample seen is its ``last``), :class:`~gcu_async.errors.LinkLost` if the client
        closes, and whatever ``predicate`` raises."""
        return await self._waiting.wait_for(predicate, timeout=timeout, what=what)

    async def wait_attitude(self, *, roll: float | None = None, pitch: float | None = None,
                            yaw: float | None = None, tolerance: float = ANGLE_TOLERANCE,
                            timeout: float = WAIT_TIMEOUT) -> TelemetrySample:  # fmt: skip
        """Wait until the camera's reported attitude (``status.attitude``: absolute Euler
        angles, degrees) is within ``tolerance`` degrees of every angle given; angles left
        ``None`` are not checked. Yaw compares the short way round (359° is 2° from 1°)."""
        return await self._waiting.wait_attitude(roll=roll, pitch=pitch, yaw=yaw,
                                                 tolerance=tolerance, timeout=timeout)  # fmt: skip

    async def wait_zoom(self, ratio: float, *, tolerance: float = ZOOM_TOLERANCE,
                        timeout: float = WAIT_TIMEOUT) -> TelemetrySample:  # fmt: skip
        """Wait until camera 1's reported zoom ratio (sub frame) is within ``tolerance`` of
        ``ratio``."""
        return await self._waiting.wait_zoom(ratio, tolerance=tolerance, timeout=timeout)

    async def reach_attitude(self, *, roll: float | None = None, pitch: float | None = None,
                             yaw: float | None = None, tolerance: float = ANGLE_TOLERANCE,
                             timeout: float = WAIT_TIMEOUT) -> TelemetrySample:  # fmt: skip
        """Euler-angle control (:meth:`enter_euler_control`) to the angles given — omitted ones
        keep the current attitude — then wait until the camera is within ``tolerance``
        degrees of all three. ``timeout`` bounds the wait after the GCU confirmed the mode
        (the command itself has its own ``command_timeout``)."""
        return await self._waiting.reach_attitude(roll=roll, pitch=pitch, yaw=yaw,
                                                  tolerance=tolerance, timeout=timeout)  # fmt: skip

    async def reach_zoom(self, ratio: float, *, tolerance: float = ZOOM_TOLERANCE,
                         timeout: float = WAIT_TIMEOUT) -> TelemetrySample:  # fmt: skip
        """:meth:`zoom_to` ``ratio`` (camera 1), then wait until the reported zoom is within
        ``tolerance`` of it. A ratio above :attr:`max_zoom` (when given) is refused before
        anything is sent; a timeout with the zoom short of the ratio names the ratio last
        reported."""
        return await self._waiting.reach_zoom(ratio, tolerance=tolerance, timeout=timeout)

    async def wait_link(self, up: bool = True, *, timeout: float = WAIT_TIMEOUT) -> None:
        """Return once the link is up (``up=False``: down); at once if it already is.
        :class:`~gcu_async.errors.WaitTimeout` after ``timeout`` seconds,
        :class:`~gcu_async.errors.LinkLost` if the client closes or fails meanwhile."""
        await self._waiting.wait_link(up, timeout=timeout)

    async def link_events(self) -> AsyncGenerator[LinkEvent, None]:
        """Iterate over link events (:class:`~gcu_async.transport.LinkEventKind`: up, lost,
        restored, restarted, gave up, an OS error, a new peer, a failed open attempt) from
        now on; ends when the client closes or fails. Up to 256 unread events are kept (the
        oldest go first)."""
        events = self._waiting.link_events()
        async with contextlib.aclosing(events):
            async for event in events:
                yield event


def _caller_stacklevel() -> int:
    """The ``stacklevel`` of a warning that names the first caller outside gcu_async.client
    (the user's ``connect(…)`` or ``GcuClient(…)`` line)."""
    frame = sys._getframe(1)
    level = 1
    while frame is not None and frame.f_globals.get("__name__", "").startswith(
            "gcu_async.client"):  # fmt: skip
        frame, level = frame.f_back, level + 1  # type: ignore[assignment]
    return level
