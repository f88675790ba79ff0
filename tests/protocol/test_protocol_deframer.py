"""Streaming deframer: any chunking, junk, false headers, CRC failures; exact counters for
hand-made cases; bounded buffering; the byte accounting invariant; and the fuzz contract.

What the deframer guarantees (the module docstring of ``deframer.py`` states it; the
contract itself, against a reference parse, is tested in test_protocol_deframer_contract.py):

* What comes out, and every counter, depends on the bytes fed, never on how they were split.
* A stream of valid packets yields exactly those packets; a valid packet nested in another
  is part of it, never a packet of its own.
* Every fed byte ends up in exactly one of: a returned packet, ``bytes_discarded``,
  ``buffered``; and ``buffered < max_length`` after every feed.
* Junk never swallows a valid packet that follows it: a false header with an in-range length
  holds the packets after it back until its span is in (at most ``max_length - 1`` bytes
  from where it starts), then its CRC fails and they come out.
* The one exception is inherent: junk whose bytes happen to form a CRC-valid frame (2^-16
  per false header) is a packet as far as any deframer can tell.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Sequence

import pytest
from hypothesis import event, given, reject
from hypothesis import strategies as st

from gcu_async.protocol import (
    GCU_HEADER,
    HOST_HEADER,
    Deframer,
    GazeAtCoordinates,
    GcuMainFrame,
    GcuPacket,
    HostMainFrame,
    HostPacket,
    UnknownCommand,
    crc16_xmodem,
    decode_packet,
)
from gcu_async.protocol.deframer import GCU_MAX_LENGTH, HOST_MAX_LENGTH
from gcu_async.protocol.packets import BASE_LENGTH, MAX_LENGTH
from helpers.protocol.strategies import gcu_packets, host_packets, seal
from helpers.protocol.vectors import GCU_EXAMPLE, HOST_EXAMPLE

VECTORS = {"gcu": (GCU_HEADER, GCU_EXAMPLE), "host": (HOST_HEADER, HOST_EXAMPLE)}


class Feeder:
    """A deframer plus bookkeeping; checks the invariants after every feed."""

    def __init__(self, header: bytes, max_length: int = MAX_LENGTH) -> None:
        self.d = Deframer(header, max_length=max_length)
        self.header = header
        self.max_length = max_length
        self.fed = 0
        self.out: list[bytes] = []

    def feed(self, chunk: bytes) -> list[bytes]:
        got = self.d.feed(chunk)
        self.fed += len(chunk)
        self.out += got
        self.check()
        return got

    def feed_all(self, chunks: Iterable[bytes]) -> list[bytes]:
        for chunk in chunks:
            self.feed(chunk)
        return self.out

    def check(self) -> None:
        d = self.d
        assert d.buffered < self.max_length
        assert sum(map(len, self.out)) + d.stats.bytes_discarded + d.buffered == self.fed
        assert d.stats.packets == len(self.out)
        for p in self.out:
            assert is_valid_frame(p, self.header, self.max_length)

    def counters(self) -> tuple[int, int, int, int, int]:
        s = self.d.stats
        return s.packets, s.bytes_discarded, s.crc_errors, s.length_errors, self.d.buffered


def is_valid_frame(p: bytes, header: bytes, max_length: int = MAX_LENGTH) -> bool:
    return (
        p[:2] == header
        and BASE_LENGTH <= len(p) <= max_length
        and int.from_bytes(p[2:4], "little") == len(p)
        and crc16_xmodem(p[:-2]).to_bytes(2, "big") == p[-2:]
    )


def chunks_at(data: bytes, cuts: Iterable[int]) -> list[bytes]:
    bounds = [0, *sorted(cuts), len(data)]
    return [data[a:b] for a, b in itertools.pairwise(bounds)]


def every_split(data: bytes) -> Iterable[list[bytes]]:
    for k in range(len(data) + 1):
        yield [data[:k], data[k:]]


def is_subsequence(needles: Sequence[bytes], haystack: Sequence[bytes]) -> bool:
    it = iter(haystack)
    return all(any(n == h for h in it) for n in needles)


def flip(data: bytes, bit: int) -> bytes:
    b = bytearray(data)
    b[bit // 8] ^= 1 << (bit % 8)
    return bytes(b)


def false_header(header: bytes, length: int) -> bytes:
    return header + length.to_bytes(2, "little")


# --- vectors: whole, byte by byte, every split ---------------------------------------------------
@pytest.mark.parametrize("name", VECTORS)
def test_vector_whole_byte_by_byte_and_every_split(name: str) -> None:
    header, vec = VECTORS[name]
    ways = [[vec], [vec[i : i + 1] for i in range(len(vec))], *every_split(vec)]
    for chunks in ways:
        f = Feeder(header)
        assert f.feed_all(chunks) == [vec]
        assert f.counters() == (1, 0, 0, 0, 0)


@pytest.mark.parametrize("name", VECTORS)
def test_stream_with_junk_every_split_exact_counters(name: str) -> None:
    header, vec = VECTORS[name]
    # leading junk ends in the first header byte (it must not merge), trailing junk ends in a
    # first header byte that stays buffered: the second may still arrive
    lead, mid, tail = b"\x00\xff" + header[:1], b"\x13\x37", b"\x01\x02" + header[:1]
    stream = lead + vec + mid + vec + vec + tail
    for chunks in [[stream], [stream[i : i + 1] for i in range(len(stream))], *every_split(stream)]:
        f = Feeder(header)
        assert f.feed_all(chunks) == [vec, vec, vec]
        assert f.counters() == (3, len(lead) + len(mid) + 2, 0, 0, 1)


def test_mixed_directions_each_deframer_gets_its_own() -> None:
    stream = HOST_EXAMPLE + GCU_EXAMPLE + b"\x00" + HOST_EXAMPLE + GCU_EXAMPLE
    for header, vec, other in (
        (GCU_HEADER, GCU_EXAMPLE, HOST_EXAMPLE),
        (HOST_HEADER, HOST_EXAMPLE, GCU_EXAMPLE),
    ):
        for chunks in every_split(stream):
            f = Feeder(header)
            assert f.feed_all(chunks) == [vec, vec]
            packets, discarded, crc_errors, length_errors, buffered = f.counters()
            assert (packets, crc_errors, length_errors, buffered) == (2, 0, 0, 0)
            assert discarded == 2 * len(other) + 1


# --- false headers -------------------------------------------------------------------------------
@pytest.mark.parametrize("name", VECTORS)
@pytest.mark.parametrize("length", [0, 5, 71, MAX_LENGTH + 1, 0x1000, 0xFFFF])
def test_false_header_with_impossible_length(name: str, length: int) -> None:
    header, vec = VECTORS[name]
    stream = false_header(header, length) + vec + false_header(header, length) + vec
    for chunks in every_split(stream):
        f = Feeder(header)
        assert f.feed_all(chunks) == [vec, vec]
        assert f.counters() == (2, 8, 0, 2, 0)


@pytest.mark.parametrize("name", VECTORS)
def test_length_above_custom_max_is_impossible(name: str) -> None:
    header, vec = VECTORS[name]
    f = Feeder(header, max_length=BASE_LENGTH)
    got = f.feed(vec)
    if len(vec) > BASE_LENGTH:  # the 73-byte GCU vector is too long for max_length=72
        assert got == []
        assert f.counters() == (0, len(vec), 0, 1, 0)
    else:
        assert got == [vec]


@pytest.mark.parametrize("name", VECTORS)
def test_plausible_false_header_with_bad_crc(name: str) -> None:
    header, vec = VECTORS[name]
    fake = false_header(header, 73) + bytes(69)  # complete span, CRC 00 00 is wrong
    stream = fake + vec + fake + vec
    for chunks in every_split(stream):
        f = Feeder(header)
        assert f.feed_all(chunks) == [vec, vec]
        assert f.counters() == (2, 2 * len(fake), 2, 0, 0)


@pytest.mark.parametrize("name", VECTORS)
def test_false_header_claiming_span_over_next_packet_after_junk(name: str) -> None:
    """After junk, a false header (200: in range for max_length 256) whose span covers the
    following packet holds it until the span is in, then fails its CRC: the packet comes
    out of the feed that brings byte 200 of the span, whatever the chunking. With the
    direction's default maximum 200 is an impossible length: out at once."""
    header, vec = VECTORS[name]
    stream = b"\x00" + false_header(header, 200) + vec + bytes(200)
    due = 1 + 200
    for chunks in every_split(stream):
        f = Feeder(header)
        first = f.feed(chunks[0])
        assert first == ([vec] if len(chunks[0]) >= due else [])
        f.feed(chunks[1])
        assert f.out == [vec]
        assert f.counters() == (1, 5 + 200, 1, 0, 0)
    make = Deframer.for_gcu_packets if header == GCU_HEADER else Deframer.for_host_packets
    d = make()
    assert d.feed(stream[: 5 + len(vec)]) == [vec]
    assert (d.stats.length_errors, d.stats.crc_errors) == (1, 0)


