"""open_transport: URL parsing table (good and bad) and end-to-end opening over loopback."""

from __future__ import annotations

import asyncio
import os
import random
import sys
from typing import Any

import pytest

from _transport_recorder import Recorder
from gcu_async.transport import (
    Backoff,
    SerialTransport,
    TcpTransport,
    UdpTransport,
    open_transport,
)


@pytest.mark.parametrize(
    ("url", "kwargs", "kind", "canonical"),
    [
        ("udp://127.0.0.1", {}, UdpTransport, "udp://127.0.0.1:2337"),
        ("udp://127.0.0.1:4000", {}, UdpTransport, "udp://127.0.0.1:4000"),
        ("UDP://localhost:4000/", {}, UdpTransport, "udp://localhost:4000"),
        ("udp://[::1]:2337", {}, UdpTransport, "udp://[::1]:2337"),
        ("udp://[::1]", {}, UdpTransport, "udp://[::1]:2337"),
        ("tcp://127.0.0.1", {}, TcpTransport, "tcp://127.0.0.1:2332"),
        ("tcp://gcu.local:65535", {}, TcpTransport, "tcp://gcu.local:65535"),
        ("tcp://[::1]:9", {}, TcpTransport, "tcp://[::1]:9"),
        ("serial:///dev/ttyUSB0", {}, SerialTransport, "serial:///dev/ttyUSB0?baudrate=115200"),
        (
            "serial:///dev/ttyUSB0?baudrate=1000000", {}, SerialTransport,
            "serial:///dev/ttyUSB0?baudrate=1000000",
        ),
        ("serial:/dev/ttyS1", {"baudrate": 250000}, SerialTransport,
         "serial:///dev/ttyS1?baudrate=250000"),
        ("serial:/dev/ttyS1", {"baudrate": 500000}, SerialTransport,
         "serial:///dev/ttyS1?baudrate=500000"),
    ],
)  # fmt: skip
def test_good_urls(url: str, kwargs: dict[str, Any], kind: type, canonical: str) -> None:
    t = open_transport(url, **kwargs)
    assert type(t) is kind
    assert t.url == canonical
    assert not t.connected
    assert open_transport(t.url).url == canonical  # the canonical URL round-trips


def test_udp_options_from_query_and_keywords() -> None:
    t = open_transport(
        "udp://127.0.0.1:4000?local_port=0&broadcast=yes&discovery=1", local_host="127.0.0.1"
    )
    assert isinstance(t, UdpTransport)
    assert (t.local_port, t.local_host, t.broadcast, t.discovery, t.follow_peer) == (
        0, "127.0.0.1", True, True, False,
    )  # fmt: skip
    t = open_transport("udp://127.0.0.1", follow_peer=True, discovery=True, broadcast=False)
    assert isinstance(t, UdpTransport)
    assert (t.local_port, t.local_host, t.broadcast, t.discovery, t.follow_peer) == (
        2338, None, False, True, True,
    )  # fmt: skip


def test_tcp_options_from_query_and_keywords() -> None:
    rng = random.Random(1)
    t = open_transport(
        "tcp://127.0.0.1:2332?connect_timeout=0.5&reconnect=false&backoff_base=0.1"
        "&backoff_factor=3&backoff_cap=4&max_attempts=none&max_total=30",
        rng=rng,
    )
    assert isinstance(t, TcpTransport)
    assert t.connect_timeout == 0.5
    assert t.reconnect is False
    assert t.backoff == Backoff(base=0.1, factor=3.0, cap=4.0, max_attempts=None, max_total=30)
    t = open_transport("tcp://127.0.0.1", max_attempts=5, connect_timeout=2)
    assert isinstance(t, TcpTransport)
    assert t.backoff == Backoff(max_attempts=5)
    assert t.connect_timeout == 2.0
    assert t.reconnect is True


