"""PacketScanner: both directions' packets, located, in stream order, whatever the split."""

from __future__ import annotations

import itertools

from hypothesis import given, settings
from hypothesis import strategies as st

from gcu_async.capture.scan import PacketScanner
from gcu_async.protocol import GCU_HEADER, HOST_HEADER
from gcu_async.protocol.deframer import Deframer
from helpers.protocol.vectors import GCU_EXAMPLE, HOST_EXAMPLE
from helpers.scale import scaled

FALSE_HEADERS = [b"\x8a\x5e\x49\x00", b"\xa8\xe5\x05\x00", GCU_HEADER, HOST_HEADER]
pieces = st.sampled_from(
    [GCU_EXAMPLE, HOST_EXAMPLE, GCU_EXAMPLE[:-1] + b"\0", b"\0" * 7, *FALSE_HEADERS]
)


@settings(max_examples=scaled(300, 30), deadline=None)
@given(parts=st.lists(st.one_of(pieces, st.binary(max_size=8)), max_size=40),
       cuts=st.lists(st.integers(0, 3000), max_size=10))  # fmt: skip
def test_any_split_gives_the_deframers_packets_at_their_offsets(
    parts: list[bytes], cuts: list[int]
) -> None:
    data = b"".join(parts)
    bounds = sorted({min(c, len(data)) for c in cuts} | {0, len(data)})
    scanner = PacketScanner()
    found = []
    for a, b in itertools.pairwise(bounds):
        found += scanner.feed(data[a:b])
        assert scanner.low >= scanner.fed - 255  # holds less than one longest packet
    found += scanner.flush()
    offsets = [offset for offset, _, _ in found]
    assert offsets == sorted(offsets)
    for offset, length, _ in found:
        assert data[offset + 2 : offset + 4] == length.to_bytes(2, "little")
    for header in (GCU_HEADER, HOST_HEADER):  # the reference: one deframer over all of it
        deframer = Deframer(header)
        want = [*deframer.feed(data), *deframer.flush()]
        got = [data[o : o + n] for o, n, _ in found if data[o : o + 2] == header]
        assert got == want
