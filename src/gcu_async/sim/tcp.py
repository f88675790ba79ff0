"""The simulator's TCP endpoint: a server on the GCU port (2332), one client at a time.

A client that connects while another is being served waits (its connection is accepted but
not read) until the previous one leaves — then it is served; any number of clients in turn.
:meth:`TcpServer.kill_connection` aborts the current connection (RST) to test reconnects.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from typing import TYPE_CHECKING

from gcu_async.sim.exchange import Exchange
from gcu_async.sim.server import SimServer
from gcu_async.sim.stall import TransportReading
from gcu_async.transport._common import format_hostport

if TYPE_CHECKING:
    from gcu_async.sim.simulator import GcuSimulator

log = logging.getLogger("gcu_async.sim")

GCU_TCP_PORT = 2332
READ_SIZE = 4096
CLOSE_TIMEOUT = 2.0


class TcpServer(SimServer):
    """TCP endpoint of a simulator; ``address`` is the bound (host, port)."""

    def __init__(self, sim: GcuSimulator, host: str = "127.0.0.1", port: int = GCU_TCP_PORT):
        self._sim = sim
        self._host = host
        self._port = port
        self._server: asyncio.Server | None = None
        self._turn = asyncio.Lock()
        self._writers: set[asyncio.StreamWriter] = set()
        self._tasks: set[asyncio.Task[None]] = set()
        self._active: asyncio.StreamWriter | None = None
        self._closing = False
        self.address: tuple[str, int] = (host, port)
        self.clients_served = 0

    @property
    def url(self) -> str:
        return f"tcp://{format_hostport(*self.address)}"

    @property
    def client_connected(self) -> bool:
        """Is a client being served right now?"""
        return self._active is not None

    async def start(self) -> None:
        if self._server is not None:
            return
        self._closing = False
        capture = self._sim.capture
        if capture is not None:
            capture.acquire()  # OSError if the file cannot be created: nothing bound yet
        try:
            self._server = await asyncio.start_server(self._serve, self._host, self._port)
        except BaseException:
            if capture is not None:
                capture.release()
            raise
        sockname = self._server.sockets[0].getsockname()
        self.address = (str(sockname[0]), int(sockname[1]))

    def kill_connection(self) -> bool:
        """Abort the connection being served now (the client sees a reset). Returns whether
        there was one."""
        writer = self._active
        if writer is None:
            return False
        log.info("killing the TCP connection to %s", writer.get_extra_info("peername"))
        writer.transport.abort()
        return True

    async def _serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        task = asyncio.current_task()
        if task is not None:
            self._tasks.add(task)
        self._writers.add(writer)
        try:
            async with self._turn:
                if not self._closing and not writer.is_closing():
                    await self._session(reader, writer)
        finally:
            self._writers.discard(writer)
            if task is not None:
                self._tasks.discard(task)
            writer.close()
            with contextlib.suppress(Exception):
                await writer.wait_closed()

    async def _session(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        peer = writer.get_extra_info("peername")
        self._active = writer
        self.clients_served += 1
        log.info("TCP client %s connected", peer)
        exchange = Exchange(self._sim, stream=True)
        reading = TransportReading(writer.transport)
        self._sim.stalls.join(reading)  # stalled: the kernel buffers what the client sends
        capture = self._sim.capture
        ends = _ends(writer)
        if capture is not None and ends is not None:
            capture.tcp_open(ends[1], ends[0])

        def send(data: bytes) -> None:
            if not writer.is_closing():
                writer.write(data)
                if capture is not None and ends is not None:
                    capture.tcp(ends[0], ends[1], data)

        try:
            while True:
                data = await reader.read(READ_SIZE)
                if not data:
                    break
                if capture is not None and ends is not None:
                    capture.tcp(ends[1], ends[0], data)
                exchange.feed(data, send)
        except (ConnectionError, OSError) as exc:
            log.debug("TCP client %s: %s", peer, exc)
        finally:
            self._sim.stalls.leave(reading)
            exchange.close()
            self._active = None
            if capture is not None and ends is not None:
                killed = writer.transport.is_closing()
                capture.tcp_close(ends[0] if killed else ends[1], ends[1] if killed else ends[0],
                                  reset=killed)  # fmt: skip
            log.info("TCP client %s left", peer)

    async def aclose(self) -> None:
        server, self._server = self._server, None
        if server is None:
            return
        if self._sim.capture is not None:
            self._sim.capture.release()
        self._closing = True
        server.close()
        for writer in list(self._writers):
            writer.transport.abort()
        tasks = list(self._tasks)
        if tasks:
            _, pending = await asyncio.wait(tasks, timeout=CLOSE_TIMEOUT)
            for task in pending:
                task.cancel()
            if pending:
                await asyncio.wait(pending, timeout=CLOSE_TIMEOUT)
        await asyncio.wait_for(server.wait_closed(), timeout=CLOSE_TIMEOUT)


def _ends(writer: asyncio.StreamWriter) -> tuple[tuple[str, int], tuple[str, int]] | None:
    """(server, client) addresses of a connection, for the capture."""
    local, peer = writer.get_extra_info("sockname"), writer.get_extra_info("peername")
    if not (isinstance(local, tuple) and isinstance(peer, tuple)):
        return None
    return (str(local[0]), int(local[1])), (str(peer[0]), int(peer[1]))
