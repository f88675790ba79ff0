"""``gcu-async mavlink-bridge`` through the real entry point: it bridges, and Ctrl-C (SIGINT)
or SIGTERM ends it with exit status 0 (docs/mavlink-bridge.md, "Command line")."""

from __future__ import annotations

import signal
import subprocess
import time

import pytest

from _bridge_rig import GIMBAL, Peer
from _sim_process import CLI, SimProcess
from gcu_async.bridge._mavlink import mavlink
from gcu_async.cli.mavlink_bridge import default_video_url


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
