"""What every simulator server has in common: open, close, a URL, ``async with``; and
:class:`ServerParts`, what a server is given of its simulator."""

from __future__ import annotations

import abc
from collections.abc import Callable
from dataclasses import dataclass

from gcu_async._lifecycle import OpenClose
from gcu_async.capture.writer import PacketCapture
from gcu_async.sim.exchange import Exchange
from gcu_async.sim.stall import StallSwitch


@dataclass(frozen=True)
class ServerParts:
    """What a server needs of its simulator (the simulator makes it; a server never sees
    the simulator itself)."""

    new_exchange: Callable[[bool], Exchange]
    """A new :class:`~gcu_async.sim.exchange.Exchange` into the simulator's model: one per
    connection (``stream=True``: a byte stream, deframed) or one for all datagrams
    (``stream=False``)."""
    stalls: StallSwitch
    """The stall switch the server's reading joins (a stall stops reading)."""
    capture: PacketCapture | None = None
    """Where the server records what it receives and sends (``None``: nowhere)."""


class SimServer(OpenClose):
    """A running endpoint of a :class:`~gcu_async.sim.GcuSimulator`.

    ``async with sim.serve_udp(...) as server:`` opens it and closes it (every socket and
    file descriptor) on exit; :meth:`open` / :meth:`close` do the same by hand.
    """

    @property
    @abc.abstractmethod
    def url(self) -> str:
        """Where a client connects, as a URL (``udp://127.0.0.1:2337``)."""

    @abc.abstractmethod
    async def open(self) -> None:
        """Bind / open; raises ``OSError`` if that fails."""

    @abc.abstractmethod
    async def close(self) -> None:
        """Stop serving and release everything. Idempotent."""

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.url}>"
