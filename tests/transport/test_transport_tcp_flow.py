"""TcpTransport flow control against a raw loopback peer that reads only when told to:
bursts drained in one event, backpressure (drop, never queue), and reset() (RST)."""

from __future__ import annotations

import asyncio
import socket
import struct
import time
from collections.abc import AsyncIterator

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gcu_async.errors import LinkLost
from gcu_async.transport import Backoff, LinkEventKind, TcpTransport
from helpers.transport.contract import packet, send_whole_or_drop
from helpers.transport.recorder import Recorder, other_tasks

LOOP = "127.0.0.1"
FAST = Backoff(base=0.01, factor=2.0, cap=0.05, max_attempts=50)


def block_loop(seconds: float) -> None:
    """Keep the event loop from running for ``seconds``, as a slow handler would: on
    purpose, so that input piles up in the kernel meanwhile."""
    time.sleep(seconds)


class SilentPeer:
    """A listening socket standing in for a GCU whose application stalls: accepted
    connections are read only when the test asks."""

    def __init__(self) -> None:
        self.listener = socket.socket()
        self.listener.bind((LOOP, 0))
        self.listener.listen(8)
        self.listener.setblocking(False)
        self.port = int(self.listener.getsockname()[1])
        self.conns: list[socket.socket] = []

    async def accept(self, timeout: float = 2.0) -> socket.socket:
        loop = asyncio.get_running_loop()
        conn, _ = await asyncio.wait_for(loop.sock_accept(self.listener), timeout)
        conn.setblocking(False)
        self.conns.append(conn)
        return conn

    def close(self) -> None:
        for s in [*self.conns, self.listener]:
            s.close()


@pytest.fixture
async def peer() -> AsyncIterator[SilentPeer]:
    p = SilentPeer()
    yield p
    p.close()


def queued(sock: socket.socket | int, request: int) -> int:
    """SIOCINQ (FIONREAD): bytes in the receive queue; SIOCOUTQ (TIOCOUTQ): bytes in the
    send queue not yet acknowledged by the peer."""
    import fcntl  # POSIX only; settled_queues skips the test where it is missing

    fd = sock if isinstance(sock, int) else sock.fileno()
    return int(struct.unpack("i", fcntl.ioctl(fd, request, b"\0" * 4))[0])


async def read_n(conn: socket.socket, n: int, timeout: float = 5.0) -> bytes:
    """Read until ``n`` bytes came (or ``timeout`` passed) from a non-blocking socket."""
    got = bytearray()
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    while len(got) < n and loop.time() < deadline:
        data, err = read_available(conn)
        assert err is None
        got += data
        await asyncio.sleep(0.001)
    return bytes(got)


def read_available(conn: socket.socket) -> tuple[bytes, BaseException | None]:
    """Everything ``conn`` can read now, and the error (or None at EOF / would block)."""
    data = bytearray()
    while True:
        try:
            chunk = conn.recv(1 << 20)
        except BlockingIOError:
            return bytes(data), None
        except OSError as exc:
            return bytes(data), exc
        if not chunk:
            return bytes(data), None
        data += chunk


async def settled_queues(conn: socket.socket, sock: socket.socket) -> tuple[int, int]:
    """(peer's receive queue, our unacknowledged send queue) once they stop changing: data
    the peer's kernel holds but has not acknowledged yet (delayed ACK) counts in both."""
    why = "kernel socket queues are read with POSIX ioctls (FIONREAD, TIOCOUTQ): not on Windows"
    pytest.importorskip("fcntl", reason=why)
    termios = pytest.importorskip("termios", reason=why)
    loop = asyncio.get_running_loop()
    deadline = loop.time() + 3.0
    last = (-1, -1)
    while loop.time() < deadline:
        now = (queued(conn, termios.FIONREAD), queued(sock.fileno(), termios.TIOCOUTQ))
        if now == last:
            return now
        last = now
        await asyncio.sleep(0.25)  # longer than the longest delayed ACK (200 ms)
    raise AssertionError(f"the socket queues did not settle: {last}")


PACKET_SIZE = 1000
"""Size of the packets these tests send when the size does not matter."""


def fill_until_dropped(t: TcpTransport, size: int = 1000, limit: int = 200_000) -> list[bytes]:
    """Send packets until the first one is dropped; return those accepted, in order."""
    accepted = []
    for k in range(limit):
        dropped = t.sends_dropped
        p = packet(k, size)
        t.send(p)
        if t.sends_dropped > dropped:
            return accepted
        accepted.append(p)
    raise AssertionError(f"the kernel took {limit} packets without pushing back")


