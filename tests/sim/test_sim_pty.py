"""The simulator on a real pseudo-terminal pair: the server contract
(tests/helpers/sim/contract.py, chunking included) and what is a pty's own; and on a serial
device path."""

from __future__ import annotations

import os
import sys

import pytest

from gcu_async.protocol import Opcode, TakePhoto, ZoomIn
from gcu_async.sim import GcuSimulator
from helpers.sim.contract import Serve, StreamServerContract, on_pty
from helpers.sim.support import FdPeer, host_bytes

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals are POSIX")


class TestPtyServer(StreamServerContract):
    stall_packets = 10  # 720 bytes: well inside a pty's buffer

    @pytest.fixture
    def serve(self) -> Serve:
        return on_pty


async def test_the_pty_is_a_device_path_and_its_url() -> None:
    async with GcuSimulator().serve_pty() as server:
        assert server.device_path.startswith("/dev/")
        assert server.url == f"serial://{server.device_path}"


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
