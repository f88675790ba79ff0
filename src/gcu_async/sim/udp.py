"""The simulator's UDP endpoint: binds the GCU port (2337) and answers each datagram.

Replies go to the sender's address; or to the sender's host at a fixed ``reply_port`` (what
emulators in the field do: port 2338); or to a fixed ``reply_to`` address — the real GCU sends to
the LAN broadcast address, port 2338 (docs/protocol-notes.md §12 "Transports"); broadcast is allowed
on the socket when ``reply_to`` is set. Replies leave from the bound port.
"""

from __future__ import annotations

import asyncio
import logging
from typing import TYPE_CHECKING, Any

from gcu_async.sim.exchange import Exchange
from gcu_async.sim.server import SimServer
from gcu_async.sim.stall import TransportReading
from gcu_async.transport._common import format_hostport

if TYPE_CHECKING:
    from gcu_async.sim.simulator import GcuSimulator

log = logging.getLogger("gcu_async.sim")

GCU_UDP_PORT = 2337
HOST_UDP_PORT = 2338


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
        sim: GcuSimulator,
        host: str = "127.0.0.1",
        port: int = GCU_UDP_PORT,
        reply_to: tuple[str, int] | None = None,
        reply_port: int | None = None,
    ) -> None:
        if reply_to is not None and reply_port is not None:
            raise ValueError("reply_to and reply_port: give at most one")
        self._sim = sim
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

    async def start(self) -> None:
        if self._transport is not None:
            return
        loop = asyncio.get_running_loop()
        self._closed = loop.create_future()
        transport, _ = await loop.create_datagram_endpoint(
            lambda: _Protocol(self),
            local_addr=(self._host, self._port),
            allow_broadcast=self.reply_to is not None,
        )
        self._transport = transport
        self._exchange = Exchange(self._sim, stream=False)
        self._reading = TransportReading(transport)
        self._sim.stalls.join(self._reading)  # stalled: the kernel queues the datagrams
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

        def send(reply: bytes) -> None:
            if not transport.is_closing():
                transport.sendto(reply, target)

        exchange.feed(data, send)

    def _lost(self) -> None:
        if self._closed is not None and not self._closed.done():
            self._closed.set_result(None)

    async def aclose(self) -> None:
        transport, self._transport = self._transport, None
        if self._reading is not None:
            self._sim.stalls.leave(self._reading)
            self._reading = None
        if self._exchange is not None:
            self._exchange.close()
        if transport is None:
            return
        transport.close()
        if self._closed is not None:
            await asyncio.wait_for(asyncio.shield(self._closed), timeout=2.0)
