"""SerialTransport through a real pseudo-terminal pair: the transport opens the follower by
its path, the test plays the GCU on the controller fd."""

from __future__ import annotations

import array
import asyncio
import errno
import os
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gcu_async.errors import LinkLost
from gcu_async.transport import BAUDRATES, Backoff, LinkEventKind, SerialTransport
from helpers.transport.contract import (
    FROM_PEER,
    TO_PEER,
    Link,
    TransportContract,
    packet,
    send_whole_or_drop,
)
from helpers.transport.recorder import Recorder, open_fds, other_tasks

_PTY_ONLY = "the serial transport is tested on a pseudo-terminal: POSIX only (not Windows)"
if sys.platform == "win32" or not hasattr(os, "openpty"):
    pytest.skip(_PTY_ONLY, allow_module_level=True)
termios = pytest.importorskip("termios", reason=_PTY_ONLY)
fcntl = pytest.importorskip("fcntl", reason=_PTY_ONLY)
tty = pytest.importorskip("tty", reason=_PTY_ONLY)


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


# -- reading everything per event, backpressure, reset ------------------------------------


TTY_HOLDS = 4095
"""The most input a tty's line discipline holds for its reader (N_TTY_BUF_SIZE - 1); more waits
in the pty's buffers and follows as the reader takes it."""


def block_loop(pty: Pty, pending: int, least: float = 0.05, limit: float = 2.0) -> None:
    """Keep the event loop from running, as a slow handler would, for ``least`` seconds and
    until the tty holds the input written (``FIONREAD``: ``pending`` bytes, or as much as it
    can hold; at most ``limit`` seconds): on purpose, so that input piles up in the kernel
    meanwhile. Not a fixed time alone: on a loaded host the tty layer can take longer than
    any to pass the bytes on."""
    start = time.monotonic()
    count = array.array("i", [0])
    while time.monotonic() < start + limit:
        fcntl.ioctl(pty.follower, termios.FIONREAD, count)
        if count[0] >= min(pending, TTY_HOLDS) and time.monotonic() >= start + least:
            return
        time.sleep(0.002)
    raise AssertionError(f"the tty held {count[0]} of {pending} bytes after {limit:g} s")


async def one_readiness_event() -> None:
    """Two loop iterations: exactly one select() saw the pre-filled fd (the default loop
    runs a resumed task before the callbacks its select() queued in the same iteration)."""
    await asyncio.sleep(0)
    await asyncio.sleep(0)


PACKET_SIZE = 100
"""Size of the packets these tests send when the size does not matter."""


def fill_until_dropped(t: SerialTransport, limit: int = 100_000) -> list[bytes]:
    """Send packets to a port nobody reads until the first is dropped; the accepted ones."""
    accepted = []
    for k in range(limit):
        dropped = t.sends_dropped
        t.send(packet(k, PACKET_SIZE))
        if t.sends_dropped > dropped:
            return accepted
        accepted.append(packet(k, PACKET_SIZE))
    raise AssertionError(f"the pty took {limit} packets without pushing back")


def read_now(fd: int) -> bytes:
    """All the controller can read right now."""
    data = bytearray()
    while True:
        try:
            chunk = os.read(fd, 65536)
        except BlockingIOError:
            return bytes(data)
        if not chunk:
            return bytes(data)
        data += chunk


def fill_input(pty: Pty) -> bytes:
    """Write into the transport's input until the pty takes no more; what was written."""
    written = bytearray()
    chunk = bytes(range(256)) * 4
    try:
        while True:
            written += chunk[: os.write(pty.controller, chunk)]
    except BlockingIOError:
        return bytes(written)


async def test_input_that_arrived_while_blocked_comes_in_one_event(pty: Pty) -> None:
    # pyserial-asyncio alone reads 1024 bytes per event; a tty read returns <= 4095
    async with SerialTransport(pty.path, 1000000) as t:
        rec = Recorder(t)
        payload = fill_input(pty)
        assert len(payload) > 3 * 4096
        block_loop(pty, len(payload))  # the loop is blocked while it all arrives
        await one_readiness_event()
        assert rec.chunks == [payload]
        assert t.bytes_received == len(payload)


async def test_read_cap_leaves_the_rest_for_the_next_event(
    pty: Pty, monkeypatch: pytest.MonkeyPatch
) -> None:
    import gcu_async.transport.serial as serial_module

    monkeypatch.setattr(serial_module, "MAX_READ_PER_EVENT", 5000)
    async with SerialTransport(pty.path) as t:
        rec = Recorder(t)
        filled = len(fill_input(pty))
        assert filled > 15_000
        block_loop(pty, filled)
        await one_readiness_event()
        sizes = [len(c) for c in rec.chunks]
        for _ in range(2):  # the select() that resumed us queued the next event: run it
            await asyncio.sleep(0)
            sizes.append(len(rec.chunks[-1]))
        assert sizes[:2] == [5000, 5000]
        assert sizes[2] <= 5000


