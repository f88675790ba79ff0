"""The one small interface every transport implements: bytes in, bytes out.

Transports know nothing of the protocol. Received bytes go to the ``on_data`` handler in
arrival order (stream transports may split or merge packets; the session's deframer copes;
datagram transports deliver one datagram per call, see :attr:`Transport.datagram`); link
changes go to ``on_event``. ``send`` never blocks: it hands bytes to the OS (or the peer),
may drop them when the OS cannot take more (stream transports, counted in
``sends_dropped``), and raises :class:`~gcu_async.errors.LinkLost` when the link is down.
:meth:`Transport.reset` discards whatever is still queued towards the peer. A transport
that may reorder and can tell when its replies arrived (UDP) also overrides the optional
:meth:`Transport.caught_up`; the others need not.
"""

from __future__ import annotations

import abc
import enum
import time
from collections.abc import Callable
from dataclasses import dataclass

from gcu_async._lifecycle import OpenClose
from gcu_async.transport._common import check_reason

DataHandler = Callable[[bytes], None]
CLOCK_RESOLUTION = time.get_clock_info("monotonic").resolution
"""Seconds: the monotonic clock's resolution, by which asyncio runs a timer before its time."""


class LinkEventKind(enum.Enum):
    """What happened to the link."""

    LOST = "lost"
    """The link went down (peer closed, I/O error, no reply for ``silence_timeout``). The
    transport tries to restore it (``reconnect=True``, the default) until it is closed, or
    until its opt-in :class:`~gcu_async.transport.Backoff` bounds run out (``GAVE_UP``)."""
    RESTORED = "restored"
    """A lost link is back (e.g. TCP reconnected; for a client: replies arrive again)."""
    GAVE_UP = "gave_up"
    """The transport stopped trying to restore a lost link: its ``max_attempts`` or
    ``max_total`` ran out, or it was made with ``reconnect=False``; the detail says why. A
    client then ends in :attr:`~gcu_async.client.ClientState.FAILED` (or, opened with
    ``wait=False``, its ``open_timeout`` ran out)."""
    PEER = "peer"
    """Bytes came from a new peer address (UDP any-source discovery)."""
    ERROR = "error"
    """The OS reported an error that leaves the link open (UDP: an ICMP port unreachable —
    nothing listens at the GCU's address yet —, no route, a full send buffer); the detail
    says which. One event per episode: the next comes after data from the GCU arrived again.
    Whether the link is up is decided by the replies, not by this."""
    RETRYING = "retrying"
    """An attempt of the client's :meth:`~gcu_async.client.GcuClient.open` failed and
    another follows (``open_timeout``, ``wait=False``); the detail says why and when."""
    UP = "up"
    """The client's first reply after it was opened: the link is up (with ``wait=False``,
    how an application learns that the GCU answered)."""
    RESTARTED = "restarted"
    """The GCU came back from an outage with its state reset (mode, zoom, recording or
    ranging changed in a way no command explains: docs/client.md, "GCU restarts"); the
    detail lists the changes. Emitted by the client, after ``RESTORED``."""


@dataclass(frozen=True)
class LinkEvent:
    kind: LinkEventKind
    detail: str = ""
    peer: tuple[str, int] | None = None


EventHandler = Callable[[LinkEvent], None]


def _drop(data: bytes) -> None:
    return None


def _ignore(event: LinkEvent) -> None:
    return None


class Transport(OpenClose):
    """Base of serial, UDP, TCP and in-memory transports.

    Use as ``async with transport:`` or call :meth:`open` / :meth:`close`. Handlers are set
    with :meth:`set_handlers` before opening and are called from the event loop.
    """

    ordered: bool = True
    """True when packets arrive in the order sent (stream transports). Datagram transports
    (UDP) may reorder; the client then guards commands against it. A fact of the class,
    which the transport registry reports (:class:`~gcu_async.transport.registry.TransportKind`)."""
    datagram: bool = False
    """True when every ``on_data`` call carries exactly one received datagram (UDP), so
    the receiver may deframe each call on its own. False for byte streams."""

    def __init__(self) -> None:
        self._on_data: DataHandler = _drop
        self._on_event: EventHandler = _ignore
        self.sends_dropped = 0
        """Sends dropped because the OS could not take more bytes (backpressure on stream
        transports: see their :meth:`send`). Always 0 on transports that never drop."""

    def set_handlers(self, on_data: DataHandler, on_event: EventHandler | None = None) -> None:
        """Route received bytes to ``on_data`` and link events to ``on_event``."""
        self._on_data = on_data
        self._on_event = on_event if on_event is not None else _ignore

    @property
    @abc.abstractmethod
    def url(self) -> str:
        """Where this transport goes, as a URL (``udp://127.0.0.1:2337``)."""

    @property
    @abc.abstractmethod
    def connected(self) -> bool:
        """True while :meth:`send` can deliver bytes."""

    def reset(self, reason: str) -> None:
        """Discard what is queued towards the peer and start the link over, so that nothing
        queued on the way can reach the peer later. Synchronous, callable from any event-loop
        callback; events it causes are delivered later via ``loop.call_soon``, never from
        inside this call. ``reason`` (text) goes into the detail of such events.

        The default does nothing: transports that queue nothing (UDP, in-memory) keep it.
        Raises TypeError if ``reason`` is not a ``str``."""
        check_reason(reason)

    def caught_up(self, due: float | None = None) -> bool:
        """Optional, for a transport that may reorder: deliver, now, what it received and
        has not delivered yet, and say whether nothing that arrived before a point in time
        is still undelivered, so that whatever it delivers later arrived after that point
        (the session's reorder proofs rely on it: docs/session-contract.md, "Assumptions",
        A4).

        With ``due`` (seconds on :func:`time.monotonic`; the caller is a timer callback of
        a loop whose time is that clock, due then), the point is when this loop iteration
        polled the OS, no earlier than ``due - CLOCK_RESOLUTION``: a transport that reads
        on the loop's level-triggered readiness events may know it without reading.
        Without ``due``, the point is this call. The default, False: it cannot tell (the
        client then assumes a responsive event loop)."""
        return False

    @abc.abstractmethod
    async def open(self) -> None:
        """Open the link. Raises :class:`~gcu_async.errors.LinkLost` if it cannot."""

    @abc.abstractmethod
    def send(self, data: bytes) -> None:
        """Send ``data`` without blocking. Raises :class:`~gcu_async.errors.LinkLost` if
        the link is down. May drop ``data`` (counted in :attr:`sends_dropped`) rather than
        queue it behind bytes the OS has not taken yet."""

    @abc.abstractmethod
    async def close(self) -> None:
        """Close the link and release every socket / fd. Idempotent."""

    def __repr__(self) -> str:
        state = "connected" if self.connected else "closed"
        return f"<{type(self).__name__} {self.url} {state}>"
