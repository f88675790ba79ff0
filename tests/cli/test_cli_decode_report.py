"""``gcu-async decode`` of a pod that sends its camera yaw signed (the Z-1Pro's logged
values), through the real entry point: the heading in the JSON, each kind of anomaly said
once on stderr, ``--report FILE`` (the GCU's report, and the host's when host packets are in
the input), a capture's times (docs/cli.md, docs/conformance.md)."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

from gcu_async.capture import PacketCapture
from gcu_async.protocol import HostMainFrame, HostPacket, NullCommand, TakePhoto
from gcu_async.protocol.headings import PAST_TURN_DETAIL, SIGNED_DETAIL
from helpers.protocol import z1pro

DECODE = [sys.executable, "-m", "gcu_async", "decode"]
HOST, GCU = ("127.0.0.1", 40000), ("127.0.0.1", 2337)


def decode(*args: str) -> tuple[list[dict[str, Any]], list[str]]:
    done = subprocess.run([*DECODE, *args], capture_output=True, text=True, timeout=60,
                          check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr
    return [json.loads(line) for line in done.stdout.splitlines()], done.stderr.splitlines()


def session() -> list[bytes]:
    """A host taking a photo, then watching: the Z-1Pro's replies to each packet, its yaw
    along the logged moves (signed west of north), one value neither reading explains."""
    host_null = HostPacket(HostMainFrame.build(subframe_request=1), None, NullCommand()).encode()
    photo = HostPacket(HostMainFrame.build(subframe_request=1), None, TakePhoto()).encode()
    packets = [photo, z1pro.reply(0, 8852, opcode=0x20, status=0)]
    for rel0, yaw0, rel1, yaw1 in z1pro.MOVES:
        packets += [host_null, z1pro.reply(rel0, yaw0), host_null, z1pro.reply(rel1, yaw1)]
    packets += [host_null, z1pro.reply(0, 40000)]
    return packets


def test_the_heading_in_the_json_and_each_kind_of_anomaly_once(tmp_path: Path) -> None:
    packets = session()
    objs, stderr = decode(b"".join(packets).hex())
    replies = [o for o in objs if o["direction"] == "gcu_to_host"]
    signed = [o for o in replies if o["main"]["attitude_raw"][2] >= 47536]
    assert len(replies) == 2 + 4 * len(z1pro.MOVES) // 2 and len(signed) > 10
    for o in replies:
        raw = o["main"]["attitude_raw"][2]
        yaw = o["main"]["attitude_deg"]["yaw"]
        assert 0.0 <= yaw < 360.0
        assert yaw == pytest.approx(((raw - 65536 if raw >= 47536 else raw) % 36000) / 100)
    first = next(i for i, o in enumerate(objs, 1) if o.get("anomalies"))
    assert stderr[0].startswith(f"gcu-async decode: packet {first} (gcu_to_host): flagged: "
                                "yaw_raw: ")  # fmt: skip
    assert stderr[0].endswith(f"({SIGNED_DETAIL})")
    assert stderr[1].endswith(f"({PAST_TURN_DETAIL})")
    assert stderr[2:] == [f"gcu-async decode: {len(signed)} packets (gcu_to_host): flagged: "
                          f"yaw_raw, shown once, at packet {first}"]  # fmt: skip


def test_report_of_hex_input_has_both_sides_and_no_times(tmp_path: Path) -> None:
    path = tmp_path / "report.txt"
    decode("--report", str(path), b"".join(session()).hex())
    text = path.read_text(encoding="utf-8")
    assert text.startswith("The input has no times (hex or raw bytes)")
    gcu, host = text.split("\n\nHost conformance to V2.0.6: ")
    assert "GCU conformance to V2.0.6: 50 replies to 50 host packets\n" in gcu
    assert "- main.yaw_raw.signed: camera yaw sent as a signed S16" in gcu
    assert "- main.yaw_raw.past_turn: " in gcu
    assert "no times given: feedback latency not measured" in gcu
    assert host.startswith("50 packets")


def test_report_of_a_capture_is_timed(tmp_path: Path) -> None:
    pcap = tmp_path / "z1pro.pcapng"
    capture = PacketCapture(pcap)
    capture.acquire()
    try:
        for packet in session()[:6]:
            if packet[:2] == b"\xa8\xe5":
                capture.udp(HOST, GCU, packet)
            else:
                time.sleep(0.01)  # the pod answers 10 ms later
                capture.udp(GCU, HOST, packet)
    finally:
        capture.release()
    path = tmp_path / "report.txt"
    objs, _ = decode("--file", str(pcap), "--report", str(path))
    times = [o["capture"]["time"] for o in objs]
    assert times == sorted(times) and times[-1] - times[0] >= 0.03
    text = path.read_text(encoding="utf-8")
    assert text.startswith("GCU conformance to V2.0.6: 3 replies to 3 host packets in ")
    assert "feedback " in text and " ms after the command's first packet" in text
