"""Streams of a capture: each UDP datagram alone, TCP and serial bytes in order.

A :class:`Unit` is what one pair of deframers reads: a UDP datagram (its end ends any
packet in it), or the bytes of one TCP direction (from a SYN, or its first segment, to the
FIN/RST or the end of the capture) or one serial direction, put in sequence order.
:class:`Reassembler` turns records into :class:`Piece` s — bytes that became readable in
order, and the end of a unit — as the records come, keeping only what waits.

**Rules.** Retransmitted bytes are taken once (the first copy in sequence order wins); a
segment that arrives early waits for the gap before it and counts from the frame that
filled the gap (bytes are attributed to the frame where they became readable); a gap never
filled is skipped at the end of its stream, as a capture that lost a segment has to.

**Bounds** (no recursion; memory bounded whatever the capture): segments waiting for a gap
hold at most :data:`WAITING_BUDGET` bytes over all streams, each segment counted with
:data:`SEGMENT_COST` bytes of bookkeeping on top of its payload; past it, the stream holding
most skips its earliest gap (as at its end). At most :data:`MAX_STREAMS` TCP/serial
directions are tracked; a new one ends the least recently active (a later segment of it
starts a new unit). Each waiting segment costs ``O(log n)``.
"""

from __future__ import annotations

import heapq
import itertools
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import NamedTuple

from gcu_async.capture.reader import Record

SYN, FIN, RST = 0x02, 0x01, 0x04
WAITING_BUDGET = 8 << 20
"""Bytes (payload plus :data:`SEGMENT_COST` each) of early segments held over all streams."""
SEGMENT_COST = 128
MAX_STREAMS = 256
"""TCP and serial directions tracked at once."""
_HALF = 2**31
_MOD = 2**32


@dataclass(eq=False)
class Unit:
    """One stream (or datagram) a pair of deframers reads."""

    link: str
    src: str
    dst: str
    index: int
    """Per (link, src, dst): 0 for the first stream, 1 after a new SYN, ..."""
    last_frame: int = 0
    """The frame of the latest bytes (frames never go back within a unit)."""

    @property
    def name(self) -> str:
        suffix = f" #{self.index}" if self.index else ""
        return f"{self.link} {self.src} -> {self.dst}{suffix}"


class Piece(NamedTuple):
    """Bytes of ``unit`` readable in order from ``frame`` on; ``end`` marks its end."""

    unit: Unit
    frame: int
    data: bytes
    end: bool = False


@dataclass(eq=False)
class _Direction:
    link: str
    src: str
    dst: str
    generation: int
    """The index of the next unit of this (link, src, dst)."""
    unit: Unit | None = None
    next_abs: int | None = None
    """Unwrapped sequence number of the next byte wanted (``None``: nothing seen yet)."""
    base: int = 0
    """32-bit sequence number at unwrapped 0."""
    waiting: list[tuple[int, int, int, bytes]] = field(default_factory=list)
    """Heap of (unwrapped seq, arrival, frame, payload) past a gap."""
    held: int = 0
    """Budget bytes the waiting segments use."""


