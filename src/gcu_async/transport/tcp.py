"""TCP transport: the host is the client, the GCU the server on port 2332 (docs/protocol-notes.md
§12 "Transports").

When an established connection drops, a :attr:`~LinkEventKind.LOST` event is emitted at
once; with ``reconnect=True`` (default) a background task then reconnects with exponential
backoff and full jitter (:class:`Backoff`): before attempt *n* (0-based) it sleeps
``uniform(0, min(cap, base * factor**n))``, by default until it succeeds or the transport
is closed. On success it emits :attr:`~LinkEventKind.RESTORED`; when the opt-in bounds run
out (``max_attempts`` attempts, or ``max_total`` seconds since the loss) it stops, stays
down and emits :attr:`~LinkEventKind.GAVE_UP` (detail ``"giving up after N reconnect
attempts: …"``); with ``reconnect=False`` ``GAVE_UP`` follows the ``LOST`` at once.
:meth:`TcpTransport.open` may be called again after that. While down,
:meth:`TcpTransport.send` raises :class:`LinkLost`.

Backpressure
    :meth:`TcpTransport.send` never queues behind bytes the kernel has not taken: when
    asyncio's write buffer is not empty (the kernel's send queue is full because the peer
    does not read), the new data is dropped whole and counted in ``sends_dropped``. A packet
    is never split or interleaved: the rest of a packet the kernel took in part stays queued
    and goes first. (The kernel's own queues are not bounded by this: see docs/transports.md.)

Reset
    :meth:`TcpTransport.reset` aborts the connection with an RST (``SO_LINGER`` on, 0 s):
    asyncio's write buffer and the kernel's send queue are discarded, so none of those
    bytes can reach the peer later. Bytes that already reached the peer's kernel receive
    buffer are *not* recalled: the peer can still read them (then gets ``ECONNRESET``).
    A ``LOST`` event whose detail starts with ``"reset: <reason>"`` follows via
    ``loop.call_soon``, then reconnection exactly as after any loss.
"""

from __future__ import annotations

import asyncio
import contextlib
import random
import socket
import struct
from typing import Any

from gcu_async.errors import LinkLost
from gcu_async.protocol.links import GCU_TCP_PORT
from gcu_async.transport._common import (
    call_guarded,
    check_port,
    check_positive,
    check_reason,
    format_hostport,
    link_lost,
)
from gcu_async.transport.backoff import (
    Backoff,
    cancel_and_wait,
    giving_up,
    not_reconnecting,
    retry,
)
from gcu_async.transport.base import LinkEvent, LinkEventKind, Transport

_CLOSE_GRACE = 1.0
"""Seconds :meth:`TcpTransport.close` lets unsent bytes flush before aborting."""
_LINGER_ABORT = struct.pack("ii", 1, 0)
"""``struct linger {l_onoff=1, l_linger=0}``: close() sends an RST and drops the send queue."""


class _TcpProtocol(asyncio.Protocol):
    def __init__(self, owner: TcpTransport) -> None:
        self._owner = owner
        self.transport: asyncio.Transport | None = None
        self.attached = False
        self.closed: asyncio.Future[None] = asyncio.get_running_loop().create_future()

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport
        self._owner._made(self)

    def data_received(self, data: bytes) -> None:
        self._owner._data(self, data)

    def eof_received(self) -> bool:
        return False  # close our side too; connection_lost follows

    def connection_lost(self, exc: Exception | None) -> None:
        if not self.closed.done():
            self.closed.set_result(None)
        self._owner._lost(self, exc)


