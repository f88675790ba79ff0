"""Captures read as streams: damage is an error naming where, after every packet before it.

Regressions of issue 17 (out-of-order TCP segments recursing, a truncated pcap record
header raising ``dpkt.NeedData``, a pcapng damaged mid-file ending silently with exit 0,
bad-CRC input explained), then hypothesis: mutated pcap and pcapng files (bit flips,
truncation, insertion, damaged length fields) through the real CLI code never give a
traceback — either the packets, or the packets before the damage and one error line that
names the record or block and its offset. (TCP segment orders: test_capture_reassembly.py.)
"""

from __future__ import annotations

import contextlib
import io
import random
import struct
from collections import Counter
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from gcu_async.capture.synth import TcpFlow, udp_packet
from gcu_async.cli import main
from gcu_async.cli.decode import decode_capture
from helpers.protocol.vectors import GCU_EXAMPLE, HOST_EXAMPLE
from helpers.scale import scaled
from helpers.wireshark.xfgcu_corpus import corpus, write_capture

HOST, GCU = ("127.0.0.1", 40000), ("127.0.0.2", 2337)
RAW_IP = 101


def pcap(records: list[bytes], *, linktype: int = RAW_IP) -> bytes:
    """A classic little-endian microsecond pcap file (written here, not by the reader's code)."""
    out = [struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, linktype)]
    for n, data in enumerate(records):
        out.append(struct.pack("<IIII", 1_700_000_000 + n, n, len(data), len(data)) + data)
    return b"".join(out)


def tcp_records(payloads: list[bytes]) -> list[bytes]:
    """A handshake, then one data segment per payload from HOST to GCU."""
    flow = TcpFlow(HOST, GCU)
    return [*flow.handshake(), *(flow.data(True, p) for p in payloads)]


