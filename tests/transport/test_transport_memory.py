"""MemoryTransport: the transport contract (tests/helpers/transport/contract.py), and the base's
defaults: datagram, reset, sends_dropped."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator

import pytest

from gcu_async.transport import MemoryTransport
from helpers.transport.contract import TO_PEER, Link, TransportContract
from helpers.transport.recorder import Recorder


async def test_reset_is_a_no_op_nothing_is_queued() -> None:
    a, b = MemoryTransport.pair()
    rec_a, rec_b = Recorder(a), Recorder(b)
    await a.open()
    await b.open()
    rec_a.events.clear()
    a.send(b"before")
    a.reset("declared lost")  # what is already handed over is delivered; nothing else exists
    a.send(b"after")
    await rec_b.wait_bytes(11)
    assert rec_b.chunks == [b"before", b"after"]
    await asyncio.sleep(0.01)
    assert rec_a.events == [] and rec_b.events == []
    assert a.connected and b.connected
    assert a.sends_dropped == 0
    assert not a.datagram


class _MemoryPeer:
    def __init__(self, end: MemoryTransport) -> None:
        self.end = end
        self.rec = Recorder(end)

    def send(self, data: bytes) -> None:
        self.end.send(data)

    async def read(self, n: int) -> bytes:
        return (await self.rec.wait_bytes(n))[:n]


class TestMemoryContract(TransportContract):
    closed_message = "link is down"

    @pytest.fixture
    async def link(self) -> AsyncIterator[Link]:
        a, b = MemoryTransport.pair()
        peer = _MemoryPeer(b)

        async def ready() -> None:
            await b.open()

        yield Link(a, peer, ready)
        await b.close()

    def after_exchange(self, link: Link, rec: Recorder) -> None:
        assert link.transport.bytes_sent == sum(map(len, TO_PEER))  # type: ignore[attr-defined]