@pytest.mark.parametrize("name", VECTORS)
def test_false_header_at_packet_boundary_waits_then_recovers(name: str) -> None:
    """In sync (right after a packet, or at the start) a header is taken at its word until
    its span is in; then its CRC fails and the packets inside it are recovered."""
    header, vec = VECTORS[name]
    fake = false_header(header, 100)
    f = Feeder(header)
    assert f.feed(vec + fake + vec) == [vec]
    assert f.d.buffered == len(fake) + len(vec)
    assert f.feed(vec) == [vec, vec]
    assert f.counters() == (3, len(fake), 1, 0, 0)


def _nested_host_packet() -> tuple[bytes, bytes]:
    """A valid host packet (gaze at coordinates, 84 bytes) whose bytes 5..76 are themselves
    a CRC-valid 72-byte host packet: control roll raw −6744 = bytes A8 E5, pitch 72 = 48 00,
    and the latitude parameter carries the inner CRC."""
    main = HostMainFrame(control_roll_raw=-6744, control_pitch_raw=72, control_yaw_raw=2)

    def packet(lat_raw: int) -> bytes:
        gaze = GazeAtCoordinates(latitude=lat_raw / 1e7, longitude=0.0, altitude=0.0)
        return HostPacket(main, None, gaze).encode()

    crc = crc16_xmodem(packet(0)[5:75])
    outer = packet((crc >> 8) << 8 | (crc & 0xFF) << 16)
    return outer, outer[5:77]