async def test_burst_that_arrived_while_blocked_comes_in_one_event(peer: SilentPeer) -> None:
    async with TcpTransport(LOOP, peer.port) as t:
        rec = Recorder(t)
        conn = await peer.accept()
        burst = b"".join(packet(k, 73) for k in range(200))
        conn.setblocking(True)
        conn.sendall(burst)
        block_loop(0.05)  # the loop is blocked while the whole burst arrives
        await asyncio.sleep(0)
        await asyncio.sleep(0)  # exactly one readiness event ran (see the UDP drain tests)
        assert rec.chunks == [burst]


async def test_backpressure_drops_new_packets_instead_of_queueing(peer: SilentPeer) -> None:
    async with TcpTransport(LOOP, peer.port) as t:
        conn = await peer.accept()
        accepted = fill_until_dropped(t)
        at_peer, our_kernel = await settled_queues(conn, t.get_extra_info("socket"))
        in_user_space = t.bytes_sent - at_peer - our_kernel
        # asyncio holds only the rest of the one packet the kernel took in part (or all of it)
        assert 0 < in_user_space <= 1000
        for _ in range(500):  # a stalled peer under a 50 Hz heartbeat: nothing more queues
            t.send(packet(0, PACKET_SIZE))
        assert t.sends_dropped == 501
        assert t.bytes_sent == len(accepted) * 1000

        # the peer resumes: it reads exactly the accepted packets, whole and in order
        expected = b"".join(accepted)
        assert await read_n(conn, len(expected)) == expected
        # once drained, sending works again
        t.send(b"after")
        await asyncio.sleep(0.05)
        assert read_available(conn) == (b"after", None)
        assert t.sends_dropped == 501


async def test_reset_discards_our_queues_but_not_what_the_peer_already_has(
    peer: SilentPeer,
) -> None:
    """The Linux fact behind reset(): after an RST the peer can still read what had reached
    its kernel receive buffer (then ECONNRESET); what was still queued on our side (the
    kernel send queue, asyncio's buffer) never arrives, on this or any later connection."""
    t = TcpTransport(LOOP, peer.port, backoff=FAST)
    rec = Recorder(t)
    await t.open()
    conn = await peer.accept()
    accepted = fill_until_dropped(t)
    stream = b"".join(accepted)
    at_peer, our_kernel = await settled_queues(conn, t.get_extra_info("socket"))
    ours_in_asyncio = t.bytes_sent - at_peer - our_kernel
    assert at_peer > 0 and our_kernel > 0 and ours_in_asyncio > 0

    t.reset("test stalled peer")
    await rec.wait_events(1)
    assert rec.events[0].kind is LinkEventKind.LOST
    assert rec.events[0].detail.startswith("reset: test stalled peer")

    got, err = read_available(conn)
    assert got == stream[:at_peer]  # what the peer's kernel had: still delivered
    assert isinstance(err, ConnectionResetError)  # then the reset
    assert read_available(conn) == (b"", None)  # and nothing more, ever

    # reconnection as after any loss; the new connection starts empty
    conn2 = await peer.accept()
    await rec.wait_events(2)
    assert rec.kinds() == [LinkEventKind.LOST, LinkEventKind.RESTORED]
    t.send(b"fresh")
    await asyncio.sleep(0.05)
    assert read_available(conn2) == (b"fresh", None)
    assert t.reconnects == 1
    await t.close()
    assert other_tasks() == set()


async def test_reset_events_come_from_the_loop_not_from_the_call(peer: SilentPeer) -> None:
    t = TcpTransport(LOOP, peer.port, backoff=FAST)
    rec = Recorder(t)
    await t.open()
    await peer.accept()
    t.reset("why")
    assert rec.events == []  # nothing synchronously
    assert not t.connected
    assert t.reconnecting
    with pytest.raises(LinkLost, match="link is down"):
        t.send(b"x")
    await asyncio.sleep(0)
    assert [(e.kind, e.detail) for e in rec.events] == [
        (LinkEventKind.LOST, f"reset: why (tcp://127.0.0.1:{peer.port})")
    ]
    await t.close()


