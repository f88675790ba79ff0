"""The bridge's MAVLink links on real loopback sockets with pymavlink peers
(docs/mavlink-bridge.md, "Links"): per-sender parsing and the destination rule on ``udpin``,
floods from thousands of source ports, ``tcp:`` peers that vanish, black-hole and return —
with the GCU's host rate counted at the simulator and both components' heartbeats counted
at a ground station throughout."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import socket
import sys
import time
from typing import Any

import pytest

from gcu_async.bridge._mavlink import mavlink, mavutil
from helpers.bridge.link_rig import free_port, link_rig, rss_mib, thread_count
from helpers.bridge.rig import CAMERA, GIMBAL, SYSTEM

REQUEST = mavlink.MAV_CMD_REQUEST_MESSAGE
INFO = mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION
FLOOD = os.path.join(os.path.dirname(os.path.dirname(__file__)), "helpers", "bridge",
                     "udp_flood.py")  # fmt: skip


class MavPeer:
    """A pymavlink connection polled without blocking; keeps what it receives."""

    def __init__(self, url: str, system: int = 254, component: int = 190) -> None:
        self.conn = mavutil.mavlink_connection(url, source_system=system,
                                               source_component=component)  # fmt: skip
        self.messages: list[Any] = []

    def poll(self) -> None:
        while True:
            try:
                msg = self.conn.recv_match(blocking=False)
            except (OSError, ConnectionError):
                return
            if msg is None:
                return
            if msg.get_type() != "BAD_DATA":
                self.messages.append(msg)

    def acks(self, command: int) -> list[Any]:
        return [m for m in self.messages if m.get_type() == "COMMAND_ACK"
                and m.command == command and m.result == mavlink.MAV_RESULT_ACCEPTED]

    def heartbeats(self) -> int:
        return sum(1 for m in self.messages if m.get_type() == "HEARTBEAT"
                   and m.get_srcSystem() == SYSTEM)  # fmt: skip

    def heartbeat(self) -> None:
        self.conn.mav.heartbeat_send(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)

    def request(self, confirmation: int = 0) -> None:
        self.conn.mav.command_long_send(SYSTEM, CAMERA, REQUEST, confirmation, INFO,
                                        0, 0, 0, 0, 0, 0)  # fmt: skip

    def close(self) -> None:
        self.conn.close()


async def until(predicate: Any, peers: list[Any], timeout: float, what: str,
                rig: Any = None) -> None:  # fmt: skip
    """Wait for ``predicate``, polling ``peers`` (and the rig's ground station)."""
    deadline = time.monotonic() + timeout
    while not predicate():
        for peer in peers:
            peer.poll()
        if rig is not None:
            rig.poll_gcs()
        if time.monotonic() > deadline:
            raise TimeoutError(f"{what}: not within {timeout} s")
        await asyncio.sleep(0.01)


def udpin_port(rig: Any) -> int:
    return int(rig.bridge.links[0].local_address[1])


def junk_socket() -> socket.socket:
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    sock.setblocking(False)
    return sock


def received_anything(sock: socket.socket) -> bool:
    try:
        return bool(sock.recv(4096))
    except BlockingIOError:
        return False


async def test_one_senders_junk_costs_another_sender_nothing() -> None:
    # issue 17: a 2-byte FD FF datagram from one sender lost 7 of the next 10 valid commands
    # of another (one parser shared by every sender of a udpin link)
    async with link_rig(["udpin:127.0.0.1:0"]) as rig:
        port = udpin_port(rig)
        station = MavPeer(f"udpout:127.0.0.1:{port}")
        junk = junk_socket()
        try:
            station.heartbeat()
            await until(lambda: station.heartbeats() > 0, [station], 5.0, "station heard")
            for _ in range(10):
                junk.sendto(b"\xfd\xff", ("127.0.0.1", port))
                await asyncio.sleep(0.02)
                station.request()
                await asyncio.sleep(0.05)
            await until(lambda: len(station.acks(REQUEST)) >= 10, [station], 5.0, "10 acks")
            assert len(station.acks(REQUEST)) == 10
        finally:
            station.close()
            junk.close()


async def test_junk_senders_are_never_written_to() -> None:
    # issue 17: any sender of one junk byte became a permanent destination of every message
    async with link_rig(["udpin:127.0.0.1:0"]) as rig:
        port = udpin_port(rig)
        station = MavPeer(f"udpout:127.0.0.1:{port}")
        socks = [junk_socket() for _ in range(200)]
        try:
            payloads = [b"\x00", b"\xfd\xff", b"\xfd\x09\x00\x00\x00\x01\x01\x00", b"\xfe"]
            for i, sock in enumerate(socks):
                sock.sendto(payloads[i % len(payloads)], ("127.0.0.1", port))
            station.heartbeat()
            await rig.pump(2.5)  # two heartbeats of each component at least
            station.poll()
            assert station.heartbeats() >= 2  # the valid sender is written to
            assert not [s for s in socks if received_anything(s)]
        finally:
            station.close()
            for sock in socks:
                sock.close()


async def test_destinations_are_capped_and_expire(monkeypatch: pytest.MonkeyPatch) -> None:
    from gcu_async.bridge import udp_link

    monkeypatch.setattr(udp_link, "DESTINATION_EXPIRY_SECONDS", 1.0)
    async with link_rig(["udpin:127.0.0.1:0"]) as rig:
        port = udpin_port(rig)
        station = MavPeer(f"udpout:127.0.0.1:{port}")
        station.heartbeat()
        await until(lambda: bool(station.messages), [station], 5.0, "station heard")
        others = [MavPeer(f"udpout:127.0.0.1:{port}", system=10 + i) for i in range(30)]
        try:
            station.heartbeat()
            await asyncio.sleep(0.05)
            for other in others:
                other.heartbeat()
            for _ in range(3):
                station.heartbeat()  # the station goes on, as ground stations do (1 Hz)
                await rig.pump(0.3)
            for other in others:
                other.poll()
            written = [o for o in others if o.messages]
            # the station was first: it stays; the others fill the free slots only
            assert len(written) == udp_link.MAX_DESTINATIONS - 1
            link = rig.bridge.links[0]
            assert len(link.destination_addresses) == udp_link.MAX_DESTINATIONS
            # all but the station fall silent: after the expiry they are no longer written to
            for _ in range(4):
                station.heartbeat()
                await rig.pump(0.5)
            station_port = station.conn.port.getsockname()[1]
            assert [a[1] for a in link.destination_addresses] == [station_port]
            for other in others:
                other.messages.clear()
                other.poll()
                other.messages.clear()
            for _ in range(4):
                station.heartbeat()
                await rig.pump(0.4)
            for other in others:
                other.poll()
            assert not [o for o in others if o.messages]
            station.poll()
            assert station.heartbeats() > 0
        finally:
            station.close()
            for other in others:
                other.close()


@pytest.mark.parametrize(("mode", "rate"), [("junk", 2000), ("mixed", 1000)])
async def test_flood_from_thousands_of_source_ports(mode: str, rate: int, caplog: Any) -> None:
    # issue 17: senders added by pymavlink's reader thread while the loop iterated over
    # them: "RuntimeError: Set changed size during iteration"
    caplog.set_level(logging.WARNING, logger="gcu_async")
    async with link_rig(["udpin:127.0.0.1:0"]) as rig:
        port = udpin_port(rig)
        station = MavPeer(f"udpout:127.0.0.1:{port}")
        station.heartbeat()
        await until(lambda: station.heartbeats() > 0, [station], 5.0, "station heard")
        await rig.pump(1.0)
        threads, rss = thread_count(), rss_mib()
        flood = await asyncio.create_subprocess_exec(
            sys.executable, FLOOD, "127.0.0.1", str(port), "6", str(rate), "4000", mode,
            stdout=asyncio.subprocess.PIPE)
        link = rig.bridge.links[0]
        try:
            start = time.monotonic()
            sent_commands = 0
            while flood.returncode is None and time.monotonic() - start < 30:
                station.heartbeat()
                station.request(confirmation=sent_commands % 256)
                sent_commands += 1
                await rig.pump(0.25)
                station.poll()
                check_bounds(link)
            end = time.monotonic()
            raw, _ = await asyncio.wait_for(flood.communicate(), 10)
            out = raw.decode()
        finally:
            if flood.returncode is None:
                flood.kill()
                await flood.communicate()
        try:
            await until(lambda: len(station.acks(REQUEST)) >= sent_commands, [station], 5.0,
                        "every command of the station answered")  # fmt: skip
        finally:
            station.close()
        grown = rss_mib() - rss
        low, high = rig.rate_range(start + 0.5, end)
        print(f"\nflood {mode}: {out.strip()} datagrams in {end - start:.1f} s; station "
              f"commands {sent_commands}, all acked; bad_data {link.bad_data}, dropped_in "
              f"{getattr(link, 'dropped_in', '?')}, senders dropped "
              f"{getattr(link, 'senders_dropped', '?')}, destinations refused "
              f"{getattr(link, 'destinations_refused', '?')}; RSS +{grown:.1f} MiB; threads "
              f"{threads} -> {thread_count()}; GCU host rate {low}-{high}/s")  # fmt: skip
        rig.check_rates(start + 0.5, end)
        assert int(out) >= 5 * rate  # 200 new source ports per 400 datagrams
        assert thread_count() <= threads
        assert grown < 20, grown
        assert rig.bridge.stats["handler_errors"] == 0
        assert not [r for r in caplog.records if r.levelno >= logging.ERROR]


def check_bounds(link: Any) -> None:
    """The udpin link's tables and inbox within their documented caps."""
    try:
        from gcu_async.bridge import links, udp_link
    except ImportError:  # the pymavlink-connection links before issue 17 had none
        return
    assert len(link._senders) <= udp_link.MAX_SENDERS
    assert len(link.destination_addresses) <= udp_link.MAX_DESTINATIONS
    assert link._inbox_bytes <= links.INBOX_BYTES


class BlackHole:
    """A listener on ``port`` whose backlog is full: connects to it hang (SYN dropped)."""

    def __init__(self, port: int) -> None:
        self.listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.listener.bind(("127.0.0.1", port))
        self.listener.listen(0)
        self.fillers = []
        for _ in range(3):
            sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            sock.setblocking(False)
            with contextlib.suppress(BlockingIOError):
                sock.connect(("127.0.0.1", port))
            self.fillers.append(sock)

    def close(self) -> None:
        for sock in self.fillers:
            sock.close()
        self.listener.close()


async def test_tcp_peer_vanishes_black_holes_and_returns() -> None:
    # issue 17: a tcp: peer going away froze the bridge (host rate 50/s -> 0.8/s, gimbal
    # heartbeat stopped): pymavlink's autoreconnect slept on the event loop's thread
    port = free_port(socket.SOCK_STREAM)
    peer = MavPeer(f"tcpin:127.0.0.1:{port}", system=250)
    async with link_rig([f"tcp:127.0.0.1:{port}"]) as rig:
        try:
            await until(lambda: peer.heartbeats() > 0, [peer], 5.0, "tcp peer fed")
            threads, rss = thread_count(), rss_mib()
            start = time.monotonic()
            peer.request()
            await until(lambda: peer.acks(REQUEST), [peer], 3.0, "tcp peer answered", rig)
            peer.close()  # gone: connects are refused
            await rig.pump(2.5)
            hole = BlackHole(port)  # now connects hang
            await rig.pump(3.0)
            hole.close()
            peer = MavPeer(f"tcpin:127.0.0.1:{port}", system=250)  # back
            back = time.monotonic()
            done = back + 6.0
            while not peer.heartbeats() and time.monotonic() < done:
                peer.poll()
                await rig.pump(0.05)
            assert peer.heartbeats(), "the bridge did not reconnect"
            fed_again = time.monotonic() - back
            peer.messages.clear()
            peer.request()
            while not peer.acks(REQUEST) and time.monotonic() < done + 3:
                peer.poll()
                await rig.pump(0.05)
            assert peer.acks(REQUEST)
            end = time.monotonic()
            low, high = rig.rate_range(start, end)
            print(f"\ntcp peer gone/black-holed/back over {end - start:.1f} s: fed again "
                  f"{fed_again:.2f} s after its return; GCU host rate {low}-{high}/s")
            rig.check_rates(start, end)
            link = rig.bridge.links[0]
            assert link.reopened >= 1
            assert rig.bridge.stats["handler_errors"] == 0
            assert thread_count() <= threads
            assert rss_mib() - rss < 20
        finally:
            peer.close()


class PtyPeer:
    """The far end of a serial link: a pseudo-terminal's master, with a pymavlink parser."""

    def __init__(self, link_path: str) -> None:
        self.master, slave = os.openpty()
        os.set_blocking(self.master, False)
        self.slave_name = os.ttyname(slave)
        os.close(slave)  # the bridge opens the slave by its (symlinked) name
        tmp = link_path + ".new"
        os.symlink(self.slave_name, tmp)
        os.replace(tmp, link_path)
        self.parser = mavlink.MAVLink(None, srcSystem=253, srcComponent=190)
        self.parser.robust_parsing = True
        self.messages: list[Any] = []

    def poll(self) -> None:
        while True:
            try:
                data = os.read(self.master, 4096)
            except (BlockingIOError, OSError):
                return
            if not data:
                return
            for msg in self.parser.parse_buffer(data) or []:
                if msg.get_type() != "BAD_DATA":
                    self.messages.append(msg)

    def heartbeats(self) -> int:
        return sum(1 for m in self.messages if m.get_type() == "HEARTBEAT")

    def request(self) -> None:
        msg = mavlink.MAVLink_command_long_message(SYSTEM, CAMERA, REQUEST, 0, INFO,
                                                   0, 0, 0, 0, 0, 0)  # fmt: skip
        os.write(self.master, msg.pack(self.parser))

    def acked(self) -> bool:
        return any(m.get_type() == "COMMAND_ACK" and m.command == REQUEST
                   and m.result == mavlink.MAV_RESULT_ACCEPTED for m in self.messages)

    def close(self) -> None:
        os.close(self.master)


async def test_serial_device_unplugged_and_back(tmp_path: Any) -> None:
    path = str(tmp_path / "autopilot-tty")
    peer = PtyPeer(path)
    async with link_rig([f"{path},115200"]) as rig:
        try:
            await until(lambda: peer.heartbeats() > 0, [peer], 5.0, "serial peer fed")
            start = time.monotonic()
            peer.request()
            await until(peer.acked, [peer], 3.0, "serial peer answered", rig)
            peer.close()  # unplugged: the device node is gone
            await rig.pump(2.5)
            peer = PtyPeer(path)  # plugged in again (a new node behind the same name)
            await until(lambda: peer.heartbeats() > 0, [peer], 6.0, "serial reopened", rig)
            peer.request()
            await until(peer.acked, [peer], 3.0, "answered after reopening", rig)
            end = time.monotonic()
            rig.check_rates(start, end)
            assert rig.bridge.links[0].reopened >= 1
        finally:
            with contextlib.suppress(OSError):
                peer.close()


async def test_tcpin_caps_clients_and_never_waits_for_a_stalled_one() -> None:
    from gcu_async.bridge import links, stream_link

    async with link_rig(["tcpin:127.0.0.1:0"]) as rig:
        link = rig.bridge.links[0]
        port = link.local_address[1]
        threads, rss = thread_count(), rss_mib()
        start = time.monotonic()
        clients = []
        try:
            for _ in range(stream_link.MAX_TCP_CLIENTS + 4):
                sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)  # before the SYN
                sock.settimeout(2)
                sock.connect(("127.0.0.1", port))
                sock.setblocking(False)
                clients.append(sock)
                await rig.pump(0.05)
            # the clients never read: the bridge's unsent bytes for each stay bounded and
            # what does not fit is dropped, never waited for
            await rig.pump(1.0)
            assert link.clients_refused == 4
            for client in link._clients:  # small kernel buffers: user space fills in seconds
                sock = client.peer.transport.get_extra_info("socket")
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 4096)
            for component, message in [
                    (GIMBAL, mavlink.MAVLINK_MSG_ID_GIMBAL_DEVICE_ATTITUDE_STATUS),
                    (GIMBAL, mavlink.MAVLINK_MSG_ID_GIMBAL_MANAGER_STATUS),
                    (CAMERA, mavlink.MAVLINK_MSG_ID_CAMERA_SETTINGS),
                    (CAMERA, mavlink.MAVLINK_MSG_ID_CAMERA_CAPTURE_STATUS),
                    (CAMERA, mavlink.MAVLINK_MSG_ID_CAMERA_FOV_STATUS)]:  # fmt: skip
                rig.gcs.command(component, mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, message, 10_000)
            await rig.pump(5.0)  # 500 messages/s to every client
            end = time.monotonic()
            rig.check_rates(start, end)
            assert link.dropped_out > 0
            for client in link._clients:
                assert client.peer.transport.get_write_buffer_size() <= (
                    links.SEND_BUFFER_BYTES + 1024)
            assert thread_count() <= threads
            assert rss_mib() - rss < 20
        finally:
            for sock in clients:
                sock.close()


