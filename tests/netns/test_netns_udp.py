"""The real UDP topology, across two hosts (network namespaces, see ``helpers.netns.lan``).

The simulator runs on host A like a real GCU: it receives on 10.213.0.1:2337 and replies
from port 2337 to the subnet's broadcast address, 10.213.0.255, port 2338. The client runs
on host B and listens on 2338 (the transport's defaults: ``udp://10.213.0.1``). Everything
runs as separate processes inside the namespaces: ``gcu-async sim`` on A, ``gcu-async
send`` / ``monitor`` and a passive listener on B.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Iterator
from typing import Any

import pytest

from gcu_async.protocol import ExecutionStatus, Opcode, decode_gcu_packet
from gcu_async.sim.udp import interface_broadcast
from helpers.netns.lan import (
    BROADCAST,
    CLI,
    GCU_ADDRESS,
    HOST_ADDRESS,
    Lan,
    datagrams,
    lan_fixture,
    line,
    stop,
)

GCU_URL = f"udp://{GCU_ADDRESS}"  # port 2337, listen on 2338: the defaults


@pytest.fixture
def lan() -> Iterator[Lan]:
    yield from lan_fixture()


def _real_gcu(lan: Lan) -> Any:
    sim, line = lan.sim("--listen", f"udp://{GCU_ADDRESS}:2337", "--reply-to", "broadcast")
    assert f"listening on udp://{GCU_ADDRESS}:2337 (replies to {BROADCAST}:2338)" in line
    return sim


def test_replies_leave_port_2337_for_the_subnet_broadcast_address_port_2338(lan: Lan) -> None:
    sim = _real_gcu(lan)
    listener = lan.sniffer(2338)  # a third party on host B: it never sends anything
    done = lan.cli(lan.host, "send", GCU_URL, "take-photo", "--timeout", "5")
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    assert result["ok"] and result["command"] == "TAKE_PHOTO", result
    seen = datagrams(stop(listener)[0])
    # The replies to the client's packets reached the silent listener too, photo feedback
    # included: all of them from 10.213.0.1:2337 to 10.213.0.255.
    assert {(tuple(d["source"]), d["destination"]) for d in seen} == {
        ((GCU_ADDRESS, 2337), BROADCAST)
    }
    feedback = [decode_gcu_packet(bytes.fromhex(d["data"])).feedback for d in seen]
    # The command repeats in every packet until its feedback arrives, and the GCU answers
    # each repeat: a loaded host sees the feedback more than once, the photo taken once.
    photo = [f for f in feedback if f.opcode == Opcode.TAKE_PHOTO]
    assert photo and all(f.result is ExecutionStatus.SUCCESS for f in photo), feedback
    log = stop(sim)[1]
    assert log.count("executed TAKE_PHOTO") == 1, log


def test_app_and_monitor_on_port_2338_at_once(lan: Lan) -> None:
    """Two client processes on host B, both bound to 2338: the monitor keeps showing
    telemetry while ``send`` moves the gimbal, and each sees the other's replies."""
    sim = _real_gcu(lan)
    monitor = lan.start(lan.host, *CLI, "monitor", GCU_URL, "--json", "--interval", "0.25")
    lines = [json.loads(line(monitor, 10.0, "monitor"))]
    assert lines[0]["link"]["up"] and lines[0]["status"] is not None
    done = lan.cli(lan.host, "send", GCU_URL, "enter-euler-control", "0", "-30", "20",
                   "--timeout", "5")
    assert done.returncode == 0, (done.stdout, done.stderr)
    result = json.loads(done.stdout)
    assert result["ok"] and result["command"] == "EULER_CONTROL", result
    assert result["attitude_deg"]["pitch"] == pytest.approx(-30.0, abs=0.5)
    assert result["attitude_deg"]["yaw"] == pytest.approx(20.0, abs=0.5)
    # The monitor shows the new pose within 40 of its lines (10 s). Its lines can run behind
    # the GCU on a loaded host (each shows what it had received when printed): not the next
    # line, but one soon.
    def moved(x: dict[str, Any]) -> bool:
        pose = x["status"]["attitude_deg"]
        return bool(pose["pitch"] == pytest.approx(-30.0, abs=0.5)
                    and pose["yaw"] == pytest.approx(20.0, abs=0.5))  # fmt: skip

    for _ in range(40):
        lines.append(json.loads(line(monitor, 5.0, "monitor")))
        if moved(lines[-1]):
            break
    shown = lines[-1]
    out, err = stop(monitor)
    assert monitor.returncode == 130, err  # SIGTERM: interrupted
    lines += [json.loads(text) for text in out.splitlines()]
    assert all(x["status"] is not None and x["link"]["up"] for x in lines), lines
    assert moved(shown), [x["status"]["attitude_deg"] for x in lines]
    assert shown["status"]["mode"] == "EULER_CONTROL"  # set by the other process
    last = lines[-1]
    # The monitor received the replies to send's packets too: more replies than it sent
    # packets, and the feedback to send's EULER_CONTROL, which it matched to nothing.
    link = last["link"]
    assert link["packets_received"] > link["packets_sent"] + 2, link
    assert link["unmatched_feedback"] >= 1, link
    assert link["lost_count"] == 0
    log = stop(sim)[1]
    assert log.count("executed EULER_CONTROL") == 1, log


