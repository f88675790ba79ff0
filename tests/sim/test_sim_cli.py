"""``gcu-async sim`` through the real console script, in a subprocess."""

from __future__ import annotations

import contextlib
import os
import re
import selectors
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from gcu_async.cli import main
from gcu_async.cli._exit import EXIT_INTERRUPTED
from gcu_async.errors import RemoteProtocolError
from gcu_async.protocol import Deframer, GcuPacket, Opcode, Palette, TakePhoto, decode_gcu_packet
from gcu_async.sim import parse_listen_url
from helpers.sim.support import host_bytes

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals and ptys")
tty = pytest.importorskip("tty", reason="POSIX signals and ptys")

_SCRIPT = Path(sys.executable).with_name("gcu-async")
CLI = (
    [str(_SCRIPT)]
    if _SCRIPT.exists()
    else [sys.executable, "-c", "import sys; from gcu_async.cli import main; sys.exit(main())"]
)


def _readline(proc: subprocess.Popen[str], timeout: float = 10.0) -> str:
    assert proc.stdout is not None
    with selectors.DefaultSelector() as sel:
        sel.register(proc.stdout, selectors.EVENT_READ)
        if not sel.select(timeout):
            raise TimeoutError("the simulator printed nothing")
    return proc.stdout.readline()


