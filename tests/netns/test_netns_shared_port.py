"""Sharing the host port 2338 between processes (the app and ``gcu-async monitor``).

First what Linux itself does, measured across two hosts (network namespaces, ``helpers.netns.lan``):
with SO_REUSEADDR or SO_REUSEPORT on every socket bound to 0.0.0.0:2338, a datagram to the
subnet's broadcast address reaches every socket, a unicast datagram exactly one; without
either option the second bind fails. Then what the transport does: SO_REUSEPORT on a fixed
local port (same user only, unlike SO_REUSEADDR), none on an ephemeral one, and two clients
on one port both served by a simulator that broadcasts (loopback, no root needed).
"""

from __future__ import annotations

import asyncio
import socket
import sys
from collections import Counter
from collections.abc import Iterator

import pytest

from gcu_async import GcuClient
from gcu_async.errors import LinkLost
from gcu_async.protocol import Opcode
from gcu_async.sim import GcuSimulator
from gcu_async.transport import UdpTransport, open_transport
from helpers.netns.lan import (
    BROADCAST,
    GCU_ADDRESS,
    HOST_ADDRESS,
    SNIFFER,
    Lan,
    collect,
    lan_fixture,
)

LINUX = sys.platform.startswith("linux")
N = 20  # datagrams of each kind

# Host A, like a GCU: from port 2337, N datagrams to the broadcast address and N unicast to
# host B, both to port 2338.
SEND = f"""
import socket
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.setsockopt(socket.SOL_SOCKET, socket.SO_BROADCAST, 1)
s.bind(("{GCU_ADDRESS}", 2337))
for i in range({N}):
    s.sendto(b"broadcast", ("{BROADCAST}", 2338))
    s.sendto(b"unicast", ("{HOST_ADDRESS}", 2338))
"""


@pytest.fixture
def lan() -> Iterator[Lan]:
    yield from lan_fixture()


@pytest.mark.parametrize("option", ["reuseaddr", "reuseport"])
def test_linux_delivers_broadcast_to_every_socket_and_unicast_to_one(
    lan: Lan, option: str
) -> None:
    sockets = 3
    listener = lan.sniffer(2338, option, sockets)
    sent = lan.run(lan.gcu, sys.executable, "-c", SEND, timeout=10)
    assert sent.returncode == 0, sent.stderr
    seen = collect(listener, sockets * N + N)
    got = Counter((d["socket"], bytes.fromhex(d["data"]).decode()) for d in seen)
    assert all(got[(i, "broadcast")] == N for i in range(sockets)), got
    unicast = {i: got[(i, "unicast")] for i in range(sockets)}
    assert sorted(unicast.values()) == [0] * (sockets - 1) + [N], got  # all to one socket
    if option == "reuseaddr":
        assert unicast[sockets - 1] == N, got  # the socket bound last takes them
    assert len(seen) == sockets * N + N


def test_linux_refuses_a_second_socket_without_either_option(lan: Lan) -> None:
    listener = lan.sniffer(2338, "reuseport", 1)
    script = (
        "import socket\n"
        "s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)\n"
        "s.bind(('0.0.0.0', 2338))\n"
    )
    done = lan.run(lan.host, sys.executable, "-c", script, timeout=10)
    assert done.returncode != 0 and "Address already in use" in done.stderr
    # ... and an SO_REUSEADDR socket cannot join SO_REUSEPORT ones either.
    done = lan.run(lan.host, *SNIFFER, "2338", "reuseaddr", "1", timeout=10)
    assert done.returncode != 0 and "Address already in use" in done.stderr
    collect(listener, 0)


# A socket of this user on 2338, then one of another user (nobody, 65534) tries to join.
OTHER_USER = """
import os, socket, sys
option = getattr(socket, sys.argv[1])
mine = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
mine.setsockopt(socket.SOL_SOCKET, option, 1)
mine.bind(("0.0.0.0", 2338))
pid = os.fork()
if pid == 0:
    os.setgid(65534)
    os.setuid(65534)
    theirs = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    theirs.setsockopt(socket.SOL_SOCKET, option, 1)
    try:
        theirs.bind(("0.0.0.0", 2338))
        print("joined", flush=True)
    except OSError as exc:
        print("refused", exc.errno, flush=True)
    os._exit(0)
os.waitpid(pid, 0)
"""


@pytest.mark.parametrize(("option", "outcome"), [("SO_REUSEPORT", "refused 98"),
                                                 ("SO_REUSEADDR", "joined")])  # fmt: skip
def test_only_so_reuseport_keeps_other_users_off_the_port(
    lan: Lan, option: str, outcome: str
) -> None:
    """Why the transport uses SO_REUSEPORT: with SO_REUSEADDR another user's process can
    bind 2338 too and, bound last, takes the unicast datagrams."""
    done = lan.run(lan.host, sys.executable, "-c", OTHER_USER, option, timeout=10)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == outcome


