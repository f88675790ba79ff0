"""URLs: ``open_transport``'s parsing table (good and bad, options from the query and from
keywords), end-to-end opening over loopback, and one rule for both sides: the client's
transport URLs (``open_transport``/``connect``) and the simulator's listen URLs
(``parse_listen_url``, ``gcu-async sim --listen``) are read by the same parser
(transport/url.py ``split_url``, per scheme from the transport registry), so one table holds
what each side makes of every URL. The only differences are the ones the docs name: a listen
URL may be ``pty`` and may bind port 0 (any free port)."""

from __future__ import annotations

import asyncio
import os
import random
import re
import sys
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcu_async.client.connect import connect
from gcu_async.protocol.links import (
    BAUDRATES,
    DEFAULT_BAUDRATE,
    GCU_TCP_PORT,
    GCU_UDP_PORT,
)
from gcu_async.sim import GcuSimulator, ListenSpec, parse_listen_url
from gcu_async.transport import (
    Backoff,
    SerialTransport,
    TcpTransport,
    Transport,
    UdpTransport,
    open_transport,
)
from helpers.transport.recorder import Recorder


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
    t = open_transport("tcp://127.0.0.1?max_attempts=none&max_total=none")
    assert isinstance(t, TcpTransport)
    assert t.backoff == Backoff() and not t.backoff.bounded  # reconnects until closed


@pytest.mark.parametrize("url", ["udp://127.0.0.1:2337", "serial:///dev/ttyUSB0"])
def test_every_transport_takes_the_reconnect_options(url: str) -> None:
    """Serial and UDP restore a lost link as TCP does, with the same options."""
    rng = random.Random(1)
    t = open_transport(f"{url}?reconnect=0&backoff_cap=4&max_attempts=3&max_total=none",
                       rng=rng)  # fmt: skip
    assert isinstance(t, (UdpTransport, SerialTransport))
    assert t.backoff == Backoff(cap=4.0, max_attempts=3)
    assert t._reopen.enabled is False
    assert open_transport(url).backoff == Backoff()


