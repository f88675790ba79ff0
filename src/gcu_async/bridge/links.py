"""MAVLink links on asyncio transports, pymavlink only for framing (docs/mavlink-bridge.md,
"Links").

pymavlink's connection classes block (``recv_match`` waits, ``autoreconnect`` sleeps in the
caller's thread, a TCP connect blocks) and share one parser among every sender of a
``udpin`` socket, so the bridge does not use them: each link here is an asyncio transport
(datagram endpoint, TCP connection or server, pyserial-asyncio port) on the event loop's
thread, and every peer — each UDP sender address, each TCP connection, the serial port — has
its own pymavlink ``MAVLink`` parser. Nothing on the loop's thread blocks: name lookups and
opening a serial device run in a daemon thread (at most one per link at a time), awaited
with a timeout.

One owner per connection: the link's owner task opens the transport, waits for its loss and
reopens it every :data:`RETRY_SECONDS` (each attempt bounded by :data:`OPEN_TIMEOUT`);
nothing else creates or replaces a transport. :meth:`MavlinkLink.close` cancels the owner and
aborts the transports at once.

Received bytes are queued (at most :data:`INBOX_BYTES` per link: UDP datagrams beyond it are
dropped and counted, stream links stop reading until it drains) and parsed on the loop for at
most :data:`DRAIN_SECONDS` per loop iteration, so a flood cannot hold the loop. Writing never
waits: a peer whose transport already holds :data:`SEND_BUFFER_BYTES` unsent bytes misses the
message (counted in ``dropped_out``).
"""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import logging
import socket
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any, TypeVar

from gcu_async.bridge._mavlink import mavlink, new_parser
from gcu_async.bridge.endpoint import Endpoint

log = logging.getLogger("gcu_async.bridge")
T = TypeVar("T")

SILENCE_SECONDS = 3.0
"""No message for this long counts as a lost MAVLink link (logged; restored on the next)."""
RETRY_SECONDS = 1.0
"""Pause between attempts to reopen a lost connection (and to connect a ``tcp:`` link)."""
OPEN_TIMEOUT = 2.0
"""Longest one open attempt may take (name lookup, TCP connect, serial open)."""
INBOX_BYTES = 256 * 1024
"""Most received bytes a link holds unparsed."""
DRAIN_SECONDS = 0.002
"""Longest the link parses and delivers in one event-loop iteration."""
SEND_BUFFER_BYTES = 64 * 1024
"""Most unsent bytes a peer's transport may hold; beyond it messages to that peer are dropped."""
LOG_INTERVAL = 10.0
"""A repeating log line of one kind appears at most once per this many seconds per link."""

STATION_SECONDS = 5.0
"""A ``udpin`` sender is a station for this long after its last HEARTBEAT (ground stations
send one a second; MAVLink counts a peer lost after about five missed)."""

OnMessage = Callable[["MavlinkLink", "Peer", Any], None]
HEARTBEAT = mavlink.MAVLINK_MSG_ID_HEARTBEAT


class Peer:
    """One source of bytes with its own parser: a UDP sender address, a TCP connection, the
    serial port. ``valid_at`` is when it last sent a valid MAVLink message, ``heartbeat_at``
    a HEARTBEAT; ``share`` is the bridge's bookkeeping for it while it holds a share of its
    own (:meth:`MavlinkLink.own_share`), which goes when the link forgets the peer."""

    __slots__ = ("addr", "heartbeat_at", "parser", "share", "stream", "transport", "valid_at")

    def __init__(self, transport: Any, addr: Any = None, *, stream: bool = False) -> None:
        self.transport = transport
        self.addr = addr
        self.stream = stream
        self.parser = new_parser()
        self.valid_at: float | None = None
        self.heartbeat_at: float | None = None
        self.share: Any = None

    def heartbeating(self, now: float) -> bool:
        """A HEARTBEAT came from it within :data:`STATION_SECONDS`."""
        return self.heartbeat_at is not None and now - self.heartbeat_at <= STATION_SECONDS


