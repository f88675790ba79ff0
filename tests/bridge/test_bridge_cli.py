"""``gcu-async mavlink-bridge`` through the real entry point: it bridges, and Ctrl-C (SIGINT)
or SIGTERM ends it with exit status 0 (docs/mavlink-bridge.md, "Command line")."""

from __future__ import annotations

import contextlib
import signal
import subprocess
import time

import pytest

from gcu_async.bridge._mavlink import mavlink
from gcu_async.cli.mavlink_bridge import default_video_url
from helpers.bridge.rig import GIMBAL, Peer
from helpers.sim.process import CLI, SimProcess


def wait_for(peer: Peer, kind: str, pred, timeout: float = 10.0):  # type: ignore[no-untyped-def]
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        msg = peer.conn.recv_match(type=kind, blocking=True, timeout=0.2)
        if msg is not None and pred(msg):
            return msg
    raise TimeoutError(f"no {kind} within {timeout} s")


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_bridge_runs_and_stops_with_status_0(sig: signal.Signals) -> None:
    sim = SimProcess("--listen", "udp://127.0.0.1:0")
    gcs = Peer(255, 190)
    proc = None
    try:
        proc = subprocess.Popen(
            [*CLI, "mavlink-bridge", f"{sim.url}?local_port=0", "--mavlink", gcs.url,
             "--system-id", "7", "--max-zoom", "30"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
        hb = wait_for(gcs, "HEARTBEAT", lambda m: m.get_srcComponent() == GIMBAL
                      and m.system_status == mavlink.MAV_STATE_ACTIVE)
        assert hb.get_srcSystem() == 7
        gcs.conn.mav.command_long_send(7, GIMBAL, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW, 0,
                                       -30, 0, float("nan"), float("nan"), 0, 0, 0)
        ack = wait_for(gcs, "COMMAND_ACK", lambda m: m.result != mavlink.MAV_RESULT_IN_PROGRESS)
        assert ack.result == mavlink.MAV_RESULT_ACCEPTED
        assert proc.poll() is None
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=10)
    finally:
        if proc is not None and proc.poll() is None:
            proc.kill()
            proc.communicate()
        gcs.close()
        log = sim.stop()
    assert proc.returncode == 0, err
    assert "Traceback" not in err
    assert "stopped" in err
    assert "executed ANGLE_CONTROL" in log


@pytest.mark.parametrize(("args", "status"), [
    (["udp://127.0.0.1:9"], 2),  # --mavlink is required
    (["ftp://x", "--mavlink", "udpout:127.0.0.1:9"], 2),
    (["udp://127.0.0.1:9", "--mavlink", "udpout:127.0.0.1:9", "--system-id", "0"], 2),
    (["udp://127.0.0.1:9", "--mavlink", "udpout:127.0.0.1:9", "--video-url", "ftp://x"], 2),
    (["udp://127.0.0.1:9", "--mavlink", "/dev/no-such-serial-port,57600"], 1),
])  # fmt: skip
def test_usage_errors_and_failures(args: list[str], status: int) -> None:
    done = subprocess.run([*CLI, "mavlink-bridge", *args], capture_output=True, text=True,
                          timeout=60, check=False)  # fmt: skip
    assert done.returncode == status, done.stderr
    assert "Traceback" not in done.stderr


def test_default_video_url_is_the_gcus_address() -> None:
    assert default_video_url("udp://192.168.144.108") == "rtsp://192.168.144.108:554/"
    assert default_video_url("tcp://[fe80::1]:2332") == "rtsp://[fe80::1]:554/"
    assert default_video_url("serial:///dev/ttyUSB0") is None


@pytest.mark.parametrize("connection", [
    "udpin:127.0.0.1:99999",  # port out of range
    "udpin:::1:14550",  # IPv6 without brackets
    "tcp:127.0.0.1:x",  # port not a number
    "udpout:127.0.0.1",  # no port
    "tcp::5760",  # no host
    "ftp:127.0.0.1:1",  # unknown scheme
    "udp:0.0.0.0:14550",  # pymavlink's alias: refused with the two names to use
    "udpout:127.0.0.1:0",  # nowhere to send to
    "udpin:[::1:14550",  # unclosed bracket
    "tcpin:bad_host!:5760",
    "/dev/ttyACM0,fast",
    "/dev/ttyACM0,10",  # baud out of range
    "",
])  # fmt: skip
def test_malformed_connection_is_a_one_line_usage_error(connection: str) -> None:
    # issue 17: six of these printed a traceback and exited 1. A listener on a port that is
    # taken comes first: had anything opened before the check, that would fail (status 1).
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("127.0.0.1", 0))
        busy = f"udpin:127.0.0.1:{taken.getsockname()[1]}"
        done = subprocess.run([*CLI, "mavlink-bridge", "udp://127.0.0.1:9?local_port=0",
                               "--mavlink", busy, "--mavlink", connection],
                              capture_output=True, text=True, timeout=60, check=False)
    assert done.returncode == 2, done.stderr
    lines = done.stderr.splitlines()
    assert len(lines) == 1, done.stderr
    assert lines[0].startswith(f"gcu-async mavlink-bridge: connection {connection!r}: ")


