"""Streaming deframer: bytes in any chunking → complete, CRC-checked packets.

One per direction (``8A 5E`` for GCU replies, ``A8 E5`` for host packets). A single
function owns resynchronisation: after an impossible length or a CRC failure it hunts again
from the byte after the false header, so junk can never swallow a valid packet that follows.
Every byte fed ends up in exactly one of: a returned packet, ``bytes_discarded`` or
``buffered``. At most ``max_length - 1`` bytes stay buffered between calls.
"""

from __future__ import annotations

from dataclasses import dataclass

from gcu_async.protocol.crc import crc16_xmodem
from gcu_async.protocol.packets import BASE_LENGTH, GCU_HEADER, HOST_HEADER, MAX_LENGTH


@dataclass
class DeframerStats:
    """Counters of one deframer."""

    packets: int = 0
    bytes_discarded: int = 0
    crc_errors: int = 0
    length_errors: int = 0


class Deframer:
    """Sync on ``header``, check length and CRC, return whole packets as ``bytes``."""

    __slots__ = ("_buf", "_header", "_max", "stats")

    def __init__(self, header: bytes, *, max_length: int = MAX_LENGTH) -> None:
        if len(header) != 2:
            raise ValueError(f"header: expected 2 bytes, got {len(header)}")
        if not BASE_LENGTH <= max_length <= 0xFFFF:
            raise ValueError(f"max_length: {max_length} is outside [{BASE_LENGTH}, 65535]")
        self._header = bytes(header)
        self._max = max_length
        self._buf = bytearray()
        self.stats = DeframerStats()

    @classmethod
    def for_gcu_packets(cls, *, max_length: int = MAX_LENGTH) -> Deframer:
        """Deframer for GCU → host replies (what a client reads)."""
        return cls(GCU_HEADER, max_length=max_length)

    @classmethod
    def for_host_packets(cls, *, max_length: int = MAX_LENGTH) -> Deframer:
        """Deframer for host → GCU packets (what a GCU or the simulator reads)."""
        return cls(HOST_HEADER, max_length=max_length)

    @property
    def buffered(self) -> int:
        """Bytes held while waiting for the rest of a packet."""
        return len(self._buf)

    def reset(self) -> None:
        """Drop buffered bytes (counted as discarded), e.g. after a reconnect."""
        self.stats.bytes_discarded += len(self._buf)
        self._buf.clear()

    def feed(self, data: bytes | bytearray | memoryview) -> list[bytes]:
        """Add ``data``; return every packet completed by it, in order. Never raises on
        malformed input: bad bytes are counted and skipped."""
        buf = self._buf
        buf += data
        out: list[bytes] = []
        header = self._header
        first = header[0]
        max_len = self._max
        stats = self.stats
        pos = 0
        n = len(buf)
        while True:
            i = buf.find(header, pos)
            if i < 0:
                # keep a trailing first header byte: the second may arrive next
                keep = n - 1 if n > pos and buf[n - 1] == first else n
                stats.bytes_discarded += keep - pos
                pos = keep
                break
            stats.bytes_discarded += i - pos
            pos = i
            if n - i < 4:
                break
            length = buf[i + 2] | (buf[i + 3] << 8)
            if not BASE_LENGTH <= length <= max_len:
                stats.length_errors += 1
                stats.bytes_discarded += 1
                pos = i + 1
                continue
            if n - i < length:
                if self._later_packet(i):
                    # a complete valid packet starts inside this candidate's span: the
                    # candidate is a false header and must not hold the valid one back
                    stats.length_errors += 1
                    stats.bytes_discarded += 1
                    pos = i + 1
                    continue
                break
            end = i + length
            crc = crc16_xmodem(memoryview(buf)[i : end - 2])
            if crc != (buf[end - 2] << 8 | buf[end - 1]):
                stats.crc_errors += 1
                stats.bytes_discarded += 1
                pos = i + 1
                continue
            out.append(bytes(buf[i:end]))
            stats.packets += 1
            pos = end
        if pos:
            del buf[:pos]
        return out

    def _later_packet(self, start: int) -> bool:
        """Is there a complete, CRC-valid packet starting after ``start``?"""
        buf = self._buf
        n = len(buf)
        j = buf.find(self._header, start + 1)
        while j >= 0 and n - j >= BASE_LENGTH:
            length = buf[j + 2] | (buf[j + 3] << 8)
            if BASE_LENGTH <= length <= self._max and n - j >= length:
                end = j + length
                if crc16_xmodem(memoryview(buf)[j : end - 2]) == (buf[end - 2] << 8 | buf[end - 1]):
                    return True
            j = buf.find(self._header, j + 1)
        return False
