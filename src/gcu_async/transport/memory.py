"""In-memory transport pair for unit tests: what one end sends, the other receives on the
next event-loop iteration (never synchronously, like a real link)."""

from __future__ import annotations

import asyncio

from gcu_async.errors import LinkLost
from gcu_async.transport.base import LinkEvent, LinkEventKind, Transport


class MemoryTransport(Transport):
    """One end of an in-memory link; make both ends with :meth:`pair`."""

    def __init__(self, name: str = "memory") -> None:
        super().__init__()
        self._name = name
        self._peer: MemoryTransport | None = None
        self._open = False
        self.bytes_sent = 0

    @classmethod
    def pair(cls, names: tuple[str, str] = ("a", "b")) -> tuple[MemoryTransport, MemoryTransport]:
        """Two connected ends."""
        a, b = cls(names[0]), cls(names[1])
        a._peer, b._peer = b, a
        return a, b

    @property
    def url(self) -> str:
        return f"memory://{self._name}"

    @property
    def connected(self) -> bool:
        return self._open and self._peer is not None and self._peer._open

    async def open(self) -> None:
        if self._peer is None:
            raise LinkLost(f"{self.url}: no peer")
        self._open = True
        if self._peer._open:
            self._peer._on_event(LinkEvent(LinkEventKind.RESTORED, f"{self.url} opened"))

    def send(self, data: bytes) -> None:
        peer = self._peer
        if not self._open or peer is None or not peer._open:
            raise LinkLost(f"{self.url}: link is down")
        self.bytes_sent += len(data)
        asyncio.get_running_loop().call_soon(peer._deliver, bytes(data))

    def _deliver(self, data: bytes) -> None:
        if self._open:
            self._on_data(data)

    async def close(self) -> None:
        if not self._open:
            return
        self._open = False
        peer = self._peer
        if peer is not None and peer._open:
            peer._on_event(LinkEvent(LinkEventKind.LOST, f"{self.url} closed"))