def test_accepted_connection_forms_start() -> None:
    # every documented form opens (a serial device is tried in test_usage_errors_and_failures)
    sim = SimProcess("--listen", "udp://127.0.0.1:0")
    gcs = Peer(255, 190)
    proc = subprocess.Popen(
        [*CLI, "mavlink-bridge", f"{sim.url}?local_port=0", "--mavlink", gcs.url,
         "--mavlink", "udpin:127.0.0.1:0", "--mavlink", "udpin:[::1]:0",
         "--mavlink", "tcpin:127.0.0.1:0", "--mavlink", "tcp:localhost:9"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
    try:
        wait_for(gcs, "HEARTBEAT", lambda m: m.get_srcComponent() == GIMBAL)
        assert proc.poll() is None
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=10)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
        gcs.close()
        sim.stop()
    assert proc.returncode == 0, err
    assert "Traceback" not in err


class _GoneTcpPeer:
    """A TCP peer that accepts the bridge, then goes away: ``refused`` (closed, connects
    refused) or ``black-holed`` (a listener whose backlog is full: connects hang)."""

    def __init__(self) -> None:
        import socket

        self.socket = socket
        self.listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.listener.bind(("127.0.0.1", 0))
        self.listener.listen(1)
        self.port = self.listener.getsockname()[1]
        self.others: list = []

    def accept(self, timeout: float = 10.0) -> None:
        self.listener.settimeout(timeout)
        conn, _ = self.listener.accept()
        conn.settimeout(timeout)
        assert conn.recv(4096)  # the bridge writes to it
        self.others.append(conn)

    def vanish(self, how: str) -> None:
        socket = self.socket
        for conn in self.others:
            conn.close()
        self.others.clear()
        self.listener.close()
        if how == "black-holed":
            self.listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            self.listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            self.listener.bind(("127.0.0.1", self.port))
            self.listener.listen(0)
            for _ in range(3):  # fill the backlog: the bridge's SYNs are dropped
                filler = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
                filler.setblocking(False)
                with contextlib.suppress(BlockingIOError):
                    filler.connect(("127.0.0.1", self.port))
                self.others.append(filler)

    def close(self) -> None:
        for conn in self.others:
            conn.close()
        self.listener.close()


@pytest.mark.parametrize("how", ["refused", "black-holed"])
def test_sigterm_ends_the_bridge_within_2_s_while_a_tcp_peer_is_gone(how: str) -> None:
    # issue 17: with the tcp: peer gone, SIGTERM did not end the bridge within 8 s
    sim = SimProcess("--listen", "udp://127.0.0.1:0")
    gcs = Peer(255, 190)
    peer = _GoneTcpPeer()
    proc = subprocess.Popen(
        [*CLI, "mavlink-bridge", f"{sim.url}?local_port=0", "--mavlink",
         f"tcp:127.0.0.1:{peer.port}", "--mavlink", gcs.url],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
    try:
        wait_for(gcs, "HEARTBEAT", lambda m: m.get_srcComponent() == GIMBAL
                 and m.system_status == mavlink.MAV_STATE_ACTIVE)
        peer.accept()
        peer.vanish(how)
        time.sleep(2.5)  # the bridge has noticed and is reconnecting
        # still serving: both components' heartbeats keep coming
        for component in (GIMBAL, mavlink.MAV_COMP_ID_CAMERA):
            wait_for(gcs, "HEARTBEAT", lambda m, c=component: m.get_srcComponent() == c,
                     timeout=2.0)
        assert proc.poll() is None
        sent = time.monotonic()
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=10)
        took = time.monotonic() - sent
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
        gcs.close()
        peer.close()
        sim.stop()
    assert proc.returncode == 0, err
    assert "Traceback" not in err
    print(f"\nSIGTERM with the tcp peer {how}: ended in {took:.2f} s")
    assert took < 2.0, took
