"""What every simulator server has in common: start, close, a URL, ``async with``."""

from __future__ import annotations

import abc
from types import TracebackType
from typing import TypeVar

_S = TypeVar("_S", bound="SimServer")


class SimServer(abc.ABC):
    """A running endpoint of a :class:`~gcu_async.sim.GcuSimulator`.

    ``async with sim.serve_udp(...) as server:`` starts it and closes it (every socket and
    file descriptor) on exit; :meth:`start` / :meth:`aclose` do the same by hand.
    """

    @property
    @abc.abstractmethod
    def url(self) -> str:
        """Where a client connects, as a URL (``udp://127.0.0.1:2337``)."""

    @abc.abstractmethod
    async def start(self) -> None:
        """Bind / open; raises ``OSError`` if that fails."""

    @abc.abstractmethod
    async def aclose(self) -> None:
        """Stop serving and release everything. Idempotent."""

    async def __aenter__(self: _S) -> _S:
        await self.start()
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        await self.aclose()

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.url}>"