# -- the transport ------------------------------------------------------------------------


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("0.0.0.0", 0))
        return int(s.getsockname()[1])


def _reuseport(t: UdpTransport) -> int:
    sock = t.get_extra_info("socket")
    return int(sock.getsockopt(socket.SOL_SOCKET, socket.SO_REUSEPORT))


@pytest.mark.skipif(not hasattr(socket, "SO_REUSEPORT"), reason="no SO_REUSEPORT here")
async def test_a_fixed_port_is_shared_an_ephemeral_one_is_not() -> None:
    port = _free_port()
    first = UdpTransport("127.0.0.1", 9, local_port=port)
    second = UdpTransport("127.0.0.1", 9, local_port=port)
    ephemeral = UdpTransport("127.0.0.1", 9, local_port=0)
    assert first.reuse_port and second.reuse_port and not ephemeral.reuse_port
    try:
        await first.open()
        await second.open()  # the same port
        await ephemeral.open()
        assert first.local_address == second.local_address == ("0.0.0.0", port)
        assert (_reuseport(first), _reuseport(second), _reuseport(ephemeral)) == (1, 1, 0)
    finally:
        for t in (first, second, ephemeral):
            await t.close()


@pytest.mark.skipif(not hasattr(socket, "SO_REUSEPORT"), reason="no SO_REUSEPORT here")
async def test_reuse_port_false_binds_exclusively() -> None:
    port = _free_port()
    shared = UdpTransport("127.0.0.1", 9, local_port=port)
    exclusive = UdpTransport("127.0.0.1", 9, local_port=port, reuse_port=False)
    await shared.open()
    try:
        with pytest.raises(LinkLost, match=f"cannot bind 0.0.0.0:{port}"):
            await exclusive.open()
    finally:
        await shared.close()
    await exclusive.open()  # alone it binds; and then nobody can join it
    try:
        assert _reuseport(exclusive) == 0
        with pytest.raises(LinkLost, match=f"cannot bind 0.0.0.0:{port}"):
            await UdpTransport("127.0.0.1", 9, local_port=port).open()
    finally:
        await exclusive.close()


def test_reuse_port_option_is_checked() -> None:
    with pytest.raises(ValueError, match="reuse_port: 'yes' is not True, False or None"):
        UdpTransport("127.0.0.1", reuse_port="yes")  # type: ignore[arg-type]
    t = open_transport("udp://127.0.0.1?reuse_port=0")
    assert isinstance(t, UdpTransport) and t.reuse_port is False
    t = open_transport("udp://127.0.0.1", reuse_port=None)
    assert isinstance(t, UdpTransport) and t.reuse_port is hasattr(socket, "SO_REUSEPORT")
    with pytest.raises(ValueError, match="reuse_port: 'maybe' is not a boolean"):
        open_transport("udp://127.0.0.1?reuse_port=maybe")


def test_without_so_reuseport_the_default_is_exclusive(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delattr(socket, "SO_REUSEPORT", raising=False)  # e.g. Windows
    assert UdpTransport("127.0.0.1").reuse_port is False
    with pytest.raises(ValueError, match="reuse_port: True is not possible here"):
        UdpTransport("127.0.0.1", reuse_port=True)


@pytest.mark.skipif(not LINUX, reason="broadcast on the loopback interface is Linux's")
async def test_two_clients_on_one_port_both_get_the_broadcast_replies() -> None:
    """The app and a monitor in miniature: a simulator answering to 127.255.255.255 (the
    loopback subnet's broadcast address) and two clients bound to the same fixed port;
    each one's commands succeed, and each sees the other's replies."""
    port = _free_port()
    sim = GcuSimulator()
    async with sim.serve_udp(host="127.0.0.1", port=0, reply_to=("127.255.255.255", port)) as s:
        app = GcuClient(UdpTransport("127.0.0.1", s.address[1], local_port=port))
        monitor = GcuClient(UdpTransport("127.0.0.1", s.address[1], local_port=port))
        async with app, monitor:
            photo, zoom = await asyncio.wait_for(
                asyncio.gather(app.take_photo(), monitor.zoom_in()), 5
            )
            assert (photo.opcode, zoom.opcode) == (Opcode.TAKE_PHOTO, Opcode.ZOOM_IN)
            await asyncio.sleep(0.2)
            for client in (app, monitor):
                link = client.link
                assert link.up and link.unmatched_feedback >= 1  # the other's feedback
                assert link.packets_received > link.packets_sent, link
    assert sim.model.executions[Opcode.TAKE_PHOTO] == 1
    assert sim.model.executions[Opcode.ZOOM_IN] == 1