async def test_backpressure_drops_whole_packets_instead_of_queueing(pty: Pty) -> None:
    async with SerialTransport(pty.path) as t:
        rec = Recorder(t)
        accepted = fill_until_dropped(t)
        assert len(accepted) * 100 > 4096  # the OS took what it could, the rest waits
        sent = t.bytes_sent
        for _ in range(500):  # a stalled UART under a 50 Hz heartbeat: nothing more queues
            t.send(packet(0, PACKET_SIZE))
        assert t.sends_dropped == 501
        assert t.bytes_sent == sent == len(accepted) * 100
        # the other side resumes reading: exactly the accepted packets, whole, in order
        expected = b"".join(accepted)
        assert await pty.read(len(expected)) == expected
        await asyncio.sleep(0.05)
        assert read_now(pty.controller) == b""
        t.send(b"after")  # drained: sending works again
        assert await pty.read(5) == b"after"
        assert rec.events == []


async def test_reset_discards_queued_output_and_unread_input(pty: Pty) -> None:
    async with SerialTransport(pty.path) as t:
        rec = Recorder(t)
        accepted = fill_until_dropped(t)
        stream = b"".join(accepted)
        await asyncio.sleep(0.02)  # pyserial-asyncio cannot write more: the pty is full
        pty.write(b"stale reply")  # arrives, but nobody reads it before the reset
        t.reset("link declared lost")
        assert t.connected  # the port stays open
        await asyncio.sleep(0.05)
        assert rec.chunks == [] and rec.events == []  # stale input gone, no event
        got = read_now(pty.controller)
        # only what had already crossed to the other side survives: a prefix, far short
        # of what was accepted (the backpressure test shows all of it arrives otherwise)
        assert got == stream[: len(got)]
        assert len(got) < len(stream) - 4096
        t.send(b"fresh")  # nothing queued any more: not dropped
        assert await pty.read(5) == b"fresh"
        assert t.sends_dropped == 1  # only the one fill_until_dropped provoked
        pty.write(b"new reply")
        assert await rec.wait_bytes(9) == b"new reply"


async def test_reset_when_the_device_is_gone_reports_lost_from_the_loop(pty: Pty) -> None:
    t = SerialTransport(pty.path)
    rec = Recorder(t)
    await t.open()
    pty.close(pty.controller)
    t.reset("why")  # tcflush fails with EIO
    assert rec.events == []  # not from inside reset()
    await rec.wait_events(1)
    assert rec.kinds() == [LinkEventKind.LOST]
    assert "Input/output error" in rec.events[0].detail
    assert not t.connected
    await t.close()
    assert len(rec.events) == 1


async def test_write_failure_raises_linklost_and_reports_lost(pty: Pty) -> None:
    t = SerialTransport(pty.path)
    rec = Recorder(t)
    await t.open()
    pty.close(pty.controller)
    with pytest.raises(LinkLost, match=r"write failed: .*Input/output error"):
        t.send(b"x")
    await rec.wait_events(1)
    assert rec.kinds() == [LinkEventKind.LOST]
    assert "Input/output error" in rec.events[0].detail
    with pytest.raises(LinkLost, match="port is closed"):
        t.send(b"x")
    await t.close()


