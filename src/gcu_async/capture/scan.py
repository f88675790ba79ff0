"""Packets of both directions in one byte stream, located by offset, fed in pieces.

:class:`PacketScanner` runs one :class:`~gcu_async.protocol.deframer.Deframer` per direction
over the same bytes (so its packets are the deframers' reference parse, whatever the
chunking) and says where each packet starts. It keeps only the bytes a deframer may still
return a packet from (at most the deframer's ``max_length - 1``) plus the piece being fed,
and returns packets in stream order as soon as neither direction can return an earlier one.

It also remembers why bytes that looked like a packet were not one — the first span that
failed its CRC, the first header whose span the stream cut short, the first out-of-range
length — from the protocol core's own checks (:class:`~gcu_async.errors.RemoteProtocolError`
``reason``, the deframers' counters), so that "no valid packet" can say what was wrong.
"""

from __future__ import annotations

import heapq
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from gcu_async.errors import ProtocolErrorReason, RemoteProtocolError
from gcu_async.protocol.crc import crc16_xmodem
from gcu_async.protocol.deframer import Deframer
from gcu_async.protocol.packets import (
    BASE_LENGTH,
    CRC_STRUCT,
    GCU_HEADER,
    HOST_HEADER,
    decode_gcu_packet,
    decode_host_packet,
)

Found = tuple[int, int, dict[str, Any]]
"""(offset, length, JSON object) of one packet."""
_PRIORITY = {"crc": 0, "cut": 1, "length": 2}


@dataclass(frozen=True)
class Rejection:
    """Bytes with a packet header that are not a packet, and why."""

    kind: str
    """``"crc"``, ``"cut"`` (the stream ended inside the span) or ``"length"``."""
    offset: int
    message: str

    def more_telling(self, other: Rejection) -> bool:
        """A CRC failure tells more than a cut-short span, which tells more than a length."""
        return _PRIORITY[self.kind] < _PRIORITY[other.kind]


class DecodedPacket(dict[str, Any]):
    """A packet's JSON object that also holds its bytes and the decoded packet
    (``PacketScanner(keep=True)``), e.g. to feed a conformance report."""

    __slots__ = ("packet", "raw")

    def __init__(self, raw: bytes, packet: Any) -> None:
        super().__init__(packet.as_dict())
        self.raw = raw
        self.packet = packet


class _Direction:
    __slots__ = ("decode", "deframer", "header", "name")

    def __init__(self, header: bytes, decode: Callable[[bytes], Any], name: str) -> None:
        self.header = header
        self.deframer = Deframer(header)
        self.decode = decode
        self.name = name


