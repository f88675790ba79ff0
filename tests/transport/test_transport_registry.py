"""The transport registry drives every scheme-dependent place (the client's URLs, the
simulator's listen URLs and ``serve``, the pytest plugin), and the arrival hook
(``Transport.caught_up``) is optional: a transport that cannot tell keeps the default."""

from __future__ import annotations

import asyncio
import importlib
import time
from pathlib import Path
from typing import Any

import pytest

from gcu_async import pytest_plugin
from gcu_async.client.driver import Driver, loop_keeps
from gcu_async.client.telemetry import Callbacks, Telemetry
from gcu_async.session import Session
from gcu_async.sim import GcuSimulator, ListenSpec, parse_listen_url
from gcu_async.sim.memory import MemoryServer
from gcu_async.sim.server import ServerParts, SimServer
from gcu_async.transport import MemoryTransport, Transport, UdpTransport, open_transport
from gcu_async.transport.options import as_int
from gcu_async.transport.registry import KINDS, TransportKind, UrlParts, kind_of
from gcu_async.transport.tap import CapturingTransport


def test_every_listener_resolves_to_a_function() -> None:
    for kind in KINDS.values():
        assert kind.listener is not None, kind.scheme
        module, _, name = kind.listener.partition(":")
        assert callable(getattr(importlib.import_module(module), name)), kind.listener


def test_ordering_and_datagram_facts_come_from_the_transport_class() -> None:
    assert (KINDS["udp"].ordered, KINDS["udp"].datagram) == (False, True)
    for scheme in ("tcp", "serial", "pty"):
        assert (KINDS[scheme].ordered, KINDS[scheme].datagram) == (True, False), scheme
    udp = UdpTransport("127.0.0.1", 9)
    assert (udp.ordered, udp.datagram) == (KINDS["udp"].ordered, KINDS["udp"].datagram)


def test_scheme_lists_in_messages_come_from_the_registry() -> None:
    with pytest.raises(ValueError, match=r"allowed: udp://, tcp:// or serial://\)"):
        open_transport("pty://x")
    with pytest.raises(ValueError, match=r"allowed: udp://, tcp://, serial:// or pty\)"):
        parse_listen_url("ftp://x")
    with pytest.raises(ValueError, match="scheme: 'PTY' is not supported"):
        kind_of("PTY")
    assert kind_of("PTY", listen=True) is KINDS["pty"]


class _LoopServer(SimServer):
    """A memory endpoint standing in for a new transport's simulator side."""

    def __init__(self, parts: ServerParts, spec: ListenSpec) -> None:
        self.inner = MemoryServer(parts)
        self.spec = spec

    @property
    def url(self) -> str:
        return f"loop://{self.spec.host}:{self.spec.port}"

    async def open(self) -> None:
        await self.inner.open()

    async def close(self) -> None:
        await self.inner.close()


def listen_loop(parts: ServerParts, spec: ListenSpec) -> SimServer:
    return _LoopServer(parts, spec)


def _connect_loop(parts: UrlParts, options: dict[str, object]) -> Transport:
    transport = MemoryTransport(f"{parts.host}:{parts.port}:{options.get('depth', 1)}")
    return transport


@pytest.fixture
def loop_kind(monkeypatch: pytest.MonkeyPatch) -> TransportKind:
    """A new transport added as one record: every scheme-dependent place takes it."""
    kind = TransportKind(
        "loop", "host", MemoryTransport, _connect_loop, f"{__name__}:listen_loop",
        default_port=4242, options={"depth": as_int}, fixture_listen="loop://127.0.0.1:0",
    )  # fmt: skip
    monkeypatch.setitem(KINDS, "loop", kind)
    return kind


def test_one_record_adds_a_transport_everywhere(loop_kind: TransportKind) -> None:
    transport = open_transport("loop://gcu.local?depth=3")
    assert isinstance(transport, MemoryTransport) and transport.url == "memory://gcu.local:4242:3"
    with pytest.raises(ValueError, match="option: 'speed' is not a loop URL option"):
        open_transport("loop://gcu.local?speed=3")
    spec = parse_listen_url("loop://127.0.0.1:0")
    assert (spec.kind, spec.host, spec.port) == ("loop", "127.0.0.1", 0)
    server = GcuSimulator().serve("loop://127.0.0.1:5")
    assert isinstance(server, _LoopServer) and server.url == "loop://127.0.0.1:5"
    endpoint = pytest_plugin.start_endpoint(GcuSimulator(), "loop")
    assert isinstance(endpoint, _LoopServer) and endpoint.spec.port == 0


