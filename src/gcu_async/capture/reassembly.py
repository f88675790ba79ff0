"""Streams of a capture: each UDP datagram alone, TCP and serial bytes in order.

A :class:`Unit` is what one deframer reads: a UDP datagram (``final``: its end ends any
packet in it), or the bytes of one TCP direction (from a SYN, or its first segment, to the
FIN/RST or the end of the capture) or one serial direction, put in sequence order.
Retransmitted bytes are taken once; a segment that arrives early waits for the gap before
it (a gap never filled is skipped at the end, as a capture that lost a segment has to).
``frames`` maps stream offsets to the frame that brought those bytes, so that a packet is
attributed to the frame where its last byte arrived.
"""

from __future__ import annotations

import bisect
from collections.abc import Iterable
from dataclasses import dataclass, field

from gcu_async.capture.reader import Record

SYN, FIN, RST = 0x02, 0x01, 0x04
MAX_EARLY_SEGMENTS = 1024
"""Segments held waiting for a gap; beyond that the gap is skipped."""


@dataclass
class Unit:
    """Bytes one deframer reads, and where they came from."""

    link: str
    src: str
    dst: str
    index: int
    """Per (link, src, dst): 0 for the first stream, 1 after a new SYN, ..."""
    data: bytearray = field(default_factory=bytearray)
    starts: list[int] = field(default_factory=list)
    """Stream offsets at which each frame's bytes begin (ascending)."""
    frames: list[int] = field(default_factory=list)

    def add(self, frame: int, payload: bytes) -> None:
        """Append ``payload``, which became readable in order at ``frame`` (a segment that
        came early counts from the frame that filled the gap before it)."""
        if not payload:
            return
        if self.frames and frame < self.frames[-1]:
            frame = self.frames[-1]
        self.starts.append(len(self.data))
        self.frames.append(frame)
        self.data += payload

    def frame_of(self, offset: int) -> int:
        """The frame that brought the byte at ``offset``."""
        return self.frames[bisect.bisect_right(self.starts, offset) - 1]

    @property
    def name(self) -> str:
        suffix = f" #{self.index}" if self.index else ""
        return f"{self.link} {self.src} -> {self.dst}{suffix}"


@dataclass
class _TcpDirection:
    unit: Unit
    next_seq: int | None = None
    early: dict[int, tuple[int, bytes]] = field(default_factory=dict)
    """seq -> (frame, payload) of segments past a gap."""

    def segment(self, frame: int, seq: int, flags: int, payload: bytes) -> None:
        if self.next_seq is None:
            self.next_seq = (seq + 1) % 2**32 if flags & SYN else seq
            if flags & SYN:
                return
        self._place(frame, seq, payload)

    def _place(self, frame: int, seq: int, payload: bytes) -> None:
        assert self.next_seq is not None
        ahead = (seq - self.next_seq) % 2**32
        if ahead >= 2**31:  # behind: a retransmission, maybe with new bytes at its end
            skip = 2**32 - ahead
            if skip >= len(payload):
                return
            payload, ahead = payload[skip:], 0
        if ahead:
            if len(self.early) < MAX_EARLY_SEGMENTS:
                self.early.setdefault(seq, (frame, payload))
            return
        self.unit.add(frame, payload)
        self.next_seq = (self.next_seq + len(payload)) % 2**32
        self._drain()

    def _drain(self) -> None:
        while self.early:
            assert self.next_seq is not None
            best = min(self.early, key=lambda s: (s - self.next_seq) % 2**32)  # type: ignore[operator]
            ahead = (best - self.next_seq) % 2**32
            if 0 < ahead < 2**31:
                return
            frame, payload = self.early.pop(best)
            self._place(frame, best, payload)

    def flush(self) -> None:
        """End of the stream: skip gaps, take what waited in order."""
        while self.early:
            assert self.next_seq is not None
            best = min(self.early, key=lambda s: (s - self.next_seq) % 2**32)  # type: ignore[operator]
            self.next_seq = best
            self._drain()


def units(records: Iterable[Record]) -> list[Unit]:
    """The units of a capture, in the order they start."""
    out: list[Unit] = []
    tcp: dict[tuple[str, str], _TcpDirection] = {}
    serial: dict[tuple[str, str], Unit] = {}
    generations: dict[tuple[str, str, str], int] = {}

    def new_unit(link: str, src: str, dst: str) -> Unit:
        key = (link, src, dst)
        index = generations.get(key, -1) + 1
        generations[key] = index
        unit = Unit(link, src, dst, index if link != "udp" else 0)
        out.append(unit)
        return unit

    for rec in records:
        if rec.link == "udp":
            new_unit("udp", rec.src, rec.dst).add(rec.frame, rec.payload)
        elif rec.link == "serial":
            key = (rec.src, rec.dst)
            if key not in serial:
                serial[key] = new_unit("serial", rec.src, rec.dst)
            serial[key].add(rec.frame, rec.payload)
        else:
            key = (rec.src, rec.dst)
            direction = tcp.get(key)
            if direction is None or (rec.flags & SYN and direction.next_seq is not None):
                if direction is not None:
                    direction.flush()
                direction = tcp[key] = _TcpDirection(new_unit("tcp", rec.src, rec.dst))
            direction.segment(rec.frame, rec.seq, rec.flags, rec.payload)
            if rec.flags & (FIN | RST):
                direction.flush()
    for direction in tcp.values():
        direction.flush()
    return [unit for unit in out if unit.data]
