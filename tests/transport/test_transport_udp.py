"""UdpTransport against real datagram sockets on loopback (ephemeral ports only)."""

from __future__ import annotations

import asyncio
import errno
import socket
from collections.abc import AsyncIterator
from typing import Any, cast

import pytest

from gcu_async.errors import LinkLost
from gcu_async.transport import LinkEventKind, UdpTransport
from gcu_async.transport.udp import is_broadcast_address
from helpers.transport.contract import FROM_PEER, TO_PEER, Link, TransportContract
from helpers.transport.recorder import Recorder

LOOP = "127.0.0.1"


class Peer(asyncio.DatagramProtocol):
    """A plain datagram endpoint standing in for a GCU (or a stranger)."""

    def __init__(self) -> None:
        self.received: list[tuple[bytes, tuple[Any, ...]]] = []
        self.transport: asyncio.DatagramTransport | None = None
        self.got = asyncio.Event()

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        # (asyncio's selector datagram transport does not subclass DatagramTransport on 3.11)
        self.transport = cast(asyncio.DatagramTransport, transport)

    def datagram_received(self, data: bytes, addr: tuple[Any, ...]) -> None:
        self.received.append((data, addr))
        self.got.set()

    @property
    def address(self) -> tuple[str, int]:
        assert self.transport is not None
        host, port = self.transport.get_extra_info("sockname")[:2]
        return host, port

    def send(self, data: bytes, addr: tuple[str, int] | None) -> None:
        assert self.transport is not None
        assert addr is not None
        self.transport.sendto(data, addr)

    async def wait_count(self, n: int, timeout: float = 2.0) -> None:
        async def loop() -> None:
            while len(self.received) < n:
                self.got.clear()
                await self.got.wait()

        await asyncio.wait_for(loop(), timeout)