async def test_a_hung_name_lookup_costs_one_thread_and_never_delays_close(
        monkeypatch: pytest.MonkeyPatch) -> None:  # fmt: skip
    import threading

    from gcu_async.bridge import links
    from gcu_async.bridge.bridge import make_link

    release = threading.Event()
    calls: list[str] = []

    def hung_lookup(host: str, *args: Any, **kwargs: Any) -> Any:
        calls.append(host)
        release.wait(30)  # a resolver that does not answer
        raise OSError("no answer")

    monkeypatch.setattr(links.socket, "getaddrinfo", hung_lookup)
    monkeypatch.setattr(links, "OPEN_TIMEOUT", 0.2)
    monkeypatch.setattr(links, "RETRY_SECONDS", 0.05)
    link = make_link("tcp:gimbal-gcs.example:5760")
    before = thread_count()
    try:
        await link.open(lambda link, peer, msg: None)
        await asyncio.sleep(1.5)  # several attempts time out meanwhile
        assert len(calls) == 1  # the later attempts wait for the first lookup's thread
        assert thread_count() == before + 1
        started = time.monotonic()
        await link.close()
        assert time.monotonic() - started < 0.2
    finally:
        release.set()


async def asked_and_answered(station: MavPeer, rig: Any, steps: list[str]) -> None:
    """The station asks, retransmitting every 0.5 s as ground stations do (a burst may have
    filled the socket's receive buffer: the kernel drops datagrams of every sender alike),
    and is answered within 3 s."""
    answered = len(station.acks(REQUEST))
    deadline = time.monotonic() + 3.0
    while len(station.acks(REQUEST)) <= answered:
        assert time.monotonic() < deadline, f"station not answered after {steps}"
        station.heartbeat()
        station.request()
        resend = time.monotonic() + 0.5
        while time.monotonic() < resend and len(station.acks(REQUEST)) <= answered:
            station.poll()
            rig.poll_gcs()
            await asyncio.sleep(0.01)


