"""Getting up (docs/client.md, "Lifecycle"): with ``open_timeout`` the client keeps trying
until the GCU answers — a GCU powered later, a TCP server not yet listening — reports each
failed attempt as a RETRYING link event, gives up with LinkLost when the time is out, and
stops at once when closed. Real sockets on loopback against the simulator."""

from __future__ import annotations

import asyncio
import socket
import time

import pytest

from gcu_async import LinkLost, connect
from gcu_async.client import ClientState
from gcu_async.sim import GcuSimulator
from gcu_async.transport.base import LinkEvent, LinkEventKind


def free_tcp_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
        return port


async def test_udp_gcu_powered_later() -> None:
    sim = GcuSimulator(pod="D-90Pro(TA)")
    async with sim.serve_udp("127.0.0.1", 0) as server:
        sim.silence(1.2)  # not answering yet
        gcu = connect(server.url, local_port=0, connect_timeout=0.3, open_timeout=10.0)
        events: list[LinkEvent] = []
        gcu.on_link_change(events.append)
        t0 = time.monotonic()
        async with gcu:
            assert time.monotonic() - t0 >= 1.0
            assert gcu.link.up
            await gcu.take_photo()
        retries = [e for e in events if e.kind is LinkEventKind.RETRYING]
        assert retries and retries[0].detail.startswith("attempt 1 failed: ")
        assert "no reply from the GCU within 0.3 s" in retries[0].detail


async def test_tcp_server_listening_later() -> None:
    port = free_tcp_port()
    sim = GcuSimulator(pod="D-90Pro(TA)")
    gcu = connect(f"tcp://127.0.0.1:{port}", connect_timeout=0.3, open_timeout=10.0)
    events: list[LinkEvent] = []
    gcu.on_link_change(events.append)
    opening = asyncio.create_task(gcu.open())
    await asyncio.sleep(1.0)
    assert not opening.done()
    async with sim.serve_tcp("127.0.0.1", port):
        await asyncio.wait_for(opening, 10.0)
        try:
            await gcu.take_photo()
        finally:
            await gcu.close()
    assert any(e.kind is LinkEventKind.RETRYING and "cannot connect" in e.detail for e in events)


async def test_gives_up_after_open_timeout_naming_the_attempts() -> None:
    port = free_tcp_port()
    gcu = connect(f"tcp://127.0.0.1:{port}", connect_timeout=0.2, open_timeout=1.0)
    t0 = time.monotonic()
    with pytest.raises(LinkLost, match=r"no GCU within open_timeout 1 s \(\d+ attempts; last: "):
        await gcu.open()
    assert 0.5 <= time.monotonic() - t0 <= 1.5
    assert gcu.state is ClientState.CLOSED


async def test_close_stops_the_retries_and_the_client_opens_again_later() -> None:
    port = free_tcp_port()
    gcu = connect(f"tcp://127.0.0.1:{port}", connect_timeout=0.2, open_timeout=60.0)
    opening = asyncio.create_task(gcu.open())
    await asyncio.sleep(0.8)
    with pytest.raises(RuntimeError, match="not reentrant"):
        await gcu.open()
    t0 = time.monotonic()
    await gcu.close()
    with pytest.raises(LinkLost, match="closed while opening"):
        await asyncio.wait_for(opening, 5.0)
    assert time.monotonic() - t0 < 0.5
    assert gcu.state is ClientState.CLOSED
    sim = GcuSimulator(pod="D-90Pro(TA)")
    async with sim.serve_tcp("127.0.0.1", port), gcu:  # reusable
        await gcu.take_photo()


async def test_without_open_timeout_one_attempt_fails_at_once() -> None:
    port = free_tcp_port()
    gcu = connect(f"tcp://127.0.0.1:{port}", connect_timeout=0.5)
    t0 = time.monotonic()
    with pytest.raises(LinkLost, match="cannot connect"):
        await gcu.open()
    assert time.monotonic() - t0 < 0.5


@pytest.mark.parametrize(("value", "error"), [
    (0, ValueError), (-1.0, ValueError), (float("nan"), ValueError), (True, TypeError),
    ("5", TypeError),
])  # fmt: skip
def test_open_timeout_is_checked(value: object, error: type[Exception]) -> None:
    with pytest.raises(error, match="open_timeout"):
        connect("udp://127.0.0.1:2337", open_timeout=value)