@pytest.mark.parametrize(
    ("url", "kwargs", "expected"),
    [
        ("http://127.0.0.1", {}, "scheme: 'http' is not supported (allowed: udp://, tcp://"),
        ("127.0.0.1:2337", {}, "scheme: "),
        ("/dev/ttyUSB0", {}, "scheme: missing (use udp://, tcp:// or serial://)"),
        ("memory://a", {}, "scheme: 'memory' is not supported"),
        ("udp://", {}, "host: missing"),
        ("udp://:2337", {}, "host: missing"),
        ("udp://127.0.0.1:65536", {}, "port: '65536' is not a valid port"),
        ("tcp://127.0.0.1:http", {}, "port: 'http' is not a valid port"),
        ("tcp://127.0.0.1:", {}, "port: '' is not a valid port"),
        ("tcp://127.0.0.1:-1", {}, "port: '-1' is not a valid port"),
        ("udp://::1:2337", {}, "host: '::1:2337': put an IPv6 address in brackets"),
        ("udp://[::1", {}, "host: cannot parse"),
        ("udp://[::g]:1", {}, "host: "),
        ("udp://[127.0.0.1]:1", {}, "host: "),
        ("udp://[::1]x", {}, "host: unexpected 'x' after '[::1]'"),
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
        ("tcp://127.0.0.1", {"rng": 4}, "rng: 4 is not a random.Random"),
        ("serial://dev/ttyUSB0", {}, "device: host part 'dev' is not allowed"),
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


@pytest.mark.realtime
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


@pytest.mark.realtime
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


@pytest.mark.realtime
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


@pytest.mark.realtime
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


# --- one rule for the client's and the simulator's URLs --------------------------------
Place = tuple[str, str, object]  # (scheme, host or device, port or baud rate)
"""Where a URL points, as either side reads it."""

# url, what the client makes of it, what the simulator makes of it (a Place, or the text
# the ValueError must contain: the field it names and why)
TABLE: list[tuple[str, Place | str, Place | str]] = [
    ("udp://127.0.0.1", ("udp", "127.0.0.1", GCU_UDP_PORT), ("udp", "127.0.0.1", GCU_UDP_PORT)),
    ("UDP://127.0.0.1:4000/", ("udp", "127.0.0.1", 4000), ("udp", "127.0.0.1", 4000)),
    ("udp://[::1]", ("udp", "::1", GCU_UDP_PORT), ("udp", "::1", GCU_UDP_PORT)),
    ("udp://[::1]:9", ("udp", "::1", 9), ("udp", "::1", 9)),
    ("tcp://gcu.local", ("tcp", "gcu.local", GCU_TCP_PORT), ("tcp", "gcu.local", GCU_TCP_PORT)),
    ("tcp://10.0.0.1:65535", ("tcp", "10.0.0.1", 65535), ("tcp", "10.0.0.1", 65535)),
    ("serial:///dev/ttyUSB0", ("serial", "/dev/ttyUSB0", DEFAULT_BAUDRATE),
     ("serial", "/dev/ttyUSB0", DEFAULT_BAUDRATE)),
    ("serial:/dev/ttyS1?baudrate=1000000", ("serial", "/dev/ttyS1", 1000000),
     ("serial", "/dev/ttyS1", 1000000)),
    ("serial://COM3", ("serial", "COM3", DEFAULT_BAUDRATE), ("serial", "COM3", DEFAULT_BAUDRATE)),
    ("serial:///COM7?baudrate=250000", ("serial", "COM7", 250000), ("serial", "COM7", 250000)),
    # the two documented differences
    ("udp://127.0.0.1:0", "port: '0' is not a valid port (allowed 1-65535)",
     ("udp", "127.0.0.1", 0)),
    ("tcp://[::1]:0", "port: '0' is not a valid port (allowed 1-65535)", ("tcp", "::1", 0)),
    ("pty", "scheme: missing", ("pty", "", None)),
    # refused by both, for the same reason
    ("udp://127.0.0.1:70000", "port: '70000' is not a valid port",
     "port: '70000' is not a valid port"),
    ("tcp://", "host: missing", "host: missing"),
    ("udp://user@127.0.0.1", "host: user information", "host: user information"),
    ("udp://::1", "put an IPv6 address in brackets", "put an IPv6 address in brackets"),
    ("udp://[1.2.3.4]", "host: ", "host: "),  # the reason's words depend on the Python
    ("udp://999.1.1.1", "host: '999.1.1.1' is not a valid IPv4 address",
     "host: '999.1.1.1' is not a valid IPv4 address"),
    ("tcp://bad_name!", "is not a valid host name", "is not a valid host name"),
    ("tcp://127.0.0.1/x", "path: '/x' is not allowed", "path: '/x' is not allowed"),
    ("udp://127.0.0.1#f", "fragment: 'f' is not allowed", "fragment: 'f' is not allowed"),
    ("ftp://127.0.0.1", "scheme: 'ftp' is not supported", "scheme: 'ftp' is not supported"),
    ("serial://ttyUSB0", "device: host part 'ttyUSB0' is not allowed",
     "device: host part 'ttyUSB0' is not allowed"),
    ("serial://", "device: missing", "device: missing"),
    ("serial:///dev/ttyUSB0?baudrate=9600",
     "baudrate: 9600 is not supported (allowed: 115200, 250000, 500000, 1000000)",
     "baudrate: 9600 is not supported (allowed: 115200, 250000, 500000, 1000000)"),
    ("serial:///dev/ttyUSB0?baudrate=fast", "baudrate: 'fast' is not an integer",
     "baudrate: 'fast' is not an integer"),
    ("serial:///dev/ttyUSB0?parity=E", "option: 'parity' is not a serial URL option",
     "option: 'parity' is not a serial URL option"),
    ("udp://127.0.0.1?local_port=0", ("udp", "127.0.0.1", GCU_UDP_PORT),
     "'local_port' is not a udp URL option"),  # a transport's option: no listen option
]  # fmt: skip


def client_place(transport: Transport) -> Place:
    if isinstance(transport, SerialTransport):
        return ("serial", transport.device, transport.baudrate)
    assert isinstance(transport, (UdpTransport, TcpTransport))
    scheme = "udp" if isinstance(transport, UdpTransport) else "tcp"
    return (scheme, transport._host, transport._port)  # what it will connect to


def listen_place(spec: ListenSpec) -> Place:
    if spec.kind == "serial":
        return ("serial", spec.path, spec.baudrate)
    if spec.kind == "pty":
        return ("pty", "", None)
    return (spec.kind, spec.host, spec.port)


@pytest.mark.parametrize(("url", "client", "listen"), TABLE, ids=[row[0] for row in TABLE])
def test_one_table_for_client_and_simulator_urls(
    url: str, client: Place | str, listen: Place | str
) -> None:
    if isinstance(client, str):
        with pytest.raises(ValueError, match=re.escape(client)) as caught:
            open_transport(url)
        assert str(caught.value).startswith(f"{url}: ")  # the URL first, then the field
        assert client in str(caught.value)
        assert "\n" not in str(caught.value)
    else:
        assert client_place(open_transport(url)) == client
    if isinstance(listen, str):
        with pytest.raises(ValueError, match=re.escape(listen)) as caught:
            parse_listen_url(url)
        assert str(caught.value).startswith(f"listen URL {url!r}: ")
        assert listen in str(caught.value)
    else:
        assert listen_place(parse_listen_url(url)) == listen


def test_the_table_covers_every_scheme_and_difference() -> None:
    """The table is the contract: it keeps a row of each kind (so it cannot shrink to
    agreeing rows only)."""
    agree = [r for r in TABLE if not isinstance(r[1], str) and r[1] == r[2]]
    refused_by_both = [r for r in TABLE if isinstance(r[1], str) and isinstance(r[2], str)]
    differ = [r for r in TABLE if r not in agree and r not in refused_by_both]
    assert {r[1][0] for r in agree if not isinstance(r[1], str)} == {"udp", "tcp", "serial"}
    assert len(refused_by_both) >= 10
    assert {r[0] for r in differ} >= {"udp://127.0.0.1:0", "pty"}


hosts = st.one_of(
    st.ip_addresses(v=4).map(str),
    st.ip_addresses(v=6).map(lambda a: f"[{a}]"),
    st.from_regex(r"[a-z][a-z0-9-]{0,10}[a-z0-9](\.[a-z][a-z0-9]{0,5}){0,2}", fullmatch=True),
)


@given(
    scheme=st.sampled_from(["udp", "tcp"]),
    host=hosts,
    port=st.one_of(st.none(), st.integers(0, 70000)),
)
def test_any_host_and_port_mean_the_same_to_both(scheme: str, host: str, port: int | None) -> None:
    url = f"{scheme}://{host}" + ("" if port is None else f":{port}")
    try:
        client: Place | None = client_place(open_transport(url))
    except ValueError:
        client = None
    try:
        listen: Place | None = listen_place(parse_listen_url(url))
    except ValueError:
        listen = None
    if port == 0:  # the only difference: the simulator binds any free port
        assert client is None and listen is not None and listen[2] == 0
    elif port is not None and port > 65535:
        assert client is None and listen is None
    else:
        assert client is not None and client == listen
        assert client[2] == (port if port is not None else
                             {"udp": GCU_UDP_PORT, "tcp": GCU_TCP_PORT}[scheme])  # fmt: skip


@given(baudrate=st.integers(1, 2_000_000))
def test_baud_rates_are_the_same_on_both_sides(baudrate: int) -> None:
    url = f"serial:///dev/ttyUSB0?baudrate={baudrate}"
    ok = baudrate in BAUDRATES
    for parse in (open_transport, parse_listen_url):
        if ok:
            parse(url)
        else:
            with pytest.raises(ValueError, match=f"baudrate: {baudrate} is not supported"):
                parse(url)


@pytest.mark.realtime
@pytest.mark.parametrize("listen", ["udp://127.0.0.1:0", "tcp://127.0.0.1:0"])
async def test_a_server_url_is_a_client_url_and_a_listen_url(listen: str) -> None:
    """The other direction: what a running simulator endpoint says it is (``server.url``)
    is a URL the client connects to, and that the simulator reads as the same place."""
    sim = GcuSimulator()
    async with sim.serve(listen) as server:
        again = parse_listen_url(server.url)
        assert listen_place(again)[1:] == client_place(open_transport(server.url))[1:]
        options = {"local_port": 0} if listen.startswith("udp") else {}
        async with connect(server.url, connect_timeout=2.0, **options) as gcu:
            await asyncio.wait_for(gcu.wait_for(lambda sample: True), 2.0)
