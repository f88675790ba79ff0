"""The Lua dissector against ``gcu-async decode``, on captures written by the library.

Every packet of every kind (:mod:`helpers.wireshark.xfgcu_corpus`) crosses UDP, TCP and a serial
link with junk, CRC-failed copies and cuts; tshark with the dissector and ``gcu-async decode
--file`` read the same file, and every field of every packet must agree
(:mod:`helpers.wireshark.xfgcu_compare`).
"""

from __future__ import annotations

import json
import random
import subprocess
import sys
from pathlib import Path

from gcu_async.capture import PacketCapture
from gcu_async.capture.synth import TcpFlow
from gcu_async.cli.decode import decode_capture
from helpers.protocol.vectors import GCU_EXAMPLE, HOST_EXAMPLE
from helpers.wireshark.tshark import dissect, needs_tshark, verbose
from helpers.wireshark.xfgcu_compare import compare, compare_capture, packets_by_stream
from helpers.wireshark.xfgcu_corpus import GCU, HOST, anomalous_packets, corpus, write_capture

pytestmark = needs_tshark


def decode_file(path: Path) -> list[dict]:
    """``gcu-async decode --file`` in a subprocess: its JSON lines."""
    done = subprocess.run([sys.executable, "-m", "gcu_async", "decode", "--file", str(path)],
                          capture_output=True, text=True, timeout=120, check=True)  # fmt: skip
    return [json.loads(line) for line in done.stdout.splitlines()]


def test_every_packet_kind_over_udp_tcp_and_serial(tmp_path: Path) -> None:
    path = tmp_path / "corpus.pcapng"
    packets = corpus()
    write_capture(path, packets, seed=7)
    objs = decode_file(path)
    frames = dissect(path)
    compared, fields = compare_capture(objs, frames)
    # each packet crosses three links; UDP datagrams with junk carry a second copy
    assert compared >= 3 * len(packets)
    assert fields > 40 * compared
    assert {o["capture"]["link"] for o in objs} == {"udp", "tcp", "serial"}
    print(f"\ncorpus: {compared} packets, {fields} fields agree")
    # a second pass (what the GUI does when it redraws) shows exactly the same
    two_pass = dissect(path, "-2")
    assert [(f.number, [[(x.name, x.show) for x in i.fields] for i in f.items]) for f in frames] \
        == [(f.number, [[(x.name, x.show) for x in i.fields] for i in f.items]) for f in two_pass]


def test_junk_crc_failures_and_anomalous_packets_are_flagged(tmp_path: Path) -> None:
    path = tmp_path / "bad.pcapng"
    capture = PacketCapture(path)
    capture.acquire()
    bad = bytearray(GCU_EXAMPLE)
    bad[30] ^= 0x10
    capture.udp(GCU, HOST, b"\x00junk" + bytes(bad) + GCU_EXAMPLE)  # junk, CRC error, good
    capture.udp(GCU, HOST, GCU_EXAMPLE[:50])  # truncated
    for packet in anomalous_packets():
        capture.udp(HOST if packet[:2] == b"\xa8\xe5" else GCU, GCU, packet)
    capture.release()
    frames = dissect(path)
    first = frames[0]
    assert [item.kind for item in first.items] == ["junk", "bad", "packet"]
    assert first.items[0].has("xfgcu.junk.expert")
    assert first.items[1].has("xfgcu.crc.bad")
    assert not first.items[2].has("xfgcu.crc.bad")
    assert frames[1].items[0].kind == "junk" and frames[1].items[0].has("xfgcu.truncated")
    anomalous = frames[2:]
    assert len(anomalous) == len(anomalous_packets())
    objs = decode_capture(path.read_bytes())
    flagged = [o for o in objs if o["capture"]["frame"] > 2]
    assert len(flagged) == len(anomalous_packets())
    for frame, obj in zip(anomalous, flagged, strict=True):
        assert [item.kind for item in frame.items] == ["packet"]
        item = frame.items[0]
        assert item.has("xfgcu.anomaly") and item.has("xfgcu.anomaly.expert")
        # liberal receive, as in decode: the same messages, in the same order
        assert [f.show for f in item.named("xfgcu.anomaly")] == [
            a["message"] for a in obj["anomalies"]]
    compare_capture(objs, frames)


def test_random_bytes_never_raise_a_lua_error(tmp_path: Path) -> None:
    rng = random.Random(3)
    path = tmp_path / "noise.pcapng"
    capture = PacketCapture(path)
    capture.acquire()
    headers = (b"\xa8\xe5", b"\x8a\x5e")
    for i in range(300):
        data = bytearray(rng.randbytes(rng.randrange(0, 300)))
        for _ in range(rng.randrange(0, 4)):  # false headers with lengths in and out of range
            if len(data) >= 4:
                at = rng.randrange(0, len(data) - 3)
                length = rng.randrange(0, 400).to_bytes(2, "little")
                data[at : at + 4] = rng.choice(headers) + length
        capture.udp(HOST, GCU, bytes(data))
        capture.tcp(("127.0.0.1", 40001), ("127.0.0.1", 2332), bytes(data))
        capture.serial("/dev/noise", bytes(data), outbound=bool(i % 2))
    capture.release()
    frames = dissect(path)  # raises on any Lua error
    assert frames
    assert not packets_by_stream(frames)  # no CRC-valid packet in the noise


