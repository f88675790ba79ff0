"""TcpTransport against real asyncio TCP servers on loopback (ephemeral ports only)."""

from __future__ import annotations

import asyncio
import contextlib
import random
import socket
from collections.abc import AsyncIterator
from typing import Any

import pytest

from gcu_async.errors import LinkLost
from gcu_async.transport import Backoff, LinkEventKind, TcpTransport
from helpers.transport.contract import FROM_PEER, TO_PEER, Link, TransportContract
from helpers.transport.recorder import Recorder, other_tasks

LOOP = "127.0.0.1"


class Server:
    """A loopback TCP server that records what it receives and can drop its clients."""

    def __init__(self, echo: bool = False) -> None:
        self.echo = echo
        self.server: asyncio.AbstractServer | None = None
        self.writers: list[asyncio.StreamWriter] = []
        self.received = bytearray()
        self.connected = asyncio.Event()
        self.got = asyncio.Event()
        self.port = 0

    async def start(self, port: int = 0) -> Server:
        self.server = await asyncio.start_server(self._handle, LOOP, port)
        self.port = self.server.sockets[0].getsockname()[1]
        return self

    async def _handle(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self.writers.append(writer)
        self.connected.set()
        while chunk := await reader.read(65536):
            self.received += chunk
            self.got.set()
            if self.echo:
                writer.write(chunk)
        writer.close()

    async def wait_connected(self, n: int = 1, timeout: float = 2.0) -> asyncio.StreamWriter:
        async def wait() -> None:
            while len(self.writers) < n:
                self.connected.clear()
                await self.connected.wait()

        await asyncio.wait_for(wait(), timeout)
        return self.writers[n - 1]

    async def wait_received(self, n: int, timeout: float = 2.0) -> bytes:
        async def wait() -> None:
            while len(self.received) < n:
                self.got.clear()
                await self.got.wait()

        await asyncio.wait_for(wait(), timeout)
        return bytes(self.received)

    async def stop(self) -> None:
        """Stop listening (new connects are refused), then drop every client."""
        if self.server is not None:
            self.server.close()
        for writer in self.writers:
            writer.close()
        for writer in self.writers:
            with contextlib.suppress(ConnectionError, asyncio.TimeoutError):
                await asyncio.wait_for(writer.wait_closed(), 1.0)
        if self.server is not None:
            await asyncio.wait_for(self.server.wait_closed(), 2.0)
            self.server = None


@pytest.fixture
async def servers() -> AsyncIterator[list[Server]]:
    made: list[Server] = []
    yield made
    for server in made:
        await server.stop()


async def start(servers: list[Server], port: int = 0, echo: bool = False) -> Server:
    server = await Server(echo).start(port)
    servers.append(server)
    return server


def free_port() -> int:
    """A loopback port nobody listens on (bound then released)."""
    with socket.socket() as s:
        s.bind((LOOP, 0))
        return int(s.getsockname()[1])


class MaxRandom(random.Random):
    """Deterministic 'jitter': always the top of the range."""

    def random(self) -> float:
        return 1.0


async def test_connection_refused_on_open_raises_linklost() -> None:
    port = free_port()
    t = TcpTransport(LOOP, port)
    with pytest.raises(LinkLost, match=f"tcp://127.0.0.1:{port}: cannot connect") as info:
        await t.open()
    assert isinstance(info.value, ConnectionError)
    assert isinstance(info.value.__cause__, ConnectionRefusedError)
    assert not t.connected
    with pytest.raises(LinkLost, match="link is down"):
        t.send(b"x")
    await t.close()
    assert other_tasks() == set()


async def test_connect_timeout_raises_linklost() -> None:
    # A listener with a full backlog that never accepts: Linux drops further SYNs.
    listener = socket.socket()
    fillers: list[socket.socket] = []
    try:
        listener.bind((LOOP, 0))
        listener.listen(0)
        port = listener.getsockname()[1]
        for _ in range(3):
            filler = socket.socket()
            fillers.append(filler)
            filler.setblocking(False)
            filler.connect_ex((LOOP, port))
        await asyncio.sleep(0.05)
        t = TcpTransport(LOOP, port, connect_timeout=0.2)
        loop = asyncio.get_running_loop()
        started = loop.time()
        with pytest.raises(LinkLost, match=r"connect timed out after 0\.2 s"):
            await t.open()
        assert 0.15 <= loop.time() - started < 1.0
        await t.close()
    finally:
        for s in fillers:
            s.close()
        listener.close()
    assert other_tasks() == set()


async def test_server_drop_gives_lost_then_restored_within_backoff_bounds(
    servers: list[Server],
) -> None:
    loop = asyncio.get_running_loop()
    server = await start(servers)
    port = server.port
    backoff = Backoff(base=0.02, factor=2.0, cap=0.16, max_attempts=60)
    seed = 20240611
    t = TcpTransport(LOOP, port, backoff=backoff, rng=random.Random(seed))
    rec = Recorder(t)
    await t.open()
    await server.wait_connected()

    await server.stop()
    await rec.wait_events(1)
    assert rec.events[0].kind is LinkEventKind.LOST
    assert "peer closed the connection" in rec.events[0].detail
    assert not t.connected
    assert t.reconnecting
    with pytest.raises(LinkLost, match="reconnecting"):
        t.send(b"while down")

    down_for = 0.3
    await asyncio.sleep(down_for)
    server2 = await start(servers, port=port)
    restarted_at = loop.time() - rec.event_times[0]

    await rec.wait_events(2)
    assert rec.kinds() == [LinkEventKind.LOST, LinkEventKind.RESTORED]
    assert t.connected
    assert not t.reconnecting
    elapsed = rec.event_times[1] - rec.event_times[0]

    # The schedule, computed here independently: full jitter over min(cap, base * 2**n).
    rng = random.Random(seed)
    k = t.reconnect_attempts
    delays = [rng.random() * min(0.16, 0.02 * 2**n) for n in range(k)]
    assert k >= 2  # some attempts were refused while the server was down
    # the sleeps are lower bounds; connect attempts and scheduling add a little each
    assert sum(delays) - 0.001 <= elapsed <= sum(delays) + 0.05 * k + 0.5
    # attempt k-1 was refused, so it started (no earlier than its schedule) before the
    # restart; attempt k, the first to succeed, did not start long before the restart
    assert sum(delays[:-1]) < restarted_at
    assert sum(delays) + 0.05 * k + 0.3 >= restarted_at

    t.send(b"back again")
    assert await server2.wait_received(10) == b"back again"
    writer = await server2.wait_connected()
    writer.write(b"hello")
    assert await rec.wait_bytes(5) == b"hello"
    assert t.reconnects == 1
    await t.close()
    assert other_tasks() == set()


async def test_gives_up_after_max_attempts(servers: list[Server]) -> None:
    server = await start(servers)
    backoff = Backoff(base=0.01, factor=2.0, cap=0.02, max_attempts=3)
    t = TcpTransport(LOOP, server.port, backoff=backoff, rng=MaxRandom())
    rec = Recorder(t)
    await t.open()
    await server.wait_connected()
    await server.stop()
    await rec.wait_events(2)
    assert rec.kinds() == [LinkEventKind.LOST, LinkEventKind.GAVE_UP]
    final = rec.events[1].detail
    assert final.startswith("giving up after 3 reconnect attempts")
    assert "cannot connect" in final
    assert t.reconnect_attempts == 3
    # MaxRandom: the delays are exactly the ceilings 0.01, 0.02, 0.02
    assert rec.event_times[1] - rec.event_times[0] >= 0.05
    await asyncio.sleep(0.05)
    assert len(rec.events) == 2  # stays down, no more attempts
    assert not t.reconnecting
    assert other_tasks() == set()
    with pytest.raises(LinkLost, match="link is down"):
        t.send(b"x")
    await t.close()


async def test_gives_up_after_max_total(servers: list[Server]) -> None:
    server = await start(servers)
    backoff = Backoff(base=0.01, factor=2.0, cap=0.02, max_attempts=None, max_total=0.2)
    t = TcpTransport(LOOP, server.port, backoff=backoff, rng=random.Random(3))
    rec = Recorder(t)
    await t.open()
    await server.wait_connected()
    await server.stop()
    await rec.wait_events(2)
    assert rec.kinds() == [LinkEventKind.LOST, LinkEventKind.GAVE_UP]
    assert rec.events[1].detail.startswith("giving up")
    elapsed = rec.event_times[1] - rec.event_times[0]
    # no attempt starts once the next sleep would end past the deadline (cap 0.02 s)
    assert 0.2 - 0.02 - 0.005 <= elapsed <= 0.2 + 0.5
    assert t.reconnect_attempts >= 5
    await t.close()


async def test_close_during_reconnect_leaves_no_task(servers: list[Server]) -> None:
    server = await start(servers)
    backoff = Backoff(base=5.0, cap=5.0, max_attempts=1)
    t = TcpTransport(LOOP, server.port, backoff=backoff, rng=MaxRandom())
    rec = Recorder(t)
    await t.open()
    await server.wait_connected()
    await server.stop()
    await rec.wait_events(1)
    assert t.reconnecting
    assert len(other_tasks()) == 1
    loop = asyncio.get_running_loop()
    started = loop.time()
    await t.close()
    assert loop.time() - started < 0.5  # the 5 s backoff sleep was cancelled
    assert not t.reconnecting
    assert other_tasks() == set()
    assert rec.kinds() == [LinkEventKind.LOST]  # no "giving up" after a deliberate close
    await t.close()


async def test_without_reconnect_gives_up_at_once_and_stays_down_until_reopened(
        servers: list[Server]) -> None:  # fmt: skip
    server = await start(servers)
    port = server.port
    t = TcpTransport(LOOP, port, reconnect=False)
    rec = Recorder(t)
    await t.open()
    await server.wait_connected()
    await server.stop()
    await rec.wait_events(2)
    assert rec.kinds() == [LinkEventKind.LOST, LinkEventKind.GAVE_UP]
    assert rec.events[1].detail == f"giving up at once: reconnect is off ({t.url})"
    assert not t.reconnecting
    assert other_tasks() == set()
    with pytest.raises(LinkLost):
        t.send(b"x")
    server2 = await start(servers, port=port)
    await t.open()
    t.send(b"again")
    assert await server2.wait_received(5) == b"again"
    await t.close()


def test_backoff_ceilings_and_full_jitter() -> None:
    b = Backoff()
    assert (b.base, b.factor, b.cap) == (0.05, 2.0, 2.0)
    assert [b.delay(n, MaxRandom()) for n in range(8)] == [
        0.05, 0.1, 0.2, 0.4, 0.8, 1.6, 2.0, 2.0,
    ]  # fmt: skip
    assert b.ceiling(5000) == 2.0  # no overflow for huge attempt numbers
    rng = random.Random(42)
    samples = [b.delay(3, rng) for _ in range(2000)]
    assert all(0.0 <= s <= 0.4 for s in samples)
    assert 0.17 <= sum(samples) / len(samples) <= 0.23  # uniform over [0, 0.4]
    assert min(samples) < 0.02
    assert max(samples) > 0.38


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"base": 0}, r"backoff_base: 0 is out of range"),
        ({"factor": 0.5}, r"backoff_factor: 0\.5 is out of range \(allowed >= 1\)"),
        ({"cap": 0.01}, r"backoff_cap: 0\.01 is smaller than backoff_base 0\.05"),
        ({"max_attempts": 0}, r"max_attempts: 0 is out of range"),
        ({"max_total": -1.0}, r"max_total: -1\.0 is out of range"),
    ],
)
def test_backoff_validation(kwargs: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        Backoff(**kwargs)


def test_backoff_is_unbounded_unless_asked() -> None:
    assert (Backoff().max_attempts, Backoff().max_total, Backoff().bounded) == (None, None, False)
    assert Backoff(max_attempts=None, max_total=None) == Backoff()
    assert Backoff(max_attempts=3).bounded and Backoff(max_total=60.0).bounded


def test_constructor_validation() -> None:
    with pytest.raises(ValueError, match=r"port: 70000 is not a valid port"):
        TcpTransport(LOOP, 70000)
    with pytest.raises(ValueError, match=r"connect_timeout: 0 is out of range"):
        TcpTransport(LOOP, connect_timeout=0)
    assert TcpTransport(LOOP).url == "tcp://127.0.0.1:2332"
    assert TcpTransport("::1", 5).url == "tcp://[::1]:5"


class _TcpPeer:
    def __init__(self, server: Server) -> None:
        self.server = server

    def send(self, data: bytes) -> None:
        self.server.writers[-1].write(data)

    async def read(self, n: int) -> bytes:
        return (await self.server.wait_received(n))[:n]


class TestTcpContract(TransportContract):
    closed_message = "link is down"

    @pytest.fixture
    async def link(self, servers: list[Server]) -> Link:
        server = await start(servers)

        async def ready() -> None:
            await server.wait_connected()

        return Link(TcpTransport(LOOP, server.port), _TcpPeer(server), ready,
                    extra={"server": server})  # fmt: skip

    def after_exchange(self, link: Link, rec: Recorder) -> None:
        t, server = link.transport, link.extra["server"]
        assert isinstance(t, TcpTransport)
        assert t.url == f"tcp://127.0.0.1:{server.port}"
        assert t.bytes_sent == sum(map(len, TO_PEER))
        assert t.bytes_received == sum(map(len, FROM_PEER))

    async def after_double_open(self, link: Link) -> None:
        await asyncio.sleep(0.02)
        assert len(link.extra["server"].writers) == 1  # one connection


async def test_bytes_echoed_back_in_order_in_1000_byte_pieces(servers: list[Server]) -> None:
    """Past one segment: 10 KiB in 1000-byte sends, echoed back whole and in order."""
    server = await start(servers, echo=True)
    async with TcpTransport(LOOP, server.port) as t:
        rec = Recorder(t)
        payload = bytes(range(256)) * 40
        for i in range(0, len(payload), 1000):
            t.send(payload[i : i + 1000])
        assert await server.wait_received(len(payload)) == payload
        assert await rec.wait_bytes(len(payload)) == payload  # echoed back, in order
        assert t.bytes_sent == t.bytes_received == len(payload)
        assert rec.events == []
    assert not t.connected
    assert other_tasks() == set()
