"""The simulator's TCP endpoint: a server on the GCU port (2332), one client at a time.

A client that connects while another is being served waits (its connection is accepted but
not read: the kernel buffers what it sends) until the previous one leaves — then it is
served; any number of clients in turn. :meth:`TcpServer.kill_connection` aborts the current
connection (RST) to test reconnects.

Every connection is an :class:`asyncio.Protocol` driven by the event loop's callbacks; the
server runs no task of its own per connection, so nothing of a connection outlives it: its
state is released in ``connection_lost``, when the socket is closed.
"""

from __future__ import annotations

import asyncio
import collections
import logging
from typing import TYPE_CHECKING

from gcu_async.protocol.links import GCU_TCP_PORT
from gcu_async.sim.exchange import Exchange
from gcu_async.sim.listen import ListenSpec
from gcu_async.sim.server import ServerParts, SimServer
from gcu_async.sim.stall import TransportReading
from gcu_async.transport._common import format_hostport

if TYPE_CHECKING:
    from gcu_async.capture.synth import Address
    from gcu_async.capture.writer import PacketCapture

log = logging.getLogger("gcu_async.sim")

CLOSE_TIMEOUT = 2.0


class _Connection(asyncio.Protocol):
    """One accepted client: waiting (reading paused) or served (fed to an Exchange)."""

    def __init__(self, server: TcpServer) -> None:
        self._server = server
        self.transport: asyncio.Transport | None = None
        self.peer: object = None
        self.exchange: Exchange | None = None
        self.reading: TransportReading | None = None
        self.early = bytearray()  # read before its turn came (see connection_made)
        self.ends: tuple[Address, Address] | None = None  # (server, client), when captured
        self.killed = False  # aborted by the server (kill_connection, close)
        self.closed: asyncio.Future[None] = asyncio.get_running_loop().create_future()

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport
        self.peer = transport.get_extra_info("peername")
        # The transport starts reading right after this call (a call_soon queued before it),
        # and on Python 3.10 that start undoes a pause_reading() made here: the server
        # takes the connection (and pauses it, when it must wait) on the next callback.
        asyncio.get_running_loop().call_soon(self._server._arrived, self)

    def data_received(self, data: bytes) -> None:
        if self.exchange is not None:
            self._captured(data, from_client=True)
            self.exchange.feed(data, self.send)
        else:  # not served yet: kept for its turn (normally the pause keeps it in the kernel)
            self.early += data

    def eof_received(self) -> bool:
        return False  # the client is done: close our side as well

    def connection_lost(self, exc: Exception | None) -> None:
        if exc is not None:
            log.debug("TCP client %s: %s", self.peer, exc)
        self._server._left(self)
        if not self.closed.done():
            self.closed.set_result(None)

    def send(self, data: bytes) -> None:
        if self.transport is not None and not self.transport.is_closing():
            self.transport.write(data)
            self._captured(data, from_client=False)

    def _captured(self, data: bytes, *, from_client: bool) -> None:
        capture = self._server.capture
        if capture is not None and self.ends is not None:
            server, client = self.ends
            capture.tcp(client, server, data) if from_client else capture.tcp(server, client, data)

    def abort(self) -> None:
        """Reset the connection from the server's side."""
        if self.transport is not None:
            self.killed = True
            self.transport.abort()