def test_an_exclusive_client_cannot_share_the_port(lan: Lan) -> None:
    """Control: with ``reuse_port=0`` the client binds 2338 exclusively, so it cannot start
    beside another listener — the sharing above is the transport's doing."""
    _real_gcu(lan)
    listener = lan.sniffer(2338)
    done = lan.cli(lan.host, "send", f"{GCU_URL}?reuse_port=0", "take-photo", "--timeout", "2")
    assert done.returncode == 1, (done.stdout, done.stderr)
    assert "cannot bind 0.0.0.0:2338" in done.stdout, done.stdout
    assert datagrams(stop(listener)[0]) == []  # nothing was sent, nothing answered


def test_reply_to_broadcast_takes_a_port_and_needs_an_interface_address(lan: Lan) -> None:
    sim, line = lan.sim("--listen", f"udp://{GCU_ADDRESS}:2337", "--reply-to", "broadcast:2339")
    assert f"(replies to {BROADCAST}:2339)" in line
    stop(sim)
    done = lan.cli(lan.gcu, "sim", "--listen", "udp://0.0.0.0:2337", "--reply-to", "broadcast")
    assert done.returncode == 2
    assert "--reply-to broadcast: 0.0.0.0" in done.stderr
    done = lan.cli(lan.gcu, "sim", "--listen", f"udp://{HOST_ADDRESS}:2337",
                   "--reply-to", "broadcast")  # fmt: skip
    assert done.returncode == 2
    assert f"--reply-to broadcast: {HOST_ADDRESS} is not the (primary) address" in done.stderr
    done = lan.cli(lan.gcu, "sim", "--listen", f"udp://{GCU_ADDRESS}:2337",
                   "--reply-to", "broadcast:0")  # fmt: skip
    assert done.returncode == 2
    assert "port must be a number in 1-65535" in done.stderr


def test_interface_broadcast_names_what_it_cannot_find(monkeypatch: pytest.MonkeyPatch) -> None:
    with pytest.raises(ValueError, match="'::1' is not an IPv4 address"):
        interface_broadcast("::1")
    with pytest.raises(ValueError, match=r"0\.0\.0\.0 is no one interface's address"):
        interface_broadcast("0.0.0.0")
    if sys.platform.startswith("linux"):
        with pytest.raises(ValueError, match=r"127\.0\.0\.1: interface lo has no broadcast"):
            interface_broadcast("127.0.0.1")
        with pytest.raises(ValueError, match=r"192\.0\.2\.1 is not the \(primary\) address of any"):
            interface_broadcast("192.0.2.1")  # TEST-NET-1: nobody's
    monkeypatch.setattr(sys, "platform", "darwin")
    with pytest.raises(ValueError, match=r"broadcast address of 10\.0\.0\.1 needs Linux: give it"):
        interface_broadcast("10.0.0.1")


def test_a_gcu_host_with_nothing_on_2337_is_reported_by_its_icmp_error(lan: Lan) -> None:
    """Host A is up but nothing listens on 2337: its kernel answers every datagram with ICMP
    port unreachable, and the client on host B says so (a warning naming host A), instead
    of only timing out (docs/transports.md, "UDP errors and reopening")."""
    if not sys.platform.startswith("linux"):
        pytest.skip("ICMP errors on an unconnected socket are read on Linux only")
    done = lan.cli(lan.host, "send", GCU_URL, "take-photo", "--timeout", "1")
    assert done.returncode == 1, (done.stdout, done.stderr)
    assert json.loads(done.stdout)["ok"] is False
    expected = f"ICMP port unreachable from {GCU_ADDRESS} for a datagram to {GCU_ADDRESS}:2337"
    assert expected in done.stderr, done.stderr
    assert done.stderr.count("ICMP port unreachable") == 1, done.stderr  # one per episode
