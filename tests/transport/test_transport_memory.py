"""MemoryTransport and the Transport base's defaults: datagram, reset, sends_dropped."""

from __future__ import annotations

import asyncio

import pytest

from _transport_recorder import Recorder
from gcu_async.transport import MemoryTransport


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


@pytest.mark.parametrize("bad", [None, 1, b"x"])
def test_reset_reason_must_be_a_str(bad: object) -> None:
    a, _ = MemoryTransport.pair()
    with pytest.raises(TypeError, match=r"^reason: expected a str, got "):
        a.reset(bad)  # type: ignore[arg-type]
