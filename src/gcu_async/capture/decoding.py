"""Every packet of a pcap or pcapng capture, decoded as the file is read.

Each packet's JSON object gets a ``capture`` object: the ``frame`` (1-based, as in
Wireshark) that brought its last byte and that frame's ``time`` (seconds since the epoch),
its ``link`` (udp, tcp, serial), ``src`` and ``dst``, and the ``stream`` it belongs to.
UDP datagrams are decoded one by one; the bytes of each TCP or serial direction are put in
order first (:mod:`~gcu_async.capture.reassembly`).

**Order.** By frame, then by the order the streams started, then by position in the stream
— exactly, as long as fewer than :data:`MAX_HELD` packets wait behind a packet that an
unfinished span in another stream might still complete (a false header near the end of a
stream that then goes quiet); past that, the earliest waiting packets come out first.

**Damage.** At the first structural damage of the file, every stream ends as at the end of
the file (so every packet before the damage comes out), then the
:class:`~gcu_async.capture.CaptureError` naming the record or block and its offset is
raised.

**Memory** is bounded: the file is read a block at a time (:mod:`~gcu_async.capture.blocks`),
the reassembly's waiting bytes and streams are bounded, each stream keeps fewer than 256
bytes of deframer state, and at most :data:`MAX_HELD` decoded packets wait to be put in order.
"""

from __future__ import annotations

import bisect
import heapq
import itertools
from collections.abc import Iterator
from typing import Any

from gcu_async.capture.blocks import CaptureError, Source
from gcu_async.capture.reader import read_records
from gcu_async.capture.reassembly import Piece, Reassembler, Unit
from gcu_async.capture.scan import PacketScanner, Rejection

MAX_HELD = 1024
"""Decoded packets held at most to put them in frame order."""


class _UnitState:
    __slots__ = ("marks", "number", "scanner")

    def __init__(self, number: int, keep: bool) -> None:
        self.number = number
        self.scanner = PacketScanner(keep=keep)
        self.marks: list[tuple[int, int, float]] = []
        """(stream offset, frame, its time) where each piece's bytes begin: those the
        scanner may still need (fewer than its deframers' longest packet, plus the last
        piece)."""

    def mark_of(self, offset: int) -> tuple[int, int, float]:
        return self.marks[bisect.bisect_right(self.marks, offset, key=_offset) - 1]

    def frame_of(self, offset: int) -> int:
        return self.mark_of(offset)[1]

    def trim(self) -> None:
        """Forget the marks before the one that covers the scanner's lowest offset."""
        drop = bisect.bisect_right(self.marks, self.scanner.low, key=_offset) - 1
        if drop > 0:
            del self.marks[:drop]


def _offset(mark: tuple[int, int, float]) -> int:
    return mark[0]


class CaptureDecoder:
    """Iterate to get every packet's JSON object (see the module's contract; ``keep``: each
    a :class:`~gcu_async.capture.scan.DecodedPacket`, with its bytes and packet)."""

    def __init__(self, source: Source, *, keep: bool = False) -> None:
        self._source = source
        self._keep = keep
        self._units: dict[Unit, _UnitState] = {}
        self._numbers = itertools.count()
        self._held: list[tuple[int, int, int, int, dict[str, Any]]] = []
        self._order = itertools.count()
        self.rejection: tuple[str, Rejection] | None = None
        """The most telling span that looked like a packet but was not, with its stream."""

    @property
    def bytes_read(self) -> int:
        return self._source.offset

    def __iter__(self) -> Iterator[dict[str, Any]]:
        reassembler = Reassembler()
        records = read_records(self._source)
        try:
            for record in records:
                self._pieces(reassembler.push(record), record.time)
                yield from self._release(self._watermark(record.frame + 1))
        except CaptureError:  # damage ends every stream as the end of the file would
            self._pieces(reassembler.finish())
            yield from self._release(None)
            raise
        self._pieces(reassembler.finish())
        yield from self._release(None)

    def _pieces(self, pieces: list[Piece], time: float = 0.0) -> None:
        """Feed the pieces one record (at ``time``) made readable; at the end of the file,
        the end of every unit."""
        for piece in pieces:
            state = self._units.get(piece.unit)
            if state is None:
                if piece.end:
                    continue
                state = self._units[piece.unit] = _UnitState(next(self._numbers), self._keep)
            if piece.end:
                self._found(piece.unit, state, state.scanner.flush())
                self._note(piece.unit, state)
                del self._units[piece.unit]
                continue
            state.marks.append((state.scanner.fed, piece.frame, time))
            self._found(piece.unit, state, state.scanner.feed(piece.data))
            state.trim()

    def _found(self, unit: Unit, state: _UnitState,
               found: list[tuple[int, int, dict[str, Any]]]) -> None:  # fmt: skip
        for offset, length, obj in found:
            _, frame, time = state.mark_of(offset + length - 1)
            obj["capture"] = {"frame": frame, "time": time, "link": unit.link, "src": unit.src,
                              "dst": unit.dst, "stream": unit.name}  # fmt: skip
            heapq.heappush(self._held, (frame, state.number, offset, next(self._order), obj))

    def _note(self, unit: Unit, state: _UnitState) -> None:
        rejection = state.scanner.rejection
        if rejection is None:
            return
        if self.rejection is None or rejection.more_telling(self.rejection[1]):
            self.rejection = (unit.name, rejection)

    def _watermark(self, upcoming: int) -> int:
        """The lowest frame a packet still to come can have."""
        if not self._held:
            return upcoming
        low = upcoming
        for state in self._units.values():
            if state.scanner.buffered:
                low = min(low, state.frame_of(state.scanner.low))
        return low

    def _release(self, below: int | None) -> Iterator[dict[str, Any]]:
        held = self._held
        while held and (below is None or held[0][0] < below or len(held) > MAX_HELD):
            yield heapq.heappop(held)[-1]
