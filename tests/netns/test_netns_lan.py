"""The namespace fixture itself (``helpers.netns.lan.Lan``): it leaves nothing behind, even when
creating the LAN fails halfway, and its processes really run on separate hosts."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from helpers.netns.lan import GCU_ADDRESS, HOST_ADDRESS, Lan, ip, namespaces, unavailable

needs_netns = pytest.mark.skipif(unavailable() is not None, reason=str(unavailable()))


def test_unavailable_says_why(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sys, "platform", "darwin")
    assert unavailable() == "network namespaces are a Linux feature"
    monkeypatch.setattr(sys, "platform", "linux")
    monkeypatch.setattr(os, "geteuid", lambda: 1000)
    assert unavailable() == "creating network namespaces needs root (ip netns add)"
    monkeypatch.setattr(os, "geteuid", lambda: 0)
    monkeypatch.setenv("PATH", "")
    assert "iproute2's `ip` is missing" in str(unavailable())


def _root_links() -> str:
    return ip("-o", "link", "show").stdout


@needs_netns
def test_close_kills_processes_and_removes_namespaces_and_links() -> None:
    lan = Lan()
    try:
        lan.create()
    except OSError as exc:
        pytest.skip(f"cannot create network namespaces here: {exc}")
    try:
        assert {lan.gcu, lan.host} <= namespaces()
        assert all(link not in _root_links() for link in lan.links)  # never in ours
        a = lan.run(lan.gcu, "ip", "-o", "-4", "addr", "show").stdout
        b = lan.run(lan.host, "ip", "-o", "-4", "addr", "show").stdout
        assert f"{GCU_ADDRESS}/24 brd 10.213.0.255" in a and f"{HOST_ADDRESS}/" not in a
        assert f"{HOST_ADDRESS}/24 brd 10.213.0.255" in b and f"{GCU_ADDRESS}/" not in b
        sleeper = lan.start(lan.host, "sleep", "60")
    finally:
        lan.close()
    assert sleeper.returncode is not None  # killed, not left running
    assert not {lan.gcu, lan.host} & namespaces()
    assert all(link not in _root_links() for link in lan.links)
    lan.close()  # idempotent


@needs_netns
def test_a_failed_create_removes_what_it_made() -> None:
    lan = Lan()
    lan.links = ("x" * 20, "y" * 20)  # too long for an interface name: `ip link add` fails
    with pytest.raises((OSError, subprocess.TimeoutExpired), match="ip link add"):
        lan.create()
    assert not {lan.gcu, lan.host} & namespaces()


def test_names_are_unique_per_lan() -> None:
    first, second = Lan(), Lan()
    assert {first.gcu, first.host}.isdisjoint({second.gcu, second.host})
    assert set(first.links).isdisjoint(second.links)
    assert all(len(link) <= 15 for link in first.links)
