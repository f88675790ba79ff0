"""The simulator as a TCP server on 127.0.0.1 (ephemeral ports): the server contract
(tests/helpers/sim/contract.py, chunking included), and what is TCP's own: clients in turn,
killing the connection, clean shutdown."""

from __future__ import annotations

import asyncio

import pytest

from gcu_async.protocol import Opcode, TakePhoto
from gcu_async.sim import GcuSimulator
from helpers.sim.contract import Serve, StreamServerContract, on_tcp
from helpers.sim.support import StreamPeer, host_bytes


class TestTcpServer(StreamServerContract):
    stall_packets = 30

    @pytest.fixture
    def serve(self) -> Serve:
        return on_tcp


async def test_several_clients_in_turn() -> None:
    sim = GcuSimulator()
    async with sim.serve_tcp(port=0) as server:
        for _ in range(3):
            peer = await StreamPeer.connect(server.address)
            reply = await peer.request(host_bytes(TakePhoto()))
            assert reply.feedback.opcode == Opcode.TAKE_PHOTO
            await peer.request(host_bytes())
            await peer.close()
        assert server.clients_served == 3
    assert sim.model.executions[Opcode.TAKE_PHOTO] == 3


async def test_a_second_client_waits_until_the_first_leaves() -> None:
    async with GcuSimulator().serve_tcp(port=0) as server:
        first = await StreamPeer.connect(server.address)
        await first.request(host_bytes())
        second = await StreamPeer.connect(server.address)
        second.writer.write(host_bytes(TakePhoto()))
        with pytest.raises(asyncio.TimeoutError):
            await second.reply(timeout=0.2)
        await first.close()
        reply = await second.reply(timeout=2.0)  # served now, its waiting packet answered
        assert reply.feedback.opcode == Opcode.TAKE_PHOTO
        await second.close()
        assert server.clients_served == 2


async def test_kill_connection_resets_the_client_and_serves_the_next() -> None:
    async with GcuSimulator().serve_tcp(port=0) as server:
        assert not server.kill_connection()
        peer = await StreamPeer.connect(server.address)
        await peer.request(host_bytes())
        assert server.client_connected
        assert server.kill_connection()
        with pytest.raises(ConnectionError):
            await peer.request(host_bytes(), timeout=2.0)
        await peer.close()
        again = await StreamPeer.connect(server.address)
        assert (await again.request(host_bytes(TakePhoto()))).feedback.status == 0
        await again.close()


async def test_closing_the_server_disconnects_clients() -> None:
    server = GcuSimulator().serve_tcp(port=0)
    await server.open()
    peer = await StreamPeer.connect(server.address)
    waiting = await StreamPeer.connect(server.address)
    await peer.request(host_bytes())
    await asyncio.wait_for(server.close(), 3.0)
    try:
        leftover = await asyncio.wait_for(peer.reader.read(100), 2.0)
    except ConnectionResetError:
        leftover = b""
    assert leftover == b""
    with pytest.raises((ConnectionError, OSError)):
        await asyncio.wait_for(asyncio.open_connection(*server.address), 2.0)
    await peer.close()
    await waiting.close()


async def test_connections_run_no_task_that_could_outlive_them() -> None:
    """A served and a waiting client add no task; once both have closed, nothing of them
    runs (a task per connection outlived its client on Python 3.12+)."""
    before = {t for t in asyncio.all_tasks() if not t.done()}
    async with GcuSimulator().serve_tcp(port=0) as server:
        first = await StreamPeer.connect(server.address)
        await first.request(host_bytes(TakePhoto()))
        second = await StreamPeer.connect(server.address)
        second.writer.write(host_bytes())
        await asyncio.sleep(0.05)
        assert {t for t in asyncio.all_tasks() if not t.done()} == before
        await first.close()
        assert (await second.reply(timeout=2.0)).feedback.opcode == 0
        await second.close()
        assert {t for t in asyncio.all_tasks() if not t.done()} == before
    assert {t for t in asyncio.all_tasks() if not t.done()} == before


async def test_a_waiting_client_is_not_read_before_its_turn() -> None:
    """Its bytes stay in the kernel (reading paused on every Python version), and bytes a
    transport delivered early anyway are kept and answered when its turn comes."""
    sim = GcuSimulator()
    async with sim.serve_tcp(port=0) as server:
        first = await StreamPeer.connect(server.address)
        await first.request(host_bytes())
        second = await StreamPeer.connect(server.address)
        second.writer.write(host_bytes(TakePhoto()) * 50)
        await second.writer.drain()
        await asyncio.sleep(0.1)
        [waiting] = server._waiting
        assert waiting.early == b""  # never read: the pause took effect
        assert sim.model.executions[Opcode.TAKE_PHOTO] == 0
        waiting.data_received(host_bytes())  # as if the transport had read it early
        await first.close()
        replies = [await second.reply(timeout=2.0) for _ in range(51)]
        # the early bytes first, then the kernel's: one null reply, 50 photo replies
        assert [r.feedback.opcode for r in replies] == [0] + [Opcode.TAKE_PHOTO] * 50
        await second.close()
    assert sim.model.executions[Opcode.TAKE_PHOTO] == 1  # the same-opcode rule: once


async def test_a_waiting_client_that_left_does_not_hold_up_the_next() -> None:
    """Its close is seen only when its turn comes (its reading is paused until then): it is
    served nothing, leaves at once, and the client behind it is served."""
    async with GcuSimulator().serve_tcp(port=0) as server:
        first = await StreamPeer.connect(server.address)
        await first.request(host_bytes())
        quitter = await StreamPeer.connect(server.address)
        third = await StreamPeer.connect(server.address)
        third.writer.write(host_bytes(TakePhoto()))
        await quitter.close()
        await first.close()
        assert (await third.reply(timeout=2.0)).feedback.opcode == Opcode.TAKE_PHOTO
        await third.close()
        assert server.clients_served == 3
