"""UDP socket errors (docs/transports.md, "UDP errors and reopening"; the module docstrings of
gcu_async.transport.udp and ._datagram): ICMP errors are heard on an unconnected socket
(Linux: the error queue), reported as one ERROR link event per episode, never close the
socket, never make the loop spin, never cost a datagram; a socket closed under the transport
is replaced. Real sockets on loopback (an ICMP port unreachable is what the kernel answers
for a loopback port nobody listens on)."""

from __future__ import annotations

import asyncio
import socket
import struct
import sys
import time

import pytest

from gcu_async import connect
from gcu_async.sim import GcuSimulator
from gcu_async.transport import _datagram
from gcu_async.transport._datagram import DrainingDatagramTransport, queued_error
from gcu_async.transport.backoff import Backoff
from gcu_async.transport.base import LinkEvent, LinkEventKind
from gcu_async.transport.udp import UdpTransport
from helpers.sim.support import host_bytes

linux_only = pytest.mark.skipif(
    not sys.platform.startswith("linux"),
    reason="ICMP errors on an unconnected UDP socket are read from Linux's error queue "
    "(IP_RECVERR); Windows turns them off (SIO_UDP_CONNRESET), macOS/BSD do not report them",
)


def silent_udp_port() -> int:
    """A loopback UDP port nobody listens on (bound, then released)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
        return port


async def until(predicate: object, timeout: float = 3.0) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():  # type: ignore[operator]
        if time.monotonic() > deadline:
            raise AssertionError("condition not met in time")
        await asyncio.sleep(0.005)


# -- the error queue entry, decoded --------------------------------------------------------


def _ancdata(level: int, kind: int, errno_: int, origin: int, typ: int, code: int,
             offender: bytes) -> list[tuple[int, int, bytes]]:  # fmt: skip
    return [(level, kind, struct.pack("=IBBBBII", errno_, origin, typ, code, 0, 0, 0) + offender)]


def _sockaddr_in(addr: str) -> bytes:
    return socket.AF_INET.to_bytes(2, sys.byteorder) + b"\0\0" + socket.inet_aton(addr) + bytes(8)


def test_queued_error_names_the_icmp_error_its_sender_and_the_destination() -> None:
    anc = _ancdata(socket.IPPROTO_IP, 11, 111, 2, 3, 3, _sockaddr_in("192.168.144.108"))
    exc = queued_error(anc, ("192.168.144.108", 2337))
    assert isinstance(exc, ConnectionRefusedError)
    assert exc.errno == 111
    assert str(exc).endswith(
        "ICMP port unreachable from 192.168.144.108 for a datagram to 192.168.144.108:2337")


def test_queued_error_ipv6_and_unknown_kinds() -> None:
    six = (socket.AF_INET6.to_bytes(2, sys.byteorder) + bytes(6)
           + socket.inet_pton(socket.AF_INET6, "fe80::1") + bytes(4))  # fmt: skip
    anc = _ancdata(socket.IPPROTO_IPV6, 25, 113, 3, 1, 3, six)
    exc = queued_error(anc, ("fe80::2", 2337, 0, 0))
    assert "ICMPv6 address unreachable from fe80::1 for a datagram to [fe80::2]:2337" in str(exc)
    other = queued_error(_ancdata(socket.IPPROTO_IP, 11, 113, 2, 3, 13, b""), ("10.0.0.1", 2337))
    assert "ICMP type 3 code 13 for a datagram to 10.0.0.1:2337" in str(other)
    local = queued_error(_ancdata(socket.IPPROTO_IP, 11, 90, 1, 0, 0, b""), ("10.0.0.1", 2337))
    assert "Message too long" in str(local)  # a local error (origin 1): the errno's text
    assert queued_error([], None).errno is not None


# -- over real sockets ------------------------------------------------------------------------


@linux_only
async def test_icmp_port_unreachable_is_one_error_event_per_episode() -> None:
    port = silent_udp_port()
    udp = UdpTransport("127.0.0.1", port, local_port=0)
    events: list[LinkEvent] = []
    udp.set_handlers(lambda data: None, events.append)
    await udp.open()
    try:
        for _ in range(5):
            udp.send(b"ping")
            await asyncio.sleep(0.02)
        await until(lambda: udp.send_errors >= 3)
        errors = [e for e in events if e.kind is LinkEventKind.ERROR]
        assert len(errors) == 1, events
        assert f"ICMP port unreachable from 127.0.0.1 for a datagram to 127.0.0.1:{port}" in (
            errors[0].detail)  # fmt: skip
        assert udp.connected and isinstance(udp.last_error, ConnectionRefusedError)

        # a reply ends the episode; the next unreachable port is reported again
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as gcu:
            gcu.bind(("127.0.0.1", port))
            gcu.settimeout(2.0)
            received = len(events)
            udp.send(b"hello")
            data, addr = gcu.recvfrom(100)
            assert data == b"hello"
            gcu.sendto(b"reply", addr)
            await until(lambda: udp.rx_datagrams == 1)
        udp.send(b"anyone?")
        await until(lambda: len([e for e in events if e.kind is LinkEventKind.ERROR]) == 2)
        assert all(e.kind is LinkEventKind.ERROR for e in events[received:])
    finally:
        await udp.close()


@linux_only
async def test_an_icmp_error_does_not_make_the_loop_spin(monkeypatch: pytest.MonkeyPatch) -> None:
    """epoll reports a non-empty error queue as readiness until it is read: the transport
    reads it, so one ICMP error costs a readiness event or two, not a busy loop."""
    calls = 0
    original = DrainingDatagramTransport._read_ready

    def counting(self: DrainingDatagramTransport) -> None:
        nonlocal calls
        calls += 1
        original(self)

    monkeypatch.setattr(DrainingDatagramTransport, "_read_ready", counting)
    udp = UdpTransport("127.0.0.1", silent_udp_port(), local_port=0)
    await udp.open()
    try:
        assert udp.draining
        udp.send(b"ping")
        await until(lambda: udp.send_errors >= 1)
        before = calls
        await asyncio.sleep(0.2)
        assert calls - before <= 2  # a spinning loop calls it thousands of times in 0.2 s

        # the pending report taken by someone else (SO_ERROR): the queue entry alone wakes
        # the reader, which must read it all the same
        udp.send(b"ping")
        time.sleep(0.05)  # noqa: ASYNC251 - the ICMP arrives while the loop is blocked
        sock = udp.get_extra_info("socket")
        assert sock.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR) == 111
        before = calls
        await until(lambda: udp.send_errors == 2)
        await asyncio.sleep(0.2)
        assert calls - before <= 3
    finally:
        await udp.close()


@linux_only
async def test_a_send_that_carries_a_pending_report_is_sent_again() -> None:
    """The kernel reports a pending ICMP error from the next sendto instead of sending that
    datagram: the transport sends it again, so no datagram is lost to an old error."""
    port = silent_udp_port()
    udp = UdpTransport("127.0.0.1", port, local_port=0)
    await udp.open()
    try:
        # synchronously (the loop cannot read the report first): an ICMP error is pending
        udp.send(b"first")
        time.sleep(0.05)  # noqa: ASYNC251 - blocks the loop on purpose
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as gcu:
            gcu.bind(("127.0.0.1", port))
            gcu.settimeout(2.0)
            udp.send(b"second")
            assert udp.send_errors == 1  # the pending report was read, with its details
            assert gcu.recvfrom(100)[0] == b"second"
    finally:
        await udp.close()


def test_without_the_error_queue_linux_hears_nothing_of_icmp() -> None:
    """Why IP_RECVERR: an unconnected socket without it gets no report at all."""
    if not sys.platform.startswith("linux"):
        pytest.skip("Linux behaviour")
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as plain, \
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as recverr:  # fmt: skip
        assert _datagram.enable_error_queue(recverr)
        port = silent_udp_port()
        for sock in (plain, recverr):
            sock.bind(("127.0.0.1", 0))
            sock.setblocking(False)
            sock.sendto(b"x", ("127.0.0.1", port))
        time.sleep(0.05)
        with pytest.raises(BlockingIOError):
            plain.recvfrom(10)
        with pytest.raises(ConnectionRefusedError):
            recverr.recvfrom(10)


@linux_only
async def test_the_client_reports_an_unreachable_gcu_then_comes_up_when_it_listens() -> None:
    port = silent_udp_port()
    sim = GcuSimulator(pod="D-90Pro(TA)")
    gcu = connect(f"udp://127.0.0.1:{port}", local_port=0, connect_timeout=0.3,
                  open_timeout=10.0)  # fmt: skip
    events: list[LinkEvent] = []
    gcu.on_link_change(events.append)
    opening = asyncio.create_task(gcu.open())
    try:
        await until(lambda: any(e.kind is LinkEventKind.ERROR for e in events))
        assert not opening.done()
        error = next(e for e in events if e.kind is LinkEventKind.ERROR)
        assert "ICMP port unreachable" in error.detail
        async with sim.serve_udp("127.0.0.1", port):
            await asyncio.wait_for(opening, 10.0)
            assert gcu.link.up
            await gcu.take_photo()
    finally:
        await gcu.close()


async def test_a_socket_closed_under_the_transport_is_replaced() -> None:
    sim = GcuSimulator(pod="D-90Pro(TA)")
    async with sim.serve_udp("127.0.0.1", 0) as server:
        udp = UdpTransport(*server.address, local_port=0,
                           backoff=Backoff(base=0.01, cap=0.05, max_attempts=5))  # fmt: skip
        events: list[LinkEvent] = []
        received: list[bytes] = []
        udp.set_handlers(on_data=received.append, on_event=events.append)
        await udp.open()
        try:
            inner = udp._dtransport
            assert inner is not None
            inner.close()  # what the event loop does after an error it cannot handle
            await until(lambda: [e.kind for e in events] == [LinkEventKind.LOST,
                                                            LinkEventKind.RESTORED])  # fmt: skip
            assert "new socket after 1 attempt(s)" in events[1].detail
            assert udp.connected and udp.reconnects == 1
            udp.send(host_bytes())
            await until(lambda: len(received) >= 1)
        finally:
            await udp.close()
        assert not udp.reconnecting


async def test_close_while_reopening_stops_the_task() -> None:
    udp = UdpTransport("127.0.0.1", silent_udp_port(), local_port=0,
                       backoff=Backoff(base=5.0, cap=5.0, max_attempts=3))  # fmt: skip
    await udp.open()
    inner = udp._dtransport
    assert inner is not None
    inner.close()
    await until(lambda: udp.reconnecting)
    t0 = time.monotonic()
    await udp.close()
    assert time.monotonic() - t0 < 1.0
    assert not udp.reconnecting and not udp.connected
