"""Codec benchmark: deframe + decode GCU → host packets, compare with pymavlink, encode.

Run from the repository root::

    .venv/bin/python benchmarks/bench_codec.py            # default: about 20 s
    .venv/bin/python benchmarks/bench_codec.py --seconds 0.2 --repeats 3 --packets 5000

Every figure is measured on one core (one thread, no multiprocessing), in the process's CPU
time (``time.process_time``). Each measurement is
repeated ``--repeats`` times, in rounds that interleave all workloads (each sample runs whole
passes for at least ``--seconds``); the best and the median sample are printed, because the
machine may be shared and noisy. pymavlink comes from the ``mavlink`` extra.
The baseline is a minimal struct-based GCU stream parser written inside this file (find the
header, ``crc_hqx``, ``struct.unpack_from``; no typed objects): the ratio of our stream decode
to it is what the library costs over the least a correct parser does.
Before timing anything, each workload is checked once for correctness (every packet / message
comes back, equal to what was encoded, and the deframer accounts for every byte), so the
timed loops measure real work.
"""

from __future__ import annotations

import argparse
import gc
import os
import platform
import random
import statistics
import struct
import sys
import time
from binascii import crc_hqx
from collections.abc import Callable, Sequence
from typing import Any

from _machine import cpu_model

from gcu_async.protocol import (
    CameraMask,
    ControlValues,
    Deframer,
    Feedback,
    GazeAtCoordinates,
    GcuMainFrame,
    GcuPacket,
    GcuSubFrame,
    HostMainFrame,
    HostPacket,
    HostSubFrame,
    Mode,
    Opcode,
    UnknownSubFrame,
    ZoomTo,
    decode_gcu_packet,
    decode_host_packet,
)

CHUNK = 4096
"""Bytes per ``feed`` in the stream runs: a typical serial/TCP read size."""

TARGET_GCU_PPS = 250_000
TARGET_MAVLINK_RATIO = 5.0
TARGET_MINIMAL_RATIO = 0.6
TARGET_ENCODE_US = 5.0


# --- machine ------------------------------------------------------------------------------
# --- timing -------------------------------------------------------------------------------
def sample_rates(one_pass: Callable[[], int], seconds: float, repeats: int) -> list[float]:
    """Run ``one_pass`` (returns the number of units it processed) in whole passes for at
    least ``seconds`` of this process's CPU time per sample; return units per CPU second of
    each of ``repeats`` samples. CPU time, not wall time: on a shared machine the wall clock
    also counts the time other processes hold the core."""
    rates = []
    for _ in range(repeats):
        gc.collect()
        units = 0
        start = time.process_time()
        deadline = start + seconds
        while True:
            units += one_pass()
            now = time.process_time()
            if now >= deadline:
                break
        rates.append(units / (now - start))
    return rates


def best_median(rates: Sequence[float]) -> tuple[float, float]:
    return max(rates), statistics.median(rates)


