"""UDP transport: the host listens on a local port (2338) and sends to the GCU (port 2337).

docs/protocol-notes.md §12 "Transports": the GCU sends from port 2337 to the LAN broadcast address,
port 2338; emulators answer by unicast to the sender. The socket is therefore *not* connected: it
binds ``local_host:local_port`` (wildcard by default, so broadcasts arrive) and filters sources
itself.

Source filtering
    By default only datagrams whose source is the configured GCU ``(host, port)`` are
    delivered; any other datagram is counted in :attr:`UdpTransport.rejected_datagrams` and
    dropped. With ``discovery=True`` every source is accepted; whenever a datagram comes
    from an address other than the current :attr:`UdpTransport.peer` the peer is updated and
    a :attr:`~LinkEventKind.PEER` event (``peer=(host, port)``) is emitted *before* its
    bytes are delivered. Sends still go to the configured address unless
    ``follow_peer=True``, in which case they go to the most recently discovered peer.
    Note: a GCU answers from its own unicast address, so when ``host`` is a broadcast
    address use ``discovery=True`` or nothing will be accepted.

Sharing the port
    With a fixed ``local_port`` (2338 by default) the socket sets SO_REUSEPORT where the
    platform has it (Linux, macOS, BSD; not Windows), so several processes of the *same
    user* can listen on 2338 at once (an application and ``gcu-async monitor``): every
    broadcast datagram reaches all of them. A *unicast* datagram to that port reaches only
    one of them (Linux picks by a hash of the addresses), so sharing suits a real GCU, which
    broadcasts, not an emulator that answers by unicast. ``reuse_port=False`` binds
    exclusively. With ``local_port=0`` it is not set: the kernel could then hand two sockets
    the same ephemeral port. See docs/transports.md, "Network topology".

Reading
    Every readiness event reads *all* queued datagrams (up to 10,000 per event, so one
    socket cannot starve the loop), each delivered by its own ``on_data`` call
    (:attr:`UdpTransport.datagram` is True): however long an event-loop iteration takes,
    replies never pile up in the kernel. asyncio's own datagram transport reads one per
    event; it is used only on loops without ``add_reader`` (Windows' proactor loop), where
    :attr:`UdpTransport.draining` is False.

Errors
    UDP is connectionless: send errors (``EMSGSIZE``, ``BlockingIOError`` when the socket's
    send buffer is full: that datagram is dropped, never queued) and ICMP errors (port
    unreachable: nothing listens at the GCU's address yet; host or network unreachable) are
    counted in :attr:`UdpTransport.send_errors` and kept in :attr:`UdpTransport.last_error`;
    the transport stays usable. The first error of an *episode* (since the socket was opened
    or since the last datagram from the GCU) is reported as an :attr:`~LinkEventKind.ERROR`
    link event, so an application learns at once that its GCU's port is unreachable instead
    of seeing only silence. On Linux the socket reads ICMP errors from its error queue
    (``IP_RECVERR``: an unconnected socket hears of none otherwise; see
    :mod:`gcu_async.transport._datagram`), each named with its sender and the datagram's
    destination. Windows reports an ICMP port unreachable by a later *receive*
    (``ConnectionResetError``); there the socket is told not to (``SIO_UDP_CONNRESET`` off,
    see :func:`ignore_icmp_connreset`), since the proactor loop of Python 3.10–3.12 stops
    reading a datagram socket after one. Silence is detected by the session's link health,
    not here. :meth:`~gcu_async.transport.Transport.reset` does nothing: no datagram is ever
    queued.

Reopening
    Errors never close the socket. If it is closed all the same (by the event loop, after an
    error it cannot handle), a :attr:`~LinkEventKind.LOST` event follows and, with
    ``reconnect=True`` (default), a background task binds a new socket on the same local
    address with :attr:`UdpTransport.backoff` (by default every 0–2 s until it succeeds or
    the transport is closed), then emits :attr:`~LinkEventKind.RESTORED`; when opt-in bounds
    run out (or with ``reconnect=False``) it emits :attr:`~LinkEventKind.GAVE_UP`, as TCP and
    serial do. A GCU that goes silent is not a loss here: the session's link health says
    the link is down, and up again with the next reply, however long the silence.
"""

from __future__ import annotations

import asyncio
import ipaddress
import random
import socket
from typing import Any

