"""The simulator on an in-memory link: the client gets a
:class:`~gcu_async.transport.memory.MemoryTransport` whose peer is the simulator."""

from __future__ import annotations

from types import TracebackType
from typing import TYPE_CHECKING

from gcu_async.errors import LinkLost
from gcu_async.sim.exchange import Exchange
from gcu_async.sim.server import SimServer
from gcu_async.transport.memory import MemoryTransport

if TYPE_CHECKING:
    from gcu_async.sim.simulator import GcuSimulator


class MemoryServer(SimServer):
    """``async with sim.serve_memory() as transport:`` gives the client's end (not yet
    opened: the client opens it); replies arrive on the next event-loop iteration."""

    def __init__(self, sim: GcuSimulator) -> None:
        self._sim = sim
        self._ours, self.transport = MemoryTransport.pair(("gcu-sim", "client"))
        self._exchange: Exchange | None = None
        self._ours.set_handlers(self._received)

    @property
    def url(self) -> str:
        return self.transport.url

    async def start(self) -> None:
        if self._exchange is not None:
            return
        self._exchange = Exchange(self._sim, stream=True)
        if self._sim.capture is not None:
            self._sim.capture.acquire()
        await self._ours.open()

    def _received(self, data: bytes) -> None:
        if self._exchange is not None:
            if self._sim.capture is not None:
                self._sim.capture.serial(self.url, data, outbound=False)
            self._exchange.feed(data, self._send)

    def _send(self, data: bytes) -> None:
        if not self._ours.connected:
            raise LinkLost("memory link: the client end is closed")
        self._ours.send(data)
        if self._sim.capture is not None:
            self._sim.capture.serial(self.url, data, outbound=True)

    async def aclose(self) -> None:
        exchange, self._exchange = self._exchange, None
        if exchange is not None:
            exchange.close()
            if self._sim.capture is not None:
                self._sim.capture.release()
        await self._ours.close()

    async def __aenter__(self) -> MemoryTransport:  # type: ignore[override]
        await self.start()
        return self.transport

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        await self.aclose()