def test_heuristics_find_packets_on_other_ports(tmp_path: Path) -> None:
    path = tmp_path / "ports.pcapng"
    capture = PacketCapture(path)
    capture.acquire()
    a, b = ("127.0.0.5", 40123), ("127.0.0.6", 50321)
    capture.udp(a, b, b"xx" + HOST_EXAMPLE)
    capture.udp(b, a, GCU_EXAMPLE)
    capture.udp(b, a, b"not the protocol at all" * 4)
    capture.tcp_open(a, b)
    capture.tcp(a, b, HOST_EXAMPLE + HOST_EXAMPLE[:10])
    capture.tcp(a, b, HOST_EXAMPLE[10:])
    capture.udp(("::1", 40000), ("::1", 40001), GCU_EXAMPLE)
    capture.release()
    frames = dissect(path)
    found = packets_by_stream(frames)
    assert sum(len(v) for v in found.values()) == 5
    assert ("udp", "[::1]:40000", "[::1]:40001") in found
    compare_capture(decode_capture(path.read_bytes()), frames)


def test_verbose_output_shows_units_names_and_the_decode_digits(tmp_path: Path) -> None:
    path = tmp_path / "vectors.pcapng"
    capture = PacketCapture(path)
    capture.acquire()
    capture.udp(HOST, GCU, HOST_EXAMPLE)
    capture.udp(GCU, HOST, GCU_EXAMPLE)
    capture.release()
    text = verbose(path, "xfgcu")
    for line in (
        "Header: 0xa8e5 (host -> GCU)", "Aircraft roll: -11.32 deg", "Aircraft yaw: 240.0 deg",
        "Latitude: 38.0300822 deg", "GNSS time: 2023-09-07T01:58:20+00:00",
        "Document's rule: 2023-09-07T01:58:38+00:00",
        "Command: NULL (0x00)", "CRC: 0x5d1b [correct]",
        "Mode: POINTING_FOLLOW (0x12)", "Pod status: 0x8001 (TRACKING_OK)",
        "Relative angle X: -8.03 deg", "Camera pitch: 9.33 deg", "Angular rate Z: -0.2 deg/s",
        "Pod model: D-90AI (code 41)", "Target distance: 589.4 m", "Camera 2 zoom: 2.0 x",
        "Time zone: UTC+8", "Feedback to: TAKE_PHOTO (0x20)", "[Result: SUCCESS]",
        ".... .... .... ...1 = Tracking OK: True", "CRC: 0xec85 [correct]",
    ):  # fmt: skip
        assert line in text, line


def test_tcp_retransmissions_and_out_of_order_segments(tmp_path: Path) -> None:
    """Segments resent, overlapping and swapped (a classic pcap, raw IP): both decoders put
    the bytes in sequence order and take each once."""
    import dpkt

    rng = random.Random(9)
    flow = TcpFlow(("127.0.0.1", 41000), ("127.0.0.1", 2332))
    stream = b"".join(corpus()[:40])
    segments = flow.handshake()
    data: list[bytes] = []
    pos = 0
    while pos < len(stream):
        n = rng.randrange(1, 150)
        data.append(flow.data(True, stream[pos : pos + n]))
        pos += n
    shuffled: list[bytes] = []
    for segment in data:
        if shuffled and rng.random() < 0.15:  # swap with the previous one
            shuffled.insert(len(shuffled) - 1, segment)
        else:
            shuffled.append(segment)
        if rng.random() < 0.1:  # resent
            shuffled.append(segment)
    path = tmp_path / "reordered.pcap"
    with path.open("wb") as f:
        writer = dpkt.pcap.Writer(f, linktype=101)
        for i, segment in enumerate([*segments, *shuffled, *flow.finish(True)]):
            writer.writepkt(segment, ts=1_700_000_000 + i / 1000)
    objs = decode_capture(path.read_bytes())
    # Wireshark hands a dissector every segment once its sequence analysis is off ...
    compared, _ = compare_capture(objs, dissect(path, "-o", "tcp.analyze_sequence_numbers:FALSE"))
    assert compared == 40
    # ... and by default none it flags (retransmitted, out of order): the dissector skips the
    # gaps they leave; what it shows is still what decode finds, in the same order
    shown = packets_by_stream(dissect(path))[("tcp", "127.0.0.1:41000", "127.0.0.1:2332")]
    assert 10 < len(shown) < 40
    found = iter(objs)
    for _, item in shown:
        assert any(not compare(o, item) for o in found), "not in decode's order"