def _burst(port: int, sources: int, per_source: int, payloads: list[bytes]) -> None:
    """Datagrams from ``sources`` fresh source ports (run in a thread: sockets release the
    GIL, the loop keeps running)."""
    for i in range(sources):
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            for j in range(per_source):
                sock.sendto(payloads[(i + j) % len(payloads)], ("127.0.0.1", port))


@pytest.mark.parametrize("seed", [17, 2026])
async def test_generated_schedule_of_link_faults(seed: int) -> None:
    """A seeded schedule of steps — junk and valid bursts from new source ports on udpin, the
    tcp: peer closing, black-holing and returning, the ground station's commands — checked
    after every step: every command of the station answered, the link's tables within their
    caps, no handler error; over the whole run the GCU host rate, both heartbeats, threads
    and memory."""
    import random

    rng = random.Random(seed)
    tcp_port = free_port(socket.SOCK_STREAM)
    tcp_peer: MavPeer | None = MavPeer(f"tcpin:127.0.0.1:{tcp_port}", system=250)
    hole: BlackHole | None = None
    valid = [mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3).pack(
        mavlink.MAVLink(None, srcSystem=100 + i, srcComponent=190)) for i in range(50)]
    junk = [b"\xfd\xff", b"\x00", b"\xfe\x09", bytes(range(256))[: rng.randrange(1, 200)]]
    async with link_rig(["udpin:127.0.0.1:0", f"tcp:127.0.0.1:{tcp_port}"]) as rig:
        port = udpin_port(rig)
        station = MavPeer(f"udpout:127.0.0.1:{port}")
        steps: list[str] = []
        try:
            station.heartbeat()
            await until(lambda: bool(station.messages), [station], 5.0, "station heard", rig)
            threads, rss = thread_count(), rss_mib()
            start = time.monotonic()
            for _ in range(10):
                step = rng.choice(["junk", "valid", "tcp-close", "tcp-hole", "tcp-back",
                                   "command"])  # fmt: skip
                steps.append(step)
                if step == "junk":
                    await asyncio.to_thread(_burst, port, 300, 2, junk)
                elif step == "valid":
                    await asyncio.to_thread(_burst, port, 50, 1, valid)
                elif step == "tcp-close" and tcp_peer is not None:
                    tcp_peer.close()
                    tcp_peer = None
                elif step == "tcp-hole" and tcp_peer is None and hole is None:
                    hole = BlackHole(tcp_port)
                elif step == "tcp-back" and tcp_peer is None:
                    if hole is not None:
                        hole.close()
                        hole = None
                    tcp_peer = MavPeer(f"tcpin:127.0.0.1:{tcp_port}", system=250)
                await rig.pump(0.3 + 0.7 * rng.random())
                await asked_and_answered(station, rig, steps)
                if tcp_peer is not None:  # connected (again): fed within 1 retry + 2 s
                    peer = tcp_peer
                    await until(peer.heartbeats, [peer], 3.5, f"tcp peer fed after {steps}", rig)
                check_bounds(rig.bridge.links[0])
                assert rig.bridge.stats["handler_errors"] == 0
            end = time.monotonic()
            rig.check_rates(start, end)
            assert thread_count() <= threads
            assert rss_mib() - rss < 20
        finally:
            station.close()
            if tcp_peer is not None:
                tcp_peer.close()
            if hole is not None:
                hole.close()
