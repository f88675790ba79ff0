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
from typing import Any

from gcu_async.capture.synth import source_address
from gcu_async.protocol.links import GCU_UDP_PORT
from gcu_async.sim.exchange import Exchange
from gcu_async.sim.listen import ListenSpec
from gcu_async.sim.server import ServerParts, SimServer
from gcu_async.sim.stall import TransportReading
from gcu_async.transport._common import format_hostport

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
    def __init__(self, server: UdpServer) -> None:
        self._server = server

    def datagram_received(self, data: bytes, addr: Any) -> None:
        self._server._datagram(data, addr)

    def error_received(self, exc: Exception) -> None:
        log.debug("UDP error: %s", exc)

    def connection_lost(self, exc: Exception | None) -> None:
        self._server._lost()


class UdpServer(SimServer):
    """UDP endpoint of a simulator; ``address`` is the bound (host, port)."""

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
        self._transport: asyncio.DatagramTransport | None = None
        self._exchange: Exchange | None = None
        self._reading: TransportReading | None = None
        self._closed: asyncio.Future[None] | None = None
        self.address: tuple[str, int] = (host, port)
        self.peers: set[tuple[str, int]] = set()
        """Addresses that have sent datagrams."""

    @property
    def url(self) -> str:
        return f"udp://{format_hostport(*self.address)}"

    async def open(self) -> None:
        if self._transport is not None:
            return
        loop = asyncio.get_running_loop()
        self._closed = loop.create_future()
        capture = self._parts.capture
        if capture is not None:
            capture.acquire()  # OSError if the file cannot be created: nothing bound yet
        try:
            transport, _ = await loop.create_datagram_endpoint(
                lambda: _Protocol(self),
                local_addr=(self._host, self._port),
                allow_broadcast=self.reply_to is not None,
            )
        except BaseException:
            if capture is not None:
                capture.release()
            raise
        self._transport = transport
        self._exchange = self._parts.new_exchange(False)
        self._reading = TransportReading(transport)
        self._parts.stalls.join(self._reading)  # stalled: the kernel queues the datagrams
        sockname = transport.get_extra_info("sockname")
        self.address = (str(sockname[0]), int(sockname[1]))

    def _datagram(self, data: bytes, addr: Any) -> None:
        transport, exchange = self._transport, self._exchange
        if transport is None or exchange is None:
            return
        peer = (str(addr[0]), int(addr[1]))
        self.peers.add(peer)
        target: Any = addr
        if self.reply_to is not None:
            target = self.reply_to
        elif self.reply_port is not None:
            target = (addr[0], self.reply_port, *addr[2:])
        capture = self._parts.capture
        local = (source_address(peer, self.address[0]), self.address[1])
        if capture is not None:
            capture.udp(peer, local, data)

        def send(reply: bytes) -> None:
            if not transport.is_closing():
                transport.sendto(reply, target)
                if capture is not None:
                    capture.udp(local, (str(target[0]), int(target[1])), reply)

        exchange.feed(data, send)

    def _lost(self) -> None:
        if self._closed is not None and not self._closed.done():
            self._closed.set_result(None)

    async def close(self) -> None:
        transport, self._transport = self._transport, None
        if self._reading is not None:
            self._parts.stalls.leave(self._reading)
            self._reading = None
        if self._exchange is not None:
            self._exchange.close()
        if transport is None:
            return
        if self._parts.capture is not None:
            self._parts.capture.release()
        transport.close()
        if self._closed is not None:
            await asyncio.wait_for(asyncio.shield(self._closed), timeout=2.0)


def listen(parts: ServerParts, spec: ListenSpec) -> UdpServer:
    """The ``udp`` listener of the transport registry (docs/architecture.md)."""
    return UdpServer(parts, spec.host, spec.port, spec.reply_to, spec.reply_port)