def test_valid_packet_containing_a_valid_packet_survives_any_chunking() -> None:
    outer, inner = _nested_host_packet()
    assert decode_packet(outer).command.opcode == 0x15
    assert is_valid_frame(inner, HOST_HEADER)  # the trap is real
    stream = outer + outer
    ways = [[stream[i : i + 1] for i in range(len(stream))], *every_split(stream)]
    for chunks in ways:
        f = Feeder(HOST_HEADER)
        assert f.feed_all(chunks) == [outer, outer]
        assert f.counters() == (2, 0, 0, 0, 0)


def _nested_cases() -> list[pytest.ParameterSet]:
    """(outer, inner, max_length), named: the 84-byte V2.0.6 host packet above; a host packet
    with an unknown opcode whose parameters are a valid host packet (152 bytes); an 88-byte
    reply (the GCU default maximum) whose bytes 9..80 are a valid 72-byte reply."""
    outer, inner = _nested_host_packet()
    inner_h = HostPacket(HostMainFrame(control_yaw_raw=5)).encode()
    unknown = HostPacket(HostMainFrame(), None, UnknownCommand(0x77, b"\x01" + inner_h + bytes(7)))
    inner_g = GcuPacket(GcuMainFrame(mode_raw=0x12)).encode()
    reply = seal(GCU_HEADER, bytes(4) + inner_g + bytes(5))
    assert len(reply) == GCU_MAX_LENGTH and len(inner_g) == BASE_LENGTH
    return [
        pytest.param(outer, inner, HOST_MAX_LENGTH, id="gaze"),
        pytest.param(unknown.encode(), inner_h, MAX_LENGTH, id="unknown-opcode"),
        pytest.param(reply, inner_g, GCU_MAX_LENGTH, id="gcu-88"),
    ]


@pytest.mark.parametrize(("outer", "inner", "max_length"), _nested_cases())
@pytest.mark.parametrize("lead", ["noise", "impossible-length", "truncated"])
def test_nested_packet_after_junk_outer_whole_at_every_split(
    outer: bytes, inner: bytes, max_length: int, lead: str
) -> None:
    """Regression: junk, then a valid packet whose bytes contain another CRC-valid packet.
    Split anywhere (and byte by byte) the outer packet comes out whole, the inner never
    (main returned the inner one and lost the outer when the outer arrived in two pieces).
    Junk: noise, a false header with an impossible length, a truncated packet."""
    header = outer[:2]
    assert is_valid_frame(outer, header, max_length) and is_valid_frame(inner, header)
    assert inner in outer[1:]
    junk = {"noise": b"\x13\x00\x37", "impossible-length": false_header(header, 5),
            "truncated": outer[:40]}[lead]  # fmt: skip
    stream = junk + outer
    ways = [[stream[i : i + 1] for i in range(len(stream))], *every_split(stream)]
    for chunks in ways:
        f = Feeder(header, max_length)
        assert f.feed_all(chunks) == [outer]
        assert f.d.buffered == 0
        assert f.d.stats.bytes_discarded == len(junk)