def run_decode(path: Path, *extra: str) -> tuple[int, list[dict[str, Any]], list[str]]:
    """The real ``gcu-async decode`` code in this process: (status, objects, stderr lines)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(["decode", "--file", str(path), *extra])
    import json

    objs = [json.loads(line) for line in out.getvalue().splitlines()]
    return status, objs, err.getvalue().splitlines()


def errors_only(lines: list[str]) -> list[str]:
    return [line for line in lines if ": flagged: " not in line]


# -- regressions ---------------------------------------------------------------------------
def test_thousands_of_out_of_order_segments_do_not_recurse(tmp_path: Path) -> None:
    """5,000 one-byte segments in reverse order: old reassembly recursed once per waiting
    segment (RecursionError past ~600); now a loop, and the packets come out whole."""
    stream = (HOST_EXAMPLE * 70)[:5000]
    records = tcp_records([stream[i : i + 1] for i in range(len(stream))])
    path = tmp_path / "reversed.pcap"
    path.write_bytes(pcap(records[:3] + records[3:][::-1]))
    objs = decode_capture(path.read_bytes())
    assert len(objs) == len(stream) // len(HOST_EXAMPLE)
    assert {o["capture"]["frame"] for o in objs} == {3 + len(stream)}  # the gap filled last


def test_a_truncated_pcap_record_header_is_one_line_naming_the_offset(tmp_path: Path) -> None:
    udp = udp_packet(HOST, GCU, HOST_EXAMPLE)
    data = pcap([udp, udp])
    path = tmp_path / "cut.pcap"
    path.write_bytes(data + struct.pack("<II", 1, 2))  # 8 of a record header's 16 bytes
    status, objs, err = run_decode(path)
    assert status == 1
    assert len(objs) == 2  # the two records before the damage
    want = (
        f"gcu-async decode: {path}: damaged capture after 2 packets: record 3 header at "
        f"offset {len(data)}: truncated: 16 bytes needed, 8 present"
    )
    assert err == [want]


def test_a_pcapng_damaged_mid_file_shows_the_packets_before_then_fails(tmp_path: Path) -> None:
    path = tmp_path / "mid.pcapng"
    write_capture(path, [HOST_EXAMPLE, GCU_EXAMPLE, HOST_EXAMPLE], links=("udp",), junk_rate=0)
    data = bytearray(path.read_bytes())
    offsets = [source_offset for source_offset, _ in _block_offsets(bytes(data))]
    second_packet = offsets[3]  # SHB, IDB, packet 1, packet 2, packet 3
    data[second_packet + 4 : second_packet + 8] = struct.pack("<I", 13)  # not a multiple of 4
    path.write_bytes(bytes(data))
    status, objs, err = run_decode(path)
    assert status == 1
    assert [o["capture"]["frame"] for o in objs] == [1]
    assert len(err) == 1 and f"block 4 (type 0x00000006) at offset {second_packet}" in err[0]
    assert "block length 13 is not a multiple of 4" in err[0]


def _block_offsets(data: bytes) -> list[tuple[int, int]]:
    """(offset, length) of every pcapng block (little-endian), read independently."""
    out, at = [], 0
    while at + 8 <= len(data):
        length = struct.unpack_from("<I", data, at + 4)[0]
        out.append((at, length))
        at += length
    return out


@pytest.mark.parametrize(("hex_text", "reason"), [
    ((GCU_EXAMPLE[:-1] + b"\x00").hex(), "a GCU reply of 73 bytes at offset 0 failed its CRC: "
                                          "computed 0x"),
    ("00 11 " + (HOST_EXAMPLE[:-2] + b"\xff\xff").hex(), "a host packet of "
     f"{len(HOST_EXAMPLE)} bytes at offset 2 failed its CRC: computed 0x"),
    (GCU_EXAMPLE[:-1].hex(), "a GCU reply at offset 0 is cut short: its header declares 73 "
                             "bytes, the input ends after 72"),
    ("8a 5e 05 00" + " 00" * 80, "a GCU reply header at offset 0 declares a length of 5 bytes"),
])  # fmt: skip
def test_no_valid_packet_says_what_was_wrong(hex_text: str, reason: str) -> None:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(["decode", hex_text])
    assert status == 1 and out.getvalue() == ""
    (line,) = err.getvalue().splitlines()
    assert reason in line, line
    if "CRC" in reason:  # the carried CRC is the packet's last two bytes, as printed
        data = bytes.fromhex(hex_text.replace(" ", ""))
        assert line.endswith(f"carried 0x{data[-2:].hex().upper()}")


# -- fuzzing: mutated files ----------------------------------------------------------------
def _base_files(tmp: Path) -> dict[str, bytes]:
    rng = random.Random(7)
    batch = [rng.choice(corpus()) for _ in range(12)]
    write_capture(tmp / "base.pcapng", batch, seed=3, junk_rate=0.3)
    ng = (tmp / "base.pcapng").read_bytes()
    flow = TcpFlow(HOST, GCU)
    stream = b"".join(batch)
    cuts = sorted(rng.sample(range(1, len(stream)), 10))
    pieces = [stream[a:b] for a, b in zip([0, *cuts], [*cuts, len(stream)], strict=True)]
    records = [udp_packet(HOST, GCU, p) for p in batch[:6]]
    records += [*flow.handshake(), *(flow.data(True, p) for p in pieces), *flow.finish(True)]
    return {"pcapng": ng, "pcap": pcap(records)}


_BASES: dict[str, bytes] = {}


def base(kind: str, tmp: Path) -> bytes:
    if not _BASES:
        _BASES.update(_base_files(tmp))
    return _BASES[kind]


def frame_ends(data: bytes) -> list[int]:
    """The file offset where each frame's record or block ends (read here, independently:
    pcap records, or the packet blocks 2, 3, 6 of a little-endian pcapng)."""
    ends = []
    if data[:4] == b"\x0a\x0d\x0d\x0a":
        for at, length in _block_offsets(data):
            if struct.unpack_from("<I", data, at)[0] in (2, 3, 6):
                ends.append(at + length)
        return ends
    at = 24
    while at + 16 <= len(data):
        at += 16 + struct.unpack_from("<I", data, at + 8)[0]
        ends.append(at)
    return ends


mutations = st.one_of(
    st.tuples(st.just("flip"), st.integers(0, 2**31), st.integers(0, 7)),
    st.tuples(st.just("truncate"), st.integers(0, 2**31), st.just(0)),
    st.tuples(st.just("insert"), st.integers(0, 2**31), st.integers(1, 64)),
    st.tuples(st.just("length"), st.integers(0, 2**31), st.integers(0, 2**32 - 1)),
)


def mutate(data: bytes, kind: str, where: int, arg: int) -> tuple[bytes, int]:
    """The mutated file and the first offset it differs at."""
    at = where % (len(data) + (kind in ("truncate", "insert")))
    if kind == "flip":
        out = bytearray(data)
        out[at] ^= 1 << arg
        return bytes(out), at
    if kind == "truncate":
        return data[:at], at
    if kind == "insert":
        return data[:at] + random.Random(arg).randbytes(arg) + data[at:], at
    at -= at % 4  # a 32-bit field: a record/block length, a captured length, ...
    at = min(at, len(data) - 4)
    return data[:at] + struct.pack("<I", arg) + data[at + 4 :], at


@settings(max_examples=scaled(200, 25), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(kind=st.sampled_from(["pcap", "pcapng"]), mutation=mutations)
def test_mutated_captures_give_packets_or_one_clear_error(
    kind: str, mutation: tuple[str, int, int], tmp_path_factory: pytest.TempPathFactory
) -> None:
    tmp = tmp_path_factory.getbasetemp()
    original = base(kind, tmp)
    data, changed = mutate(original, *mutation)
    path = tmp / f"mutated.{kind}"
    path.write_bytes(data)
    status, objs, err = run_decode(path)
    errors = errors_only(err)
    event(f"{mutation[0]}: exit {status}")
    assert status in (0, 1)
    assert not any("Traceback" in line for line in err)
    assert all(line.startswith("gcu-async decode: ") for line in err)
    if status == 0:
        assert not errors and objs
    else:
        assert len(errors) == 1, errors
        assert " offset " in errors[0] or "no valid packet" in errors[0]
    # nothing before the first changed byte is lost: every packet of a frame that ended
    # before it (in the original) comes out of the mutated file the same
    ends = frame_ends(original)
    intact = sum(1 for end in ends if end <= changed)
    full = decode_capture(original)
    before = Counter(repr(o) for o in full if o["capture"]["frame"] <= intact)
    got = Counter(repr(o) for o in objs)
    assert not before - got


def test_the_documented_bounds_are_the_codes() -> None:
    """docs/wireshark.md and docs/cli.md state the reader's bounds: the same numbers."""
    from gcu_async.capture.blocks import CHUNK, MAX_BLOCK, MAX_PACKET
    from gcu_async.capture.decoding import MAX_HELD
    from gcu_async.capture.reassembly import MAX_STREAMS, SEGMENT_COST, WAITING_BUDGET
    from gcu_async.cli.decode import RAW_PROBE

    docs = Path(__file__).resolve().parent.parent.parent / "docs"
    wireshark = " ".join((docs / "wireshark.md").read_text().split())
    cli = " ".join((docs / "cli.md").read_text().split())
    for fact in (f"longer than {MAX_PACKET:,} bytes", f"over {MAX_BLOCK:,} bytes",
                 f"{CHUNK >> 20} MiB reads", f"at most {WAITING_BUDGET >> 20} MiB",
                 f"with {SEGMENT_COST} bytes", f"most {MAX_STREAMS} TCP/serial",
                 f"at most {MAX_HELD:,} of them"):  # fmt: skip
        assert fact in wireshark, fact
    assert f"first {RAW_PROBE >> 20} MiB" in cli


