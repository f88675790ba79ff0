"""Captures made independently of the library: tcpdump (pcap) and dumpcap (pcapng) on
loopback while a client talks to the simulator, read by tshark with the dissector and by
``gcu-async decode --file``: the two must agree on every field of thousands of packets.

Traffic, all on a loopback address of the test's own (127.x.y.z) and filtered to its ports:
a client at 200 packets/s over UDP to the simulator's port 2337; a client over TCP through
a proxy (on a port of its own: the dissector's heuristics) that cuts the byte stream into
small segments, merges others and puts junk — random bytes, and for the first half of the
run false headers too — between packets, both ways, to the simulator's TCP port 2332; and a
sender of crafted datagrams (several packets, junk, CRC failures, malformed packets) to a
socket on another port. The stream ends with clean traffic, so no false header is left
waiting when the capture stops (a stream dissector cannot know that a stream has ended).
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import random
import selectors
import signal
import socket
import subprocess
import time
from collections.abc import AsyncIterator, Iterator
from pathlib import Path

import pytest

from gcu_async.cli.decode import decode_capture
from gcu_async.client.connect import connect
from gcu_async.protocol import GCU_HEADER, HOST_HEADER
from gcu_async.sim import GcuSimulator
from helpers.wireshark.tshark import DUMPCAP, TCPDUMP, dissect, needs_tshark
from helpers.wireshark.xfgcu_compare import compare_capture
from helpers.wireshark.xfgcu_corpus import corpus, corrupt

pytestmark = [needs_tshark, pytest.mark.filterwarnings("ignore:rate_hz=")]
RUN_SECONDS = 4.0
START_TIMEOUT = 10.0


def loopback_address() -> str:
    """A 127.x.y.z address of this test run (Linux routes all of 127/8 to lo)."""
    rng = random.Random(os.getpid() ^ time.monotonic_ns())
    return f"127.{rng.randrange(16, 250)}.{rng.randrange(1, 250)}.{rng.randrange(2, 250)}"


@contextlib.contextmanager
def sniffer(tool: str, path: Path, address: str, ports: list[int]) -> Iterator[None]:
    """tcpdump or dumpcap on lo, only UDP/TCP of ``address`` on ``ports``, while inside."""
    bpf = f"host {address} and (udp or tcp) and ({' or '.join(f'port {p}' for p in ports)})"
    if tool == "tcpdump":
        assert TCPDUMP is not None
        argv = [TCPDUMP, "-i", "lo", "-U", "-s", "0", "-n", "-w", str(path), bpf]
        ready = "listening on"
    else:
        assert DUMPCAP is not None
        argv = [DUMPCAP, "-i", "lo", "-s", "0", "-q", "-w", str(path), "-f", bpf]
        ready = "Capturing on"
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    assert proc.stderr is not None
    seen = b""
    try:
        with selectors.DefaultSelector() as sel:
            sel.register(proc.stderr, selectors.EVENT_READ)
            deadline = time.monotonic() + START_TIMEOUT
            while ready.encode() not in seen:
                left = deadline - time.monotonic()
                if left <= 0 or not sel.select(left):
                    break
                chunk = os.read(proc.stderr.fileno(), 4096)
                if not chunk:
                    break
                seen += chunk
        if ready.encode() not in seen:
            proc.kill()
            proc.wait(timeout=15)
            text = seen.decode(errors="replace").strip()[:300]
            pytest.skip(f"{tool} cannot capture on lo here: {text}")
        yield
        time.sleep(0.5)  # the last packets reach the capture
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(timeout=15)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(timeout=15)
        proc.stderr.close()


def junk(rng: random.Random, false_headers: bool) -> bytes:
    data = bytearray(rng.randbytes(rng.randrange(1, 24)))
    if false_headers:
        if len(data) >= 4 and rng.random() < 0.5:
            data[0:2] = rng.choice((HOST_HEADER, GCU_HEADER))
            data[2:4] = rng.randrange(60, 300).to_bytes(2, "little")
        return bytes(data)
    return bytes(b for b in data if b not in (0xA8, 0x8A))  # no header byte: nothing waits


class Proxy:
    """TCP proxy that cuts, merges and salts the stream with junk, both ways."""

    def __init__(self, upstream: tuple[str, int], seed: int) -> None:
        self.upstream = upstream
        self.rng = random.Random(seed)
        self.started = time.monotonic()
        self.tasks: set[asyncio.Task[None]] = set()

    async def handle(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        up_reader, up_writer = await asyncio.open_connection(*self.upstream)
        for w in (writer, up_writer):
            sock = w.get_extra_info("socket")
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        pumps = [asyncio.create_task(self.pump(reader, up_writer)),
                 asyncio.create_task(self.pump(up_reader, writer))]  # fmt: skip
        self.tasks.update(pumps)
        await asyncio.wait(pumps, return_when=asyncio.FIRST_COMPLETED)
        for task in pumps:
            task.cancel()
        for w in (writer, up_writer):
            w.close()

    async def pump(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        held = b""
        with contextlib.suppress(ConnectionError, asyncio.CancelledError):
            while True:
                data = await reader.read(4096)
                if not data:
                    return
                early = time.monotonic() - self.started < RUN_SECONDS / 2
                if self.rng.random() < 0.3:
                    data = junk(self.rng, early) + data
                held += data
                if self.rng.random() < 0.3:  # merge with what comes next
                    continue
                while held:  # cut into pieces, each its own segment
                    n = self.rng.choice((1, 3, 7, 40, 72, 100, 4096))
                    writer.write(held[:n])
                    held = held[n:]
                    await writer.drain()
                    if held:
                        await asyncio.sleep(0.001)


@contextlib.asynccontextmanager
async def proxy(upstream: tuple[str, int], address: str, port: int) -> AsyncIterator[int]:
    p = Proxy(upstream, seed=11)
    server = await asyncio.start_server(p.handle, address, port)
    try:
        yield int(server.sockets[0].getsockname()[1])
    finally:
        server.close()
        for task in p.tasks:
            task.cancel()
        await asyncio.wait_for(server.wait_closed(), 10)


async def heartbeat(url: str, seconds: float, **options: object) -> int:
    async with connect(url, rate_hz=200.0, **options) as gcu:
        gcu.update_aircraft(attitude=(1.0, 2.0, 3.0), position=(22.5, 113.9, 50.0))
        await asyncio.wait_for(gcu.take_photo(), 10)
        await asyncio.sleep(seconds)
        return gcu.link.packets_sent


def crafted(address: str, port: int) -> int:
    """Datagrams of several packets, junk, CRC failures and malformed packets to ``port``."""
    rng = random.Random(5)
    sent = 0
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind((address, 0))
        for packet in corpus():
            roll = rng.random()
            if roll < 0.3:
                datagram = junk(rng, True) + packet + corrupt(packet, rng) + packet
            elif roll < 0.5:
                datagram = packet + packet[: rng.randrange(1, len(packet))]
            else:
                datagram = packet
            sock.sendto(datagram, (address, port))
            sent += 1
            time.sleep(0.001)
    return sent


def traffic(address: str, sink_port: int, udp_seconds: float, proxy_port: int | None) -> None:
    async def main() -> None:
        sim = GcuSimulator()
        async with contextlib.AsyncExitStack() as stack:
            udp = await stack.enter_async_context(sim.serve_udp(address, 2337))
            jobs = [heartbeat(udp.url, udp_seconds, local_host=address, local_port=0)]
            if proxy_port is not None:
                await stack.enter_async_context(sim.serve_tcp(address, 2332))
                port = await stack.enter_async_context(
                    proxy((address, 2332), address, proxy_port)
                )
                jobs.append(heartbeat(f"tcp://{address}:{port}", RUN_SECONDS))
            jobs.append(asyncio.to_thread(crafted, address, sink_port))
            await asyncio.wait_for(asyncio.gather(*jobs), RUN_SECONDS * 10)

    asyncio.run(main())


def _sink(address: str) -> socket.socket:
    sink = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sink.bind((address, 0))
    return sink


def _free_tcp_port(address: str) -> int:
    """A TCP port free on ``address`` (the address is this run's own: nobody else takes it)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind((address, 0))
        return int(probe.getsockname()[1])


@pytest.mark.skipif(TCPDUMP is None, reason="tcpdump is not installed (Debian package tcpdump)")
def test_tcpdump_capture_of_udp_tcp_with_a_cutting_proxy(tmp_path: Path) -> None:
    address = loopback_address()
    path = tmp_path / "tcpdump.pcap"
    with _sink(address) as sink:
        sink_port = sink.getsockname()[1]
        proxy_port = _free_tcp_port(address)
        with sniffer("tcpdump", path, address, [2337, 2332, proxy_port, sink_port]):
            traffic(address, sink_port, RUN_SECONDS, proxy_port)
    objs = decode_capture(path.read_bytes())
    frames = dissect(path)
    compared, fields = compare_capture(objs, frames)
    links = {o["capture"]["link"] for o in objs}
    assert links == {"udp", "tcp"}
    assert compared >= 2000, compared
    print(f"\ntcpdump: {compared} packets, {fields} fields agree")


@pytest.mark.skipif(DUMPCAP is None, reason="dumpcap is not installed (Debian wireshark-common)")
def test_dumpcap_pcapng_capture(tmp_path: Path) -> None:
    address = loopback_address()
    path = tmp_path / "dumpcap.pcapng"
    with _sink(address) as sink:
        sink_port = sink.getsockname()[1]
        with sniffer("dumpcap", path, address, [2337, sink_port]):
            traffic(address, sink_port, 1.0, None)
    objs = decode_capture(path.read_bytes())
    compared, fields = compare_capture(objs, dissect(path))
    assert compared >= 400, compared
    print(f"\ndumpcap: {compared} packets, {fields} fields agree")