class TcpServer(SimServer):
    """TCP endpoint of a simulator; ``address`` is the bound (host, port)."""

    def __init__(self, parts: ServerParts, host: str = "127.0.0.1", port: int = GCU_TCP_PORT):
        self._parts = parts
        self._host = host
        self._port = port
        self._server: asyncio.Server | None = None
        self._connections: set[_Connection] = set()
        self._waiting: collections.deque[_Connection] = collections.deque()
        self._active: _Connection | None = None
        self._closing = False
        self.address: tuple[str, int] = (host, port)
        self.clients_served = 0

    @property
    def url(self) -> str:
        return f"tcp://{format_hostport(*self.address)}"

    @property
    def capture(self) -> PacketCapture | None:
        """The simulator's capture file, if it writes one."""
        return self._parts.capture

    @property
    def client_connected(self) -> bool:
        """Is a client being served right now?"""
        return self._active is not None

    async def open(self) -> None:
        if self._server is not None:
            return
        self._closing = False
        loop = asyncio.get_running_loop()
        capture = self._parts.capture
        if capture is not None:
            capture.acquire()  # OSError if the file cannot be created: nothing bound yet
        try:
            self._server = await loop.create_server(
                lambda: _Connection(self), self._host, self._port
            )
        except BaseException:
            if capture is not None:
                capture.release()
            raise
        sockname = self._server.sockets[0].getsockname()
        self.address = (str(sockname[0]), int(sockname[1]))

    def kill_connection(self) -> bool:
        """Abort the connection being served now (the client sees a reset). Returns whether
        there was one."""
        conn = self._active
        if conn is None or conn.transport is None:
            return False
        log.info("killing the TCP connection to %s", conn.peer)
        conn.abort()
        return True

    # -- connection callbacks ------------------------------------------------------------

    def _arrived(self, conn: _Connection) -> None:
        assert conn.transport is not None
        if conn.closed.done():
            return  # gone before the server took it
        self._connections.add(conn)
        if self._closing:
            conn.transport.abort()
        elif self._active is None:
            self._serve(conn)
        else:
            conn.transport.pause_reading()  # its turn comes when the current client leaves
            self._waiting.append(conn)

    def _serve(self, conn: _Connection) -> None:
        assert conn.transport is not None
        self._active = conn
        self.clients_served += 1
        log.info("TCP client %s connected", conn.peer)
        conn.exchange = self._parts.new_exchange(True)
        conn.reading = TransportReading(conn.transport)
        self._parts.stalls.join(conn.reading)  # stalled: the kernel buffers what the client sends
        capture = self._parts.capture
        conn.ends = _ends(conn.transport) if capture is not None else None
        if capture is not None and conn.ends is not None:
            capture.tcp_open(conn.ends[1], conn.ends[0])
        if conn.early:
            early, conn.early = bytes(conn.early), bytearray()
            conn.data_received(early)

    def _left(self, conn: _Connection) -> None:
        self._connections.discard(conn)
        if conn in self._waiting:
            self._waiting.remove(conn)
        if conn is not self._active:
            return
        if conn.reading is not None:
            self._parts.stalls.leave(conn.reading)
        if conn.exchange is not None:
            conn.exchange.close()
        self._active = None
        capture = self._parts.capture
        if capture is not None and conn.ends is not None:
            server, client = conn.ends
            if conn.killed:
                capture.tcp_close(server, client, reset=True)
            else:
                capture.tcp_close(client, server)
        log.info("TCP client %s left", conn.peer)
        while self._waiting and not self._closing:
            following = self._waiting.popleft()
            if following.transport is not None and not following.transport.is_closing():
                following.transport.resume_reading()  # a stall going on pauses it again
                self._serve(following)
                break

    async def close(self) -> None:
        server, self._server = self._server, None
        if server is None:
            return
        self._closing = True
        server.close()
        connections = list(self._connections)
        for conn in connections:
            conn.abort()
        try:
            if connections:
                await asyncio.wait([conn.closed for conn in connections], timeout=CLOSE_TIMEOUT)
            await asyncio.wait_for(server.wait_closed(), timeout=CLOSE_TIMEOUT)
        finally:
            if self._parts.capture is not None:
                self._parts.capture.release()  # after the connections' ends went into it


def _ends(transport: asyncio.BaseTransport) -> tuple[Address, Address] | None:
    """(server, client) addresses of a connection, for the capture."""
    local, peer = transport.get_extra_info("sockname"), transport.get_extra_info("peername")
    if not (isinstance(local, tuple) and isinstance(peer, tuple)):
        return None
    return (str(local[0]), int(local[1])), (str(peer[0]), int(peer[1]))


def listen(parts: ServerParts, spec: ListenSpec) -> TcpServer:
    """The ``tcp`` listener of the transport registry (docs/architecture.md)."""
    return TcpServer(parts, spec.host, spec.port)