async def test_reset_inside_a_data_handler(peer: SilentPeer) -> None:
    """The caller may be in the middle of its own handling: the LOST event waits for it."""
    t = TcpTransport(LOOP, peer.port, backoff=FAST)
    rec = Recorder(t)

    def on_data(data: bytes) -> None:
        rec.on_data(data)
        t.reset("garbage from the peer")
        rec.log.append(("handler done", None))

    t.set_handlers(on_data, rec.on_event)
    await t.open()
    conn = await peer.accept()
    conn.send(b"garbage")
    await rec.wait_events(1)
    assert [kind for kind, _ in rec.log] == ["data", "handler done", "event"]
    await peer.accept()
    await rec.wait_events(2)
    assert rec.kinds() == [LinkEventKind.LOST, LinkEventKind.RESTORED]
    await t.close()


async def test_reset_without_reconnect_gives_up_and_stays_down(peer: SilentPeer) -> None:
    t = TcpTransport(LOOP, peer.port, reconnect=False)
    rec = Recorder(t)
    await t.open()
    conn = await peer.accept()
    t.reset("done")
    assert rec.kinds() == []  # the events follow via call_soon, never from inside reset()
    await rec.wait_events(2)
    await asyncio.sleep(0.05)
    assert rec.kinds() == [LinkEventKind.LOST, LinkEventKind.GAVE_UP]
    assert not t.reconnecting
    assert other_tasks() == set()
    assert isinstance(read_available(conn)[1], ConnectionResetError)
    await t.open()  # can be opened again
    await peer.accept()
    assert t.connected
    await t.close()


async def test_reset_while_down_or_closed_does_nothing(peer: SilentPeer) -> None:
    t = TcpTransport(LOOP, peer.port, backoff=FAST)
    rec = Recorder(t)
    t.reset("never opened")
    await t.open()
    await peer.accept()
    t.reset("first")
    t.reset("second, while reconnecting")
    await peer.accept()
    await rec.wait_events(2)
    assert rec.kinds() == [LinkEventKind.LOST, LinkEventKind.RESTORED]
    assert rec.events[0].detail.startswith("reset: first (")  # the second did nothing
    assert t.reconnects == 1
    await t.close()
    t.reset("after close")
    await asyncio.sleep(0.02)
    assert len(rec.events) == 2


async def test_close_right_after_reset_emits_nothing(peer: SilentPeer) -> None:
    t = TcpTransport(LOOP, peer.port, backoff=FAST)
    rec = Recorder(t)
    await t.open()
    conn = await peer.accept()
    t.reset("then close")
    await t.close()
    await asyncio.sleep(0.02)
    assert rec.events == []  # a deliberate close reports nothing, as always
    assert other_tasks() == set()
    assert isinstance(read_available(conn)[1], ConnectionResetError)


@pytest.mark.parametrize("bad", [None, b"bytes", 3])
async def test_reset_reason_must_be_text(peer: SilentPeer, bad: object) -> None:
    async with TcpTransport(LOOP, peer.port) as t:
        await peer.accept()
        with pytest.raises(TypeError, match=r"reason: expected a str, got"):
            t.reset(bad)  # type: ignore[arg-type]
        assert t.connected
        assert not t.datagram


KERNEL_HOLDS_AT_MOST = 65536
"""Generous bound on what both kernels queue with 4 KiB socket buffers (measured: ~16 KiB)."""


@settings(max_examples=25)
@given(sizes=st.lists(st.integers(1, 30_000), min_size=1, max_size=40))
def test_any_send_sequence_reaches_a_stalled_peer_whole_or_not_at_all(sizes: list[int]) -> None:
    """Whatever the packet sizes, against a peer that stops reading (both kernel buffers
    small): each packet is either accepted (and the peer, once it reads again, gets exactly
    the accepted ones, whole and in order) or dropped and counted, and what is accepted is
    bounded by what the kernels hold plus one packet (queueing would accept everything)."""

    async def scenario() -> None:
        peer = SilentPeer()
        peer.listener.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        try:
            async with TcpTransport(LOOP, peer.port, reconnect=False) as t:
                t.get_extra_info("socket").setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 4096)
                conn = await peer.accept()
                expected = send_whole_or_drop(t, sizes)
                assert t.bytes_sent <= KERNEL_HOLDS_AT_MOST + max(sizes)
                assert await read_n(conn, len(expected)) == expected
        finally:
            peer.close()

    asyncio.run(scenario())
