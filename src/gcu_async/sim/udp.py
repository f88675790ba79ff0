"""The simulator's UDP endpoint: binds the GCU port (2337) and answers each datagram.

Replies go to the sender's address; or to the sender's host at a fixed ``reply_port`` (what
emulators in the field do: port 2338); or to a fixed ``reply_to`` address — the real GCU sends to
the LAN broadcast address, port 2338 (docs/protocol-notes.md §12 "Transports"); broadcast is allowed
on the socket when ``reply_to`` is set. Replies leave from the bound port.
:func:`interface_broadcast` finds the broadcast address of the interface that owns the
listen address (``gcu-async sim --reply-to broadcast``).
"""

from __future__ import annotations

import asyncio
import ipaddress
import logging
import socket
import struct
import sys
from collections.abc import Callable
from typing import Any

from gcu_async.capture.synth import source_address
from gcu_async.protocol.links import GCU_UDP_PORT
from gcu_async.sim.exchange import Exchange
from gcu_async.sim.listen import ListenSpec
from gcu_async.sim.server import ServerParts, SimServer
from gcu_async.sim.stall import TransportReading
from gcu_async.transport._common import format_hostport
from gcu_async.transport.udp import MAX_DATAGRAM

log = logging.getLogger("gcu_async.sim")


_SIOCGIFADDR = 0x8915  # Linux ioctls: an interface's (primary) IPv4 address,
_SIOCGIFBRDADDR = 0x8919  # and its broadcast address


def interface_broadcast(address: str) -> str:
    """The IPv4 broadcast address of the interface whose primary address is ``address``
    (10.213.0.255 for 10.213.0.1/24): where a real GCU on that subnet sends its replies.

    Linux only (``ioctl`` SIOCGIFADDR/SIOCGIFBRDADDR). Raises ``ValueError`` naming the
    address when it is not an IPv4 address, not any interface's address, or that interface
    has no broadcast address, and on other platforms."""
    try:
        ip = ipaddress.IPv4Address(address)
    except ValueError:
        raise ValueError(f"{address!r} is not an IPv4 address") from None
    if ip.is_unspecified:
        raise ValueError(f"{address} is no one interface's address: listen on the GCU's own")
    if not sys.platform.startswith("linux"):
        raise ValueError(f"finding the broadcast address of {address} needs Linux: give it")
    import fcntl  # POSIX only

    def ioctl_address(sock: socket.socket, request: int, name: str) -> str | None:
        ifreq = struct.pack("16s24x", name.encode()[:15])
        try:
            result = fcntl.ioctl(sock.fileno(), request, ifreq)
        except OSError:  # no IPv4 address, or no broadcast address
            return None
        return socket.inet_ntoa(result[20:24])

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        for _, name in socket.if_nameindex():
            if ioctl_address(sock, _SIOCGIFADDR, name) != str(ip):
                continue
            broadcast = ioctl_address(sock, _SIOCGIFBRDADDR, name)
            if broadcast is None or broadcast == "0.0.0.0":
                raise ValueError(f"{address}: interface {name} has no broadcast address")
            return broadcast
    raise ValueError(f"{address} is not the (primary) address of any interface")


class _Protocol(asyncio.DatagramProtocol):
    """The fallback's protocol (a loop without ``add_reader``: asyncio's own transport)."""

    def __init__(self, server: UdpServer) -> None:
        self._server = server

    def datagram_received(self, data: bytes, addr: Any) -> None:
        self._server._datagram(data, addr)

    def error_received(self, exc: Exception) -> None:
        log.debug("UDP error: %s", exc)

    def connection_lost(self, exc: Exception | None) -> None:
        self._server._lost()


class _Reading:
    """The socket's reader on the event loop, one datagram per readiness event; a stall
    member: paused, it leaves the datagrams to the kernel's queue."""

    def __init__(self, loop: asyncio.AbstractEventLoop, sock: socket.socket,
                 read: Callable[[], None]) -> None:  # fmt: skip
        self._loop = loop
        self._fd = sock.fileno()
        self._read = read
        loop.add_reader(self._fd, read)  # NotImplementedError: no selector (Windows' proactor)
        self._on = True
        self._closed = False

    def pause(self) -> None:
        if self._on:
            self._loop.remove_reader(self._fd)
            self._on = False

    def resume(self) -> None:
        if not self._on and not self._closed:
            self._loop.add_reader(self._fd, self._read)
            self._on = True

    def close(self) -> None:
        self.pause()
        self._closed = True