def test_a_quiet_stream_with_a_partial_packet_does_not_hold_everything_back() -> None:
    """A TCP stream ends in a false header (its span could still complete) and goes quiet;
    2,000 UDP packets follow. They wait to be put in frame order only up to MAX_HELD: the
    first comes out after at most MAX_HELD more, well before the end of the file."""
    from gcu_async.capture.blocks import Source
    from gcu_async.capture.decoding import MAX_HELD, CaptureDecoder

    flow = TcpFlow(HOST, GCU)
    records = [*flow.handshake(), flow.data(True, HOST_EXAMPLE + b"\xa8\xe5\x49\x00")]
    records += [udp_packet(GCU, HOST, GCU_EXAMPLE)] * 2000
    stream = io.BytesIO(pcap(records))
    decoder = iter(CaptureDecoder(Source(stream)))
    first = next(decoder)
    assert first["capture"]["frame"] == 4  # the TCP packet before its stream's false header
    frames = [next(decoder)["capture"]["frame"]]
    udp_record = 16 + len(records[-1])
    assert stream.tell() <= len(pcap(records[:4])) + (MAX_HELD + 2) * udp_record
    assert stream.tell() < len(stream.getvalue()) * 0.6
    assert frames == [5]
    rest = [obj["capture"]["frame"] for obj in decoder]
    assert rest == list(range(6, 6 + 1999))
    assert MAX_HELD < 1999
