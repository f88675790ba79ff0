"""The simulator on a real pseudo-terminal pair, and on a serial device path."""

from __future__ import annotations

import os
import sys

import pytest

from gcu_async.protocol import Opcode, TakePhoto, ZoomIn
from gcu_async.sim import GcuSimulator
from helpers.sim.support import FAMILIES, FdPeer, host_bytes

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals are POSIX")


async def test_every_command_family_over_a_pty() -> None:
    sim = GcuSimulator()
    async with sim.serve_pty() as server:
        assert server.device_path.startswith("/dev/")
        assert server.url == f"serial://{server.device_path}"
        peer = FdPeer.open_path(server.device_path)
        try:
            for command, status in FAMILIES:
                await peer.request(host_bytes())
                reply = await peer.request(host_bytes(command))
                assert (reply.feedback.opcode, reply.feedback.status) == (command.opcode, status)
        finally:
            peer.close()


async def test_garbage_and_chunks_over_a_pty() -> None:
    sim = GcuSimulator()
    async with sim.serve_pty() as server:
        peer = FdPeer.open_path(server.device_path)
        try:
            data = b"\x00\xff garbage \xa8\xe5\x48" + host_bytes(TakePhoto())
            for i in range(0, len(data), 7):
                peer.send(data[i : i + 7])
            assert (await peer.reply()).feedback.opcode == Opcode.TAKE_PHOTO
            assert peer.queue.empty()
        finally:
            peer.close()
    assert sim.model.stats.answered == 1
    assert sim.model.stats.bytes_discarded >= 11


async def test_a_client_can_close_and_reopen_the_pty() -> None:
    sim = GcuSimulator()
    async with sim.serve_pty() as server:
        for _ in range(3):
            peer = FdPeer.open_path(server.device_path)
            try:
                assert (await peer.request(host_bytes(ZoomIn()))).feedback.status == 0
                await peer.request(host_bytes())
            finally:
                peer.close()
    assert sim.model.executions[Opcode.ZOOM_IN] == 3


async def test_closing_releases_the_pty() -> None:
    server = GcuSimulator().serve_pty()
    await server.open()
    path = server.device_path
    assert os.stat(path)  # the follower node exists
    await server.close()
    await server.close()  # idempotent
    if sys.platform.startswith("linux"):
        with pytest.raises(FileNotFoundError):  # devpts removes the node with both ends closed
            os.stat(path)


async def test_serve_serial_opens_a_device_path() -> None:
    leader, follower = os.openpty()
    path = os.ttyname(follower)
    os.close(follower)  # the simulator opens the path itself, like a real serial device
    peer = FdPeer(leader)  # the test plays the host on the other side of the line
    try:
        async with GcuSimulator().serve_serial(path, baudrate=115200) as server:
            assert server.device_path == path
            reply = await peer.request(host_bytes(TakePhoto()))
            assert reply.feedback.opcode == Opcode.TAKE_PHOTO
    finally:
        peer.close()


async def test_serve_serial_on_a_missing_device_fails() -> None:
    with pytest.raises(OSError, match="/dev/does-not-exist"):
        await GcuSimulator().serve_serial("/dev/does-not-exist").open()