def test_false_header_inside_a_packet_does_not_cost_the_packet_while_hunting() -> None:
    """Bytes 5–8 of this packet look like a 72-byte host packet header whose CRC is wrong;
    arriving after junk (hunting), the packet must still be waited for and delivered."""
    outer, _ = _nested_host_packet()
    outer = HostPacket(*decode_packet(outer)[:2], GazeAtCoordinates(1.0, 2.0, 3.0)).encode()
    assert outer[5:9] == HOST_HEADER + b"\x48\x00"
    assert not is_valid_frame(outer[5:77], HOST_HEADER)
    stream = b"\x00" + outer
    for chunks in every_split(stream):
        f = Feeder(HOST_HEADER)
        assert f.feed_all(chunks) == [outer]
        assert f.counters() == (1, 1, 0, 0, 0)


# --- CRC failures --------------------------------------------------------------------------------
@pytest.mark.parametrize("name", VECTORS)
def test_every_single_bit_flip_is_rejected_and_the_next_packet_recovered(name: str) -> None:
    header, vec = VECTORS[name]
    for bit in range(len(vec) * 8):
        bad = flip(vec, bit)
        f = Feeder(header)
        assert vec not in f.feed(bad)
        out = f.feed_all([vec, bytes(MAX_LENGTH)])
        assert out == [vec], f"bit {bit}"
        assert f.d.buffered == 0


@pytest.mark.parametrize("name", VECTORS)
def test_bit_flip_in_body_counts_one_crc_error(name: str) -> None:
    header, vec = VECTORS[name]
    bad = flip(vec, 8 * 40 + 3)
    for chunks in every_split(bad + vec):
        f = Feeder(header)
        assert f.feed_all(chunks) == [vec]
        assert f.counters() == (1, len(bad), 1, 0, 0)


# --- buffering, reset, construction --------------------------------------------------------------
@given(
    data=st.binary(max_size=2000),
    cuts=st.lists(st.integers(0, 2000), max_size=20),
    max_length=st.sampled_from([BASE_LENGTH, 73, 100, MAX_LENGTH, 0xFFFF]),
    header=st.sampled_from([GCU_HEADER, HOST_HEADER]),
)
def test_bounded_buffering_and_accounting_on_arbitrary_bytes(
    data: bytes, cuts: list[int], max_length: int, header: bytes
) -> None:
    f = Feeder(header, max_length=max_length)
    f.feed_all(chunks_at(data, [c for c in cuts if c <= len(data)]))  # checks every feed


def test_buffer_never_reaches_max_length_on_adversarial_headers() -> None:
    header = GCU_HEADER
    f = Feeder(header)
    # a header every few bytes, each claiming the longest plausible span
    f.feed_all([false_header(header, MAX_LENGTH) + b"\x00"] * 300)
    assert f.out == []
    assert 0 < f.d.buffered < MAX_LENGTH


def test_reset_counts_buffered_bytes_as_discarded() -> None:
    f = Feeder(GCU_HEADER)
    f.feed(GCU_EXAMPLE[:50])
    assert f.d.buffered == 50
    f.d.reset()
    assert f.d.buffered == 0
    assert f.d.stats.bytes_discarded == 50
    assert f.feed(GCU_EXAMPLE) == [GCU_EXAMPLE]
    f.check()


def test_feed_accepts_bytearray_memoryview_and_empty() -> None:
    d = Deframer.for_gcu_packets()
    assert d.feed(b"") == []
    assert d.feed(bytearray(GCU_EXAMPLE[:10])) == []
    assert d.feed(memoryview(GCU_EXAMPLE)[10:]) == [GCU_EXAMPLE]
    assert Deframer.for_host_packets().feed(HOST_EXAMPLE) == [HOST_EXAMPLE]


@pytest.mark.parametrize(
    ("header", "max_length"),
    [(b"\x8a", MAX_LENGTH), (b"\x8a\x5e\x00", 100), (GCU_HEADER, 71), (GCU_HEADER, 0x10000)],
)
def test_constructor_rejects_bad_arguments(header: bytes, max_length: int) -> None:
    with pytest.raises(ValueError, match=r"header|max_length"):
        Deframer(header, max_length=max_length)


# --- hypothesis: valid packets, any chunking -----------------------------------------------------
def _cuts(total: int) -> st.SearchStrategy[list[int]]:
    return st.lists(st.integers(0, total), max_size=12)


