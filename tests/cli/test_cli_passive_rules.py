"""``gcu-async monitor --passive`` without sockets: which URLs it refuses and why (through
the entry point, in-process), the broadcast address it binds, and :class:`PassiveLink`, the
sans-I/O part, on a virtual clock (Hypothesis picks the arrival times: every silence longer
than the timeout is one outage, every reply after one a restoration)."""

from __future__ import annotations

import inspect
import ipaddress
import socket
import sys

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gcu_async import GcuClient
from gcu_async.cli import main
from gcu_async.cli.passive import (
    PassiveLink,
    interface_networks,
    passive_refusal,
    subnet_broadcast,
)
from gcu_async.conformance import GcuConformance
from gcu_async.protocol import GcuSubFrame, TakePhoto, decode_gcu_packet
from gcu_async.sim import ManualClock, SimulatorModel
from helpers.scale import scaled
from helpers.sim.support import host_bytes

LINUX = sys.platform.startswith("linux")
TEST_NETS = ("192.0.2.1", "198.51.100.1", "203.0.113.1")
"""RFC 5737's documentation addresses."""


def reply(command: object = None) -> bytes:
    """One GCU reply, as the simulator encodes it (with a sub frame)."""
    model = SimulatorModel(clock=ManualClock())
    [data] = model.receive(host_bytes(command))  # type: ignore[arg-type]
    return data


REPLY = reply()


# -- what --passive refuses, and why -------------------------------------------------------
REFUSED = [
    ("tcp://127.0.0.1", "--passive: tcp: over TCP the GCU answers only the packets of the "
     "connection they came on"),
    ("serial:///dev/ttyUSB0", "--passive: serial: a serial port has one reader"),
    ("udp://127.0.0.1?local_port=0", "--passive: local_port=0: the GCU's replies go to a fixed "
     "port"),
    ("udp://127.0.0.1?reuse_port=0", "--passive: reuse_port=0 would bind the reply port alone"),
    ("udp://[::1]", "--passive: IPv6 has no broadcast"),
    ("udp://127.0.0.1?local_host=0.0.0.0", "--passive: local_host=0.0.0.0 is the wildcard "
     "address"),
]  # fmt: skip