from gcu_async.errors import LinkLost
from gcu_async.protocol.links import GCU_UDP_PORT, HOST_UDP_PORT
from gcu_async.transport._common import (
    call_guarded,
    check_port,
    format_hostport,
    link_lost,
    same_address,
)
from gcu_async.transport._datagram import DrainingDatagramTransport
from gcu_async.transport._reopen import Reopener, Reopening
from gcu_async.transport.backoff import Backoff
from gcu_async.transport.base import LinkEvent, LinkEventKind, Transport

MAX_DATAGRAM = 65536
"""Receive buffer size: no UDP payload is larger. (On the fallback path, asyncio's default
of 256 KiB is above glibc's mmap threshold: an mmap/mremap/munmap per received datagram.)"""


def is_broadcast_address(host: str) -> bool:
    """True for 255.255.255.255 and IPv4 addresses ending in .255 (the broadcast address of
    any /24 or wider subnet; setting SO_BROADCAST for a unicast .255 host is harmless)."""
    try:
        ip = ipaddress.ip_address(host)
    except ValueError:
        return False
    return isinstance(ip, ipaddress.IPv4Address) and ip.packed[3] == 255


def _reuse_port(requested: bool | None, local_port: int) -> bool:
    """Resolve ``reuse_port``: None means "when the port is fixed and the platform can"."""
    available = hasattr(socket, "SO_REUSEPORT")
    if requested is None:
        return available and local_port != 0
    if not isinstance(requested, bool):
        raise ValueError(f"reuse_port: {requested!r} is not True, False or None")
    if requested and not available:
        raise ValueError("reuse_port: True is not possible here (the platform has no SO_REUSEPORT)")
    return requested


def ignore_icmp_connreset(sock: socket.socket) -> bool:
    """Windows: keep ``recvfrom`` on ``sock`` from failing with WSAECONNRESET after an ICMP
    port unreachable (the ``SIO_UDP_CONNRESET`` ioctl, off). Returns whether it was applied;
    elsewhere (no such ioctl) it does nothing and returns False."""
    code = getattr(socket, "SIO_UDP_CONNRESET", None)
    ioctl = getattr(sock, "ioctl", None)
    if code is None or ioctl is None:
        return False
    try:
        ioctl(code, False)
    except OSError:
        return False
    return True


async def _endpoint(
    loop: asyncio.AbstractEventLoop, sock: socket.socket, proto: _UdpProtocol
) -> asyncio.DatagramTransport:
    """A draining transport where the loop has ``add_reader``; else asyncio's own."""
    try:
        # IPv4 addresses come as (str, int) already: straight to the owner, one call less
        # per datagram (IPv6 ones are 4-tuples: through the protocol, which shortens them)
        deliver = proto.owner._datagram if sock.family == socket.AF_INET else None
        return DrainingDatagramTransport(loop, sock, proto, MAX_DATAGRAM, deliver)
    except NotImplementedError:  # e.g. Windows' proactor loop
        pass
    dtransport, _ = await loop.create_datagram_endpoint(lambda: proto, sock=sock)
    if getattr(dtransport, "max_size", 0) > MAX_DATAGRAM:  # a selector loop's transport
        dtransport.max_size = MAX_DATAGRAM  # type: ignore[attr-defined]
    return dtransport


class _UdpProtocol(asyncio.DatagramProtocol):
    def __init__(self, owner: UdpTransport) -> None:
        self.owner = owner
        self.closed: asyncio.Future[None] = asyncio.get_running_loop().create_future()

    def datagram_received(self, data: bytes, addr: tuple[Any, ...]) -> None:
        self.owner._datagram(data, (str(addr[0]), int(addr[1])))

    def error_received(self, exc: Exception) -> None:
        self.owner._error(exc)

    def connection_lost(self, exc: Exception | None) -> None:
        if not self.closed.done():
            self.closed.set_result(None)
        self.owner._lost(self, exc)


