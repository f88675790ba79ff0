"""The session's one-entry decode memo: a datagram equal to the last one decoded reuses that
packet (an idle GCU repeats its reply byte for byte at 50 Hz), and nothing it reports differs
from decoding every datagram afresh."""

from __future__ import annotations

from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcu_async.protocol import GcuMainFrame, GcuPacket
from gcu_async.session import Session, TelemetrySample
from gcu_async.session import session as session_module
from helpers.protocol.strategies import gcu_packets

pytestmark = pytest.mark.fast


def opened() -> Session:
    session = Session()
    session.open(0.0)
    return session


def samples(session: Session) -> list[TelemetrySample]:
    return [e for e in session.events() if isinstance(e, TelemetrySample)]


def errors(session: Session) -> tuple[int, int, int, int]:
    h = session.link_health(0.0)
    return h.crc_errors, h.length_errors, h.bytes_discarded, h.other_versions


# a step: which packet of the pool, and how it arrives: as bytes, as a bytearray, or with one
# byte changed (position, XOR mask)
steps = st.tuples(st.integers(0, 2), st.sampled_from(["bytes", "bytearray", "mutated"]),
                  st.integers(0, 200), st.integers(1, 255))  # fmt: skip


@given(st.lists(gcu_packets, min_size=1, max_size=3), st.lists(steps, min_size=1, max_size=40))
def test_memoized_session_reports_what_fresh_decoding_reports(
    pool: list[GcuPacket], plan: list[tuple[int, str, int, int]]
) -> None:
    """Interleaved repeats, new packets, bytearrays and corrupted copies: every datagram gives
    the telemetry (status, feedback, sub frame) and error counts a session that has never
    seen a datagram before (so has nothing to reuse) gives for it."""
    encoded = [p.encode() for p in pool]
    session = opened()
    for i, (which, how, at, mask) in enumerate(plan):
        raw = encoded[which % len(encoded)]
        data: Any = raw if how == "bytes" else bytearray(raw)
        if how == "mutated":
            data[at % len(data)] ^= mask
        now = 0.02 * (i + 1)
        fresh = opened()
        before = errors(session)
        fresh.receive(bytes(data), now, datagram=True)
        session.receive(data, now, datagram=True)
        got, want = samples(session), samples(fresh)
        assert [(s.status, s.feedback) for s in got] == [(s.status, s.feedback) for s in want]
        for g, w in zip(got, want, strict=True):
            if w.info is not None:  # the memoized session keeps its last sub frame otherwise
                assert g.info == w.info
        delta = tuple(a - b for a, b in zip(errors(session), before, strict=True))
        assert delta == errors(fresh)


def test_a_repeated_datagram_is_decoded_once(monkeypatch: pytest.MonkeyPatch) -> None:
    """Ten identical replies cost one decode; a different one is decoded, and so is the first
    again after it (one entry)."""
    calls: list[bytes] = []
    decode = session_module.decode_gcu_packet

    def counting(data: bytes) -> GcuPacket:
        calls.append(bytes(data))
        return decode(data)

    monkeypatch.setattr(session_module, "decode_gcu_packet", counting)
    a = GcuPacket(pool_main(0)).encode()
    b = GcuPacket(pool_main(1)).encode()
    session = opened()
    for i in range(10):
        session.receive(bytes(a), 0.02 * (i + 1), datagram=True)  # equal, not the same object
    assert calls == [a]
    session.receive(b, 0.3, datagram=True)
    session.receive(a, 0.32, datagram=True)
    assert calls == [a, b, a]
    assert [s.status for s in samples(session)] == [pool_main(0)] * 10 + [pool_main(1),
                                                                          pool_main(0)]


def test_a_buffer_changed_after_it_was_received_is_decoded_afresh() -> None:
    """The memo keeps only immutable bytes: a bytearray received, then overwritten with
    another packet and received again, gives the new packet."""
    a = GcuPacket(pool_main(0)).encode()
    b = GcuPacket(pool_main(1)).encode()
    buf = bytearray(a)
    session = opened()
    session.receive(buf, 0.02, datagram=True)
    buf[:] = b
    session.receive(buf, 0.04, datagram=True)
    session.receive(a, 0.06, datagram=True)
    buf[:] = a
    buf[10] ^= 0xFF  # corrupt: the CRC no longer matches
    session.receive(buf, 0.08, datagram=True)
    assert [s.status for s in samples(session)] == [pool_main(0), pool_main(1), pool_main(0)]
    assert session.link_health(0.1).crc_errors == 1


def pool_main(i: int) -> GcuMainFrame:
    return GcuMainFrame.build(attitude=(float(i), 0.0, 0.0))
