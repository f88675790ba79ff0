"""The simulator on an in-memory link: the client gets a
:class:`~gcu_async.transport.memory.MemoryTransport` whose peer is the simulator."""

from __future__ import annotations

from gcu_async.errors import LinkLost
from gcu_async.sim.exchange import Exchange
from gcu_async.sim.server import ServerParts, SimServer
from gcu_async.transport.memory import MemoryTransport


class MemoryServer(SimServer):
    """``async with sim.serve_memory() as server:`` — ``server.transport`` is the client's
    end (not yet opened: the client opens it); replies arrive on the next event-loop
    iteration."""

    def __init__(self, parts: ServerParts) -> None:
        self._parts = parts
        self._ours, self.transport = MemoryTransport.pair(("gcu-sim", "client"))
        """The client's end of the link: give it to :class:`~gcu_async.client.GcuClient`."""
        self._exchange: Exchange | None = None
        self._ours.set_handlers(self._received)

    @property
    def url(self) -> str:
        return self.transport.url

    async def open(self) -> None:
        if self._exchange is not None:
            return
        self._exchange = self._parts.new_exchange(True)
        if self._parts.capture is not None:
            self._parts.capture.acquire()
        await self._ours.open()

    def _received(self, data: bytes) -> None:
        if self._exchange is not None:
            if self._parts.capture is not None:
                self._parts.capture.serial(self.url, data, outbound=False)
            self._exchange.feed(data, self._send)

    def _send(self, data: bytes) -> None:
        if not self._ours.connected:
            raise LinkLost("memory link: the client end is closed")
        self._ours.send(data)
        if self._parts.capture is not None:
            self._parts.capture.serial(self.url, data, outbound=True)

    async def close(self) -> None:
        exchange, self._exchange = self._exchange, None
        if exchange is not None:
            exchange.close()
            if self._parts.capture is not None:
                self._parts.capture.release()
        await self._ours.close()
