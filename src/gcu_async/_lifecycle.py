"""The one lifecycle vocabulary of the package: ``open()``, ``close()``, ``async with``.

The client (:class:`~gcu_async.client.GcuClient`), every transport
(:class:`~gcu_async.transport.Transport`) and every simulator server
(:class:`~gcu_async.sim.SimServer`) share it: ``async with thing:`` opens it and gives back
the same object, and closes it on exit however the block ends.
"""

from __future__ import annotations

import abc
from types import TracebackType
from typing import TypeVar

_T = TypeVar("_T", bound="OpenClose")


class OpenClose(abc.ABC):
    """``open()`` / ``close()`` (idempotent), and ``async with`` calling them."""

    @abc.abstractmethod
    async def open(self) -> None:
        """Open (bind, connect, start); raises if that fails, with nothing left open."""

    @abc.abstractmethod
    async def close(self) -> None:
        """Close and release everything. Idempotent."""

    async def __aenter__(self: _T) -> _T:
        await self.open()
        return self

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        await self.close()