# --- GCU → host stream --------------------------------------------------------------------
def _gcu_packet(rng: random.Random, i: int) -> GcuPacket:
    """One of several realistic reply shapes: telemetry with / without the sub frame, command
    feedback with success, failure, a zoom camera mask, calibration in progress, an unknown
    sub frame, protocol version 1."""
    main = GcuMainFrame(
        rng.choice([Mode.POINTING_LOCK, Mode.POINTING_FOLLOW, Mode.TRACK, Mode.GAZE]),
        rng.randrange(0, 0x10000) & 0x1781,
        rng.randint(-1000, 1000),
        rng.randint(-1000, 1000),
        rng.randint(-18000, 17999),
        rng.randint(-9000, 9000),
        rng.randint(-18000, 17999),
        rng.randint(-9000, 9000),
        rng.randint(-18000, 17999),
        rng.randint(0, 35999),
        rng.randint(-3000, 3000),
        rng.randint(-3000, 3000),
        rng.randint(-3000, 3000),
    )
    sub: GcuSubFrame | UnknownSubFrame | None = GcuSubFrame(
        31, 50, 41, 0, rng.randint(-10, 50_000),
        rng.randint(-1_800_000_000, 1_800_000_000), rng.randint(-900_000_000, 900_000_000),
        rng.randint(-100_000, 5_000_000), rng.randint(10, 300), 20, 0, 0x2000, 8,
    )  # fmt: skip
    feedback = Feedback(Opcode.NULL)
    version = 2
    kind = i % 16
    if kind in (1, 5, 9, 13):  # no sub frame requested
        sub = None
    elif kind == 2:
        feedback = Feedback(Opcode.TAKE_PHOTO, 0)
    elif kind == 6:
        feedback = Feedback(Opcode.ZOOM_TO, int(CameraMask.CAMERA_2))  # camera 2 failed
    elif kind == 10:
        feedback = Feedback(Opcode.CALIBRATION, 2)  # in progress
    elif kind == 14:
        feedback = Feedback(Opcode.PALETTE, 2)  # thermal failure
    elif kind == 11:
        sub = UnknownSubFrame(0x02, bytes(rng.randrange(256) for _ in range(31)))
    elif kind == 15:
        version = 1
    return GcuPacket(main, sub, feedback, version)


def _junk(rng: random.Random, packet: bytes) -> bytes:
    """Garbage between packets: random noise (never a header byte), a false header with an
    impossible length, a corrupted copy of a packet (CRC error), a truncated packet, or a lone
    header byte."""
    choice = rng.randrange(5)
    if choice == 0:
        return bytes(b if b != 0x8A else 0x00 for b in rng.randbytes(rng.randint(1, 40)))
    if choice == 1:
        return b"\x8a\x5e" + rng.choice([b"\x05\x00", b"\xff\x7f", b"\x00\x10"]) + b"\x02\x11"
    if choice == 2:
        bad = bytearray(packet)
        bad[rng.randrange(5, len(bad) - 2)] ^= 0x5A
        return bytes(bad)
    if choice == 3:
        return packet[: rng.randint(5, len(packet) - 1)]
    return b"\x8a"


def build_gcu_stream(n_packets: int, seed: int) -> tuple[bytes, list[bytes], list[GcuPacket]]:
    """A mixed stream of ``n_packets`` valid packets; 1 in 20 is preceded by junk."""
    rng = random.Random(seed)
    packets = [_gcu_packet(rng, i) for i in range(n_packets)]
    wires = [p.encode() for p in packets]
    parts: list[bytes] = []
    for i, wire in enumerate(wires):
        if i % 20 == 7:
            parts.append(_junk(rng, wires[i - 1]))
        parts.append(wire)
    return b"".join(parts), wires, packets


def chunks_of(data: bytes, size: int) -> list[bytes]:
    return [data[i : i + size] for i in range(0, len(data), size)]


def gcu_stream_pass(chunks: Sequence[bytes]) -> int:
    """One pass: fresh deframer, feed every chunk, decode every packet. Returns packets."""
    deframer = Deframer.for_gcu_packets()
    feed = deframer.feed
    decode = decode_gcu_packet
    count = 0
    for chunk in chunks:
        for raw in feed(chunk):
            decode(raw)
            count += 1
    return count


def check_gcu(chunks: Sequence[bytes], stream: bytes, expected: Sequence[GcuPacket]) -> str:
    """Every packet back, equal to what was encoded, every byte accounted for; the stats."""
    deframer = Deframer.for_gcu_packets()
    got: list[bytes] = []
    for chunk in chunks:
        got.extend(deframer.feed(chunk))
    decoded = [decode_gcu_packet(raw) for raw in got]
    if decoded != list(expected):
        raise SystemExit(f"GCU check failed: {len(decoded)} decoded, {len(expected)} expected")
    st = deframer.stats
    accounted = sum(map(len, got)) + st.bytes_discarded + deframer.buffered
    if accounted != len(stream) or st.packets != len(expected):
        raise SystemExit(f"GCU check failed: {accounted} of {len(stream)} bytes accounted for")
    return (f"{st.packets} packets, {st.bytes_discarded} B discarded, {st.crc_errors} CRC"
            f" errors, {st.length_errors} length errors")  # fmt: skip


