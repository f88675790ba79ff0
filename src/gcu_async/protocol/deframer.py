"""Streaming deframer: bytes in any chunking → complete, CRC-checked packets.

One per direction (``8A 5E`` for GCU replies, ``A8 E5`` for host packets).

**Contract.** The packets returned, every counter and ``buffered`` are a function of the
bytes fed so far, never of how they were split into ``feed`` calls. The packets are those of
the *reference parse* of the stream: greedy, left to right; at position *i*, if the header
starts there, its declared length S is in ``[72, max_length]``, all S bytes are present and
the CRC matches, the packet is emitted and the parse continues after it; otherwise one byte
is discarded (a length outside the range counts a ``length_error``, a complete span with a
wrong CRC a ``crc_error``). ``feed`` stops at the first position whose bytes could still
become a valid packet (a lone first header byte at the very end, a header whose length has
not arrived, an in-range length whose span has not) and holds the rest in ``buffered``;
:meth:`Deframer.flush` ends the stream (a datagram, a closed connection): such a span loses
its first byte and the rest is parsed. So a valid packet nested inside another valid packet
is part of it, never a packet of its own.

**Accounting.** Every byte fed ends up in exactly one of: a returned packet,
``stats.bytes_discarded``, ``buffered``; and ``buffered <= max_length - 1``.

**Hold-back bound.** A packet of the reference parse starting at stream offset *s* and
ending at *e* is returned by the feed that brings the stream to ``max(e, s + max_length -
1)`` bytes, i.e. at most ``max_length - 1 - len`` bytes after its end: 15 for a 72-byte reply
with the GCU default 88, 55 for a 72-byte host packet with the host default 128. Both
defaults are at most ``2 × 72 + 1``, so a held-back packet is released by the packet right
after it: at 50 packets/s one packet period (20 ms) late at most, where a false header
declaring 255 used to hold back the next three replies (about 60 ms). Waiting is inherent:
until a candidate's span is in, nobody can tell a false header from a valid packet whose
parameters contain another packet.

**Inherent exception.** Junk whose bytes happen to form a CRC-valid frame (probability
2^-16 per false header with an in-range length) is a packet as far as any deframer can tell,
and may overlap (and so cost) a valid packet after it.

**Cost.** A feed costs O(len(data) + buffered).
"""

from __future__ import annotations

from binascii import crc_hqx
from dataclasses import dataclass

from gcu_async._checks import check_int
from gcu_async.protocol.packets import BASE_LENGTH, GCU_HEADER, HOST_HEADER, MAX_LENGTH

GCU_MAX_LENGTH = BASE_LENGTH + 16
"""Default longest GCU reply (88): V2.0.6 replies are 72 or 73 bytes (one execution-status
byte); 16 status bytes leave room for a later firmware."""
HOST_MAX_LENGTH = 128
"""Default longest host packet: V2.0.6's longest is 84 (12 parameter bytes); 56 parameter
bytes leave room for commands it does not define."""


@dataclass
class DeframerStats:
    """Counters of one deframer."""

    packets: int = 0
    bytes_discarded: int = 0
    crc_errors: int = 0
    length_errors: int = 0


class Deframer:
    """Sync on ``header``, check length and CRC, return whole packets as ``bytes``.

    ``max_length`` (``[72, 65535]``, default 256 for offline decoding; the direction
    constructors default to a realistic maximum) bounds both the packets accepted and the
    bytes a false header can hold back.
    """

    __slots__ = ("_buf", "_header", "_max", "stats")

    def __init__(self, header: bytes, *, max_length: int = MAX_LENGTH) -> None:
        if len(header) != 2:
            raise ValueError(f"header: expected 2 bytes, got {len(header)}: {bytes(header)!r}")
        self._header = bytes(header)
        self._max = check_int("max_length", max_length, BASE_LENGTH, 0xFFFF, "bytes")
        self._buf = b""
        self.stats = DeframerStats()

    @classmethod
    def for_gcu_packets(cls, *, max_length: int = GCU_MAX_LENGTH) -> Deframer:
        """Deframer for GCU → host replies (what a client reads)."""
        return cls(GCU_HEADER, max_length=max_length)

    @classmethod
    def for_host_packets(cls, *, max_length: int = HOST_MAX_LENGTH) -> Deframer:
        """Deframer for host → GCU packets (what a GCU or the simulator reads)."""
        return cls(HOST_HEADER, max_length=max_length)

    @property
    def max_length(self) -> int:
        """Longest packet accepted, in bytes."""
        return self._max

    @property
    def buffered(self) -> int:
        """Bytes held because they could still be the start of a valid packet."""
        return len(self._buf)

    def reset(self) -> None:
        """Drop buffered bytes (counted as discarded), e.g. after a reconnect. Unlike
        :meth:`flush`, a packet inside a pending span is lost with it."""
        self.stats.bytes_discarded += len(self._buf)
        self._buf = b""

    def flush(self) -> list[bytes]:
        """End of stream: settle the buffered bytes as the reference parse does (a span that
        cannot complete loses its first byte and the rest is parsed again); return the packets
        found. Afterwards ``buffered == 0``; the next feed starts a new stream."""
        out: list[bytes] = []
        while self._buf:
            self._buf = self._buf[1:]
            self.stats.bytes_discarded += 1
            out += self.feed(b"")
        return out

    def feed(self, data: bytes | bytearray | memoryview) -> list[bytes]:
        """Add ``data``; return every packet completed by it, in order. Never raises on
        malformed input: bad bytes are counted and skipped."""
        buf = self._buf + data if self._buf else bytes(data)
        out: list[bytes] = []
        header = self._header
        max_len = self._max
        stats = self.stats
        pos = 0
        n = len(buf)
        while True:
            i = buf.find(header, pos)
            if i < 0:
                # keep a trailing first header byte: the second may arrive next
                keep = n - 1 if n > pos and buf[n - 1] == header[0] else n
                stats.bytes_discarded += keep - pos
                pos = keep
                break
            if i != pos:
                stats.bytes_discarded += i - pos
                pos = i
            if n - i < 4:
                break
            end = i + (buf[i + 2] | (buf[i + 3] << 8))
            if not BASE_LENGTH <= end - i <= max_len:
                stats.length_errors += 1
                stats.bytes_discarded += 1
                pos = i + 1
                continue
            if end > n:
                break  # an in-range span not in yet: wait for it, whatever follows
            packet = buf[i:end]
            if crc_hqx(packet, 0):  # CRC-16/XMODEM (crc.py) over data + CRC is 0 iff it matches
                stats.crc_errors += 1
                stats.bytes_discarded += 1
                pos = i + 1
                continue
            out.append(packet)
            pos = end
        stats.packets += len(out)
        self._buf = buf[pos:] if pos else buf
        return out
