"""``gcu-async monitor --passive`` through the real entry point, beside an application on the
same machine: ``gcu-async sim`` answers to the loopback broadcast address like a real GCU
answers to its subnet's (``--reply-to broadcast``), the application (a client process)
binds the reply port, and the monitor shares that port.

The proof that it sends nothing is the simulator's own count: it received exactly the
packets the application sent. The same rig with the active monitor shows the count tells
(the simulator then received more), and that monitor's heartbeat is what changes the pod's
behaviour beside an application. With a simulator that answers by unicast the passive
monitor hears nothing, and the application loses nothing: bound to the broadcast address,
the monitor is never handed a reply meant for the application (a wildcard socket sharing
the port could be: tests/netns/test_netns_shared_port.py)."""

from __future__ import annotations

import json
import selectors
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from helpers.client.app_client import app_argv
from helpers.sim.process import CLI, SimProcess

pytestmark = [
    pytest.mark.skipif(not sys.platform.startswith("linux"),
                       reason="broadcast on the loopback interface is Linux's"),
    pytest.mark.skipif(not hasattr(socket, "SO_REUSEPORT"), reason="no SO_REUSEPORT here"),
]  # fmt: skip

def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("0.0.0.0", 0))
        return int(s.getsockname()[1])


def read_line(proc: subprocess.Popen[str], timeout: float) -> str:
    assert proc.stdout is not None
    with selectors.DefaultSelector() as sel:
        sel.register(proc.stdout, selectors.EVENT_READ)
        if not sel.select(timeout):
            raise AssertionError("no line in time")
    line = proc.stdout.readline()
    assert line, "the monitor ended"
    return line.rstrip("\n")


def run_app(url: str) -> dict[str, Any]:
    done = subprocess.run(app_argv(url), capture_output=True, text=True, timeout=60,
                          check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr
    result: dict[str, Any] = json.loads(done.stdout)
    return result


def stop(proc: subprocess.Popen[str]) -> tuple[str, str]:
    """SIGTERM; the monitor ends with 130 and no traceback."""
    proc.send_signal(signal.SIGTERM)
    try:
        out, err = proc.communicate(timeout=15)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 130, err
    assert "Traceback" not in err, err
    return out, err


class Rig:
    """The simulator (broadcasting to the reply port, or answering by unicast) and the port
    the application and the monitor share."""

    def __init__(self, tmp: Path, *, broadcast: bool = True) -> None:
        self.port = free_port()
        self.report = tmp / "sim.json"
        reply = ["--reply-to", f"broadcast:{self.port}"] if broadcast else []
        self.sim = SimProcess("--listen", "udp://127.0.0.1:0", *reply,
                              "--report-json", str(self.report))  # fmt: skip
        self.url = f"{self.sim.url}?local_port={self.port}"

    def monitor(self, *args: str) -> subprocess.Popen[str]:
        argv = [*CLI, "monitor", self.url, "--interval", "0.1", *args]
        proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        read_line(proc, 15.0)  # it is up (bound, or connected) before the application starts
        return proc

    def received(self) -> int:
        """Host packets the simulator received (it has stopped)."""
        self.sim.stop()
        document = json.loads(self.report.read_text(encoding="utf-8"))
        packets: int = document["conformance"]["packets"]
        return packets


@pytest.fixture
def rig(tmp_path: Path) -> Iterator[Rig]:
    made = Rig(tmp_path)
    yield made
    made.sim.kill()


def test_the_passive_monitor_shows_the_apps_session_and_sends_nothing(rig: Rig) -> None:
    monitor = rig.monitor("--passive", "--json")
    try:
        app = run_app(rig.url)
        deadline = time.monotonic() + 15
        lines = []
        while time.monotonic() < deadline:  # until the silence after the application
            lines.append(json.loads(read_line(monitor, 5.0)))
            if lines[-1]["status"] is None and any(x["status"] for x in lines):
                break
    finally:
        out, err = stop(monitor)
    lines += [json.loads(text) for text in out.splitlines()]
    assert err.startswith("gcu-async monitor: passive: hearing what udp://127.0.0.1:"), err
    assert f"broadcasts to 127.255.255.255:{rig.port}; sending nothing" in err
    heard = [x for x in lines if x["status"] is not None]
    assert heard, lines
    assert all(x["link"]["packets_sent"] == 0 for x in lines)
    last = heard[-1]["status"]
    assert last["mode"] == "EULER_CONTROL"  # the application's command
    assert last["attitude_deg"]["pitch"] == pytest.approx(-30.0, abs=0.5)
    assert last["attitude_deg"]["yaw"] == pytest.approx(45.0, abs=0.5)
    assert app["lost"] == 0 and app["received"] >= app["sent"] - 5
    # what the simulator received came from the application alone: the monitor sent nothing
    assert rig.received() == app["sent"]
    # and it heard every reply (one per packet, all broadcast)
    assert lines[-1]["link"]["packets_received"] == app["sent"]


def test_the_active_monitor_beside_the_app_sends_its_own_heartbeat(rig: Rig) -> None:
    """The control: the same count with the active monitor shows its packets."""
    monitor = rig.monitor("--json")
    try:
        app = run_app(rig.url)
    finally:
        out, _ = stop(monitor)
    line = json.loads(out.splitlines()[-1])  # printed after the application ended
    assert line["link"]["packets_sent"] > 50  # 50 Hz while the application ran (~2 s)
    assert rig.received() > app["sent"] + 50


def test_a_gcu_answering_by_unicast_is_not_heard_and_the_app_loses_nothing(
    tmp_path: Path,
) -> None:
    rig = Rig(tmp_path, broadcast=False)  # replies go to the sender: the application
    try:
        monitor = rig.monitor("--passive")
        try:
            app = run_app(rig.url)
        finally:
            out, _ = stop(monitor)
        assert app["lost"] == 0 and app["received"] >= app["sent"] - 5  # every reply its own
        lines = out.splitlines()
        assert lines and all(
            line.startswith("link DOWN: no broadcast reply heard yet") for line in lines
        ), lines
        assert "--reply-to broadcast" in lines[0], lines[0]  # says what to check
        assert rig.received() == app["sent"]
    finally:
        rig.sim.kill()