class MavlinkLink:
    """A link that, once :meth:`open`, calls ``on_message(link, msg)`` on the loop for every
    valid message, and writes what :meth:`send` gets to its destinations."""

    def __init__(self, endpoint: Endpoint) -> None:
        self.endpoint = endpoint
        self.url = endpoint.text
        self.received = 0
        """Valid messages handled (counted by :meth:`note_message`)."""
        self.bad_data = 0
        """Byte runs that were no valid MAVLink message (bad framing or CRC, or a message id
        the dialect does not know: its CRC cannot be checked)."""
        self.send_errors = 0
        """Writes the operating system refused (peer unreachable)."""
        self.dropped_in = 0
        """Datagrams dropped unparsed because :data:`INBOX_BYTES` were waiting."""
        self.dropped_out = 0
        """Messages not written to a peer whose transport held :data:`SEND_BUFFER_BYTES`."""
        self.reopened = 0
        """Connections the owner task made after a loss or a failed attempt."""
        self.last_message: float | None = None
        self.up = False
        self.pool: Any = None
        """The bridge's bookkeeping for the peers without a share of their own."""
        self._on_message: OnMessage | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._owner: asyncio.Task[None] | None = None
        self._inbox: dict[Peer, deque[list[Any]]] = {}
        """Peer → its received byte runs ([bytes, parsing begun]), peers in turn order."""
        self._inbox_bytes = 0
        self._paused: set[Any] = set()
        self._drain_handle: asyncio.Handle | None = None
        self._thread_done: asyncio.Future[None] | None = None
        self._logged: dict[str, float] = {}
        self._closing = False

    # -- lifecycle --------------------------------------------------------------------------
    async def open(self, on_message: OnMessage) -> None:
        """Open the connection (OSError if a listener cannot bind or a serial device cannot
        open; a ``tcp:`` peer that is not there yet is retried in the background) and start
        the owner task."""
        self._on_message = on_message
        self._loop = asyncio.get_running_loop()
        lost = await self._first_open()
        self._owner = self._loop.create_task(self._own(lost), name=f"mavlink {self.url}")
        log.info("mavlink %s: open", self.url)

    async def _first_open(self) -> asyncio.Future[str] | None:
        """The first connection (None: the owner task makes it in the background)."""
        return await asyncio.wait_for(self._connect(), OPEN_TIMEOUT)

    async def _connect(self) -> asyncio.Future[str]:
        """Open the transport(s); the returned future completes, with the reason, when the
        connection is lost."""
        raise NotImplementedError

    async def _own(self, lost: asyncio.Future[str] | None) -> None:
        first = lost is None  # never connected yet: try at once
        outage = False
        while True:
            if lost is not None:
                reason = await lost
                if self._closing:
                    return
                log.warning("mavlink %s: %s; reopening every %g s", self.url, reason,
                            RETRY_SECONDS)  # fmt: skip
                outage = True
            if not first:
                await asyncio.sleep(RETRY_SECONDS)
            try:
                lost = await asyncio.wait_for(self._connect(), OPEN_TIMEOUT)
            except (OSError, TimeoutError) as exc:
                lost = None
                self.log_every("reopen", logging.WARNING, "cannot connect (%s); retrying "
                               "every %g s", exc or "timeout", RETRY_SECONDS)  # fmt: skip
                outage = outage or first
            else:
                if not first:
                    self.reopened += 1
                if outage:
                    log.warning("mavlink %s: connected", self.url)
                outage = False
            first = False

    async def close(self) -> None:
        """Stop the owner task, abort every transport and drop what is queued (no waiting
        on a peer)."""
        self._closing = True
        owner, self._owner = self._owner, None
        if owner is not None:
            owner.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await owner
        self._abort()
        if self._drain_handle is not None:
            self._drain_handle.cancel()
            self._drain_handle = None
        self._inbox.clear()
        self._inbox_bytes = 0
        await asyncio.sleep(0)  # the transports' sockets close in their connection_lost
        log.info("mavlink %s: closed", self.url)

    def _abort(self) -> None:
        raise NotImplementedError

    # -- receiving --------------------------------------------------------------------------
    def feed(self, peer: Peer, data: bytes, *, stream: bool) -> None:
        """Queue ``data`` from ``peer``: a datagram is dropped when the inbox is full, a
        stream's transport stops reading until the inbox has drained to half."""
        if not data or self._closing:
            return
        if not stream and self._inbox_bytes + len(data) > INBOX_BYTES:
            self.dropped_in += 1
            return
        runs = self._inbox.get(peer)
        if runs is None:
            runs = self._inbox[peer] = deque()
        runs.append([data, False])
        self._inbox_bytes += len(data)
        if stream and self._inbox_bytes > INBOX_BYTES and peer.transport not in self._paused:
            with contextlib.suppress(RuntimeError, AttributeError):
                peer.transport.pause_reading()
                self._paused.add(peer.transport)
        if self._drain_handle is None and self._loop is not None:
            self._drain_handle = self._loop.call_soon(self._drain)

    def _drain(self) -> None:
        """Parse and deliver for at most :data:`DRAIN_SECONDS`, one message per peer in
        turn: a peer with a backlog (a flood) delays another peer's next message by one
        message of each peer with bytes waiting, not by its whole backlog."""
        self._drain_handle = None
        deadline = time.monotonic() + DRAIN_SECONDS
        inbox = self._inbox
        while inbox:
            peer = next(iter(inbox))
            runs = inbox.pop(peer)
            run = runs[0]
            data, begun = run
            run[1] = True
            msg = self._parse(peer, b"" if begun else data)
            if msg is None:
                runs.popleft()
                self._inbox_bytes -= len(data)
            if runs:
                inbox[peer] = runs  # to the back: the next peer's turn
            if msg is not None:
                self._deliver(peer, msg)
            if time.monotonic() >= deadline:
                break
        if self._paused and self._inbox_bytes <= INBOX_BYTES // 2:
            for transport in self._paused:
                with contextlib.suppress(RuntimeError, AttributeError):
                    transport.resume_reading()
            self._paused.clear()
        if inbox and self._loop is not None and not self._closing:
            self._drain_handle = self._loop.call_soon(self._drain)

    def _parse(self, peer: Peer, data: bytes) -> Any:
        try:
            return peer.parser.parse_char(data)
        except Exception as exc:  # a hostile byte stream must not stop the link
            self.bad_data += 1
            peer.parser = new_parser()
            log.debug("mavlink %s: parser reset: %s", self.url, exc)
            return None

    def _deliver(self, peer: Peer, msg: Any) -> None:
        if msg.get_type() == "BAD_DATA" or isinstance(msg, mavlink.MAVLink_unknown):
            # an unknown message id has no CRC extra, so pymavlink cannot check its CRC:
            # random bytes pass for one about once per 10^4 frames; it is not taken as valid
            self.bad_data += 1
            return
        now = time.monotonic()
        peer.valid_at = now
        if msg.get_msgId() == HEARTBEAT:
            peer.heartbeat_at = now
        self.heard_valid(peer, now)
        assert self._on_message is not None
        try:
            self._on_message(self, peer, msg)
        except Exception as exc:  # the receiver's fault; the link goes on
            self.log_every("handler", logging.WARNING, "handling %s failed: %r",
                           msg.get_type(), exc)  # fmt: skip

    def heard_valid(self, peer: Peer, now: float) -> None:
        """``peer`` sent a valid message (a listener may make it a destination)."""

    def own_share(self, peer: Peer, now: float) -> bool:
        """Does ``peer`` hold a command share of its own (a *station*), or share the link's
        pool with the others? Here: the one peer of a ``udpout``, ``tcp`` or serial link,
        which the operator named (``udpin`` and ``tcpin`` say otherwise)."""
        return True

    def peer_name(self, peer: Peer) -> str:
        """``peer`` for the log: the link, and the sender's address where there are many."""
        return self.url if peer.addr is None else f"{self.url} from {peer.addr}"

    # -- sending ----------------------------------------------------------------------------
    def send(self, data: bytes) -> None:
        """Write one packed message to every destination, never waiting."""
        for peer in self.destinations():
            self.send_to(peer, data)

    def send_to(self, peer: Peer, data: bytes) -> None:
        """Write one packed message to ``peer`` alone, never waiting (an answer goes to the
        peer that asked, whether or not it is a destination: it sent a valid message)."""
        transport = peer.transport
        if transport is None or transport.is_closing():
            return
        if transport.get_write_buffer_size() > SEND_BUFFER_BYTES:
            self.dropped_out += 1
            return
        try:
            if peer.stream:
                transport.write(data)
            else:
                transport.sendto(data, peer.addr)
        except (OSError, ValueError, RuntimeError) as exc:
            self.send_errors += 1
            self.log_every("send", logging.DEBUG, "send failed: %s", exc)

    def destinations(self) -> list[Peer]:
        """The peers :meth:`send` writes to now (a snapshot)."""
        raise NotImplementedError

    # -- health -------------------------------------------------------------------------------
    def note_message(self, now: float) -> None:
        """Count a message (on the loop) and log the link coming up."""
        self.received += 1
        self.last_message = now
        if not self.up:
            self.up = True
            if self.received > 1:  # after a loss, which was a warning
                log.warning("mavlink %s: traffic restored", self.url)
            else:
                log.info("mavlink %s: traffic started", self.url)

    def check_silence(self, now: float) -> None:
        """Log the link as lost after :data:`SILENCE_SECONDS` without a message."""
        if self.up and self.last_message is not None and now - self.last_message > SILENCE_SECONDS:
            self.up = False
            log.warning("mavlink %s: no message for %g s: link lost", self.url, SILENCE_SECONDS)

    def log_every(self, key: str, level: int, fmt: str, *args: Any) -> None:
        """Log ``fmt % args`` unless a line of kind ``key`` was logged less than
        :data:`LOG_INTERVAL` s ago."""
        now = time.monotonic()
        if now - self._logged.get(key, -LOG_INTERVAL) >= LOG_INTERVAL:
            self._logged[key] = now
            log.log(level, "mavlink %s: " + fmt, self.url, *args)

    # -- helpers for the subclasses -----------------------------------------------------------
    async def in_thread(self, fn: Callable[[], T], discard: Callable[[T], None]) -> T:
        """``fn()`` in a daemon thread (so neither the loop nor the interpreter's exit waits
        for it); a result nobody awaits any more is passed to ``discard``. A call still
        running from an earlier, timed-out attempt is awaited instead of starting another
        thread, so a link never has more than one."""
        loop = asyncio.get_running_loop()
        running = self._thread_done
        if running is not None and not running.done():
            await asyncio.shield(running)
        fut: asyncio.Future[T] = loop.create_future()
        done: asyncio.Future[None] = loop.create_future()
        self._thread_done = done

        def settle(ok: bool, value: Any) -> None:
            if not done.done():
                done.set_result(None)
            if fut.cancelled():
                if ok:
                    discard(value)
            elif ok:
                fut.set_result(value)
            else:
                fut.set_exception(value)

        def run() -> None:
            try:
                result: Any = fn()
                ok = True
            except BaseException as exc:  # handed to the awaiting task
                result, ok = exc, False
            try:
                loop.call_soon_threadsafe(settle, ok, result)
            except RuntimeError:  # the loop has closed
                if ok:
                    discard(result)

        threading.Thread(target=run, name=f"mavlink {self.url}", daemon=True).start()
        return await fut

    async def resolve(self, host: str, port: int, kind: int) -> tuple[Any, ...]:
        """The socket address for ``host`` (a literal at once, a name in a daemon thread)."""
        with contextlib.suppress(ValueError):
            ip = ipaddress.ip_address(host)
            return (host, port) if ip.version == 4 else (host, port, 0, 0)
        infos = await self.in_thread(
            lambda: socket.getaddrinfo(host, port, type=kind), lambda _: None)
        if not infos:
            raise OSError(f"no address for {host!r}")
        return tuple(infos[0][4])