class PacketScanner:
    """Feed bytes, get ``(offset, length, JSON object)`` of each packet, in stream order
    (``keep``: each object a :class:`DecodedPacket`, with its bytes and packet)."""

    def __init__(self, *, keep: bool = False) -> None:
        self.keep = keep
        self._directions = (
            _Direction(GCU_HEADER, decode_gcu_packet, "GCU reply"),
            _Direction(HOST_HEADER, decode_host_packet, "host packet"),
        )
        self._window = b""
        self._start = 0
        """Stream offset of ``_window[0]``."""
        self.fed = 0
        """Bytes fed so far."""
        self._ready: list[tuple[int, int, dict[str, Any]]] = []
        self.rejection: Rejection | None = None
        """The most telling rejected span so far (a CRC failure before a cut-short span
        before an out-of-range length; the first of each)."""
        self.rejected = 0
        """Spans rejected for their length or CRC so far (both deframers' counters)."""

    @property
    def low(self) -> int:
        """The lowest offset a packet still to come can start at."""
        return min(self.fed - d.deframer.buffered for d in self._directions)

    @property
    def buffered(self) -> bool:
        """True while a packet may still come from bytes already fed."""
        return bool(self._ready) or self.low < self.fed

    def feed(self, data: bytes) -> list[Found]:
        """Add ``data``; return the packets now certain, in stream order."""
        if data:
            self._scan(data, flush=False)
        return self._release(self.low)

    def flush(self) -> list[Found]:
        """End of the stream: every packet left (see ``Deframer.flush``)."""
        self._scan(b"", flush=True)
        self._window, self._start = b"", self.fed
        return self._release(None)

    def _scan(self, data: bytes, *, flush: bool) -> None:
        window = self._window + data if self._window else data
        begin, before = self._start, self.fed
        self.fed += len(data)
        for direction in self._directions:
            deframer = direction.deframer
            first = before - deframer.buffered  # its first unsettled byte
            errors = deframer.stats.crc_errors + deframer.stats.length_errors
            if flush and deframer.buffered:
                self._note_cut(window, first - begin, begin, direction)
            raws = deframer.flush() if flush else deframer.feed(data)
            pos = first - begin
            spans: list[tuple[int, int]] = []
            for raw in raws:
                # the reference parse emits the first valid span after the previous packet:
                # the first occurrence of these bytes from there is that span
                at = window.find(raw, pos)
                packet = direction.decode(raw)
                obj = DecodedPacket(raw, packet) if self.keep else packet.as_dict()
                self._ready.append((begin + at, len(raw), obj))
                spans.append((at, at + len(raw)))
                pos = at + len(raw)
            now = deframer.stats.crc_errors + deframer.stats.length_errors
            if now > errors:
                self.rejected += now - errors
                if self.rejection is None or self.rejection.kind != "crc":
                    settled = self.fed - deframer.buffered - begin
                    self._note_rejections(window, first - begin, settled, spans, begin,
                                          direction)  # fmt: skip
        heapq.heapify(self._ready)
        keep = self.low - begin
        self._window, self._start = window[keep:], begin + keep

    def _release(self, below: int | None) -> list[Found]:
        out: list[Found] = []
        while self._ready and (below is None or self._ready[0][0] < below):
            out.append(heapq.heappop(self._ready))
        return out

    # -- why not a packet ------------------------------------------------------------------
    def _note(self, rejection: Rejection) -> None:
        old = self.rejection
        if old is None or rejection.more_telling(old):
            self.rejection = rejection

    def _note_rejections(self, window: bytes, start: int, end: int,
                         spans: list[tuple[int, int]], begin: int,
                         direction: _Direction) -> None:  # fmt: skip
        """Find the rejected spans among the bytes ``[start, end)`` the deframer settled."""
        header, limit = direction.header, direction.deframer.max_length
        i = window.find(header, start)
        j = 0
        while 0 <= i < end and i + 4 <= len(window):
            while j < len(spans) and spans[j][1] <= i:
                j += 1
            if j < len(spans) and spans[j][0] <= i:  # inside a packet: not a candidate
                i = window.find(header, spans[j][1])
                continue
            length = window[i + 2] | (window[i + 3] << 8)
            if not BASE_LENGTH <= length <= limit:
                if self.rejection is None:
                    self._note(Rejection("length", begin + i,
                        f"a {direction.name} header at offset {begin + i} declares a length of "
                        f"{length} bytes, outside {BASE_LENGTH}..{limit}"))  # fmt: skip
            elif i + length <= len(window):
                span = window[i : i + length]
                try:
                    direction.decode(span)
                except RemoteProtocolError as exc:
                    if exc.reason is ProtocolErrorReason.CRC:
                        computed = crc16_xmodem(span[:-2])
                        carried = CRC_STRUCT.unpack_from(span, length - 2)[0]
                        self._note(Rejection("crc", begin + i,
                            f"a {direction.name} of {length} bytes at offset {begin + i} "
                            f"failed its CRC: computed 0x{computed:04X}, carried "
                            f"0x{carried:04X}"))  # fmt: skip
                        return
            i = window.find(header, i + 1)

    def _note_cut(self, window: bytes, start: int, begin: int, direction: _Direction) -> None:
        """At the end: a header with an in-range length whose span did not all arrive."""
        if self.rejection is not None and self.rejection.kind != "length":
            return
        header = direction.header
        i = window.find(header, start)
        while i >= 0 and i + 4 <= len(window):
            length = window[i + 2] | (window[i + 3] << 8)
            if BASE_LENGTH <= length <= direction.deframer.max_length and i + length > len(window):
                have = len(window) - i
                self._note(Rejection("cut", begin + i,
                    f"a {direction.name} at offset {begin + i} is cut short: its header "
                    f"declares {length} bytes, the input ends after {have}"))  # fmt: skip
                return
            i = window.find(header, i + 1)
