"""SerialTransport through a real pseudo-terminal pair: the transport opens the follower by
its path, the test plays the GCU on the controller fd."""

from __future__ import annotations

import asyncio
import errno
import os
import termios
import tty
from collections.abc import Iterator
from pathlib import Path

import pytest

from _transport_recorder import Recorder, open_fds, other_tasks
from gcu_async.errors import LinkLost
from gcu_async.transport import BAUDRATES, LinkEventKind, SerialTransport

pytestmark = pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs a pty")


class Pty:
    """A pty pair; ``controller`` is the test's end (raw, non-blocking)."""

    def __init__(self) -> None:
        self.controller, self.follower = os.openpty()
        tty.setraw(self.controller)
        os.set_blocking(self.controller, False)
        self.path = os.ttyname(self.follower)
        self._open = {self.controller, self.follower}

    def write(self, data: bytes) -> None:
        view = memoryview(data)
        while view:
            view = view[os.write(self.controller, view) :]

    async def read(self, n: int, timeout: float = 2.0) -> bytes:
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout
        buf = bytearray()
        while len(buf) < n:
            try:
                buf += os.read(self.controller, 4096)
            except BlockingIOError:
                if loop.time() > deadline:
                    raise AssertionError(f"read {len(buf)} of {n} bytes in {timeout} s") from None
                await asyncio.sleep(0.002)
        return bytes(buf)

    def close(self, fd: int) -> None:
        if fd in self._open:
            self._open.discard(fd)
            os.close(fd)

    def close_all(self) -> None:
        for fd in list(self._open):
            self.close(fd)


@pytest.fixture
def pty() -> Iterator[Pty]:
    p = Pty()
    yield p
    p.close_all()


async def test_bytes_both_directions(pty: Pty) -> None:
    every_byte = bytes(range(256))  # includes CR, LF, XON/XOFF, ^C: raw 8-bit both ways
    async with SerialTransport(pty.path, 115200) as t:
        rec = Recorder(t)
        assert t.connected
        t.send(every_byte)
        t.send(b"\xa5\x5a")
        assert await pty.read(258) == every_byte + b"\xa5\x5a"
        pty.write(every_byte * 4)
        assert await rec.wait_bytes(1024) == every_byte * 4
        assert t.bytes_sent == 258
        assert t.bytes_received == 1024
        assert rec.events == []
    assert not t.connected
    assert other_tasks() == set()


@pytest.mark.parametrize("baudrate", BAUDRATES)
async def test_opens_8n1_at_each_supported_rate(pty: Pty, baudrate: int) -> None:
    async with SerialTransport(pty.path, baudrate) as t:
        rec = Recorder(t)
        _, _, cflag, _, ispeed, ospeed, _ = termios.tcgetattr(pty.follower)
        assert cflag & termios.CSIZE == termios.CS8
        assert not cflag & termios.PARENB
        assert not cflag & termios.CSTOPB
        standard = getattr(termios, f"B{baudrate}", None)
        if standard is not None and baudrate != 250000:
            assert ispeed == ospeed == standard
        pty.write(b"ok")
        assert await rec.wait_bytes(2) == b"ok"
        assert t.url == f"serial://{pty.path}?baudrate={baudrate}"


async def test_close_releases_the_fd(pty: Pty) -> None:
    before = open_fds()
    t = SerialTransport(pty.path)
    await t.open()
    assert len(open_fds()) > len(before)
    pty.close(pty.follower)  # now only the transport holds the follower open
    await t.close()
    assert open_fds() == before - {pty.follower}
    # With no follower fd left, the controller reads EIO: the transport's fd is gone.
    with pytest.raises(OSError, match="Input/output error") as info:
        os.read(pty.controller, 1)
    assert info.value.errno == errno.EIO
    await t.close()  # idempotent
    with pytest.raises(LinkLost, match="port is closed"):
        t.send(b"x")
    assert other_tasks() == set()


async def test_peer_closing_is_reported_lost(pty: Pty) -> None:
    before = open_fds()
    t = SerialTransport(pty.path)
    rec = Recorder(t)
    await t.open()
    pty.close(pty.controller)
    await rec.wait_events(1)
    assert rec.kinds() == [LinkEventKind.LOST]
    assert pty.path in rec.events[0].detail
    assert not t.connected
    with pytest.raises(LinkLost):
        t.send(b"x")
    await t.close()
    assert open_fds() == before - {pty.controller}  # the transport released its fd too
    assert len(rec.events) == 1


async def test_missing_device_raises_linklost_naming_it(tmp_path: Path) -> None:
    path = str(tmp_path / "ttyUSB-missing")
    t = SerialTransport(path)
    with pytest.raises(LinkLost, match=f"serial {path}: cannot open") as info:
        await t.open()
    assert isinstance(info.value, ConnectionError)
    assert not t.connected
    await t.close()


@pytest.mark.parametrize("bad", [9600, 0, 115201, 2_000_000, "115200", True, None])
def test_bad_baudrate_names_field_allowed_values_and_value(bad: object) -> None:
    with pytest.raises(ValueError, match="baudrate") as info:
        SerialTransport("/dev/ttyUSB0", bad)  # type: ignore[arg-type]
    msg = str(info.value)
    assert "115200, 250000, 500000, 1000000" in msg
    assert repr(bad) in msg


def test_empty_device_rejected() -> None:
    with pytest.raises(ValueError, match="device: '' is not a device path"):
        SerialTransport("")


async def test_close_does_not_hang_when_peer_never_reads(
    pty: Pty, monkeypatch: pytest.MonkeyPatch
) -> None:
    import gcu_async.transport.serial as serial_module

    monkeypatch.setattr(serial_module, "_CLOSE_GRACE", 0.1)
    t = SerialTransport(pty.path)
    await t.open()
    t.send(b"\x55" * 1_000_000)  # far more than the pty buffers: stays queued
    await asyncio.sleep(0.05)
    loop = asyncio.get_running_loop()
    started = loop.time()
    await asyncio.wait_for(t.close(), 3.0)
    assert loop.time() - started < 1.0
    assert not t.connected
