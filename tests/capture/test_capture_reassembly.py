"""TCP reassembly: segments in any order, with overlaps and duplicates, give the stream once
and in order, with no recursion and bounded waiting bytes and streams."""

from __future__ import annotations

import itertools

from hypothesis import given, settings
from hypothesis import strategies as st

from gcu_async.capture.reader import Record
from gcu_async.capture.reassembly import Reassembler
from helpers.scale import scaled


@st.composite
def segment_schedules(draw: st.DrawFn) -> tuple[bytes, list[tuple[int, int]]]:
    """A stream and segments covering it: any cuts, reordered, some duplicated or
    overlapping a neighbour."""
    stream = draw(st.binary(min_size=1, max_size=300))
    cuts = sorted(draw(st.sets(st.integers(1, max(1, len(stream) - 1)), max_size=30)))
    bounds = [0, *[c for c in cuts if c < len(stream)], len(stream)]
    spans = list(itertools.pairwise(bounds))
    extra = draw(st.lists(st.sampled_from(spans), max_size=10))  # duplicates
    overlaps = [(a, min(len(stream), b + draw(st.integers(0, 20)))) for a, b in
                draw(st.lists(st.sampled_from(spans), max_size=5))]  # fmt: skip
    order = draw(st.permutations([*spans, *extra, *overlaps]))
    return stream, order


@settings(max_examples=scaled(300, 30), deadline=None)
@given(schedule=segment_schedules(), isn=st.integers(0, 2**32 - 1))
def test_tcp_segments_in_any_order_give_the_stream_once(
    schedule: tuple[bytes, list[tuple[int, int]]], isn: int
) -> None:
    stream, order = schedule
    reassembler = Reassembler()
    out = bytearray()
    syn = Record(1, 0.0, "tcp", "a:1", "b:2", b"", seq=isn, flags=0x02)
    pieces = reassembler.push(syn)
    for frame, (a, b) in enumerate(order, start=2):
        rec = Record(frame, 0.0, "tcp", "a:1", "b:2", stream[a:b], seq=(isn + 1 + a) % 2**32)
        pieces += reassembler.push(rec)
    pieces += reassembler.finish()
    for piece in pieces:
        out += piece.data
    assert bytes(out) == stream  # every segment present: no gap, nothing twice
    assert reassembler.held == 0
    assert sum(1 for p in pieces if p.end) == 1


def test_waiting_segments_are_bounded_and_a_gap_is_skipped_when_over() -> None:
    """Segments past a gap that is never filled: held up to the budget, then the gap is
    skipped (the bytes after it come out) instead of holding more."""
    reassembler = Reassembler(waiting_budget=10_000)
    pieces = reassembler.push(Record(1, 0.0, "tcp", "a:1", "b:2", b"", seq=0, flags=0x02))
    for n in range(200):  # byte 1 is never sent: everything waits for it
        rec = Record(n + 2, 0.0, "tcp", "a:1", "b:2", bytes([n % 256]) * 100, seq=2 + 100 * n)
        pieces += reassembler.push(rec)
        assert reassembler.held <= 10_000
    assert sum(len(p.data) for p in pieces) > 0  # the gap was given up on, not held forever
    pieces += reassembler.finish()
    assert sum(len(p.data) for p in pieces) == 200 * 100


def test_streams_are_bounded() -> None:
    reassembler = Reassembler(max_streams=4)
    ended = 0
    for n in range(50):
        rec = Record(n + 1, 0.0, "serial", f"interface {n}", "sent", b"x")
        ended += sum(1 for p in reassembler.push(rec) if p.end)
    assert ended == 46  # each new stream past 4 ended the least recently active
    assert sum(1 for p in reassembler.finish() if p.end) == 4