@pytest.fixture(params=["draining", "fallback"])
async def reader_path(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> str:
    """Run a test on both receive paths: the draining reader, and asyncio's own datagram
    transport, which UdpTransport falls back to on loops without add_reader (Windows'
    proactor loop; simulated here by refusing add_reader on the running loop)."""
    if request.param == "fallback":

        def refuse(*args: object) -> None:
            raise NotImplementedError("add_reader is refused by this test")

        monkeypatch.setattr(asyncio.get_running_loop(), "add_reader", refuse)
    return str(request.param)


@pytest.fixture
async def make_peer(reader_path: str) -> AsyncIterator[Any]:
    made: list[asyncio.DatagramTransport] = []

    async def make(host: str = LOOP) -> Peer:
        loop = asyncio.get_running_loop()
        transport, peer = await loop.create_datagram_endpoint(Peer, local_addr=(host, 0))
        made.append(transport)
        return peer

    yield make
    for transport in made:
        transport.close()
    await asyncio.sleep(0)  # let connection_lost run, releasing the sockets


def udp_to(peer: Peer, **kw: Any) -> UdpTransport:
    kw.setdefault("local_host", LOOP)
    kw.setdefault("local_port", 0)
    return UdpTransport(peer.address[0], peer.address[1], **kw)


async def test_datagrams_from_other_sources_are_counted_and_dropped(make_peer: Any) -> None:
    gcu = await make_peer()
    stranger = await make_peer()
    async with udp_to(gcu) as t:
        rec = Recorder(t)
        stranger.send(b"not from the gcu", t.local_address)
        stranger.send(b"nor this", t.local_address)
        gcu.send(b"from the gcu", t.local_address)
        await rec.wait_until(lambda: len(rec.chunks) == 1)
        # loopback queues datagrams in send order: the strangers' were handled first
        assert rec.chunks == [b"from the gcu"]
        assert t.rejected_datagrams == 2
        assert t.rx_datagrams == 1
        assert rec.events == []


async def test_same_host_other_port_is_rejected(make_peer: Any) -> None:
    gcu = await make_peer()
    same_ip = await make_peer()
    assert same_ip.address[0] == gcu.address[0]
    async with udp_to(gcu) as t:
        rec = Recorder(t)
        same_ip.send(b"wrong port", t.local_address)
        gcu.send(b"ok", t.local_address)
        await rec.wait_until(lambda: len(rec.chunks) == 1)
        assert rec.chunks == [b"ok"]
        assert t.rejected_datagrams == 1


async def test_discovery_reports_peer_and_accepts_any_source(make_peer: Any) -> None:
    configured = await make_peer()
    a = await make_peer()
    b = await make_peer()
    async with udp_to(configured, discovery=True) as t:
        assert isinstance(t, UdpTransport)
        rec = Recorder(t)
        assert t.peer is None
        a.send(b"hello from a", t.local_address)
        a.send(b"again from a", t.local_address)
        await rec.wait_until(lambda: len(rec.chunks) == 2)
        assert t.peer == a.address
        peer_event = rec.events[0]
        assert peer_event.kind is LinkEventKind.PEER
        assert peer_event.peer == a.address
        # the event comes before the bytes of the datagram that revealed the peer
        assert [kind for kind, _ in rec.log] == ["event", "data", "data"]

        # without follow_peer, sends still go to the configured address
        t.send(b"to configured")
        await configured.wait_count(1)
        assert configured.received[0][0] == b"to configured"
        assert a.received == []

        b.send(b"from b", t.local_address)
        await rec.wait_until(lambda: len(rec.chunks) == 3)
        assert [e.peer for e in rec.events] == [a.address, b.address]
        assert t.peer == b.address
        assert t.rejected_datagrams == 0


async def test_follow_peer_sends_to_discovered_peer(make_peer: Any) -> None:
    configured = await make_peer()
    gcu = await make_peer()
    async with udp_to(configured, discovery=True, follow_peer=True) as t:
        assert isinstance(t, UdpTransport)
        rec = Recorder(t)
        assert t.remote_address == configured.address
        gcu.send(b"i am here", t.local_address)
        await rec.wait_until(lambda: len(rec.chunks) == 1)
        assert t.remote_address == gcu.address
        t.send(b"to the discovered gcu")
        await gcu.wait_count(1)
        assert gcu.received[0][0] == b"to the discovered gcu"
        assert configured.received == []


def _broadcast_flag(t: UdpTransport) -> int:
    sock = t.get_extra_info("socket")
    assert sock is not None
    return int(sock.getsockopt(socket.SOL_SOCKET, socket.SO_BROADCAST))


async def test_broadcast_flag_set_when_asked(make_peer: Any) -> None:
    gcu = await make_peer()
    async with udp_to(gcu, broadcast=True) as t:
        assert _broadcast_flag(t) == 1
    async with udp_to(gcu) as t:
        assert _broadcast_flag(t) == 0


def test_broadcast_address_detection() -> None:
    assert is_broadcast_address("127.255.255.255")
    assert is_broadcast_address("255.255.255.255")
    assert not is_broadcast_address("127.0.0.1")
    assert not is_broadcast_address("::1")
    assert not is_broadcast_address("localhost")


async def test_broadcast_remote_sets_flag_and_sends(reader_path: str) -> None:
    # 127.255.255.255 is the loopback network's broadcast address: the kernel refuses to
    # send there (EACCES) unless SO_BROADCAST is set.
    auto = UdpTransport("127.255.255.255", 9, local_host=LOOP, local_port=0)
    assert auto.broadcast
    async with auto:
        assert _broadcast_flag(auto) == 1
        auto.send(b"anyone there?")
        await asyncio.sleep(0.02)
        assert auto.send_errors == 0
    off = UdpTransport("127.255.255.255", 9, local_host=LOOP, local_port=0, broadcast=False)
    async with off:
        off.send(b"anyone there?")
        assert off.send_errors == 1
        assert isinstance(off.last_error, PermissionError)
        assert off.connected


async def test_send_errors_are_counted_and_not_fatal(make_peer: Any) -> None:
    gcu = await make_peer()
    async with udp_to(gcu) as t:
        assert isinstance(t, UdpTransport)
        t.send(b"x" * 70_000)  # larger than any UDP datagram: EMSGSIZE
        assert t.send_errors == 1
        assert isinstance(t.last_error, OSError)
        assert t.last_error.errno == errno.EMSGSIZE
        assert t.connected
        t.send(b"still alive")
        await gcu.wait_count(1)
        assert gcu.received[0][0] == b"still alive"


async def test_bind_conflict_raises_linklost(make_peer: Any) -> None:
    gcu = await make_peer()
    busy = await make_peer()
    t = UdpTransport(LOOP, gcu.address[1], local_host=LOOP, local_port=busy.address[1])
    with pytest.raises(LinkLost, match=f"cannot bind 127.0.0.1:{busy.address[1]}") as info:
        await t.open()
    assert isinstance(info.value, ConnectionError)
    assert not t.connected
    await t.close()


async def test_ipv6_loopback(make_peer: Any) -> None:
    if not socket.has_ipv6:
        pytest.skip("no IPv6")
    try:
        gcu = await make_peer("::1")
    except OSError:
        pytest.skip("::1 not available")
    async with UdpTransport("::1", gcu.address[1], local_host="::1", local_port=0) as t:
        assert isinstance(t, UdpTransport)
        rec = Recorder(t)
        assert t.url == f"udp://[::1]:{gcu.address[1]}"
        t.send(b"v6")
        await gcu.wait_count(1)
        gcu.send(b"v6 back", t.local_address)
        await rec.wait_bytes(7)
        assert rec.data == b"v6 back"


def test_constructor_validates_ports() -> None:
    with pytest.raises(ValueError, match=r"port: 0 is not a valid port \(allowed 1-65535\)"):
        UdpTransport(LOOP, 0)
    with pytest.raises(ValueError, match=r"local_port: 70000 is not a valid port"):
        UdpTransport(LOOP, 2337, local_port=70000)
    assert UdpTransport(LOOP).url == "udp://127.0.0.1:2337"
    assert UdpTransport(LOOP).local_port == 2338


async def test_reset_is_a_no_op(make_peer: Any) -> None:
    gcu = await make_peer()
    async with udp_to(gcu) as t:
        rec = Recorder(t)
        t.send(b"one")
        t.reset("declared lost")  # no datagram is ever queued: nothing to discard
        t.send(b"two")
        await gcu.wait_count(2)
        assert [d for d, _ in gcu.received] == [b"one", b"two"]
        gcu.send(b"reply", t.local_address)
        await rec.wait_bytes(5)
        assert rec.events == []
        assert t.connected
        assert t.sends_dropped == 0
        with pytest.raises(TypeError, match="reason"):
            t.reset(42)  # type: ignore[arg-type]


class _UdpPeer:
    """The :class:`Peer` datagram endpoint as the contract's peer of ``transport``."""

    def __init__(self, peer: Peer, transport: UdpTransport) -> None:
        self.peer, self.transport = peer, transport

    def send(self, data: bytes) -> None:
        self.peer.send(data, self.transport.local_address)

    async def read(self, n: int) -> bytes:
        async def loop() -> bytes:
            while len(data := b"".join(d for d, _ in self.peer.received)) < n:
                self.peer.got.clear()
                await self.peer.got.wait()
            return data

        return await asyncio.wait_for(loop(), 2.0)


class TestUdpContract(TransportContract):
    """The contract on both receive paths (``reader_path``: draining and fallback)."""

    datagram = True
    ordered = False
    closed_message = "closed"

    @pytest.fixture
    async def link(self, make_peer: Any, reader_path: str) -> Link:
        gcu = await make_peer()
        t = udp_to(gcu)
        return Link(t, _UdpPeer(gcu, t), extra={"gcu": gcu, "reader_path": reader_path})

    def after_exchange(self, link: Link, rec: Recorder) -> None:
        t, gcu = link.transport, link.extra["gcu"]
        assert isinstance(t, UdpTransport)
        assert t.draining is (link.extra["reader_path"] == "draining")
        assert t.peer == gcu.address
        assert all(source[:2] == t.local_address for _, source in gcu.received)
        assert [data for data, _ in gcu.received] == TO_PEER
        assert t.rx_datagrams == len(FROM_PEER)
        assert t.rejected_datagrams == 0
        assert t.tx_datagrams == len(TO_PEER)