@pytest.mark.parametrize(("url", "message"), REFUSED)
def test_a_link_it_cannot_watch_is_a_usage_error_saying_why(
    url: str, message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["monitor", "--passive", url]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1, err
    assert err.startswith(f"gcu-async monitor: {message}"), err


def test_tcp_and_serial_refusals_say_what_to_do_instead() -> None:
    for url in ("tcp://127.0.0.1", "serial:///dev/ttyUSB0"):
        why = passive_refusal(url)
        assert why is not None and "watch over UDP" in why and "capture=FILE" in why


def test_a_bad_url_is_reported_as_the_active_monitor_reports_it(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["monitor", "--passive", "udp://127.0.0.1?nonsense=1"]) == 2
    assert main(["monitor", "udp://127.0.0.1?nonsense=1"]) == 2
    passive, active = capsys.readouterr().err.splitlines()
    assert passive == active
    assert "option: 'nonsense' is not a udp URL option" in passive


def test_timeout_is_for_the_active_monitor_only(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["monitor", "--passive", "udp://127.0.0.1", "--timeout", "1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("gcu-async monitor: --timeout: not with --passive"), err


@pytest.mark.skipif(not hasattr(socket, "SO_REUSEPORT"), reason="no SO_REUSEPORT here")
@pytest.mark.parametrize("url", ["udp://127.0.0.1", "udp://192.168.144.108?local_port=2339",
                                 "udp://gcu.example?local_host=192.168.144.255"])  # fmt: skip
def test_a_udp_url_on_a_shared_fixed_port_is_accepted(url: str) -> None:
    assert passive_refusal(url) is None


def test_without_so_reuseport_it_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delattr(socket, "SO_REUSEPORT", raising=False)  # e.g. Windows
    why = passive_refusal("udp://127.0.0.1?reuse_port=none")
    assert why is not None and "no SO_REUSEPORT" in why


# -- the address it binds --------------------------------------------------------------------
@pytest.mark.skipif(not LINUX, reason="the interfaces' subnets are read with Linux ioctls")
def test_the_broadcast_address_of_the_subnet_holding_the_gcu() -> None:
    assert subnet_broadcast("127.0.0.1") == "127.255.255.255"
    assert subnet_broadcast("127.4.5.6") == "127.255.255.255"  # all of 127/8 is lo's
    networks = interface_networks()
    for network in networks:  # every other subnet of this host: its own broadcast address
        if network.prefixlen < 31:
            assert subnet_broadcast(str(network[1])) == str(network.broadcast_address)
    # a documentation address on none of them (this host may use one of the three)
    nobody = next(str(ip) for ip in map(ipaddress.IPv4Address, TEST_NETS)
                  if not any(ip in n for n in networks))  # fmt: skip
    with pytest.raises(ValueError, match=rf"{nobody} is on none of this host's subnets"):
        subnet_broadcast(nobody)


def test_elsewhere_the_broadcast_address_must_be_given(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sys, "platform", "darwin")
    with pytest.raises(ValueError, match=r"needs Linux: give it, udp://HOST\?local_host="):
        subnet_broadcast("127.0.0.1")


def test_the_silence_timeout_is_the_clients_default() -> None:
    default = inspect.signature(GcuClient).parameters["silence_timeout"].default
    assert PassiveLink().silence_timeout == default


# -- PassiveLink, sans-I/O --------------------------------------------------------------------
def test_replies_become_samples_and_health_and_nothing_is_sent() -> None:
    link = PassiveLink(silence_timeout=1.0)
    assert link.health(0.0).up is False and link.health(0.0).last_reply_age is None
    samples = link.receive(REPLY, 10.0)
    assert len(samples) == 1
    sample = samples[0]
    assert sample.status == decode_gcu_packet(REPLY).main and sample.received_at == 10.0
    assert isinstance(sample.info, GcuSubFrame)
    health = link.health(10.5)
    assert health.up and health.packets_received == 1 and health.last_reply_age == 0.5
    assert (health.packets_sent, health.send_errors, health.unmatched_feedback) == (0, 0, 0)


def test_a_reply_without_a_sub_frame_keeps_the_latest() -> None:
    link = PassiveLink()
    first = link.receive(REPLY, 0.0)[0].info
    packet = decode_gcu_packet(REPLY)
    bare = packet._replace(sub=None).encode()
    assert decode_gcu_packet(bare).sub is None
    assert link.receive(bare, 0.02)[0].info == first


def test_damaged_bytes_are_counted_and_leftovers_never_join_the_next_datagram() -> None:
    link = PassiveLink()
    bad = bytearray(REPLY)
    bad[10] ^= 0xFF
    assert link.receive(bytes(bad), 0.0) == []
    assert link.receive(REPLY[:40], 0.01) == []  # half a reply: settled with its datagram
    assert len(link.receive(REPLY[40:] + REPLY, 0.02)) == 1
    health = link.health(0.02)
    assert health.crc_errors == 1 and health.bytes_discarded >= 40 + 33
    assert health.packets_received == 1


def test_other_versions_are_counted() -> None:
    packet = decode_gcu_packet(REPLY)
    link = PassiveLink()
    link.receive(packet._replace(version=7).encode(), 0.0)
    assert link.health(0.0).other_versions == 1


def test_it_feeds_the_gcu_conformance_report() -> None:
    conformance = GcuConformance()
    link = PassiveLink(conformance=conformance)
    for i in range(5):
        link.receive(reply(TakePhoto() if i == 2 else None), i * 0.02)
    assert conformance.report().replies == 5


@settings(max_examples=scaled(200, 25), deadline=None)
@given(st.lists(st.floats(0.001, 3.0), min_size=1, max_size=40), st.floats(0.05, 2.0))
def test_every_silence_longer_than_the_timeout_is_one_outage(gaps: list[float],
                                                             timeout: float) -> None:
    """However often health is read (here: before each reply and in every gap), each
    silence longer than the timeout counts once as lost, and the reply that ends it once as
    restored; the link is up exactly while the last reply is at most ``timeout`` old."""
    link = PassiveLink(silence_timeout=timeout)
    now = 0.0
    link.receive(REPLY, now)
    outages = 0
    for gap in gaps:
        link.health(now + gap / 2)  # reads in between change nothing
        link.health(now + gap / 2)
        before, now = now, now + gap
        silence = now - before  # the gap as the clock has it (floats round)
        outages += silence > timeout
        assert link.health(now).up is (silence <= timeout)
        link.receive(REPLY, now)
        assert link.health(now).up
    health = link.health(now)
    assert (health.lost_count, health.restored_count) == (outages, outages)
    assert health.packets_received == len(gaps) + 1
    later = link.health(now + timeout + 0.001)
    assert not later.up and later.lost_count == outages + 1