def test_a_record_without_a_listener_is_refused_by_the_simulator(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    kind = TransportKind("dial", "host", MemoryTransport, _connect_loop, None, default_port=1)
    monkeypatch.setitem(KINDS, "dial", kind)
    assert isinstance(open_transport("dial://h"), MemoryTransport)
    with pytest.raises(ValueError, match=r"listen URL 'dial://h': scheme: 'dial' is not supp"):
        parse_listen_url("dial://h")


def test_the_plugin_offers_every_record_with_a_loopback_endpoint() -> None:
    offered = {k.scheme for k in KINDS.values() if k.fixture_listen is not None}
    assert set(pytest_plugin.TRANSPORTS) == {"memory", *offered}
    assert offered == {"udp", "tcp", "serial"}


# --- the arrival hook: optional, forwarded by the capture wrapper ---------------------------
def test_only_transports_that_read_on_demand_override_the_hook(tmp_path: Path) -> None:
    from gcu_async.capture.writer import PacketCapture

    a, _ = MemoryTransport.pair()
    assert type(a).caught_up is Transport.caught_up and not a.caught_up()
    assert UdpTransport.caught_up is not Transport.caught_up
    udp = UdpTransport("127.0.0.1", 9, local_port=0)
    assert not udp.caught_up()  # not open: nothing it can tell
    capture = PacketCapture(tmp_path / "c.pcapng")
    assert not CapturingTransport(a, capture).caught_up()
    link = _Link(empty=True)
    wrapped = CapturingTransport(link, capture)
    assert wrapped.caught_up() and link.reads == 1  # the wrapped transport's answer
    link.was_empty = False
    assert not wrapped.caught_up(5.0) and link.dues == [5.0]


class _Link(Transport):
    """An unordered transport with scripted answers to the arrival hook."""

    ordered = False

    def __init__(self, empty: bool) -> None:
        super().__init__()
        self.was_empty, self.empty, self.reads, self.dues = True, empty, 0, []

    def caught_up(self, due: float | None = None) -> bool:
        if due is not None:
            self.dues.append(due)
            return self.was_empty
        self.reads += 1
        return self.empty

    url = "link://x"  # type: ignore[assignment]
    connected = True  # type: ignore[assignment]

    async def open(self) -> None:
        return None

    def send(self, data: bytes) -> None:
        return None

    async def close(self) -> None:
        return None


def _driver(link: Transport, clock: Any) -> Driver:
    return Driver(Session(), link, clock, Telemetry(lambda consumed: None), Callbacks("link"),
                  check_support=False, max_zoom=None)  # fmt: skip


def test_the_driver_bounds_arrival_by_the_loop_then_by_reading_then_not() -> None:
    clock: list[float] = [10.0]

    def fake() -> float:
        return clock[0]

    loop = asyncio.new_event_loop()
    try:
        assert loop_keeps(time.monotonic, loop) and not loop_keeps(fake, loop)

        class Skewed(type(loop)):  # type: ignore[misc]
            def time(self) -> float:
                return 0.0

        skewed = Skewed()
        assert not loop_keeps(time.monotonic, skewed)
        skewed.close()
    finally:
        loop.close()
    a, _ = MemoryTransport.pair()
    assert _driver(a, time.monotonic)._arrival_start() is None  # ordered: nothing to bound
    # the loop keeps the driver's clock: the heartbeat timer bounds arrival, no reads
    link = _Link(empty=True)
    driver = _driver(link, time.monotonic)
    driver._arrived_after = driver._arrival_start()
    driver._loop_clock = True
    assert driver._arrived_after is not None and link.reads == 1
    driver._timer_when = 50.0
    driver._on_timer()
    assert 50.0 - 0.01 <= driver._arrived_after < 50.0 and link.dues == [50.0]
    link.was_empty = False
    driver._timer_when = 60.0
    driver._on_timer()  # not known empty at the poll: no new bound
    assert driver._arrived_after < 50.0
    driver._pump()  # the loop's bound: no reads before sending
    assert link.reads == 1
    # another clock than the loop's: read the link empty before each send
    link = _Link(empty=True)
    driver = _driver(link, fake)
    driver._arrived_after = driver._arrival_start()
    assert (driver._arrived_after, link.reads) == (10.0, 1)
    clock[0] = 11.0
    driver._pump()
    assert (driver._arrived_after, link.reads) == (11.0, 2)
    link.empty = False
    clock[0] = 12.0
    driver._pump()  # could not read it empty: the bound stays
    assert driver._arrived_after == 11.0
    driver._timer_when = 99.0
    driver._on_timer()
    assert driver._arrived_after == 11.0 and link.dues == []
    assert _driver(link, fake)._arrival_start() is None  # cannot read it empty now


def test_an_unordered_transport_without_the_hook_gets_no_bound() -> None:
    class Plain(MemoryTransport):
        ordered = False

    assert _driver(Plain(), time.monotonic)._arrival_start() is None
