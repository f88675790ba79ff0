"""One URL rule for both sides: the client's transport URLs (``open_transport``/``connect``)
and the simulator's listen URLs (``parse_listen_url``, ``gcu-async sim --listen``) are read
by the same parser (transport/url.py ``split_url``), so one table holds what each side makes
of every URL. The only differences are the ones the docs name: a listen URL may be ``pty``
and may bind port 0 (any free port)."""

from __future__ import annotations

import asyncio
import re

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
from gcu_async.transport import SerialTransport, TcpTransport, Transport, UdpTransport
from gcu_async.transport.url import open_transport

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
    ("serial:///dev/ttyUSB0?baudrate=9600", "baudrate: 9600 is not supported",
     "baudrate: 9600 is not supported"),
    ("serial:///dev/ttyUSB0?baudrate=fast", "baudrate: 'fast' is not an integer",
     "baudrate: 'fast' is not an integer"),
    ("serial:///dev/ttyUSB0?parity=E", "'parity' is not a serial URL option",
     "'parity' is not a serial URL option"),
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