# --- minimal struct-based parser: the baseline ---------------------------------------------
_MIN_BODY = struct.Struct("<2sHB" "BHhhhhhhhHhhh7x" "B" "BBBHiiiiHHBHb2x" "B")
"""Bytes 0–69 of a GCU reply, written out from the document (not from gcu_async)."""


def minimal_stream_pass(chunks: Sequence[bytes]) -> int:
    """The least a correct GCU stream parser does, written for speed and nothing else: find
    the header, read the length (72–88), check the CRC, unpack bytes 0–69 into a tuple (no
    typed objects, no counters, no anomalies). Returns packets."""
    return len(minimal_stream_parse(chunks))


def minimal_stream_parse(chunks: Sequence[bytes]) -> list[tuple[Any, ...]]:
    unpack = _MIN_BODY.unpack_from
    out: list[tuple[Any, ...]] = []
    append = out.append
    buf = b""
    for chunk in chunks:
        buf = buf + chunk if buf else chunk
        n = len(buf)
        pos = 0
        while True:
            i = buf.find(b"\x8a\x5e", pos)
            if i < 0:
                pos = n - 1 if n > pos and buf[n - 1] == 0x8A else n
                break
            if n - i < 4:
                pos = i
                break
            end = i + (buf[i + 2] | buf[i + 3] << 8)
            if not 72 <= end - i <= 88:
                pos = i + 1
                continue
            if end > n:
                pos = i
                break
            if crc_hqx(buf[i:end], 0):
                pos = i + 1
                continue
            append(unpack(buf, i))
            pos = end
        buf = buf[pos:]
    return out


def check_minimal(chunks: Sequence[bytes], expected: Sequence[GcuPacket]) -> None:
    """The baseline finds every packet, each unpacked to the fields our decoder gives."""
    got = minimal_stream_parse(chunks)
    if len(got) != len(expected):
        raise SystemExit(f"minimal parser check failed: {len(got)} of {len(expected)} packets")
    for fields, packet in zip(got, expected, strict=True):
        if fields[3:16] != tuple(packet.main) or fields[2] != packet.version:
            raise SystemExit(f"minimal parser check failed: {fields} is not {packet}")


# --- pymavlink ----------------------------------------------------------------------------
def build_mavlink_stream(n_messages: int, seed: int) -> tuple[bytes, list[bytes], Any]:
    """ATTITUDE and GLOBAL_POSITION_INT alternately, MAVLink 2, packed by pymavlink."""
    from pymavlink.dialects.v20 import common as mavlink2

    rng = random.Random(seed)
    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=154)
    wires = []
    for i in range(n_messages):
        t = 1000 + i * 20
        if i % 2 == 0:
            msg = mav.attitude_encode(
                t, rng.uniform(-3, 3), rng.uniform(-1.5, 1.5), rng.uniform(-3, 3),
                rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1),
            )  # fmt: skip
        else:
            msg = mav.global_position_int_encode(
                t, rng.randint(-900_000_000, 900_000_000),
                rng.randint(-1_800_000_000, 1_800_000_000), rng.randint(1, 5_000_000),
                rng.randint(1, 500_000), rng.randint(-3000, 3000),
                rng.randint(-3000, 3000), rng.randint(-500, 500), rng.randint(0, 35999),
            )  # fmt: skip
        wires.append(bytes(msg.pack(mav)))
        mav.seq = (mav.seq + 1) % 256
    return b"".join(wires), wires, mavlink2