@pytest.mark.parametrize(
    ("url", "kwargs", "expected"),
    [
        ("http://127.0.0.1", {}, "scheme: 'http' is not supported (allowed: udp://, tcp://"),
        ("127.0.0.1:2337", {}, "scheme: "),
        ("/dev/ttyUSB0", {}, "scheme: missing (use udp://, tcp:// or serial://)"),
        ("memory://a", {}, "scheme: 'memory' is not supported"),
        ("udp://", {}, "host: missing"),
        ("udp://:2337", {}, "host: missing"),
        ("udp://127.0.0.1:0", {}, "port: '0' is not a valid port (allowed 1-65535)"),
        ("udp://127.0.0.1:65536", {}, "port: '65536' is not a valid port"),
        ("tcp://127.0.0.1:http", {}, "port: 'http' is not a valid port"),
        ("tcp://127.0.0.1:", {}, "port: '' is not a valid port"),
        ("tcp://127.0.0.1:-1", {}, "port: '-1' is not a valid port"),
        ("udp://::1:2337", {}, "host: '::1:2337': put an IPv6 address in brackets"),
        ("udp://[::1", {}, "host: cannot parse"),
        ("udp://[::g]:1", {}, "host: "),
        ("udp://[127.0.0.1]:1", {}, "host: "),
        ("udp://[::1]x", {}, "host: unexpected 'x' after '[::1]'"),
        ("udp://999.1.1.1", {}, "host: '999.1.1.1' is not a valid IPv4 address"),
        ("udp://bad_host", {}, "host: 'bad_host' is not a valid host name or address"),
        ("udp://-bad.example", {}, "host: '-bad.example' is not a valid host name"),
        ("tcp://user@127.0.0.1", {}, "host: user information"),
        ("tcp://127.0.0.1/path", {}, "path: '/path' is not allowed"),
        ("tcp://127.0.0.1#frag", {}, "fragment: 'frag' is not allowed"),
        ("udp://127.0.0.1?nope=1", {}, "option: 'nope' is not a udp URL option (allowed: "),
        ("udp://127.0.0.1", {"baudrate": 115200}, "option: 'baudrate' is not a udp option"),
        ("tcp://127.0.0.1?rng=1", {}, "option: 'rng' is not a tcp URL option"),
        ("udp://127.0.0.1?local_port=1&local_port=2", {}, "option: 'local_port' is given twice"),
        (
            "udp://127.0.0.1?local_port=0", {"local_port": 0},
            "option: 'local_port' is given both in the URL query and as a keyword argument",
        ),
        ("udp://127.0.0.1?local_port=x", {}, "local_port: 'x' is not an integer"),
        ("udp://127.0.0.1?local_port=70000", {}, "local_port: 70000 is not a valid port"),
        ("udp://127.0.0.1?broadcast=maybe", {}, "broadcast: 'maybe' is not a boolean"),
        ("udp://127.0.0.1", {"discovery": 1}, "discovery: 1 is not a bool (True or False)"),
        ("udp://127.0.0.1?local_host=no_such", {}, "local_host: 'no_such' is not a valid host"),
        ("udp://127.0.0.1?junk", {}, "query: 'junk' is not name=value pairs"),
        ("tcp://127.0.0.1?connect_timeout=soon", {}, "connect_timeout: 'soon' is not a number"),
        ("tcp://127.0.0.1?connect_timeout=-1", {}, "connect_timeout: -1.0 is out of range"),
        ("tcp://127.0.0.1?backoff_factor=0.5", {}, "backoff_factor: 0.5 is out of range"),
        ("tcp://127.0.0.1?max_attempts=0", {}, "max_attempts: 0 is out of range"),
        ("tcp://127.0.0.1?max_attempts=none", {}, "max_attempts, max_total: at least one"),
        ("tcp://127.0.0.1", {"rng": 4}, "rng: 4 is not a random.Random"),
        (
            "serial:///dev/ttyUSB0?baudrate=9600", {},
            "baudrate: 9600 is not supported (allowed: 115200, 250000, 500000, 1000000)",
        ),
        ("serial:///dev/ttyUSB0?baudrate=fast", {}, "baudrate: 'fast' is not an integer"),
        ("serial:///dev/ttyUSB0?parity=E", {}, "option: 'parity' is not a serial URL option"),
        ("serial://dev/ttyUSB0", {}, "device: host part 'dev' is not allowed"),
        ("serial://", {}, "device: missing"),
        ("serial:", {}, "device: missing"),
    ],
)  # fmt: skip
def test_bad_urls(url: str, kwargs: dict[str, Any], expected: str) -> None:
    with pytest.raises(ValueError, match=r"^\S.*: ") as info:
        open_transport(url, **kwargs)
    msg = str(info.value)
    assert msg.startswith(f"{url}: ")
    assert expected in msg[len(url) + 2 :]
    assert "\n" not in msg


