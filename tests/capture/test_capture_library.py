"""Captures written by the library: a client and a simulator recording one real session.

Over UDP, TCP (with a killed connection and the reconnect), a pty and the in-memory link,
the client (``capture=``) and the simulator (``capture=``) each write a pcapng file; the
host packets the client recorded sending are exactly those the simulator recorded
receiving, and both files read the same in tshark with the dissector as in ``gcu-async
decode --file``, field by field. The command-line ``--capture`` options, the missing extra
and the ``wireshark`` sub-command are covered too.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import subprocess
import sys
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import pytest

from gcu_async import GcuClient
from gcu_async.capture import CaptureUnavailable, PacketCapture
from gcu_async.cli.decode import decode_capture
from gcu_async.client.connect import connect
from gcu_async.protocol import GCU_HEADER, HOST_HEADER
from gcu_async.sim import GcuSimulator
from gcu_async.transport.serial import SerialTransport
from gcu_async.transport.tap import CapturingTransport
from gcu_async.wireshark import dissector_path
from helpers.sim.process import CLI, SimProcess
from helpers.wireshark.tshark import dissect, needs_tshark
from helpers.wireshark.xfgcu_compare import compare_capture

WAIT = 10.0


async def _session(gcu: GcuClient, seconds: float) -> None:
    """Some commands and heartbeats (bounded)."""
    await asyncio.wait_for(gcu.take_photo(), WAIT)
    await asyncio.wait_for(gcu.zoom_to(3.0), WAIT)
    await asyncio.wait_for(gcu.track((0.4, 0.4, 0.6, 0.6)), WAIT)
    gcu.update_aircraft(attitude=(1.5, -2.25, 123.45), position=(22.5, 113.9, 50.0),
                        satellites=12, gnss_week=2300, gnss_ms=123456)  # fmt: skip
    await asyncio.sleep(seconds)
    await asyncio.wait_for(gcu.set_osd(True), WAIT)


def _packets(path: Path, header: bytes) -> list[str]:
    """The hex of every packet with ``header`` that decode finds in a capture."""
    out = []
    for obj in decode_capture(path.read_bytes()):
        direction = "host_to_gcu" if header == HOST_HEADER else "gcu_to_host"
        if obj.get("direction") == direction:
            out.append(repr({k: v for k, v in obj.items() if k != "capture"}))
    return out


def check_pair(client: Path, sim: Path) -> int:
    """Both sides recorded the same packets; tshark and decode agree on both files."""
    sent, received = _packets(client, HOST_HEADER), _packets(sim, HOST_HEADER)
    assert sent and sent == received
    replies_sent, replies_got = _packets(sim, GCU_HEADER), _packets(client, GCU_HEADER)
    assert replies_got and replies_got == replies_sent[: len(replies_got)]
    total = 0
    for path in (client, sim):
        objs = decode_capture(path.read_bytes())
        compared, _ = compare_capture(objs, dissect(path))
        assert compared == len(objs)
        total += compared
    return total


@contextlib.asynccontextmanager
async def served(sim: GcuSimulator, listen: str) -> AsyncIterator[Any]:
    server = sim.serve(listen)
    await server.open()
    try:
        yield server
    finally:
        await server.close()


@needs_tshark
async def test_udp_session_recorded_by_client_and_simulator(tmp_path: Path) -> None:
    sim = GcuSimulator(capture=tmp_path / "sim.pcapng")
    async with served(sim, "udp://127.0.0.1:0") as server:
        async with connect(server.url, local_port=0, capture=tmp_path / "client.pcapng") as gcu:
            assert isinstance(gcu.transport, CapturingTransport)
            assert gcu.transport.local_address is not None  # read from the wrapped transport
            await _session(gcu, 1.0)
        await asyncio.sleep(0.2)  # the last datagrams reach the simulator
    assert sim.capture is not None and not sim.capture.active
    total = check_pair(tmp_path / "client.pcapng", tmp_path / "sim.pcapng")
    assert total > 100


@needs_tshark
async def test_tcp_session_with_a_reconnect(tmp_path: Path) -> None:
    sim = GcuSimulator(capture=tmp_path / "sim.pcapng")
    async with (
        served(sim, "tcp://127.0.0.1:0") as server,
        connect(server.url, capture=tmp_path / "client.pcapng") as gcu,
    ):
        await _session(gcu, 0.5)
        assert server.kill_connection()
        deadline = asyncio.get_running_loop().time() + WAIT
        while gcu.transport.reconnects == 0 or not gcu.link.up:  # type: ignore[attr-defined]
            assert asyncio.get_running_loop().time() < deadline
            await asyncio.sleep(0.02)
        await _session(gcu, 0.5)
    objs = decode_capture((tmp_path / "client.pcapng").read_bytes())
    streams = {o["capture"]["stream"] for o in objs}
    assert len(streams) == 4  # two connections, both directions
    frames = dissect(tmp_path / "client.pcapng")
    compared, _ = compare_capture(objs, frames)
    assert compared == len(objs)
    sim_objs = decode_capture((tmp_path / "sim.pcapng").read_bytes())
    compared, _ = compare_capture(sim_objs, dissect(tmp_path / "sim.pcapng"))
    assert compared == len(sim_objs)


@needs_tshark
@pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs a POSIX pty")
async def test_serial_session_over_a_pty(tmp_path: Path) -> None:
    sim = GcuSimulator(capture=tmp_path / "sim.pcapng")
    async with served(sim, "pty") as server:
        transport = SerialTransport(server.device_path)
        async with GcuClient(transport, capture=tmp_path / "client.pcapng") as gcu:
            await _session(gcu, 1.0)
        await asyncio.sleep(0.2)
    total = check_pair(tmp_path / "client.pcapng", tmp_path / "sim.pcapng")
    assert total > 100
    objs = decode_capture((tmp_path / "client.pcapng").read_bytes())
    assert {o["capture"]["link"] for o in objs} == {"serial"}


@needs_tshark
async def test_memory_link_and_a_shared_capture_object(tmp_path: Path) -> None:
    capture = PacketCapture(tmp_path / "memory.pcapng")
    sim = GcuSimulator()
    async with sim.serve_memory() as server:
        transport = server.transport
        async with GcuClient(transport, capture=capture) as gcu:
            await _session(gcu, 0.2)
            assert capture.active and capture.records > 0
            # flushed as written: readable while the capture runs
            assert decode_capture(capture.path.read_bytes())
        async with GcuClient(transport, capture=capture) as gcu:  # reopened: a new section
            await asyncio.wait_for(gcu.focus(), WAIT)
    assert not capture.active
    objs = decode_capture(capture.path.read_bytes())
    compared, _ = compare_capture(objs, dissect(capture.path))
    assert compared == len(objs) > 20


def run_cli(*args: str, timeout: float = 60.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*CLI, *args], capture_output=True, text=True, timeout=timeout,
                          check=False)  # fmt: skip


@needs_tshark
def test_cli_capture_options(tmp_path: Path) -> None:
    sim = SimProcess("--listen", "udp://127.0.0.1:0", "--capture", str(tmp_path / "sim.pcapng"))
    try:
        url = sim.url + "?local_port=0"
        sent = run_cli("send", url, "take-photo", "--capture", str(tmp_path / "send.pcapng"))
        assert sent.returncode == 0, sent.stderr
        watched = run_cli("monitor", url, "--count", "2", "--interval", "0.1",
                          "--capture", str(tmp_path / "monitor.pcapng"))  # fmt: skip
        assert watched.returncode == 0, watched.stderr
    finally:
        sim.stop()
    demo = run_cli("demo", "--quick", "--no-live", "--listen", "tcp://127.0.0.1:0",
                   "--capture", str(tmp_path / "demo.pcapng"), timeout=120)  # fmt: skip
    assert demo.returncode == 0, demo.stdout[-2000:] + demo.stderr
    for name in ("sim", "send", "monitor", "demo"):
        path = tmp_path / f"{name}.pcapng"
        done = run_cli("decode", "--file", str(path))
        assert done.returncode == 0, (name, done.stderr)
        objs = decode_capture(path.read_bytes())
        compared, _ = compare_capture(objs, dissect(path))
        assert compared == len(objs) > 0, name


def test_capture_without_the_extra_names_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    for name in ("dpkt", "pcapng"):
        monkeypatch.setitem(sys.modules, name, None)  # import fails as if not installed
    with pytest.raises(CaptureUnavailable, match=r"'capture' extra.*gcu-async\[capture\]"):
        PacketCapture(tmp_path / "x.pcapng")
    with pytest.raises(ImportError, match="capture"):
        connect("udp://127.0.0.1:9", capture=tmp_path / "x.pcapng")
    assert not (tmp_path / "x.pcapng").exists()


def test_cli_capture_errors(tmp_path: Path) -> None:
    missing = tmp_path / "no" / "such" / "dir" / "x.pcapng"
    done = run_cli("send", "udp://127.0.0.1:9?local_port=0", "take-photo", "--timeout", "1",
                   "--capture", str(missing))  # fmt: skip
    assert done.returncode == 1 and "No such file" in done.stdout
    bad = run_cli("sim", "--listen", "udp://127.0.0.1:0", "--capture", str(tmp_path))
    assert bad.returncode == 2 and "capture" in bad.stderr and "directory" in bad.stderr
    unwritable = run_cli("sim", "--listen", "udp://127.0.0.1:0", "--capture", str(missing))
    assert unwritable.returncode == 1
    assert "cannot write the capture file" in unwritable.stderr, unwritable.stderr


def test_wireshark_command(tmp_path: Path) -> None:
    path = run_cli("wireshark", "--print-path")
    assert path.returncode == 0
    assert Path(path.stdout.strip()) == dissector_path()
    assert dissector_path().read_text().startswith("-- xfgcu.lua")
    dest = tmp_path / "plugins"
    installed = run_cli("wireshark", "--install", "--dest", str(dest))
    assert installed.returncode == 0, installed.stderr
    assert (dest / "xfgcu.lua").read_bytes() == dissector_path().read_bytes()
    home = tmp_path / "home"
    env = {**os.environ, "HOME": str(home), "PATH": "/nonexistent"}  # no tshark to ask
    done = subprocess.run([*CLI, "wireshark", "--install"], capture_output=True, text=True,
                          env=env, timeout=60, check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr
    expected = home / ".local" / "lib" / "wireshark" / "plugins" / "xfgcu.lua"
    if sys.platform != "win32":
        assert Path(done.stdout.strip()) == expected and expected.is_file()
    bare = run_cli("wireshark")  # no option: as --print-path
    assert bare.returncode == 0 and Path(bare.stdout.strip()) == dissector_path(), bare.stderr
    assert run_cli("wireshark", "--print-path", "--install").returncode == 2
    assert run_cli("wireshark", "--print-path", "--dest", "x").returncode == 2