class Reassembler:
    """Records in, :class:`Piece` s out (see the module's rules and bounds)."""

    def __init__(self, *, waiting_budget: int = WAITING_BUDGET,
                 max_streams: int = MAX_STREAMS) -> None:  # fmt: skip
        self._budget = waiting_budget
        self._max_streams = max_streams
        self._held = 0
        self._streams: OrderedDict[tuple[str, str, str], _Direction] = OrderedDict()
        self._arrival = itertools.count()

    @property
    def held(self) -> int:
        """Budget bytes the segments waiting for a gap use now (all streams)."""
        return self._held

    def push(self, rec: Record) -> list[Piece]:
        """The pieces ``rec`` makes readable (in order), including units it ends."""
        out: list[Piece] = []
        if rec.link == "udp":
            unit = Unit("udp", rec.src, rec.dst, 0, rec.frame)
            if rec.payload:
                out.append(Piece(unit, rec.frame, rec.payload))
            out.append(Piece(unit, rec.frame, b"", True))
            return out
        key = (rec.link, rec.src, rec.dst)
        direction = self._streams.get(key)
        if direction is not None:
            self._streams.move_to_end(key)
        if rec.link == "serial":
            if direction is None:
                direction = self._track(key, 0, out)
            self._emit(direction, rec.frame, rec.payload, out)
            return out
        if direction is None or (rec.flags & SYN and direction.next_abs is not None):
            generation = 0 if direction is None else direction.generation
            if direction is not None:
                self._end(direction, out)
            direction = self._track(key, generation, out)
        self._segment(direction, rec, out)
        if rec.flags & (FIN | RST):
            self._end(direction, out)
        return out

    def finish(self) -> list[Piece]:
        """End of the capture: every stream ends (waiting segments taken, gaps skipped)."""
        out: list[Piece] = []
        for direction in self._streams.values():
            self._end(direction, out)
        self._streams.clear()
        return out

    # -- streams ----------------------------------------------------------------------------
    def _track(self, key: tuple[str, str, str], generation: int, out: list[Piece]) -> _Direction:
        if len(self._streams) >= self._max_streams:
            _, oldest = self._streams.popitem(last=False)
            self._end(oldest, out)
        direction = self._streams[key] = _Direction(*key, generation)
        return direction

    def _emit(self, direction: _Direction, frame: int, data: bytes, out: list[Piece]) -> None:
        if not data:
            return
        unit = direction.unit
        if unit is None:
            unit = direction.unit = Unit(direction.link, direction.src, direction.dst,
                                         direction.generation)  # fmt: skip
            direction.generation += 1
        unit.last_frame = max(unit.last_frame, frame)
        out.append(Piece(unit, unit.last_frame, data))

    def _end(self, direction: _Direction, out: list[Piece]) -> None:
        while direction.waiting:
            self._skip_gap(direction, out)
        if direction.unit is not None:
            out.append(Piece(direction.unit, direction.unit.last_frame, b"", True))
            direction.unit = None

    # -- TCP ------------------------------------------------------------------------------------
    def _segment(self, direction: _Direction, rec: Record, out: list[Piece]) -> None:
        if direction.next_abs is None:
            direction.base = (rec.seq + 1) % _MOD if rec.flags & SYN else rec.seq
            direction.next_abs = 0
            if rec.flags & SYN:
                return
        if not rec.payload:
            return
        ahead = (rec.seq - direction.base - direction.next_abs) % _MOD
        seq = direction.next_abs + (ahead if ahead < _HALF else ahead - _MOD)
        self._take(direction, seq, rec.frame, rec.payload, out)
        self._drain(direction, out)
        while self._held > self._budget:
            biggest = max(self._streams.values(), key=lambda d: d.held)
            self._skip_gap(biggest, out)

    def _take(self, direction: _Direction, seq: int, frame: int, payload: bytes,
              out: list[Piece]) -> None:  # fmt: skip
        """Place one segment: emit its new bytes if in order, else make it wait."""
        assert direction.next_abs is not None
        behind = direction.next_abs - seq
        if behind >= len(payload):
            return  # a retransmission of bytes already taken
        if behind > 0:
            payload, seq = payload[behind:], direction.next_abs
        if seq > direction.next_abs:
            heapq.heappush(direction.waiting, (seq, next(self._arrival), frame, payload))
            cost = len(payload) + SEGMENT_COST
            direction.held += cost
            self._held += cost
            return
        self._emit(direction, frame, payload, out)
        direction.next_abs += len(payload)

    def _drain(self, direction: _Direction, out: list[Piece]) -> None:
        """Take every waiting segment the stream has now reached (a loop, not recursion)."""
        waiting = direction.waiting
        while waiting and waiting[0][0] <= direction.next_abs:  # type: ignore[operator]
            seq, _, frame, payload = heapq.heappop(waiting)
            cost = len(payload) + SEGMENT_COST
            direction.held -= cost
            self._held -= cost
            self._take(direction, seq, frame, payload, out)

    def _skip_gap(self, direction: _Direction, out: list[Piece]) -> None:
        """Give up on the earliest gap: go on from the first waiting segment."""
        if direction.waiting:
            direction.next_abs = direction.waiting[0][0]
            self._drain(direction, out)