@given(data=st.data(), direction=st.sampled_from(["gcu", "host"]))
def test_valid_packets_any_chunking(data: st.DataObject, direction: str) -> None:
    header = GCU_HEADER if direction == "gcu" else HOST_HEADER
    strategy = gcu_packets if direction == "gcu" else host_packets
    packets = [p.encode() for p in data.draw(st.lists(strategy, min_size=1, max_size=5))]
    stream = b"".join(packets)
    f = Feeder(header)
    assert f.feed_all(chunks_at(stream, data.draw(_cuts(len(stream))))) == packets
    assert f.counters() == (len(packets), 0, 0, 0, 0)


# --- the fuzz contract ---------------------------------------------------------------------------
def _encoded(direction: str) -> st.SearchStrategy[bytes]:
    return (gcu_packets if direction == "gcu" else host_packets).map(lambda p: p.encode())


def junk(direction: str) -> st.SearchStrategy[bytes]:
    """Line noise, lone header bytes, false headers (impossible and plausible lengths),
    truncated and bit-flipped packets of this direction, packets of the other direction."""
    header = GCU_HEADER if direction == "gcu" else HOST_HEADER
    other = "host" if direction == "gcu" else "gcu"
    mine = _encoded(direction)
    impossible = st.one_of(st.integers(0, BASE_LENGTH - 1), st.integers(MAX_LENGTH + 1, 0xFFFF))
    piece = st.one_of(
        st.binary(max_size=64),
        st.sampled_from([header[:1], header[1:], header, GCU_HEADER + HOST_HEADER]),
        impossible.map(lambda n: false_header(header, n)),
        st.builds(
            lambda n, body: false_header(header, n) + body,
            st.integers(BASE_LENGTH, MAX_LENGTH),
            st.binary(max_size=100),
        ),
        mine.flatmap(lambda p: st.integers(1, len(p) - 1).map(lambda k: p[:k])),
        mine.flatmap(lambda p: st.integers(0, 8 * len(p) - 1).map(lambda b: flip(p, b))),
        _encoded(other),
    )
    return st.lists(piece, max_size=4).map(b"".join)


def _check_delivered(expected: Sequence[bytes], out: Sequence[bytes]) -> None:
    if is_subsequence(expected, out):
        return
    if any(p not in expected for p in out):
        # junk formed a CRC-valid frame overlapping a packet: ambiguous for any deframer
        event("junk formed a CRC-valid frame")
        reject()
    raise AssertionError(f"valid packets lost: expected {len(expected)}, got {len(out)}")


@pytest.mark.parametrize("direction", ["gcu", "host"])
@given(data=st.data())
def test_fuzz_junk_anywhere_never_raises_and_loses_no_packet(
    direction: str, data: st.DataObject
) -> None:
    header = GCU_HEADER if direction == "gcu" else HOST_HEADER
    n = data.draw(st.integers(1, 4), label="packets")
    packets = [data.draw(_encoded(direction), label="packet") for _ in range(n)]
    junks = [data.draw(junk(direction), label="junk") for _ in range(n + 1)]
    stream = b"".join(j + p for j, p in zip(junks[:-1], packets, strict=True)) + junks[-1]
    # enough further bytes (no header byte among them) to complete any candidate's span
    stream += bytes(MAX_LENGTH)
    f = Feeder(header)
    f.feed_all(chunks_at(stream, data.draw(_cuts(len(stream)), label="cuts")))
    _check_delivered(packets, f.out)
    assert f.d.buffered == 0


@pytest.mark.parametrize("direction", ["gcu", "host"])
@given(data=st.data())
def test_fuzz_packet_after_junk_is_delivered_within_the_hold_back_bound(
    direction: str, data: st.DataObject
) -> None:
    """A packet after junk comes out no later than the feed that brings the stream to
    ``start + max_length - 1`` bytes (its own end if later)."""
    header = GCU_HEADER if direction == "gcu" else HOST_HEADER
    n = data.draw(st.integers(1, 4), label="packets")
    packets = [data.draw(_encoded(direction), label="packet") for _ in range(n)]
    junks = [b"\x00" + data.draw(junk(direction), label="junk") for _ in range(n)]
    stream, dues = b"", []
    for j, p in zip(junks, packets, strict=True):
        stream += j + p
        dues.append(max(len(stream), len(stream) - len(p) + MAX_LENGTH - 1))
    stream += bytes(MAX_LENGTH)
    f = Feeder(header)
    fed = 0
    for chunk in chunks_at(stream, data.draw(_cuts(len(stream)), label="cuts")):
        f.feed(chunk)
        fed += len(chunk)
        _check_delivered([p for p, due in zip(packets, dues, strict=True) if due <= fed], f.out)
    _check_delivered(packets, f.out)
