"""What the library promises beyond Linux (docs/transports.md, "Windows"), tested here on
Linux: Windows serial port names in URLs; UDP receive surviving ICMP port unreachable (a
real one on a connected socket, and Windows' flavour injected into the read path); the
package and the test suite importing without the POSIX-only modules; the pytest plugin's
pty transport skipping with a reason where pseudo-terminals do not exist."""

from __future__ import annotations

import asyncio
import os
import re
import socket
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import pytest

from gcu_async.sim import ManualClock, parse_listen_url
from gcu_async.sim.stall import POLL_SECONDS, StallSwitch, TransportReading
from gcu_async.transport import SerialTransport, UdpTransport, open_transport
from gcu_async.transport._datagram import DrainingDatagramTransport
from gcu_async.transport.base import LinkEventKind
from gcu_async.transport.udp import ignore_icmp_connreset
from gcu_async.transport.url import serial_device
from helpers.transport.recorder import Recorder

ROOT = Path(__file__).resolve().parents[2]
LOOP = "127.0.0.1"

# -- serial://COM3 ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("url", "device"),
    [
        ("serial://COM3", "COM3"),
        ("serial:///COM3", "COM3"),  # the form that used to open "/COM3"
        ("serial:COM3", "COM3"),
        ("serial://COM3/", "COM3"),
        ("serial://com12?baudrate=1000000", "com12"),
        ("SERIAL://COM255", "COM255"),
        ("serial:///dev/ttyUSB0", "/dev/ttyUSB0"),  # POSIX paths as before
        ("serial:/dev/ttyS1", "/dev/ttyS1"),
        ("serial:///dev/COM3", "/dev/COM3"),  # only a bare /COMn is a Windows name
        ("serial:///COMMON", "/COMMON"),
        ("serial:///COM3/x", "/COM3/x"),
    ],
)
def test_serial_url_device(url: str, device: str) -> None:
    t = open_transport(url)
    assert isinstance(t, SerialTransport)
    assert t.device == device
    again = open_transport(t.url)  # the canonical URL names the same device
    assert isinstance(again, SerialTransport) and again.device == device
    assert parse_listen_url(url).path == device  # the simulator reads it the same way


@pytest.mark.parametrize(
    ("url", "message"),
    [
        ("serial://COM0", "device: host part 'COM0' is not allowed"),
        ("serial://COM3/x", "device: host part 'COM3' is not allowed"),
        ("serial://COM3:5", "device: host part 'COM3:5' is not allowed"),
        ("serial://ttyUSB0", "device: host part 'ttyUSB0' is not allowed"),
        ("serial://LPT1", "device: host part 'LPT1' is not allowed"),
        ("serial://", "device: missing"),
    ],
)
def test_bad_serial_urls_name_the_field(url: str, message: str) -> None:
    with pytest.raises(ValueError, match=rf"^{url}: {message} \(use serial:///dev/ttyUSB0, or "):
        open_transport(url)
    with pytest.raises(ValueError, match=message):
        parse_listen_url(url)


def test_serial_device_is_exact_about_windows_names() -> None:
    assert serial_device("COM1", "") == "COM1"
    assert serial_device("", "/COM10") == "COM10"
    assert serial_device("", "/%43OM4") == "COM4"  # still quoted: decoded first
    with pytest.raises(ValueError, match="host part"):
        serial_device("COM1x", "")
    with pytest.raises(ValueError, match="host part"):
        serial_device("COM01", "")


# -- UDP: ICMP port unreachable is reported, never fatal ---------------------------------------


def _free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind((LOOP, 0))
        return int(s.getsockname()[1])


