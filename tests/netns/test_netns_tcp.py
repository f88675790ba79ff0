"""TCP across two hosts (network namespaces, see ``helpers.netns.lan``): the simulator is the TCP
server on host A (10.213.0.1:2332), ``gcu-async send`` and ``monitor`` connect from host B.
"""

from __future__ import annotations

import json
from collections.abc import Iterator

import pytest

from helpers.netns.lan import GCU_ADDRESS, HOST_ADDRESS, Lan, lan_fixture, stop

GCU_URL = f"tcp://{GCU_ADDRESS}"  # port 2332


@pytest.fixture
def lan() -> Iterator[Lan]:
    yield from lan_fixture()


def test_commands_and_telemetry_over_tcp_across_hosts(lan: Lan) -> None:
    sim, line = lan.sim("--listen", f"tcp://{GCU_ADDRESS}:2332")
    assert f"listening on tcp://{GCU_ADDRESS}:2332" in line
    done = lan.cli(lan.host, "send", GCU_URL, "enter-euler-control", "0", "-45", "-60",
                   "--timeout", "5")
    assert done.returncode == 0, (done.stdout, done.stderr)
    result = json.loads(done.stdout)
    assert result["ok"] and result["command"] == "EULER_CONTROL", result
    assert result["attitude_deg"]["pitch"] == pytest.approx(-45.0, abs=0.5)
    done = lan.cli(lan.host, "monitor", GCU_URL, "--json", "--interval", "0.1", "--count", "5")
    assert done.returncode == 0, done.stderr
    lines = [json.loads(text) for text in done.stdout.splitlines()]
    assert len(lines) == 5 and all(x["link"]["up"] and x["status"] for x in lines), lines
    attitude = lines[-1]["status"]["attitude_deg"]
    assert attitude["pitch"] == pytest.approx(-45.0, abs=0.5)
    assert attitude["yaw"] == pytest.approx(300.0, abs=0.5)  # -60 as 0-360
    log = stop(sim)[1]
    # Both connections came from host B's address.
    assert log.count(f"TCP client ('{HOST_ADDRESS}',") == 4, log  # connected + left, twice
    assert log.count("executed EULER_CONTROL") == 1, log


def test_no_tcp_server_on_host_b(lan: Lan) -> None:
    """Control: the same command to host B's own address is refused (exit 1)."""
    lan.sim("--listen", f"tcp://{GCU_ADDRESS}:2332")
    done = lan.cli(lan.host, "send", f"tcp://{HOST_ADDRESS}", "take-photo", "--timeout", "1")
    assert done.returncode == 1, (done.stdout, done.stderr)
    assert json.loads(done.stdout)["ok"] is False
