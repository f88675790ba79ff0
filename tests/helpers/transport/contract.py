"""The transport contract (transport/base.py), written once: :class:`TransportContract` holds
the behaviours every transport shares; each backend's test file subclasses it with a ``link``
fixture (python-can's habit), and keeps only what is its own.

A subclass provides the ``link`` fixture (a :class:`Link`: the transport, not yet opened,
and the peer playing the GCU on the other side, real sockets or a pty) and may extend the
hooks, which hold the backend's own assertions about the same exchange.
"""

from __future__ import annotations

import asyncio
import re
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

import pytest

from gcu_async.errors import LinkLost
from gcu_async.transport import Transport
from helpers.transport.recorder import Recorder, other_tasks

EVERY_BYTE = bytes(range(256))
"""Every byte value: CR, LF, XON/XOFF, ^C and 0xA5 0x5A go through untouched."""
def packet(k: int, size: int) -> bytes:
    """Packet ``k`` of a stream in which every byte position can be checked."""
    return (k.to_bytes(4, "big") * (size // 4 + 1))[:size]


def send_whole_or_drop(t: Transport, sizes: list[int]) -> bytes:
    """Send one :func:`packet` of each size to a peer that does not read; check that each
    was accepted whole or dropped and counted (``sends_dropped``, ``bytes_sent``), and
    return the accepted bytes, in order, which the peer must later read exactly."""
    accepted, dropped = [], 0
    for k, size in enumerate(sizes):
        before = t.sends_dropped
        t.send(packet(k, size))
        if t.sends_dropped > before:
            dropped += 1
        else:
            accepted.append(packet(k, size))
    assert t.sends_dropped == dropped
    assert t.bytes_sent == sum(map(len, accepted))
    return b"".join(accepted)


TO_PEER = [EVERY_BYTE, b"\xa5\x5a host packet"]
"""What the transport sends in the exchange test, packet by packet."""
FROM_PEER = [bytes([i]) * (i + 1) for i in range(50)] + [EVERY_BYTE]
"""What the peer sends back, packet by packet (datagram transports keep the packets)."""


class Peer(Protocol):
    """The GCU's side of a link."""

    def send(self, data: bytes) -> None:
        """Send ``data`` to the transport (one datagram on datagram links)."""

    async def read(self, n: int) -> bytes:
        """The first ``n`` bytes the transport sent (all datagrams, joined); fails after a
        bounded wait."""


async def _nothing() -> None:
    return None


@dataclass
class Link:
    """A transport and its peer, for one test."""

    transport: Transport
    peer: Peer
    ready: Callable[[], Awaitable[None]] = _nothing
    """Wait, after the transport opened, until the peer can send to it (TCP: accepted)."""
    extra: dict[str, Any] = field(default_factory=dict)
    """Whatever the backend's hooks need (its peer's address, a pty's fds …)."""


class TransportContract:
    """The shared behaviours of every :class:`~gcu_async.transport.Transport`."""

    datagram = False
    """Whether every ``on_data`` call carries one datagram (the class's fact)."""
    ordered = True
    closed_message = ""
    """What ``send`` on a closed transport says (a regular expression)."""

    # -- hooks: the backend's own assertions about the same exchange ----------------------
    def after_exchange(self, link: Link, rec: Recorder) -> None:
        """After :meth:`test_bytes_both_directions_in_order`'s exchange, while open."""

    async def after_double_open(self, link: Link) -> None:
        """After the second ``open()`` of an open transport: no second link was made."""

    # -- the contract ----------------------------------------------------------------------
    async def test_bytes_both_directions_in_order(self, link: Link) -> None:
        t = link.transport
        async with t:
            await link.ready()
            rec = Recorder(t)
            assert t.connected
            for packet in TO_PEER:
                t.send(packet)
            sent = b"".join(TO_PEER)
            assert await link.peer.read(len(sent)) == sent
            for packet in FROM_PEER:
                link.peer.send(packet)
            received = b"".join(FROM_PEER)
            assert await rec.wait_bytes(len(received)) == received
            if t.datagram:
                assert rec.chunks == FROM_PEER  # one datagram per call, in order
            assert rec.events == []
            self.after_exchange(link, rec)
        assert not t.connected
        assert other_tasks() == set()

    async def test_close_is_idempotent_and_send_after_close_raises(self, link: Link) -> None:
        t = link.transport
        with pytest.raises(LinkLost):
            t.send(b"not open yet")
        await t.close()  # never opened
        await t.open()
        await t.open()  # already open: no second socket, connection or fd
        await link.ready()
        await self.after_double_open(link)
        await t.close()
        await t.close()
        assert not t.connected
        with pytest.raises(LinkLost, match=self.closed_message):
            t.send(b"too late")
        assert other_tasks() == set()

    async def test_handler_exception_does_not_stop_delivery(self, link: Link) -> None:
        loop = asyncio.get_running_loop()
        reported: list[dict[str, Any]] = []
        loop.set_exception_handler(lambda _loop, ctx: reported.append(ctx))
        try:
            async with link.transport as t:
                await link.ready()
                rec = Recorder(t)

                def on_data(data: bytes) -> None:
                    rec.on_data(data)
                    if len(rec.chunks) == 1:
                        raise RuntimeError("handler bug")

                t.set_handlers(on_data, rec.on_event)
                link.peer.send(b"first")
                await rec.wait_bytes(5)
                link.peer.send(b"second")
                assert await rec.wait_bytes(11) == b"firstsecond"
                if t.datagram:
                    assert rec.chunks == [b"first", b"second"]
                assert t.connected
                assert rec.events == []
                assert len(reported) == 1
                assert isinstance(reported[0]["exception"], RuntimeError)
        finally:
            loop.set_exception_handler(None)

    @pytest.mark.parametrize("bad", [None, 1, b"x"])
    async def test_reset_checks_its_reason(self, link: Link, bad: object) -> None:
        t = link.transport
        t.reset("never opened")
        async with t:
            await link.ready()
            message = f"reason: expected a str, got {type(bad).__name__} {bad!r}"
            with pytest.raises(TypeError, match=f"^{re.escape(message)}$"):
                t.reset(bad)  # type: ignore[arg-type]
            assert t.connected
        t.reset("after close")

    async def test_datagram_and_ordering_facts(self, link: Link) -> None:
        t = link.transport
        assert t.datagram is self.datagram
        assert t.ordered is self.ordered
        assert type(t).datagram is self.datagram  # a fact of the class (the registry reads it)
