"""The transport registry drives every scheme-dependent place (the client's URLs, the
simulator's listen URLs and ``serve``, the pytest plugin), and the arrival-bound capability
is an optional protocol (transport/arrival.py), not a member of every transport."""

from __future__ import annotations

import asyncio
import importlib
import time
from pathlib import Path

import pytest

from gcu_async import pytest_plugin
from gcu_async.sim import GcuSimulator, ListenSpec, parse_listen_url
from gcu_async.sim.memory import MemoryServer
from gcu_async.sim.server import ServerParts, SimServer
from gcu_async.transport import MemoryTransport, Transport, UdpTransport, open_transport
from gcu_async.transport.arrival import ArrivalBound, ReadsOnDemand, arrival_bound
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


# --- the arrival-bound capability: optional, asked for -----------------------------------
def test_only_transports_that_read_on_demand_have_the_capability(tmp_path: Path) -> None:
    from gcu_async.capture.writer import PacketCapture

    a, _ = MemoryTransport.pair()
    assert not isinstance(a, ReadsOnDemand)
    assert not any(hasattr(a, name) for name in ("drains", "empty_at_poll", "read_pending"))
    udp = UdpTransport("127.0.0.1", 9, local_port=0)
    assert isinstance(udp, ReadsOnDemand)
    capture = PacketCapture(tmp_path / "c.pcapng")
    assert isinstance(CapturingTransport(udp, capture), ReadsOnDemand)
    assert not isinstance(CapturingTransport(a, capture), ReadsOnDemand)


class _Link(Transport):
    """An unordered transport with scripted answers to the capability's questions."""

    ordered = False

    def __init__(self, drains: bool, empty: bool) -> None:
        super().__init__()
        self.drains, self.was_empty, self.empty, self.reads = drains, True, empty, 0

    def empty_at_poll(self, due: float) -> bool:
        return self.was_empty

    def read_pending(self) -> bool:
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


def test_arrival_bound_picks_the_loop_then_reading_then_none() -> None:
    loop = asyncio.new_event_loop()
    try:
        clock: list[float] = [10.0]

        def fake() -> float:
            return clock[0]

        a, _ = MemoryTransport.pair()
        assert arrival_bound(a, time.monotonic, loop) is None  # ordered: nothing to bound
        link = _Link(drains=True, empty=True)
        bound = arrival_bound(link, time.monotonic, loop)
        assert isinstance(bound, ArrivalBound) and bound.from_loop and link.reads == 0
        bound.timer_ran(50.0)
        assert bound.value < 50.0 and bound.value >= 50.0 - 0.01
        link.was_empty = False
        bound.timer_ran(60.0)  # not known empty at the poll: no new bound
        assert bound.value < 50.0
        bound.before_send()  # the loop's bound: no reads
        assert link.reads == 0
        # another clock than the loop's: read the link empty before each send
        bound = arrival_bound(link, fake, loop)
        assert isinstance(bound, ArrivalBound) and not bound.from_loop
        assert (bound.value, link.reads) == (10.0, 1)
        clock[0] = 11.0
        bound.before_send()
        assert (bound.value, link.reads) == (11.0, 2)
        link.empty = False
        clock[0] = 12.0
        bound.before_send()  # could not read it empty: the bound stays
        assert bound.value == 11.0
        bound.timer_ran(99.0)
        assert bound.value == 11.0
        assert arrival_bound(link, fake, loop) is None  # cannot read it empty now
    finally:
        loop.close()


def test_an_unordered_transport_without_the_capability_gets_no_bound() -> None:
    class Plain(MemoryTransport):
        ordered = False

    loop = asyncio.new_event_loop()
    try:
        a = Plain()
        assert not isinstance(a, ReadsOnDemand)
        assert arrival_bound(a, time.monotonic, loop) is None
    finally:
        loop.close()