def test_empty_url() -> None:
    with pytest.raises(ValueError, match=r"^'': scheme: missing"):
        open_transport("")


def test_non_string_url() -> None:
    with pytest.raises(ValueError, match="url: 2337 is not a string"):
        open_transport(2337)  # type: ignore[arg-type]


async def test_udp_url_end_to_end() -> None:
    loop = asyncio.get_running_loop()
    received: asyncio.Queue[tuple[bytes, Any]] = asyncio.Queue()

    class Gcu(asyncio.DatagramProtocol):
        def datagram_received(self, data: bytes, addr: Any) -> None:
            received.put_nowait((data, addr))

    gcu, _ = await loop.create_datagram_endpoint(Gcu, local_addr=("127.0.0.1", 0))
    try:
        port = gcu.get_extra_info("sockname")[1]
        async with open_transport(f"udp://127.0.0.1:{port}?local_port=0&local_host=127.0.0.1") as t:
            rec = Recorder(t)
            t.send(b"ping")
            data, addr = await asyncio.wait_for(received.get(), 2.0)
            assert data == b"ping"
            gcu.sendto(b"pong", addr)
            assert await rec.wait_bytes(4) == b"pong"
    finally:
        gcu.close()
        await asyncio.sleep(0)


async def test_udp_ipv6_url_end_to_end() -> None:
    loop = asyncio.get_running_loop()
    received: asyncio.Queue[tuple[bytes, Any]] = asyncio.Queue()

    class Gcu(asyncio.DatagramProtocol):
        def datagram_received(self, data: bytes, addr: Any) -> None:
            received.put_nowait((data, addr))

    try:
        gcu, _ = await loop.create_datagram_endpoint(Gcu, local_addr=("::1", 0))
    except OSError:
        pytest.skip("::1 not available")
    try:
        port = gcu.get_extra_info("sockname")[1]
        url = f"udp://[::1]:{port}?local_port=0&local_host=::1"
        async with open_transport(url) as t:
            rec = Recorder(t)
            t.send(b"ping6")
            data, addr = await asyncio.wait_for(received.get(), 2.0)
            assert data == b"ping6"
            gcu.sendto(b"pong6", addr)
            assert await rec.wait_bytes(5) == b"pong6"
    finally:
        gcu.close()
        await asyncio.sleep(0)


async def test_tcp_url_end_to_end() -> None:
    async def echo(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        writer.write(await reader.read(100))
        await writer.drain()
        writer.close()

    server = await asyncio.start_server(echo, "127.0.0.1", 0)
    try:
        port = server.sockets[0].getsockname()[1]
        async with open_transport(f"tcp://127.0.0.1:{port}", reconnect=False) as t:
            rec = Recorder(t)
            t.send(b"echo me")
            assert await rec.wait_bytes(7) == b"echo me"
    finally:
        server.close()
        await server.wait_closed()


@pytest.mark.skipif(
    sys.platform == "win32" or not hasattr(os, "openpty"),
    reason="a pseudo-terminal stands in for the serial port: POSIX only",
)
async def test_serial_url_end_to_end() -> None:
    import tty

    controller, follower = os.openpty()
    try:
        tty.setraw(controller)
        path = os.ttyname(follower)
        async with open_transport(f"serial://{path}?baudrate=500000") as t:
            rec = Recorder(t)
            os.write(controller, b"\x00\xff")
            assert await rec.wait_bytes(2) == b"\x00\xff"
    finally:
        os.close(controller)
        os.close(follower)