def mavlink_buffer_pass(mavlink2: Any, chunks: Sequence[bytes]) -> int:
    """One pass: fresh parser, ``parse_buffer(chunk)`` per chunk. Returns messages."""
    parse = mavlink2.MAVLink(None).parse_buffer
    count = 0
    for chunk in chunks:
        msgs = parse(chunk)
        if msgs:
            count += len(msgs)
    return count


def mavlink_char_pass(mavlink2: Any, datagrams: Sequence[bytes]) -> int:
    """One pass: fresh parser, ``parse_char(message)`` per whole message. Returns messages."""
    parse = mavlink2.MAVLink(None).parse_char
    count = 0
    for datagram in datagrams:
        if parse(datagram) is not None:
            count += 1
    return count


def check_mavlink(mavlink2: Any, chunks: Sequence[bytes], wires: Sequence[bytes]) -> None:
    mav = mavlink2.MAVLink(None)
    got: list[Any] = []
    for chunk in chunks:
        got.extend(mav.parse_buffer(chunk) or [])
    if [bytes(m.get_msgbuf()) for m in got] != list(wires):
        raise SystemExit(f"pymavlink check failed: {len(got)} of {len(wires)} messages")
    names = {m.get_type() for m in got}
    if names != {"ATTITUDE", "GLOBAL_POSITION_INT"}:
        raise SystemExit(f"pymavlink check failed: message types {names}")


# --- host packet encode -------------------------------------------------------------------
def prebuilt_host_parts() -> tuple[HostMainFrame, HostSubFrame, GazeAtCoordinates]:
    main = HostMainFrame.build(
        control=ControlValues.rates(0.0, -5.0, 12.5, zoom=2.0),
        attitude=(1.5, -2.25, 271.3),
        acceleration=(0.12, -0.04, 0.01),
        velocity=(12.3, -4.5, 0.6),
    )
    sub = HostSubFrame.build(
        latitude=38.0300822, longitude=170.9175332, altitude=123.456, satellites=17,
        gnss_week=2310, gnss_ms=345_678_900, relative_altitude=80.0,
    )  # fmt: skip
    command = GazeAtCoordinates(latitude=38.03, longitude=170.92, altitude=41.123)
    return main, sub, command


def encode_prebuilt_pass(parts: tuple[HostMainFrame, HostSubFrame, Any], n: int) -> int:
    main, sub, command = parts
    for _ in range(n):
        HostPacket(main, sub, command).encode()
    return n


def encode_from_units_pass(n: int) -> int:
    for i in range(n):
        main = HostMainFrame.build(
            control=ControlValues.angles(0.0, -30.0 + (i & 7), 45.0),
            attitude=(1.5, -2.25, 271.3),
            acceleration=(0.12, -0.04, 0.01),
            velocity=(12.3, -4.5, 0.6),
        )
        sub = HostSubFrame.build(
            latitude=38.0300822, longitude=170.9175332, altitude=123.456, satellites=17,
            gnss_week=2310, gnss_ms=345_678_900, relative_altitude=80.0,
        )  # fmt: skip
        HostPacket(main, sub, ZoomTo(ratio=10.0 + (i & 7))).encode()
    return n


# --- main ---------------------------------------------------------------------------------
def _rate_line(label: str, rates: Sequence[float], unit: str, bytes_per_unit: float) -> str:
    best, med = best_median(rates)
    return (
        f"  {label:<24}: best {best:>9,.0f} {unit}/s {best * bytes_per_unit / 1e6:6.2f} MB/s"
        f" | median {med:>9,.0f} {unit}/s {med * bytes_per_unit / 1e6:6.2f} MB/s"
    )