class UdpServer(SimServer):
    """UDP endpoint of a simulator; ``address`` is the bound (host, port).

    Reads as the client's UDP transport does: its own socket on the event loop
    (``add_reader``), each datagram received into one reused buffer (``recvfrom_into``),
    replies sent with ``sendto`` at once (a reply the socket refuses, its send buffer full,
    is dropped and counted in ``sim.stats.send_errors``, never queued). On a loop without
    ``add_reader`` (Windows' proactor loop) asyncio's datagram transport reads instead.
    """

    def __init__(
        self,
        parts: ServerParts,
        host: str = "127.0.0.1",
        port: int = GCU_UDP_PORT,
        reply_to: tuple[str, int] | None = None,
        reply_port: int | None = None,
    ) -> None:
        if reply_to is not None and reply_port is not None:
            raise ValueError("reply_to and reply_port: give at most one")
        self._parts = parts
        self._host = host
        self._port = port
        self.reply_to = reply_to
        self.reply_port = reply_port
        self._sock: socket.socket | None = None
        self._sendto: Callable[[bytes, Any], object] | None = None
        self._buffer = memoryview(bytearray(MAX_DATAGRAM))
        self._transport: asyncio.DatagramTransport | None = None
        self._exchange: Exchange | None = None
        self._reading: _Reading | TransportReading | None = None
        self._closed: asyncio.Future[None] | None = None
        self.address: tuple[str, int] = (host, port)
        self.peers: set[tuple[str, int]] = set()
        """Addresses that have sent datagrams."""

    @property
    def url(self) -> str:
        return f"udp://{format_hostport(*self.address)}"

    async def open(self) -> None:
        if self._sock is not None:
            return
        loop = asyncio.get_running_loop()
        capture = self._parts.capture
        if capture is not None:
            capture.acquire()  # OSError if the file cannot be created: nothing bound yet
        try:
            sock = await self._bind(loop)
            try:
                self._reading = _Reading(loop, sock, self._read_ready)
                self._sendto = sock.sendto
            except NotImplementedError:  # e.g. Windows' proactor loop
                self._closed = loop.create_future()
                transport, _ = await loop.create_datagram_endpoint(lambda: _Protocol(self),
                                                                   sock=sock)  # fmt: skip
                self._transport = transport
                self._sendto = transport.sendto
                self._reading = TransportReading(transport)
        except BaseException:
            if capture is not None:
                capture.release()
            raise
        self._sock = sock
        self._exchange = self._parts.new_exchange(False)
        self._parts.stalls.join(self._reading)  # stalled: the kernel queues the datagrams
        sockname = sock.getsockname()
        self.address = (str(sockname[0]), int(sockname[1]))

    async def _bind(self, loop: asyncio.AbstractEventLoop) -> socket.socket:
        """A non-blocking UDP socket bound to the first address ``host`` resolves to that
        can be bound (as ``loop.create_datagram_endpoint(local_addr=...)`` binds)."""
        infos = await loop.getaddrinfo(self._host, self._port, type=socket.SOCK_DGRAM,
                                       proto=socket.IPPROTO_UDP)  # fmt: skip
        error: OSError | None = None
        for family, kind, proto, _, address in infos:
            sock = socket.socket(family, kind, proto)
            try:
                sock.setblocking(False)
                if self.reply_to is not None:
                    sock.setsockopt(socket.SOL_SOCKET, socket.SO_BROADCAST, 1)
                sock.bind(address)
            except OSError as exc:
                sock.close()
                error = OSError(exc.errno, f"error while attempting to bind on address "
                                           f"{address!r}: {exc.strerror}")  # fmt: skip
                continue
            return sock
        raise error if error is not None else OSError(f"{self._host!r}: no address to bind")

    def _read_ready(self) -> None:
        sock = self._sock
        if sock is None:
            return
        try:
            n, addr = sock.recvfrom_into(self._buffer)
        except (BlockingIOError, InterruptedError):
            return
        except OSError as exc:  # e.g. an ICMP error reported for an earlier reply
            log.debug("UDP error: %s", exc)
            return
        self._datagram(bytes(self._buffer[:n]), addr)

    def _datagram(self, data: bytes, addr: Any) -> None:
        exchange, sendto = self._exchange, self._sendto
        if exchange is None or sendto is None:
            return
        peer = addr if len(addr) == 2 else (str(addr[0]), int(addr[1]))  # IPv6: 4 items
        self.peers.add(peer)
        target: Any = addr
        if self.reply_to is not None:
            target = self.reply_to
        elif self.reply_port is not None:
            target = (addr[0], self.reply_port, *addr[2:])
        capture = self._parts.capture
        if capture is None:

            def send(reply: bytes) -> None:
                sendto(reply, target)

        else:
            local = (source_address(peer, self.address[0]), self.address[1])
            capture.udp(peer, local, data)

            def send(reply: bytes) -> None:
                sendto(reply, target)
                capture.udp(local, (str(target[0]), int(target[1])), reply)

        exchange.feed(data, send)

    def _lost(self) -> None:
        if self._closed is not None and not self._closed.done():
            self._closed.set_result(None)

    async def close(self) -> None:
        sock, self._sock = self._sock, None
        transport, self._transport = self._transport, None
        if self._reading is not None:
            self._parts.stalls.leave(self._reading)
            if isinstance(self._reading, _Reading):
                self._reading.close()
            self._reading = None
        if self._exchange is not None:
            self._exchange.close()
        if sock is None:
            return
        self._sendto = None
        if self._parts.capture is not None:
            self._parts.capture.release()
        if transport is None:
            sock.close()
            return
        transport.close()
        if self._closed is not None:
            await asyncio.wait_for(asyncio.shield(self._closed), timeout=2.0)


def listen(parts: ServerParts, spec: ListenSpec) -> UdpServer:
    """The ``udp`` listener of the transport registry (docs/architecture.md)."""
    return UdpServer(parts, spec.host, spec.port, spec.reply_to, spec.reply_port)