class TcpTransport(Transport):
    """Stream link to a GCU's TCP server at ``host:port``.

    ``connect_timeout`` bounds every connection attempt (seconds). ``reconnect`` enables
    the background reconnection described in the module docstring, scheduled by
    ``backoff`` and randomised by ``rng`` (pass a seeded :class:`random.Random` for
    reproducible delays).
    """

    def __init__(
        self,
        host: str,
        port: int = GCU_TCP_PORT,
        *,
        connect_timeout: float = 3.0,
        reconnect: bool = True,
        backoff: Backoff | None = None,
        rng: random.Random | None = None,
    ) -> None:
        super().__init__()
        if not isinstance(host, str) or not host:
            raise ValueError(f"host: {host!r} is not a host name or address")
        self._host = host
        self._port = check_port("port", port)
        self._connect_timeout = check_positive("connect_timeout", connect_timeout)
        self._reconnect = bool(reconnect)
        self.backoff = backoff if backoff is not None else Backoff()
        self._rng = rng if rng is not None else random.Random()
        self._proto: _TcpProtocol | None = None
        self._live: set[_TcpProtocol] = set()
        self._task: asyncio.Task[None] | None = None
        self._closing = False
        self.bytes_sent = 0
        """Bytes accepted by :meth:`send` (dropped sends excluded)."""
        self.bytes_received = 0
        self.reconnect_attempts = 0
        """Connection attempts made during the current (or last) outage."""
        self.reconnects = 0
        """Outages ended by a successful reconnection."""

    @property
    def url(self) -> str:
        return f"tcp://{format_hostport(self._host, self._port)}"

    @property
    def connected(self) -> bool:
        proto = self._proto
        return (
            proto is not None and proto.transport is not None and not proto.transport.is_closing()
        )

    @property
    def connect_timeout(self) -> float:
        """Seconds allowed for each connection attempt."""
        return self._connect_timeout

    @property
    def reconnect(self) -> bool:
        """Whether a lost connection is re-established in the background."""
        return self._reconnect

    def get_extra_info(self, name: str, default: Any = None) -> Any:
        """asyncio's transport information (``"socket"``, ``"peername"``, ...) while up."""
        proto = self._proto
        if proto is None or proto.transport is None:
            return default
        return proto.transport.get_extra_info(name, default)

    @property
    def reconnecting(self) -> bool:
        """True while the link is down and the background reconnect task is trying."""
        return self._task is not None and not self._task.done() and not self.connected

    async def open(self) -> None:
        """Connect (bounded by ``connect_timeout``). Raises :class:`LinkLost` on failure.

        Does nothing if already connected; stops a running reconnect task first."""
        if self.connected:
            return
        self._closing = False
        await self._stop_task()
        await self._connect(self._connect_timeout)

    def send(self, data: bytes) -> None:
        """Hand ``data`` to the socket, or drop it whole (counted in ``sends_dropped``) when
        asyncio's write buffer still holds bytes the kernel did not take. Raises
        :class:`LinkLost` while the link is down."""
        proto = self._proto
        if proto is None or proto.transport is None or proto.transport.is_closing():
            state = " (reconnecting)" if self.reconnecting else ""
            raise LinkLost(f"{self.url}: link is down{state}")
        if proto.transport.get_write_buffer_size():
            self.sends_dropped += 1
            return
        self.bytes_sent += len(data)
        proto.transport.write(bytes(data))

    def reset(self, reason: str) -> None:
        """Abort the connection with an RST, discarding asyncio's write buffer and the
        kernel's send queue; then (via ``loop.call_soon``) emit ``LOST`` with detail
        ``"reset: <reason> (<url>)"`` and, with ``reconnect=True``, reconnect as after any
        loss (``reconnect=False``: ``GAVE_UP`` follows the ``LOST``). :meth:`send` raises
        :class:`LinkLost` from this call on until reconnected. Bytes already in the peer's
        receive buffer stay readable by the peer. Does nothing while the link is down.
        Raises TypeError if ``reason`` is not a ``str``."""
        check_reason(reason)
        proto = self._proto
        if proto is None or proto.transport is None or proto.transport.is_closing():
            return
        self._proto = None
        transport = proto.transport
        sock = transport.get_extra_info("socket")
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, _LINGER_ABORT)
        transport.abort()  # drops the write buffer; closes the socket on the next iteration
        asyncio.get_running_loop().call_soon(self._reset_event, reason)
        self._start_reconnect()

    async def close(self) -> None:
        """Stop reconnecting and close the socket; returns once everything is released.
        Idempotent."""
        self._closing = True
        self._proto = None
        await self._stop_task()
        protos = list(self._live)
        if not protos:
            return
        for proto in protos:
            if proto.transport is not None:
                proto.transport.close()
        closed = [proto.closed for proto in protos]
        await asyncio.wait(closed, timeout=_CLOSE_GRACE)
        for proto in protos:
            if not proto.closed.done() and proto.transport is not None:
                proto.transport.abort()
        await asyncio.wait(closed)

    # -- connection management -------------------------------------------------------------

    async def _connect(self, timeout: float) -> None:
        loop = asyncio.get_running_loop()
        made: list[_TcpProtocol] = []

        def factory() -> _TcpProtocol:
            proto = _TcpProtocol(self)
            made.append(proto)
            return proto

        try:
            await asyncio.wait_for(loop.create_connection(factory, self._host, self._port), timeout)
        except asyncio.TimeoutError as exc:
            if made and made[0].attached:
                return  # connected just as the timeout fired: keep it
            raise link_lost(self.url, f"connect timed out after {timeout:g} s", exc) from exc
        except OSError as exc:
            raise link_lost(self.url, "cannot connect", exc) from exc
        if not made or not made[0].attached:
            reason = "transport closed" if self._closing else "socket connected to itself"
            raise LinkLost(f"{self.url}: cannot connect: {reason}")

    async def _stop_task(self) -> None:
        task, self._task = self._task, None
        await cancel_and_wait(task)

    async def _reconnect_loop(self) -> None:
        self.reconnect_attempts = 0

        def counted(n: int) -> None:
            self.reconnect_attempts = n

        try:
            last = await retry(self._connect, self.backoff, self._rng, self._connect_timeout,
                               counted)  # fmt: skip
            if last is not None:
                call_guarded(self._on_event, giving_up(self.url, self.reconnect_attempts, last),
                             "event")  # fmt: skip
        finally:
            if self._task is asyncio.current_task():
                self._task = None

    # -- callbacks from _TcpProtocol --------------------------------------------------------

    def _made(self, proto: _TcpProtocol) -> None:
        transport = proto.transport
        assert transport is not None
        self._live.add(proto)
        if self._closing:
            transport.abort()
            return
        if transport.get_extra_info("sockname") == transport.get_extra_info("peername"):
            transport.abort()  # TCP simultaneous open on loopback: no server there
            return
        restoring = self.reconnecting
        proto.attached = True
        self._proto = proto
        if restoring:
            self.reconnects += 1
            detail = f"{self.url}: reconnected after {self.reconnect_attempts} attempt(s)"
            call_guarded(self._on_event, LinkEvent(LinkEventKind.RESTORED, detail), "event")

    def _data(self, proto: _TcpProtocol, data: bytes) -> None:
        if proto is self._proto:
            self.bytes_received += len(data)
            call_guarded(self._on_data, data, "data")

    def _lost(self, proto: _TcpProtocol, exc: Exception | None) -> None:
        self._live.discard(proto)
        if proto is not self._proto:
            return
        self._proto = None
        if self._closing:
            return
        reason = f"connection lost: {exc}" if exc is not None else "peer closed the connection"
        event = LinkEvent(LinkEventKind.LOST, f"{self.url}: {reason}")
        call_guarded(self._on_event, event, "event")
        if not self._reconnect:
            call_guarded(self._on_event, not_reconnecting(self.url), "event")
        self._start_reconnect()

    def _reset_event(self, reason: str) -> None:
        if not self._closing:  # a deliberate close() since: no event, as for any close
            event = LinkEvent(LinkEventKind.LOST, f"reset: {reason} ({self.url})")
            call_guarded(self._on_event, event, "event")
            if not self._reconnect:
                call_guarded(self._on_event, not_reconnecting(self.url), "event")

    def _start_reconnect(self) -> None:
        if self._reconnect and not self._closing and self._proto is None:
            self._task = asyncio.get_running_loop().create_task(
                self._reconnect_loop(), name=f"gcu_async reconnect {self.url}"
            )