@pytest.fixture(params=["draining", "fallback"])
async def reader_path(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> str:
    """The draining reader, and asyncio's own datagram transport (the path Windows' proactor
    loop takes; simulated by refusing add_reader)."""
    if request.param == "fallback":

        def refuse(*args: object) -> None:
            raise NotImplementedError("add_reader is refused by this test")

        monkeypatch.setattr(asyncio.get_running_loop(), "add_reader", refuse)
    return str(request.param)


async def test_icmp_port_unreachable_on_receive_keeps_the_link(reader_path: str) -> None:
    """A GCU not listening yet answers with ICMP port unreachable. Linux reports it to a
    connected socket's next receive (Windows to any UDP socket's): the transport counts it,
    stays open, and receives the GCU's datagrams once it is up — every time."""
    port = _free_udp_port()
    async with UdpTransport(LOOP, port, local_port=0, local_host=LOOP) as t:
        assert t.draining is (reader_path == "draining")
        rec = Recorder(t)
        # connect the socket (Linux reports ICMP errors to a connected socket's receive);
        # asyncio's transport hands out a wrapper, so go through the descriptor
        sock = socket.socket(fileno=t.get_extra_info("socket").fileno())
        try:
            sock.connect((LOOP, port))
        finally:
            sock.detach()  # the transport owns the descriptor
        for round_ in range(1, 4):
            t.send(b"anyone there?")
            await rec.wait_until(lambda r=round_: t.send_errors >= r)  # type: ignore[misc]
            assert isinstance(t.last_error, ConnectionRefusedError)
            assert t.connected
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as gcu:
            gcu.bind((LOOP, port))  # the GCU is up now, on the port that refused
            gcu.sendto(b"reply", t.local_address)
            await rec.wait_bytes(5)
        assert rec.data == b"reply"
        # no LOST: the link never went down; the three errors were one episode, one event
        assert t.connected and [e.kind for e in rec.events] == [LinkEventKind.ERROR]
        assert t.send_errors == 3


class _IcmpSocket(socket.socket):
    """A UDP socket whose next receives fail as Windows reports an ICMP port unreachable
    (WSAECONNRESET), or with another OS error, before the datagrams queued behind."""

    def __init__(self) -> None:
        super().__init__(socket.AF_INET, socket.SOCK_DGRAM)
        self.failures: list[OSError] = []

    def recvfrom_into(self, *args: Any, **kwargs: Any) -> Any:
        if self.failures:
            raise self.failures.pop(0)
        return super().recvfrom_into(*args, **kwargs)


class _Collect(asyncio.DatagramProtocol):
    def __init__(self) -> None:
        self.datagrams: list[bytes] = []
        self.errors: list[Exception] = []

    def datagram_received(self, data: bytes, addr: Any) -> None:
        self.datagrams.append(data)

    def error_received(self, exc: Exception) -> None:
        self.errors.append(exc)


async def test_connection_reset_on_receive_does_not_end_the_drain() -> None:
    loop = asyncio.get_running_loop()
    sock = _IcmpSocket()
    sock.bind((LOOP, 0))
    sock.setblocking(False)
    proto = _Collect()
    transport = DrainingDatagramTransport(loop, sock, proto, 2048)
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sender:
            for n in range(3):
                sender.sendto(bytes([n]), sock.getsockname())
            await asyncio.sleep(0.05)
            sock.failures += [ConnectionResetError(10054, "WSAECONNRESET"),
                              ConnectionRefusedError(111, "refused")]  # fmt: skip
            assert transport.read_all()  # both reports consumed, then all three datagrams
            assert proto.datagrams == [b"\x00", b"\x01", b"\x02"]
            assert [type(e) for e in proto.errors] == [ConnectionResetError, ConnectionRefusedError]
            # any other receive error is reported and ends this drain; the next one goes on
            sender.sendto(b"later", sock.getsockname())
            await asyncio.sleep(0.05)
            sock.failures.append(OSError(5, "EIO"))
            assert not transport.read_all()
            assert transport.read_all()
            assert proto.datagrams[-1] == b"later"
            assert not transport.is_closing()
    finally:
        transport.close()
        await asyncio.sleep(0)  # the socket closes on the next iteration
    assert sock.fileno() == -1


async def test_udp_transport_counts_receive_resets_and_reads_on(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Through UdpTransport: Windows' receive-side report (ConnectionResetError) is counted
    like any ICMP error, the datagram behind it is delivered, and the link stays up."""
    made: list[_IcmpSocket] = []

    def icmp_socket(*args: Any, **kwargs: Any) -> _IcmpSocket:
        made.append(_IcmpSocket())
        return made[-1]

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as gcu:
        gcu.bind((LOOP, 0))
        t = UdpTransport(LOOP, gcu.getsockname()[1], local_port=0, local_host=LOOP)
        monkeypatch.setattr("gcu_async.transport.udp.socket.socket", icmp_socket)
        await t.open()
        monkeypatch.undo()
        try:
            rec = Recorder(t)
            [sock] = made
            sock.failures.append(ConnectionResetError(10054, "WSAECONNRESET"))
            gcu.sendto(b"after the reset", t.local_address)
            await rec.wait_bytes(15)
            assert (t.send_errors, type(t.last_error)) == (1, ConnectionResetError)
            assert t.connected and [e.kind for e in rec.events] == [LinkEventKind.ERROR]
        finally:
            await t.close()


def test_sio_udp_connreset_is_switched_off_where_it_exists(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    calls: list[tuple[int, bool]] = []

    class WindowsSocket:
        def ioctl(self, code: int, flag: bool) -> None:
            calls.append((code, flag))

    class RefusingSocket:
        def ioctl(self, code: int, flag: bool) -> None:
            raise OSError("not supported")

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as real:
        if not hasattr(socket, "SIO_UDP_CONNRESET"):
            assert ignore_icmp_connreset(real) is False  # Linux, macOS: nothing to do
    monkeypatch.setattr(socket, "SIO_UDP_CONNRESET", 0x9800000C, raising=False)
    assert ignore_icmp_connreset(WindowsSocket()) is True  # type: ignore[arg-type]
    assert calls == [(0x9800000C, False)]
    assert ignore_icmp_connreset(RefusingSocket()) is False  # type: ignore[arg-type]
    monkeypatch.delattr(socket, "SIO_UDP_CONNRESET")
    assert ignore_icmp_connreset(WindowsSocket()) is False  # type: ignore[arg-type]
    assert len(calls) == 1


# -- without the POSIX-only modules (as on Windows) --------------------------------------------

_NO_POSIX = textwrap.dedent(
    """
    import os, sys
    import serial  # pyserial picks its backend by os.name: on Windows it needs none of these
    for name in ("termios", "tty", "pty", "fcntl", "resource", "grp", "pwd"):
        sys.modules[name] = None  # importing it raises ImportError, as on Windows
    for name in ("openpty", "ttyname"):
        if hasattr(os, name):
            delattr(os, name)
    """
)


def _run_without_posix(
    code: str, cwd: Path, timeout: float = 120
) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST_")}
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    return subprocess.run(
        [sys.executable, "-c", _NO_POSIX + textwrap.dedent(code)],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
    )


def test_the_package_imports_without_posix_only_modules() -> None:
    proc = _run_without_posix(
        """
        import gcu_async, gcu_async.cli, gcu_async.sim, gcu_async.pytest_plugin
        from gcu_async import GcuClient, connect
        from gcu_async.transport import open_transport
        assert gcu_async.pytest_plugin.PTY_AVAILABLE is False
        print(open_transport("serial://COM3").device)
        """,
        ROOT,
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "COM3"


def test_the_test_suite_collects_without_posix_only_modules() -> None:
    """Every test module imports where ``tty``/``termios``/``fcntl`` do not exist: the
    pseudo-terminal tests skip (with their reason) instead of breaking collection."""
    proc = _run_without_posix(
        """
        import pytest
        raise SystemExit(pytest.main(["--collect-only", "-q", "-p", "no:cacheprovider",
                                      "-rs", "tests"]))
        """,
        ROOT,
        timeout=300,
    )
    output = proc.stdout + proc.stderr
    assert proc.returncode == 0, output[-4000:]
    assert not re.search(r"^ERROR|\b\d+ errors?\b", output, re.MULTILINE), output[-4000:]
    assert re.search(r"^\d+ tests collected", output, re.MULTILINE), output[-4000:]
    assert "pseudo-terminal: POSIX only" in output, output[-4000:]  # test_transport_serial


def test_plugin_serial_transport_skips_without_ptys(tmp_path: Path) -> None:
    (tmp_path / "pyproject.toml").write_text(
        '[tool.pytest.ini_options]\nasyncio_mode = "auto"\n'
        'asyncio_default_fixture_loop_scope = "function"\n',
        encoding="utf-8",
    )
    (tmp_path / "test_serial.py").write_text(
        textwrap.dedent(
            """
            import pytest

            @pytest.fixture
            def gcu_sim_transport() -> str:
                return "serial"

            async def test_photo(gcu_client) -> None:
                await gcu_client.take_photo()
            """
        ),
        encoding="utf-8",
    )
    proc = _run_without_posix(
        """
        import pytest
        raise SystemExit(pytest.main(["-p", "no:cacheprovider", "-rs"]))
        """,
        tmp_path,
    )
    output = proc.stdout + proc.stderr
    assert proc.returncode == 0, output
    assert "1 skipped" in output, output
    assert "gcu_sim_transport 'serial' is a pseudo-terminal: POSIX only" in output, output


# -- Python 3.10: datagram transports that cannot pause -----------------------------------------


async def test_a_transport_that_cannot_pause_reading_does_not_break_a_stall() -> None:
    """Python 3.10's datagram transport has pause_reading() but raises NotImplementedError
    from it: a stall must still start, be timed and end (the exchange holds the packets)."""

    class Unpausable(asyncio.BaseTransport):
        def __init__(self) -> None:
            super().__init__()
            self.calls: list[str] = []

        def is_closing(self) -> bool:
            return False

        def pause_reading(self) -> None:
            self.calls.append("pause")
            raise NotImplementedError

        def resume_reading(self) -> None:
            self.calls.append("resume")
            raise NotImplementedError

    clock = ManualClock()
    switch = StallSwitch(clock)
    transport = Unpausable()
    switch.join(TransportReading(transport))
    switch.stall(1.0)
    assert switch.stalled and transport.calls == ["pause"]
    clock.advance(1.0)
    await asyncio.sleep(POLL_SECONDS * 3)
    assert not switch.stalled
    assert transport.calls == ["pause", "resume"]