class UdpTransport(Reopening, Transport):
    """Datagram link to a GCU at ``host:port``.

    ``local_host`` defaults to the wildcard address of the remote's address family;
    ``local_port`` 0 picks an ephemeral port (see :attr:`local_address`). ``broadcast``
    sets SO_BROADCAST; ``None`` (default) sets it when ``host`` looks like a broadcast
    address (see :func:`is_broadcast_address`). ``reuse_port`` sets SO_REUSEPORT; ``None``
    (default) sets it when ``local_port`` is not 0 and the platform has it. ``discovery``,
    ``follow_peer`` and ``reuse_port``: see the module docstring.
    """

    ordered = False
    """UDP datagrams may arrive out of order."""
    datagram = True
    """Every ``on_data`` call carries exactly one datagram."""

    def __init__(
        self,
        host: str,
        port: int = GCU_UDP_PORT,
        *,
        local_host: str | None = None,
        local_port: int = HOST_UDP_PORT,
        broadcast: bool | None = None,
        discovery: bool = False,
        follow_peer: bool = False,
        reuse_port: bool | None = None,
        reconnect: bool = True,
        backoff: Backoff | None = None,
        rng: random.Random | None = None,
    ) -> None:
        super().__init__()
        if not isinstance(host, str) or not host:
            raise ValueError(f"host: {host!r} is not a host name or address")
        self._host = host
        self._port = check_port("port", port)
        self._local_host = local_host
        self._local_port = check_port("local_port", local_port, allow_zero=True)
        self._broadcast = is_broadcast_address(host) if broadcast is None else bool(broadcast)
        self._discovery = bool(discovery)
        self._follow_peer = bool(follow_peer)
        self._reuse_port = _reuse_port(reuse_port, self._local_port)
        self._reopen = Reopener(reconnect, backoff, rng)
        self._erring = False  # an ERROR event was emitted and no datagram has arrived since
        self._proto: _UdpProtocol | None = None
        self._dtransport: asyncio.DatagramTransport | None = None
        self._remote: tuple[str, int] | None = None
        self._peer: tuple[str, int] | None = None
        self._local: tuple[str, int] | None = None
        self.rx_datagrams = 0
        """Datagrams delivered to the data handler."""
        self.rejected_datagrams = 0
        """Datagrams dropped because they came from another source than the GCU."""
        self.tx_datagrams = 0
        """Datagrams handed to the OS."""
        self.send_errors = 0
        """Errors reported by the OS for this socket (sends and ICMP); never fatal."""
        self.last_error: Exception | None = None
        """The most recent of those errors."""

    @property
    def url(self) -> str:
        return f"udp://{format_hostport(self._host, self._port)}"

    @property
    def connected(self) -> bool:
        return self._dtransport is not None and not self._dtransport.is_closing()

    @property
    def draining(self) -> bool:
        """True while open on a loop with ``add_reader``: each readiness event reads every
        queued datagram. False before :meth:`open` and on the fallback (proactor) path."""
        return isinstance(self._dtransport, DrainingDatagramTransport)

    @property
    def broadcast(self) -> bool:
        """Whether SO_BROADCAST is (to be) set on the socket."""
        return self._broadcast

    @property
    def reuse_port(self) -> bool:
        """Whether SO_REUSEPORT is (to be) set: other sockets of this user may then bind
        the same local port, and broadcasts reach all of them."""
        return self._reuse_port

    @property
    def discovery(self) -> bool:
        """Whether datagrams from any source are accepted."""
        return self._discovery

    @property
    def follow_peer(self) -> bool:
        """Whether sends go to the discovered peer instead of the configured address."""
        return self._follow_peer

    @property
    def local_port(self) -> int:
        """The configured local port (0 = ephemeral; see :attr:`local_address`)."""
        return self._local_port

    @property
    def local_host(self) -> str | None:
        """The configured local address (None = wildcard)."""
        return self._local_host

    def get_extra_info(self, name: str, default: Any = None) -> Any:
        """asyncio's transport information (``"socket"``, ``"sockname"``, ...) while open."""
        if self._dtransport is None:
            return default
        return self._dtransport.get_extra_info(name, default)

    @property
    def peer(self) -> tuple[str, int] | None:
        """Where datagrams are accepted from: the resolved GCU address, or with
        ``discovery=True`` the last source that answered (None until one did)."""
        return self._peer

    @property
    def remote_address(self) -> tuple[str, int] | None:
        """Where :meth:`send` sends to right now (resolved), or None before :meth:`open`."""
        if self._follow_peer and self._peer is not None:
            return self._peer
        return self._remote

    @property
    def local_address(self) -> tuple[str, int] | None:
        """The bound (host, port) once open; useful with ``local_port=0``."""
        return self._local

    async def open(self) -> None:
        """Resolve the GCU address, bind the local socket and start receiving.

        Raises :class:`LinkLost` if the host cannot be resolved or the port bound. Stops a
        running reopen task first."""
        if self.connected:
            return
        self._reopen.closing = False
        await self._reopen.stop()
        await self._bind()

    async def _bind(self, timeout: float | None = None) -> None:
        """Bind a socket and start receiving (``timeout``: unused, for :func:`retry`)."""
        loop = asyncio.get_running_loop()
        try:
            infos = await loop.getaddrinfo(
                self._host, self._port, type=socket.SOCK_DGRAM, proto=socket.IPPROTO_UDP
            )
        except OSError as exc:
            raise link_lost(self.url, f"cannot resolve {self._host!r}", exc) from exc
        family, _, _, _, sockaddr = infos[0]
        remote = (str(sockaddr[0]), int(sockaddr[1]))
        wildcard = "::" if family == socket.AF_INET6 else "0.0.0.0"
        local_host = self._local_host if self._local_host is not None else wildcard
        sock = socket.socket(family, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
        try:
            if self._broadcast:
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_BROADCAST, 1)
            if self._reuse_port:
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEPORT, 1)
            sock.bind((local_host, self._local_port))
            sock.setblocking(False)
            ignore_icmp_connreset(sock)
            proto = _UdpProtocol(self)
            dtransport = await _endpoint(loop, sock, proto)
        except OSError as exc:
            sock.close()
            where = format_hostport(local_host, self._local_port)
            raise link_lost(self.url, f"cannot bind {where}", exc) from exc
        except BaseException:
            sock.close()
            raise
        bound = sock.getsockname()
        self._local = (str(bound[0]), int(bound[1]))
        self._remote = remote
        self._peer = None if self._discovery else remote
        self._proto = proto
        self._dtransport = dtransport
        self._erring = False

    def send(self, data: bytes) -> None:
        """Send one datagram to :attr:`remote_address`. Raises :class:`LinkLost` if closed.

        OS errors are counted (:attr:`send_errors`), not raised: see the module docstring."""
        dtransport = self._dtransport
        dest = self._peer if self._follow_peer and self._peer is not None else self._remote
        if dtransport is None or dtransport.is_closing() or dest is None:
            raise LinkLost(f"{self.url}: transport is closed")
        self.tx_datagrams += 1
        dtransport.sendto(data if type(data) is bytes else bytes(data), dest)

    def caught_up(self, due: float | None = None) -> bool:
        """The arrival hook (:meth:`~gcu_async.transport.Transport.caught_up`): on the
        draining reader (:attr:`draining`), True once nothing that arrived before the point
        in time it names is unread (it may read and deliver to make sure). False on the
        fallback path (no ``add_reader``: Windows' proactor loop), which cannot tell."""
        dtransport = self._dtransport
        return (isinstance(dtransport, DrainingDatagramTransport)
                and not dtransport.is_closing() and dtransport.caught_up(due))  # fmt: skip

    async def close(self) -> None:
        """Stop reopening, close the socket; returns once it is released. Idempotent."""
        self._reopen.closing = True
        await self._reopen.stop()
        dtransport, proto = self._dtransport, self._proto
        self._dtransport = None
        if dtransport is None or proto is None:
            return
        dtransport.close()
        await asyncio.shield(proto.closed)

    # -- callbacks from _UdpProtocol ------------------------------------------------------

    def _datagram(self, data: bytes, source: tuple[str, int]) -> None:
        if self._dtransport is None:
            return
        if self._discovery:
            if self._peer is None or not same_address(self._peer, source):
                self._peer = source
                event = LinkEvent(
                    LinkEventKind.PEER, f"{self.url}: datagram from {format_hostport(*source)}",
                    peer=source,
                )  # fmt: skip
                call_guarded(self._on_event, event, "event")
        elif source != self._remote and (self._remote is None
                                         or not same_address(self._remote, source)):  # fmt: skip
            self.rejected_datagrams += 1
            return
        self.rx_datagrams += 1
        if self._erring:
            self._erring = False  # the episode is over: the next error is reported again
        try:  # call_guarded, inline: this runs for every datagram
            self._on_data(data)
        except Exception as exc:
            asyncio.get_running_loop().call_exception_handler(
                {"message": "gcu_async transport: data handler raised", "exception": exc}
            )

    def _error(self, exc: Exception) -> None:
        self.send_errors += 1
        self.last_error = exc
        if not self._erring and self._dtransport is not None:
            self._erring = True
            event = LinkEvent(LinkEventKind.ERROR, f"{self.url}: {exc}")
            call_guarded(self._on_event, event, "event")

    def _lost(self, proto: _UdpProtocol, exc: Exception | None) -> None:
        if proto is not self._proto or self._dtransport is None:
            return  # closed by us
        self._dtransport = None
        detail = f"{self.url}: socket closed" + (f": {exc}" if exc else "")
        call_guarded(self._on_event, LinkEvent(LinkEventKind.LOST, detail), "event")
        # binding takes no time worth bounding (resolving might: getaddrinfo of a name)
        self._reopen.start(self.url, self._bind, 5.0, f"{self.url}: new socket", self._on_event)