async def test_read_error_in_the_middle_of_draining(
    pty: Pty, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A device that fails while being drained: what was read is delivered, then LOST."""
    import gcu_async.transport.serial as serial_module

    t = SerialTransport(pty.path)
    rec = Recorder(t)
    await t.open()
    calls = []

    class FailingOs:
        """The serial module's ``os``: its second read fails as an unplugged device's."""

        def __getattr__(self, name: str) -> object:
            return getattr(os, name)

        def read(self, fd: int, n: int) -> bytes:
            calls.append(n)
            if len(calls) == 2:
                raise OSError(errno.EIO, "Input/output error")
            return os.read(fd, n)

    monkeypatch.setattr(serial_module, "os", FailingOs())
    pty.write(b"\x5a" * 10_000)
    block_loop(pty, 10_000)
    await rec.wait_events(1)
    monkeypatch.undo()
    # pyserial-asyncio's read (1024 bytes), then our first (a tty hands out <= 4095)
    assert 1024 < len(rec.data) <= 1024 + 4096
    assert rec.data == b"\x5a" * len(rec.data)
    assert len(calls) == 2
    assert "Input/output error" in rec.events[0].detail
    assert not t.connected
    await t.close()


PTY_HOLDS_AT_MOST = 65536
"""Generous bound on what a pty queues towards a side that does not read (~16-20 KiB)."""


@settings(max_examples=25)
@given(sizes=st.lists(st.integers(1, 8000), min_size=1, max_size=40))
def test_any_send_sequence_reaches_a_stalled_reader_whole_or_not_at_all(
    sizes: list[int],
) -> None:
    """Whatever the packet sizes, towards a side that stops reading: each packet is either
    accepted (then read later exactly, whole and in order) or dropped and counted, and what
    is accepted is bounded by what the pty holds plus one packet."""

    async def scenario() -> None:
        p = Pty()
        try:
            async with SerialTransport(p.path) as t:
                expected = send_whole_or_drop(t, sizes)
                assert t.bytes_sent <= PTY_HOLDS_AT_MOST + max(sizes)
                assert await p.read(len(expected), timeout=5.0) == expected
                await asyncio.sleep(0.01)
                assert read_now(p.controller) == b""
        finally:
            p.close_all()

    asyncio.run(scenario())


async def test_an_unplugged_device_is_reopened_when_it_comes_back(tmp_path: Path) -> None:
    """Unplug: the device's far end goes away (LOST). Replug: a new device appears under the
    same name (a udev symlink, as /dev/serial/by-id/... is): the transport reopens it,
    reports RESTORED, and bytes flow both ways again."""
    link = tmp_path / "ttyGCU"
    first = Pty()
    link.symlink_to(first.path)
    fast = Backoff(base=0.01, cap=0.05, max_attempts=None, max_total=10.0)
    t = SerialTransport(str(link), backoff=fast)
    rec = Recorder(t)
    second: Pty | None = None
    try:
        await t.open()
        first.close(first.controller)  # unplugged
        await rec.wait_events(1)
        assert rec.kinds() == [LinkEventKind.LOST]
        link.unlink()
        first.close_all()
        await asyncio.sleep(0.2)
        assert t.reconnecting and t.reconnect_attempts >= 2  # it keeps trying, quietly
        assert rec.kinds() == [LinkEventKind.LOST]
        second = Pty()
        link.symlink_to(second.path)  # plugged in again
        await rec.wait_events(2)
        assert rec.kinds() == [LinkEventKind.LOST, LinkEventKind.RESTORED]
        assert t.connected and t.reconnects == 1
        t.send(b"ping")
        assert await second.read(4) == b"ping"
        second.write(b"pong")
        assert (await rec.wait_bytes(4))[-4:] == b"pong"
    finally:
        await t.close()
        first.close_all()
        if second is not None:
            second.close_all()
    assert other_tasks() == set()


async def test_reopening_gives_up_after_its_bounds_and_close_stops_it(tmp_path: Path) -> None:
    pty = Pty()
    try:
        t = SerialTransport(pty.path, backoff=Backoff(base=0.01, cap=0.02, max_attempts=3))
        rec = Recorder(t)
        await t.open()
        pty.close(pty.controller)
        await rec.wait_events(2)
        assert rec.kinds() == [LinkEventKind.LOST, LinkEventKind.GAVE_UP]
        assert rec.events[1].detail.startswith("giving up after 3 reconnect attempts")
        assert not t.reconnecting
        await t.close()
        # a failed open() starts no reopening: the caller decides
        t2 = SerialTransport(str(tmp_path / "absent"), backoff=Backoff(base=0.01, cap=0.02,
                                                                       max_attempts=None,
                                                                       max_total=30.0))
        rec2 = Recorder(t2)
        with pytest.raises(LinkLost):
            await t2.open()
        assert rec2.events == []
        await t2.close()
    finally:
        pty.close_all()
    assert other_tasks() == set()


def test_reconnect_options_are_checked() -> None:
    with pytest.raises(TypeError, match="reconnect"):
        SerialTransport("/dev/null", reconnect=1)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="backoff"):
        SerialTransport("/dev/null", backoff={"base": 1})  # type: ignore[arg-type]


async def test_close_while_reopening_stops_the_task_without_an_event() -> None:
    pty = Pty()
    try:
        t = SerialTransport(pty.path, backoff=Backoff(base=0.01, cap=0.02, max_attempts=None,
                                                      max_total=30.0))  # fmt: skip
        rec = Recorder(t)
        await t.open()
        pty.close(pty.controller)
        await rec.wait_events(1)
        await asyncio.sleep(0.1)
        assert t.reconnecting
        await t.close()
        assert not t.reconnecting
        await asyncio.sleep(0.1)
        assert rec.kinds() == [LinkEventKind.LOST]
    finally:
        pty.close_all()
    assert other_tasks() == set()


class _PtyPeer:
    def __init__(self, pty: Pty) -> None:
        self.pty = pty

    def send(self, data: bytes) -> None:
        self.pty.write(data)

    async def read(self, n: int) -> bytes:
        return await self.pty.read(n)


class TestSerialContract(TransportContract):
    """The contract through a real pseudo-terminal (raw 8-bit both ways)."""

    closed_message = "port is closed"

    @pytest.fixture
    def link(self, pty: Pty) -> Link:
        return Link(SerialTransport(pty.path, 115200), _PtyPeer(pty), extra={"pty": pty})

    def after_exchange(self, link: Link, rec: Recorder) -> None:
        t = link.transport
        assert isinstance(t, SerialTransport)
        assert t.bytes_sent == sum(map(len, TO_PEER))
        assert t.bytes_received == sum(map(len, FROM_PEER))

    async def after_double_open(self, link: Link) -> None:
        pty = link.extra["pty"]
        fds = open_fds()
        await link.transport.open()  # a third time: still no new fd
        assert open_fds() == fds
        assert pty.path in link.transport.url