def _us_line(label: str, rates: Sequence[float]) -> tuple[str, float]:
    best, med = 1e6 / max(rates), 1e6 / statistics.median(rates)
    return f"  {label:<44}: best {best:5.2f} us | median {med:5.2f} us per packet", best


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--packets", type=int, default=20_000,
                    help="valid GCU packets (and MAVLink messages) per stream [20000]")
    ap.add_argument("--seconds", type=float, default=0.4,
                    help="minimum duration of one sample [0.4]")
    ap.add_argument("--repeats", type=int, default=5,
                    help="samples per measurement, taken in interleaved rounds [5]")
    ap.add_argument("--seed", type=int, default=2006, help="random seed of the streams")
    args = ap.parse_args(argv)  # fmt: skip
    if args.packets < 40 or args.seconds <= 0 or args.repeats < 1:
        ap.error("need --packets >= 40, --seconds > 0, --repeats >= 1")

    try:
        import pymavlink
    except ImportError:
        raise SystemExit("pymavlink is missing: .venv/bin/pip install -e '.[mavlink]'") from None

    print("gcu_async codec benchmark")
    print(f"  python    : {platform.python_implementation()} {platform.python_version()}"
          f" ({sys.executable})")
    print(f"  cpu       : {cpu_model()} ({platform.machine()}, {os.cpu_count()} logical CPUs);"
          " one core, one thread")
    print(f"  pymavlink : {getattr(pymavlink, '__version__', '?')}")
    print(f"  sampling  : {args.repeats} interleaved rounds, each sample >= {args.seconds:g} s"
          " of process CPU time;"
          " best and median shown")  # fmt: skip

    # workloads, each checked once before anything is timed
    stream, gcu_wires, gcu_packets = build_gcu_stream(args.packets, args.seed)
    chunks = chunks_of(stream, CHUNK)
    stream_stats = check_gcu(chunks, stream, gcu_packets)
    check_minimal(chunks, gcu_packets)
    check_gcu(gcu_wires, b"".join(gcu_wires), gcu_packets)
    mstream, mwires, mavlink2 = build_mavlink_stream(args.packets, args.seed)
    mchunks = chunks_of(mstream, CHUNK)
    check_mavlink(mavlink2, mchunks, mwires)
    parts = prebuilt_host_parts()
    zoom_parts = (parts[0], parts[1], ZoomTo(ratio=30.0))
    for p in (parts, zoom_parts):
        if decode_host_packet(HostPacket(*p).encode()) != HostPacket(*p):
            raise SystemExit("encode check failed: the packet does not decode to itself")
    n_enc = 2000

    workloads: dict[str, Callable[[], int]] = {
        "gcu_stream": lambda: gcu_stream_pass(chunks),
        "minimal_stream": lambda: minimal_stream_pass(chunks),
        "gcu_datagram": lambda: gcu_stream_pass(gcu_wires),
        "mav_buffer": lambda: mavlink_buffer_pass(mavlink2, mchunks),
        "mav_char": lambda: mavlink_char_pass(mavlink2, mwires),
        "encode_gaze": lambda: encode_prebuilt_pass(parts, n_enc),
        "encode_zoom": lambda: encode_prebuilt_pass(zoom_parts, n_enc),
        "encode_units": lambda: encode_from_units_pass(n_enc),
    }
    rates: dict[str, list[float]] = {name: [] for name in workloads}
    for _ in range(args.repeats):  # rounds: machine noise hits every workload alike
        for name, one_pass in workloads.items():
            rates[name] += sample_rates(one_pass, args.seconds, 1)

    gcu_bpp = len(stream) / len(gcu_wires)
    gram_bpp = sum(map(len, gcu_wires)) / len(gcu_wires)
    n_junk = len(stream) - sum(map(len, gcu_wires))
    print(f"\nGCU -> host: {len(gcu_wires)} packets of 72/73 B + {n_junk} B of junk"
          f" = {len(stream)} B; Deframer.for_gcu_packets().feed(chunk) + decode_gcu_packet"
          " per packet (MB = 1e6 B)")  # fmt: skip
    print(f"  deframer stats per stream pass: {stream_stats}")
    print(_rate_line(f"stream, {CHUNK}-B feeds", rates["gcu_stream"], "pkt", gcu_bpp))
    print(_rate_line("one packet per feed", rates["gcu_datagram"], "pkt", gram_bpp))
    print(_rate_line("minimal parser (baseline)", rates["minimal_stream"], "pkt", gcu_bpp))
    min_best = max(rates["gcu_stream"]) / max(rates["minimal_stream"])
    min_med = statistics.median(rates["gcu_stream"]) / statistics.median(rates["minimal_stream"])
    print(f"  bytes/s ratio, ours ({CHUNK}-B stream) / minimal struct parser (find header,"
          f" crc_hqx, unpack_from; same chunks): best {min_best:.2f}x | median {min_med:.2f}x")

    mav_bpm = len(mstream) / len(mwires)
    print(f"\npymavlink: {len(mwires)} MAVLink 2 messages, ATTITUDE + GLOBAL_POSITION_INT"
          f" alternately, {len(mstream)} B; fresh MAVLink(None) per pass, CRC via"
          f" {mavlink2.x25crc.__name__} (no junk: pymavlink raises on it by default)")  # fmt: skip
    print(_rate_line(f"parse_buffer({CHUNK}-B)", rates["mav_buffer"], "msg", mav_bpm))
    print(_rate_line("parse_char(1 message)", rates["mav_char"], "msg", mav_bpm))
    # the ratio: our stream path against pymavlink's faster path (best vs best, median vs
    # median), and like for like: one packet / message per call on both sides
    ref = "mav_buffer" if max(rates["mav_buffer"]) >= max(rates["mav_char"]) else "mav_char"
    ref_name = f"parse_buffer({CHUNK}-B)" if ref == "mav_buffer" else "parse_char(1 message)"
    ours_best, ours_med = best_median([r * gcu_bpp for r in rates["gcu_stream"]])
    ref_best, ref_med = best_median([r * mav_bpm for r in rates[ref]])
    ratio_best, ratio_med = ours_best / ref_best, ours_med / ref_med
    print(f"  bytes/s ratio, ours ({CHUNK}-B stream) / pymavlink {ref_name} (its faster"
          f" path): best {ratio_best:.2f}x | median {ratio_med:.2f}x")  # fmt: skip
    g_best, g_med = best_median([r * gram_bpp for r in rates["gcu_datagram"]])
    c_best, c_med = best_median([r * mav_bpm for r in rates["mav_char"]])
    print(f"  bytes/s ratio, one packet per feed / parse_char(1 message):"
          f" best {g_best / c_best:.2f}x | median {g_med / c_med:.2f}x")  # fmt: skip

    print("\nHost packet encode, main + sub frame + command with parameters:")
    line, enc_best = _us_line("HostPacket(..., GazeAtCoordinates).encode()", rates["encode_gaze"])
    print(line + " (84 B; parts pre-built)")
    line, _ = _us_line("HostPacket(..., ZoomTo).encode()", rates["encode_zoom"])
    print(line + " (75 B; parts pre-built)")
    line, _ = _us_line("build from units + encode", rates["encode_units"])
    print(line + " (HostMainFrame.build, HostSubFrame.build, ZoomTo, encode)")

    pps_best = max(rates["gcu_stream"])
    print("\nTargets (best sample):")
    rows = [
        (f"GCU packets/s >= {TARGET_GCU_PPS:,} (stream)", pps_best >= TARGET_GCU_PPS,
         f"{pps_best:,.0f}"),
        (f"bytes/s >= {TARGET_MINIMAL_RATIO}x minimal parser", min_best >= TARGET_MINIMAL_RATIO,
         f"{min_best:.2f}x"),
        (f"bytes/s >= {TARGET_MAVLINK_RATIO}x pymavlink", ratio_best >= TARGET_MAVLINK_RATIO,
         f"{ratio_best:.2f}x"),
        (f"full host packet encode <= {TARGET_ENCODE_US} us", enc_best <= TARGET_ENCODE_US,
         f"{enc_best:.2f} us (GazeAtCoordinates)"),
    ]  # fmt: skip
    for name, ok, value in rows:
        print(f"  {'met ' if ok else 'MISSED'} {name:<40} {value}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
