"""The simulator on an in-memory link (what the client's unit tests use): the server contract
(tests/helpers/sim/contract.py, chunking included) and what is the link's own."""

from __future__ import annotations

import asyncio

import pytest

from gcu_async.errors import LinkLost
from gcu_async.protocol import Deframer
from gcu_async.sim import FaultConfig, FaultPlan, GcuSimulator
from gcu_async.transport import LinkEvent, LinkEventKind, MemoryTransport
from helpers.sim.contract import Serve, StreamServerContract, on_memory
from helpers.sim.support import host_bytes


@pytest.mark.realtime  # the contract's waits are on the real clock
class TestMemoryServer(StreamServerContract):
    stall_packets = 5
    os_buffered = False  # no OS buffer: the simulator holds what arrives during a stall

    @pytest.fixture
    def serve(self) -> Serve:
        return on_memory


async def test_the_memory_link_is_the_clients_transport() -> None:
    async with GcuSimulator().serve_memory() as server:
        transport = server.transport
        assert isinstance(transport, MemoryTransport)
        assert not transport.connected  # not yet opened: the client opens it
        await transport.open()
        assert transport.connected
        await transport.close()


async def test_closing_the_simulator_loses_the_link() -> None:
    events: list[LinkEvent] = []
    server = GcuSimulator().serve_memory()
    assert await server.__aenter__() is server  # async with gives the server itself
    transport = server.transport
    transport.set_handlers(lambda data: None, events.append)
    await transport.open()
    await server.close()
    assert [e.kind for e in events] == [LinkEventKind.LOST]
    with pytest.raises(LinkLost):
        transport.send(host_bytes())
    await transport.close()


async def test_a_reply_to_a_closed_client_is_counted_not_raised() -> None:
    sim = GcuSimulator(faults=FaultPlan(replies=FaultConfig(delay=0.05, seed=2)))
    async with sim.serve_memory() as server:
        transport = server.transport
        await transport.open()
        transport.send(host_bytes())
        await asyncio.sleep(0)  # delivered to the simulator; its reply is delayed
        await transport.close()
        for _ in range(50):
            if sim.stats.send_errors:
                break
            await asyncio.sleep(0.01)
    assert sim.stats.send_errors == 1
    assert sim.stats.replies_sent == 0


async def test_faults_apply_on_the_memory_link_too() -> None:
    sim = GcuSimulator(faults=FaultPlan(replies=FaultConfig(duplicate=1.0)))
    deframer = Deframer.for_gcu_packets()
    packets: list[bytes] = []
    async with sim.serve_memory() as server:
        transport = server.transport
        transport.set_handlers(lambda data: packets.extend(deframer.feed(data)))
        await transport.open()
        transport.send(host_bytes())
        for _ in range(50):
            if len(packets) >= 2:
                break
            await asyncio.sleep(0.01)
        await transport.close()
    assert len(packets) == 2
    assert packets[0] == packets[1]