class Sim:
    def __init__(self, *args: str) -> None:
        self.proc = subprocess.Popen(
            [*CLI, "sim", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )
        self.line = _readline(self.proc)
        match = re.search(r"listening on (\S+)", self.line)
        assert match, self.line
        self.url = match.group(1)

    def stop(self, sig: int = signal.SIGTERM) -> tuple[int, str]:
        self.proc.send_signal(sig)
        _, err = self.proc.communicate(timeout=10)
        return self.proc.returncode, err

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.communicate(timeout=10)


@pytest.fixture
def sims() -> Iterator[list[Sim]]:
    made: list[Sim] = []
    yield made
    for sim in made:
        sim.kill()


def _udp_request(address: tuple[str, int], data: bytes, timeout: float = 2.0) -> GcuPacket:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.settimeout(timeout)
        s.sendto(data, address)
        reply, source = s.recvfrom(4096)
        assert source == address
        return decode_gcu_packet(reply)


def _address(url: str) -> tuple[str, int]:
    spec = parse_listen_url(url)
    return spec.host, spec.port


def test_udp_sim_answers_logs_and_stops_on_sigterm(sims: list[Sim]) -> None:
    sim = Sim("--listen", "udp://127.0.0.1:0")
    sims.append(sim)
    assert sim.url.startswith("udp://127.0.0.1:")
    assert "D-90Pro(TA)" in sim.line
    reply = _udp_request(_address(sim.url), host_bytes(TakePhoto()))
    assert (reply.feedback.opcode, reply.feedback.status) == (Opcode.TAKE_PHOTO, 0)
    status, err = sim.stop(signal.SIGTERM)
    assert status == EXIT_INTERRUPTED  # a signal ended it (docs/cli.md)
    assert "executed TAKE_PHOTO" in err
    assert "Traceback" not in err


def test_tcp_sim_with_a_pod_and_ctrl_c(sims: list[Sim]) -> None:
    sim = Sim("--listen", "tcp://127.0.0.1:0", "--pod", "Z-6A")
    sims.append(sim)
    deframer = Deframer.for_gcu_packets()
    with socket.create_connection(_address(sim.url), timeout=2.0) as s:
        s.sendall(host_bytes(Palette(1)))
        packets: list[bytes] = []
        deadline = time.monotonic() + 2.0
        while not packets and time.monotonic() < deadline:
            packets += deframer.feed(s.recv(4096))
    reply = decode_gcu_packet(packets[0])
    assert (reply.feedback.opcode, reply.feedback.status) == (Opcode.PALETTE, 0x02)
    status, err = sim.stop(signal.SIGINT)
    assert status == EXIT_INTERRUPTED  # a signal ended it (docs/cli.md)
    assert "Traceback" not in err


def test_pty_sim_prints_the_device_path(sims: list[Sim]) -> None:
    sim = Sim("--listen", "pty", "--quiet")
    sims.append(sim)
    path = parse_listen_url(sim.url).path
    assert path in sim.line
    fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
    try:
        tty.setraw(fd)
        os.write(fd, host_bytes(TakePhoto()))
        deframer = Deframer.for_gcu_packets()
        packets: list[bytes] = []
        with selectors.DefaultSelector() as sel:
            sel.register(fd, selectors.EVENT_READ)
            deadline = time.monotonic() + 2.0
            while not packets and time.monotonic() < deadline:
                if sel.select(0.1):
                    packets += deframer.feed(os.read(fd, 4096))
        assert decode_gcu_packet(packets[0]).feedback.opcode == Opcode.TAKE_PHOTO
    finally:
        os.close(fd)
    status, err = sim.stop()
    assert status == EXIT_INTERRUPTED  # a signal ended it (docs/cli.md)
    assert "executed" not in err  # --quiet


def test_sigusr2_silences_and_sigusr1_kills_the_tcp_connection(sims: list[Sim]) -> None:
    udp = Sim("--listen", "udp://127.0.0.1:0", "--silence", "30")
    sims.append(udp)
    _udp_request(_address(udp.url), host_bytes())
    udp.proc.send_signal(signal.SIGUSR2)
    silenced = False
    deadline = time.monotonic() + 3.0
    while not silenced and time.monotonic() < deadline:  # the signal lands asynchronously
        try:
            _udp_request(_address(udp.url), host_bytes(), timeout=0.25)
        except TimeoutError:
            silenced = True
    assert silenced
    assert udp.stop()[0] == EXIT_INTERRUPTED  # a signal ended it (docs/cli.md)

    tcp = Sim("--listen", "tcp://127.0.0.1:0")
    sims.append(tcp)
    with socket.create_connection(_address(tcp.url), timeout=2.0) as s:
        s.sendall(host_bytes())
        assert s.recv(4096)
        tcp.proc.send_signal(signal.SIGUSR1)
        s.settimeout(2.0)
        with contextlib.suppress(ConnectionResetError):  # a reset, or an orderly end
            assert s.recv(4096) == b""
    status, err = tcp.stop()
    assert status == EXIT_INTERRUPTED  # a signal ended it (docs/cli.md)
    assert "killing the TCP connection" in err


def test_reply_port_sends_to_the_senders_host(sims: list[Sim]) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as listener:
        listener.bind(("127.0.0.1", 0))
        listener.settimeout(2.0)
        port = listener.getsockname()[1]
        sim = Sim("--listen", "udp://127.0.0.1:0", "--reply-port", str(port))
        sims.append(sim)
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sender:
            sender.sendto(host_bytes(TakePhoto()), _address(sim.url))
            reply, source = listener.recvfrom(4096)
        assert source == _address(sim.url)
        assert decode_gcu_packet(reply).feedback.opcode == Opcode.TAKE_PHOTO
    assert sim.stop()[0] == EXIT_INTERRUPTED  # a signal ended it (docs/cli.md)


def test_loss_one_drops_everything(sims: list[Sim]) -> None:
    sim = Sim("--listen", "udp://127.0.0.1:0", "--loss", "1", "--seed", "5")
    sims.append(sim)
    with pytest.raises(TimeoutError):
        _udp_request(_address(sim.url), host_bytes(TakePhoto()), timeout=0.3)
    assert sim.stop()[0] == EXIT_INTERRUPTED  # a signal ended it (docs/cli.md)


BAD_OPTIONS = [
    (["--listen", "ftp://127.0.0.1"], "--listen: listen URL"),
    (["--listen", "udp://127.0.0.1:70000"], "port"),
    (["--listen", "tcp://"], "host: missing"),
    (["--pod", "X-1"], "--pod: 'X-1' is not one of"),
    (["--loss", "1.5"], "--loss"),
    (["--delay", "-1"], "--delay"),
    (["--listen", "tcp://127.0.0.1:0", "--reply-to", "127.0.0.1:2338"], "--reply-to"),
    (["--reply-to", "nohost"], "--reply-to"),
    (["--reply-port", "0"], "--reply-port"),
    (["--silence", "-2"], "--silence"),
    (["--reorder-hold", "-0.001"], "--reorder-hold"),
    (["--reorder-hold", "nan"], "--reorder-hold"),
    (["--reorder-hold", "inf"], "--reorder-hold"),
    (["--stall", "0"], "--stall"),
    (["--stall", "inf"], "--stall"),
    (["--max-zoom", "0.5"], "--max-zoom: 0.5 is outside"),
]


@pytest.mark.parametrize(("args", "message"), BAD_OPTIONS[:2])
def test_bad_options_give_one_line_and_status_2(args: list[str], message: str) -> None:
    done = subprocess.run([*CLI, "sim", *args], capture_output=True, text=True, timeout=20)
    assert done.returncode == 2
    assert done.stdout == ""
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert message in lines[0]


@pytest.mark.parametrize(("args", "message"), BAD_OPTIONS)
def test_every_bad_option_is_one_line_status_2(
    args: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["sim", *args]) == 2  # the same entry point, in-process (fast)
    out, err = capsys.readouterr()
    assert out == ""
    assert len(err.strip().splitlines()) == 1, err
    assert message in err


def test_listen_url_parsing() -> None:
    assert parse_listen_url("udp://127.0.0.1").port == 2337
    assert parse_listen_url("tcp://127.0.0.1").port == 2332
    assert parse_listen_url("tcp://[::1]:5000").host == "::1"
    spec = parse_listen_url("serial:///dev/ttyUSB0?baudrate=1000000")
    assert (spec.kind, spec.path, spec.baudrate) == ("serial", "/dev/ttyUSB0", 1000000)
    assert parse_listen_url("pty").kind == "pty"
    with pytest.raises(ValueError, match="baudrate"):
        parse_listen_url("serial:///dev/ttyUSB0?baudrate=fast")
    with pytest.raises(ValueError, match="'parity' is not a serial URL option"):
        parse_listen_url("serial:///dev/ttyUSB0?parity=E")


def test_faults_on_a_bad_direction_is_a_usage_error() -> None:
    done = subprocess.run([*CLI, "sim", "--faults-on", "sideways"], capture_output=True,
                          text=True, timeout=20)  # fmt: skip
    assert done.returncode == 2
    assert "--faults-on" in done.stderr.strip().splitlines()[-1]


def test_help_documents_the_fault_model_and_its_bound() -> None:
    done = subprocess.run([*CLI, "sim", "--help"], capture_output=True, text=True, timeout=20)
    assert done.returncode == 0
    text = " ".join(done.stdout.split())
    for option in ("--reorder-hold", "--faults-on", "--stall", "--delay"):
        assert option in text
    assert "--delay + --reorder-hold" in text
    assert "Both copies of a duplicate get the same d" in text


def test_reorder_hold_holds_each_reply_that_long(sims: list[Sim]) -> None:
    """--reorder 1 on replies only: every reply is held exactly --reorder-hold (0.2 s, far
    above the 5 ms default); a lower bound, robust on a slow machine."""
    sim = Sim("--listen", "udp://127.0.0.1:0", "--reorder", "1", "--reorder-hold", "0.2",
              "--faults-on", "replies", "-q")  # fmt: skip
    sims.append(sim)
    for _ in range(3):
        started = time.monotonic()
        reply = _udp_request(_address(sim.url), host_bytes(TakePhoto()), timeout=5.0)
        assert 0.2 <= time.monotonic() - started < 5.0
        assert reply.feedback.opcode == Opcode.TAKE_PHOTO
    assert sim.stop()[0] == EXIT_INTERRUPTED  # a signal ended it (docs/cli.md)


@pytest.mark.parametrize(
    ("direction", "outcome"),
    [("requests", "nothing"), ("replies", "corrupt"), ("both", "nothing")],
)
def test_faults_on_picks_the_direction(sims: list[Sim], direction: str, outcome: str) -> None:
    """--corrupt 1: a corrupted request is never answered; a corrupted reply arrives and
    fails its CRC check."""
    sim = Sim("--listen", "udp://127.0.0.1:0", "--corrupt", "1", "--faults-on", direction,
              "-q")  # fmt: skip
    sims.append(sim)
    if outcome == "nothing":
        with pytest.raises(TimeoutError):
            _udp_request(_address(sim.url), host_bytes(), timeout=0.3)
    else:
        with pytest.raises(RemoteProtocolError):
            _udp_request(_address(sim.url), host_bytes(), timeout=2.0)
    assert sim.stop()[0] == EXIT_INTERRUPTED  # a signal ended it (docs/cli.md)


def test_reply_delays_stay_within_delay_plus_hold_over_real_sockets(sims: list[Sim]) -> None:
    """Real timestamps: the exact bound is checked in virtual time (test_sim_fault_bounds);
    here the CLI's faults are shown to reach the wire. Lower bounds are exact (held replies
    are at least --reorder-hold late); the upper bound has a margin for a loaded machine."""
    delay, hold, margin = 0.03, 0.05, 0.5
    sim = Sim("--listen", "udp://127.0.0.1:0", "--delay", str(delay), "--reorder", "0.5",
              "--reorder-hold", str(hold), "--duplicate", "0.5", "--faults-on", "replies",
              "--seed", "3", "-q")  # fmt: skip
    sims.append(sim)
    address = _address(sim.url)
    n = 40
    sent: dict[int, float] = {}
    arrivals: dict[int, list[float]] = {}
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.setblocking(False)
        with selectors.DefaultSelector() as sel:
            sel.register(s, selectors.EVENT_READ)

            def collect(until: float) -> None:
                while (left := until - time.monotonic()) > 0:
                    if sel.select(left):
                        data, _ = s.recvfrom(4096)
                        now = time.monotonic()
                        yaw = round(decode_gcu_packet(data).main.attitude.yaw)
                        arrivals.setdefault(yaw, []).append(now)

            for i in range(n):
                sent[i] = time.monotonic()
                s.sendto(host_bytes(attitude=(0.0, 0.0, float(i))), address)
                collect(time.monotonic() + 0.01)
            collect(time.monotonic() + 1.0)
    assert sorted(arrivals) == list(range(n))  # every request answered (no loss asked)
    latencies = [t - sent[i] for i, times in arrivals.items() for t in times]
    assert max(latencies) < delay + hold + margin
    assert max(latencies) >= hold  # some replies were held back
    doubled = [times for times in arrivals.values() if len(times) == 2]
    assert doubled, "--duplicate 0.5 doubled no reply in 40"
    assert all(abs(a - b) < margin for a, b in doubled)  # the copies travel together
    assert all(len(times) <= 2 for times in arrivals.values())
    assert sim.stop()[0] == EXIT_INTERRUPTED  # a signal ended it (docs/cli.md)


def test_sighup_stalls_for_stall_seconds_then_answers_everything(sims: list[Sim]) -> None:
    sim = Sim("--listen", "udp://127.0.0.1:0", "--stall", "2", "-q")
    sims.append(sim)
    address = _address(sim.url)
    _udp_request(address, host_bytes())
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.settimeout(0.25)
        sim.proc.send_signal(signal.SIGHUP)
        sent = 0
        stalled = False
        deadline = time.monotonic() + 3.0
        while not stalled and time.monotonic() < deadline:  # the signal lands asynchronously
            waiting_since = time.monotonic()
            s.sendto(host_bytes(attitude=(0.0, 0.0, float(sent))), address)
            sent += 1
            try:
                data, _ = s.recvfrom(4096)
                assert round(decode_gcu_packet(data).main.attitude.yaw) == sent - 1
            except TimeoutError:
                stalled = True
        assert stalled
        first_waiting = sent - 1
        for _ in range(10):
            s.sendto(host_bytes(attitude=(0.0, 0.0, float(sent))), address)
            sent += 1
        s.settimeout(5.0)
        tags = [round(decode_gcu_packet(s.recvfrom(4096)[0]).main.attitude.yaw)]
        waited = time.monotonic() - waiting_since
        tags += [round(decode_gcu_packet(s.recvfrom(4096)[0]).main.attitude.yaw)
                 for _ in range(first_waiting + 1, sent)]  # fmt: skip
    assert tags == list(range(first_waiting, sent))  # all of them, in order
    assert waited >= 1.0  # the 2 s stall began at most one 0.25 s probe before
    status, err = sim.stop()
    assert status == EXIT_INTERRUPTED  # a signal ended it (docs/cli.md)
    assert "Traceback" not in err


def test_without_stall_sighup_keeps_its_default_action(sims: list[Sim]) -> None:
    sim = Sim("--listen", "udp://127.0.0.1:0", "-q")
    sims.append(sim)
    sim.proc.send_signal(signal.SIGHUP)
    sim.proc.communicate(timeout=10)
    assert sim.proc.returncode == -signal.SIGHUP


REPORT_HEAD = "Host conformance to V2.0.6"


@pytest.mark.parametrize("quiet", [False, True])
def test_quiet_prints_no_report_at_exit_and_the_file_still_gets_it(
    sims: list[Sim], tmp_path: Path, quiet: bool
) -> None:
    """``-q`` means quiet: no command log and no report at exit on stderr; ``--report``
    (asking for it) still writes it. Without ``-q`` both are printed."""
    report = tmp_path / "host.txt"
    sim = Sim("--listen", "udp://127.0.0.1:0", "--report", str(report), *(["-q"] * quiet))
    sims.append(sim)
    _udp_request(_address(sim.url), host_bytes(TakePhoto()))
    status, err = sim.stop(signal.SIGTERM)
    assert status == EXIT_INTERRUPTED
    assert report.read_text(encoding="utf-8").startswith(f"{REPORT_HEAD}: 1 packets")
    if quiet:
        assert err == ""
    else:
        assert REPORT_HEAD in err and "executed TAKE_PHOTO" in err


def test_help_says_what_quiet_leaves_out() -> None:
    done = subprocess.run([*CLI, "sim", "--help"], capture_output=True, text=True, timeout=20)
    text = " ".join(done.stdout.split())
    assert "log nothing and print no report at exit (--report, --report-json and SIGQUIT " \
           "still give it)" in text  # fmt: skip


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="broadcast on loopback: Linux")
def test_reply_to_broadcast_on_loopback_reaches_every_listener_on_the_port(
    sims: list[Sim],
) -> None:
    """The loopback interface has no broadcast address of its own, yet Linux delivers a
    datagram to 127.255.255.255 to every socket on its port: ``--reply-to broadcast``
    there is a GCU on this machine that every local listener hears (two here, sharing the
    port as the application and ``monitor --passive`` do)."""
    listeners = []
    try:
        for _ in range(2):
            s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEPORT, 1)
            s.bind(("0.0.0.0", listeners[0].getsockname()[1] if listeners else 0))
            s.settimeout(2.0)
            listeners.append(s)
        port = listeners[0].getsockname()[1]
        sim = Sim("--listen", "udp://127.0.0.1:0", "--reply-to", f"broadcast:{port}")
        sims.append(sim)
        assert f"(replies to 127.255.255.255:{port})" in sim.line
        listeners[0].sendto(host_bytes(TakePhoto()), _address(sim.url))
        for s in listeners:
            reply, source = s.recvfrom(4096)
            assert source == _address(sim.url)
            assert decode_gcu_packet(reply).feedback.opcode == Opcode.TAKE_PHOTO
    finally:
        for s in listeners:
            s.close()
