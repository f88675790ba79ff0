"""The deframer's contract, checked against an independent reference parse.

* Chunk independence: for every stream and every way of splitting it, after every feed the
  packets returned so far, every counter and ``buffered`` equal those of the reference parse
  of the bytes fed so far; after :meth:`Deframer.flush` they equal the reference parse of
  the whole stream.
* Hold-back bound: a packet starting at offset s and ending at e is returned by the feed
  that brings the stream to ``max(e, s + max_length - 1)`` bytes.
* The two regressions of the issue: (a) a valid packet nested in another, after junk, at
  every split; (b) ``8A 5E xx yy`` after a reply, for all 65,536 ``xx yy``.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterable
from typing import NamedTuple

import crcmod.predefined
import pytest
from hypothesis import event, given, settings
from hypothesis import strategies as st

from gcu_async.protocol import (
    COMMAND_TYPES,
    GCU_HEADER,
    HOST_HEADER,
    Deframer,
    Feedback,
    GcuMainFrame,
    GcuPacket,
    HostPacket,
    UnknownCommand,
)
from gcu_async.protocol.deframer import GCU_MAX_LENGTH, HOST_MAX_LENGTH
from helpers.protocol.strategies import gcu_packets, host_main_frames, host_packets, seal
from helpers.scale import scaled

BASE = 72
_xmodem = crcmod.predefined.mkCrcFun("xmodem")  # independent of the library's CRC
HEADERS = {"gcu": GCU_HEADER, "host": HOST_HEADER}


# --- the reference parse -------------------------------------------------------------------------
class Ref(NamedTuple):
    packets: list[tuple[int, bytes]]
    """(start offset, packet) in stream order."""
    discarded: int
    crc_errors: int
    length_errors: int
    buffered: int

    def counters(self) -> tuple[int, int, int, int, int]:
        return len(self.packets), self.discarded, self.crc_errors, self.length_errors, self.buffered


def reference(stream: bytes, header: bytes, max_length: int, *, final: bool) -> Ref:
    """Greedy, left to right, one position at a time. ``final=False`` stops (and buffers the
    rest) at the first position whose bytes could still become a valid packet; ``final=True``
    treats the stream as ended: an incomplete span loses its first byte like any other."""
    packets: list[tuple[int, bytes]] = []
    discarded = crc_errors = length_errors = 0
    i, n = 0, len(stream)
    while i < n:
        if stream[i : i + 2] == header:
            if n - i >= 4:
                length = stream[i + 2] + 256 * stream[i + 3]
                if not BASE <= length <= max_length:
                    length_errors += 1
                elif n - i >= length:
                    if _xmodem(stream[i : i + length - 2]) == int.from_bytes(
                        stream[i + length - 2 : i + length], "big"
                    ):
                        packets.append((i, stream[i : i + length]))
                        i += length
                        continue
                    crc_errors += 1
                elif not final:
                    break
            elif not final:
                break
        elif i == n - 1 and stream[i] == header[0] and not final:
            break
        discarded += 1
        i += 1
    return Ref(packets, discarded, crc_errors, length_errors, n - i)


def _holds_a_frame(packet: bytes, header: bytes) -> bool:
    """Does ``packet`` contain a CRC-valid frame after its own start?"""
    inner = reference(packet[1:], header, len(packet), final=True).packets
    return bool(inner)


def counters(d: Deframer) -> tuple[int, int, int, int, int]:
    s = d.stats
    return s.packets, s.bytes_discarded, s.crc_errors, s.length_errors, d.buffered


def chunks_at(data: bytes, cuts: Iterable[int]) -> list[bytes]:
    bounds = [0, *sorted(c for c in cuts if 0 <= c <= len(data)), len(data)]
    return [data[a:b] for a, b in itertools.pairwise(bounds)]


def sealed(header: bytes, length: int, fill: int = 0x11) -> bytes:
    """A valid packet of ``length`` bytes whose body is ``fill`` repeated."""
    return seal(header, bytes([fill]) * (length - 7))


def nest(header: bytes, length: int, inner: bytes, offset: int, fill: int = 0x33) -> bytes:
    """A valid packet of ``length`` bytes with ``inner`` at ``offset`` (from byte 0)."""
    body = bytearray([fill]) * (length - 7)
    body[offset - 5 : offset - 5 + len(inner)] = inner
    return seal(header, bytes(body))


def flip_last(p: bytes) -> bytes:
    return p[:-1] + bytes([p[-1] ^ 1])


def test_reference_parse_finds_what_it_should() -> None:
    """The reference itself, on cases whose answer is known by construction."""
    a, b = sealed(GCU_HEADER, 72), sealed(GCU_HEADER, 88, 0x22)
    assert reference(a + b, GCU_HEADER, 88, final=True) == Ref([(0, a), (72, b)], 0, 0, 0, 0)
    assert reference(a + b, GCU_HEADER, 87, final=True).packets == [(0, a)]
    outer = nest(GCU_HEADER, 88, a, 8)
    assert reference(b"\x00" + outer, GCU_HEADER, 88, final=True).packets == [(1, outer)]
    assert reference(b"\x00" + outer[:-1], GCU_HEADER, 88, final=False) == Ref([], 1, 0, 0, 87)
    assert reference(b"\x00" + outer[:-1], GCU_HEADER, 88, final=True).packets == [(9, a)]
    assert reference(GCU_HEADER[:1], GCU_HEADER, 88, final=False).buffered == 1
    assert reference(GCU_HEADER + b"\x05\x00", GCU_HEADER, 88, final=False) == Ref([], 4, 0, 1, 0)
    assert reference(flip_last(a) + a, GCU_HEADER, 88, final=True) == Ref([(72, a)], 72, 1, 0, 0)


# --- streams: packets, nested packets, junk, false headers, CRC failures -------------------------
def _max_lengths(direction: str) -> st.SearchStrategy[int]:
    default = GCU_MAX_LENGTH if direction == "gcu" else HOST_MAX_LENGTH
    return st.one_of(st.sampled_from([BASE, 73, 84, default, 256]), st.integers(BASE, 300))


def _sealed_packets(header: bytes, max_length: int) -> st.SearchStrategy[bytes]:
    return st.integers(BASE, max_length).flatmap(
        lambda n: st.binary(min_size=n - 7, max_size=n - 7).map(lambda body: seal(header, body))
    )


@st.composite
def _nested(draw: st.DrawFn, header: bytes, length: int, depth: int = 2) -> bytes:
    """A valid packet of ``length`` bytes whose body holds a valid packet (itself nested when
    there is room): by hand for any direction, or through the library's encoder as a host
    packet with an unknown opcode carrying the inner packet in its parameters."""
    room = length - 7
    if depth > 1 and room >= BASE + 7 and draw(st.booleans()):
        inner = draw(_nested(header, draw(st.integers(BASE + 7, room)), depth - 1))
    else:
        inner = draw(_sealed_packets(header, room))
    if header == HOST_HEADER and draw(st.booleans()) and length >= BASE + len(inner):
        pad = length - BASE - len(inner)
        cut = draw(st.integers(0, pad))
        params = draw(st.binary(min_size=pad, max_size=pad))
        code = draw(st.integers(0, 255).filter(lambda c: c not in COMMAND_TYPES))
        command = UnknownCommand(code=code, params=params[:cut] + inner + params[cut:])
        return HostPacket(draw(host_main_frames), None, command).encode()
    offset = draw(st.integers(5, length - 2 - len(inner)))
    filler = draw(st.binary(min_size=room, max_size=room))
    body = filler[: offset - 5] + inner + filler[offset - 5 + len(inner) :]
    return seal(header, body[:room])


def _flip(p: bytes, bit: int) -> bytes:
    b = bytearray(p)
    b[bit // 8] ^= 1 << (bit % 8)
    return bytes(b)


def _pieces(
    direction: str, max_length: int
) -> tuple[st.SearchStrategy[bytes], st.SearchStrategy[bytes]]:
    """(junk, packets) for one direction: junk is line noise, header fragments, false headers
    with every kind of declared length, bit-flipped (CRC failure) and truncated packets,
    packets of the other direction; packets are valid ones (through the encoder or sealed by
    hand; they may exceed ``max_length``, then they are length errors), nested ones, and
    valid ones right after a false header with an in-range length (the hold-back trap)."""
    header = HEADERS[direction]
    other = HOST_HEADER if direction == "gcu" else GCU_HEADER
    encoded = (gcu_packets if direction == "gcu" else host_packets).map(lambda p: p.encode())
    valid = st.one_of(encoded, _sealed_packets(header, max_length))
    in_range = st.integers(BASE, max_length).map(lambda n: header + n.to_bytes(2, "little"))
    false_header = st.one_of(
        st.integers(0, BASE - 1),  # too small
        st.integers(max_length + 1, 0xFFFF),  # too large
        st.integers(BASE, max_length),  # in range
    ).map(lambda n: header + n.to_bytes(2, "little"))
    junk = st.one_of(
        st.binary(min_size=1, max_size=40),
        st.sampled_from([header[:1], header[1:], header, header + header, other]),
        st.builds(lambda h, body: h + body, false_header, st.binary(max_size=120)),
        valid.flatmap(lambda p: st.integers(0, 8 * len(p) - 1).map(lambda b: _flip(p, b))),
        valid.flatmap(lambda p: st.integers(1, len(p) - 1).map(lambda k: p[:k])),
        _sealed_packets(other, 100),
    )
    packets = [valid, st.builds(lambda h, p: h + p, in_range, valid)]
    if max_length >= BASE + 7:
        packets.append(st.integers(BASE + 7, max_length).flatmap(lambda n: _nested(header, n)))
    return junk, st.one_of(*packets)


@st.composite
def streams(draw: st.DrawFn, direction: str) -> tuple[int, bytes]:
    """``max_length`` and a stream: 1–6 packets, each after 0–2 pieces of junk, then 0–2
    more (whatever the stream ends with stays buffered until the flush)."""
    max_length = draw(_max_lengths(direction), label="max_length")
    junk, packets = _pieces(direction, max_length)
    parts: list[bytes] = []
    for _ in range(draw(st.integers(1, 6), label="packets")):
        parts += draw(st.lists(junk, max_size=2), label="junk")
        parts.append(draw(packets, label="packet"))
    parts += draw(st.lists(st.one_of(junk, packets), max_size=2), label="tail")
    return max_length, b"".join(parts)


# --- chunk independence --------------------------------------------------------------------------
@pytest.mark.parametrize("direction", ["gcu", "host"])
@settings(max_examples=scaled(200, 25))
@given(data=st.data())
def test_every_split_matches_the_reference_after_every_feed(
    direction: str, data: st.DataObject
) -> None:
    header = HEADERS[direction]
    max_length, stream = data.draw(streams(direction))
    cuts = data.draw(st.lists(st.integers(0, len(stream)), max_size=30), label="cuts")
    d = Deframer(header, max_length=max_length)
    out: list[bytes] = []
    fed = 0
    for chunk in chunks_at(stream, cuts):
        out += d.feed(chunk)
        fed += len(chunk)
        ref = reference(stream[:fed], header, max_length, final=False)
        assert out == [p for _, p in ref.packets]
        assert counters(d) == ref.counters()
        assert d.buffered <= max_length - 1
        assert sum(map(len, out)) + d.stats.bytes_discarded + d.buffered == fed
    flushed = d.flush()
    out += flushed
    ref = reference(stream, header, max_length, final=True)
    assert out == [p for _, p in ref.packets]
    event(f"packets: {min(len(out), 5)}{'+' if len(out) >= 5 else ''}")
    event(f"crc errors: {min(ref.crc_errors, 1)}, length errors: {min(ref.length_errors, 1)}")
    if flushed:
        event("flush returned packets")
    if any(_holds_a_frame(p, header) for p in out):
        event("a returned packet holds a CRC-valid frame")
    assert counters(d) == ref.counters()
    assert d.buffered == 0


@pytest.mark.parametrize("direction", ["gcu", "host"])
@settings(max_examples=scaled(200, 25))
@given(data=st.data())
def test_byte_by_byte_each_packet_comes_out_within_the_hold_back_bound(
    direction: str, data: st.DataObject
) -> None:
    """Fed one byte at a time, each packet of the reference parse comes out exactly once, in
    order, after its last byte and no later than byte ``start + max_length - 1``."""
    header = HEADERS[direction]
    max_length, stream = data.draw(streams(direction))
    d = Deframer(header, max_length=max_length)
    delivered: list[tuple[int, bytes]] = []  # (stream length when returned, packet)
    for k in range(len(stream)):
        delivered += [(k + 1, p) for p in d.feed(stream[k : k + 1])]
    delivered += [(len(stream) + 1, p) for p in d.flush()]  # + 1: only the flush returned it
    ref = reference(stream, header, max_length, final=True)
    assert [p for _, p in delivered] == [p for _, p in ref.packets]
    for (when, packet), (start, _) in zip(delivered, ref.packets, strict=True):
        end = start + len(packet)
        assert end <= when <= max(end, start + max_length - 1)
        if end < when <= len(stream):
            event("a packet was held back past its end")


@pytest.mark.parametrize("direction", ["gcu", "host"])
@pytest.mark.parametrize("length", [BASE, 80, 88, 128, 256, 0xFFFF])
def test_worst_case_hold_back_is_exact(direction: str, length: int) -> None:
    """The closest a false header can start before a packet is 4 bytes (nearer, its length
    bytes would be the packet's own header: an impossible length). Declaring ``max_length``,
    it holds the packet until the stream reaches ``start - 4 + max_length`` bytes: not one
    byte longer, and not shorter, whatever the chunking."""
    header = HEADERS[direction]
    packet = sealed(header, BASE)
    fake = header + length.to_bytes(2, "little")
    stream = packet + fake + packet + bytes(length)
    start = len(packet) + len(fake)
    due = max(start + len(packet), start - 4 + length)
    for cut in sorted({start + 1, start + BASE - 1, due - 2, due - 1, due, due + 1, len(stream)}):
        d = Deframer(header, max_length=length)
        first = d.feed(stream[:cut])
        assert first == ([packet, packet] if cut >= due else [packet]), cut
        assert d.feed(stream[cut:]) == ([] if cut >= due else [packet])
        assert d.buffered == 0


# --- regression (b): a false header after a reply ------------------------------------------------
def _replies() -> list[bytes]:
    """Four distinct V2.0.6 replies: 73, 72, 73 and 73 bytes."""
    main = GcuMainFrame(mode_raw=0x12, miss_x=-500, miss_y=500, yaw_raw=6215)
    feedbacks = [Feedback(0x20, 0), Feedback(0), Feedback(0x25, 2), Feedback(0x01, 2)]
    return [GcuPacket(main._replace(roll_raw=k), None, fb).encode() for k, fb in
            enumerate(feedbacks)]  # fmt: skip


def _delivery_feeds(
    make: Callable[[], Deframer], values: Iterable[int]
) -> Iterable[tuple[int, list[int]]]:
    """For each ``value``: feed reply 0, ``8A 5E`` + ``value`` (LE), replies 1–3, cut just
    before and just at each reply's expected delivery; yield (value, stream length at which
    each reply came out)."""
    replies = _replies()
    r0, rest = replies[0], b"".join(replies[1:])
    ends = list(itertools.accumulate(len(r) for r in replies))
    ends = [ends[0], *(e + 4 for e in ends[1:])]
    max_length = make().max_length
    for value in values:
        # zero bytes after the replies complete any false header's span
        stream = r0 + GCU_HEADER + value.to_bytes(2, "little") + rest + bytes(max_length)
        due = _due(ends, len(r0), value, max_length)
        d = make()
        fed, seen = 0, []
        for chunk in chunks_at(stream, {t - 1 for t in due} | set(due)):
            fed += len(chunk)
            got = d.feed(chunk)
            seen += [fed] * len(got)
            assert got == replies[len(seen) - len(got) : len(seen)]
        assert counters(d)[0] == 4 and d.buffered == 0
        yield value, seen


def _due(ends: list[int], fake_at: int, value: int, max_length: int) -> list[int]:
    """Expected delivery of each reply: at its end; when the false header's length is in
    range, the replies after it not before its span is in (and its CRC fails)."""
    if not BASE <= value <= max_length:
        return list(ends)
    return [ends[0], *(max(end, fake_at + value) for end in ends[1:])]


def test_the_false_headers_of_the_regression_are_not_valid_frames() -> None:
    """The expectation in ``_due`` assumes no false header's span is CRC-valid (each is with
    probability 2^-16): true of these replies, checked here."""
    replies = _replies()
    stream = replies[0] + b"".join(replies[1:])
    for value in range(BASE, 257):
        span = (GCU_HEADER + value.to_bytes(2, "little") + stream[73:] + bytes(256))[:value]
        assert _xmodem(span[:-2]) != int.from_bytes(span[-2:], "big")


def test_false_header_after_a_reply_every_xx_yy_default_max_length() -> None:
    """``8A 5E xx yy`` right after a reply, for all 65,536 ``xx yy``: every reply comes out
    exactly when ``_due`` says, which is at most 15 bytes after its own end (the bound
    ``start + 88 - 1``; the false header starts 4 bytes before the reply, so 12 here), never
    a packet's span later. On main ``8A 5E FF 00`` (255, then in range) held all three replies
    back; now 255 is an impossible length and costs nothing."""
    replies = _replies()
    ends = list(itertools.accumulate(len(r) for r in replies))
    ends = [ends[0], *(e + 4 for e in ends[1:])]
    starts = [e - len(r) for e, r in zip(ends, replies, strict=True)]
    assert Deframer.for_gcu_packets().max_length == GCU_MAX_LENGTH == 88
    late = 0
    for value, seen in _delivery_feeds(Deframer.for_gcu_packets, range(0x10000)):
        assert seen == _due(ends, len(replies[0]), value, GCU_MAX_LENGTH), value
        for when, start, end, r in zip(seen, starts, ends, replies, strict=True):
            assert when <= max(end, start + GCU_MAX_LENGTH - 1)
            assert when - end <= 15 < len(r)
        late += seen != ends
    # only the lengths whose span ends after reply 1 hold it back: 77 … 88
    assert late == GCU_MAX_LENGTH - (ends[1] - len(replies[0])) == 12
    assert _due(ends, 73, 0x00FF, GCU_MAX_LENGTH) == ends  # the FF 00: no hold-back


def test_false_header_after_a_reply_larger_max_length_holds_longer() -> None:
    """The same with ``max_length=256`` (the old default), in-range lengths only: the bound
    still holds exactly, and it is why the default is small: 8A 5E FF 00 holds reply 1 back
    until 255 bytes after the false header, past the end of reply 3."""
    replies = _replies()
    ends = list(itertools.accumulate(len(r) for r in replies))
    ends = [ends[0], *(e + 4 for e in ends[1:])]
    for value, seen in _delivery_feeds(
        lambda: Deframer.for_gcu_packets(max_length=256), range(BASE, 257)
    ):
        assert seen == _due(ends, 73, value, 256)
        assert seen[1] <= max(ends[1], ends[1] - len(replies[1]) + 256 - 1)
    assert _due(ends, 73, 0x00FF, 256)[1] == 73 + 255 > ends[3]


# --- defaults, flush -----------------------------------------------------------------------------
def test_default_maximum_lengths() -> None:
    """GCU 88, host 128: both accept V2.0.6's longest packets (73 and 84 bytes) and are at
    most 2 × 72 + 1, so a held-back packet is released by the packet after it; one byte more
    is a length error unless ``max_length`` says otherwise."""
    for make, header, default, longest in (
        (Deframer.for_gcu_packets, GCU_HEADER, GCU_MAX_LENGTH, 73),
        (Deframer.for_host_packets, HOST_HEADER, HOST_MAX_LENGTH, 84),
    ):
        assert make().max_length == default <= 2 * BASE + 1
        assert Deframer(header).max_length == 256  # the generic constructor: offline decoding
        for length in (BASE, longest, default):
            assert make().feed(sealed(header, length)) == [sealed(header, length)]
        too_long = sealed(header, default + 1)
        d = make()
        assert d.feed(too_long) == []
        assert counters(d) == (0, len(too_long), 0, 1, 0)
        assert make(max_length=default + 1).feed(too_long) == [too_long]


def test_flush_settles_a_span_cut_short_by_the_end_of_the_stream() -> None:
    """A false header with an in-range length at the end of a datagram holds a valid packet
    inside its span; ``flush`` treats the stream as ended and returns it. ``reset`` drops
    it (counted)."""
    packet = sealed(GCU_HEADER, 73)
    stream = b"\x00" + GCU_HEADER + b"\x58\x00" + packet  # 88: the span needs 11 more bytes
    d = Deframer.for_gcu_packets()
    assert d.feed(stream) == []
    assert counters(d) == (0, 1, 0, 0, len(stream) - 1)
    assert d.flush() == [packet]
    assert counters(d) == (1, 5, 0, 0, 0)
    assert d.flush() == []
    assert d.feed(packet) == [packet]  # a new stream
    d = Deframer.for_gcu_packets()
    d.feed(stream)
    d.reset()
    assert counters(d) == (0, len(stream), 0, 0, 0)


@pytest.mark.parametrize("direction", ["gcu", "host"])
@given(data=st.data())
def test_flush_then_feed_is_two_streams(direction: str, data: st.DataObject) -> None:
    """After a flush the deframer starts afresh: feeding a second stream gives the reference
    parse of that stream alone, counters adding up."""
    header = HEADERS[direction]
    max_length, first = data.draw(streams(direction))
    second = data.draw(streams(direction))[1]
    d = Deframer(header, max_length=max_length)
    out = d.feed(first) + d.flush() + d.feed(second) + d.flush()
    a = reference(first, header, max_length, final=True)
    b = reference(second, header, max_length, final=True)
    assert out == [p for _, p in a.packets + b.packets]
    assert counters(d) == tuple(x + y for x, y in zip(a.counters(), b.counters(), strict=True))
