"""``gcu-async monitor --passive`` in the real UDP topology, across two hosts (network
namespaces, see ``helpers.netns.lan``): the simulator on host A replies like a real GCU, to
10.213.0.255:2338; on host B an application and the passive monitor share port 2338, each
with the transport's defaults (``udp://10.213.0.1``). The monitor finds the broadcast
address itself (host B's interface 10.213.0.2/24), shows the application's session, and
the simulator received exactly what the application sent."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import pytest

from helpers.client.app_client import app_argv
from helpers.netns.lan import BROADCAST, CLI, GCU_ADDRESS, Lan, lan_fixture, line, stop

GCU_URL = f"udp://{GCU_ADDRESS}"  # port 2337, listen on 2338: the defaults


@pytest.fixture
def lan() -> Iterator[Lan]:
    yield from lan_fixture()


def test_the_passive_monitor_hears_another_process_session_and_sends_nothing(
    lan: Lan, tmp_path: Path
) -> None:
    report = tmp_path / "sim.json"
    sim, first = lan.sim("--listen", f"udp://{GCU_ADDRESS}:2337", "--reply-to", "broadcast",
                         "-q", "--report-json", str(report))  # fmt: skip
    assert f"(replies to {BROADCAST}:2338)" in first
    monitor = lan.start(lan.host, *CLI, "monitor", "--passive", GCU_URL, "--json",
                        "--interval", "0.2")  # fmt: skip
    lines = [json.loads(line(monitor, 10.0, "the monitor"))]  # bound: no reply heard yet
    assert lines[0]["status"] is None and lines[0]["link"]["up"] is False
    done = lan.run(lan.host, *app_argv(GCU_URL, yaw=20.0), timeout=60)
    assert done.returncode == 0, done.stderr
    app = json.loads(done.stdout)
    assert app["lost"] == 0
    for _ in range(50):  # until a line of silence after the application: all replies heard
        lines.append(json.loads(line(monitor, 5.0, "the monitor")))
        if lines[-1]["status"] is None and any(x["status"] for x in lines):
            break
    out, err = stop(monitor)
    assert monitor.returncode == 130, err
    assert (f"passive: hearing what {GCU_URL}:2337 broadcasts to {BROADCAST}:2338; sending "
            "nothing") in err  # fmt: skip
    lines += [json.loads(text) for text in out.splitlines()]
    heard = [x for x in lines if x["status"] is not None]
    assert heard, lines
    last = heard[-1]["status"]
    assert last["mode"] == "EULER_CONTROL"  # set by the other process
    assert last["attitude_deg"]["pitch"] == pytest.approx(-30.0, abs=0.5)
    assert last["attitude_deg"]["yaw"] == pytest.approx(20.0, abs=0.5)
    assert all(x["link"]["packets_sent"] == 0 for x in lines)
    assert lines[-1]["link"]["packets_received"] == app["sent"]  # every broadcast reply
    stop(sim)
    assert json.loads(report.read_text(encoding="utf-8"))["conformance"]["packets"] == app["sent"]
