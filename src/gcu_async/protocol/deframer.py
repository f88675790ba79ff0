"""Streaming deframer: bytes in any chunking → complete, CRC-checked packets.

One per direction (``8A 5E`` for GCU replies, ``A8 E5`` for host packets). A single
function owns resynchronisation: after an impossible length or a CRC failure it hunts again
from the byte after the false header, so junk can never swallow a valid packet that follows.
Every byte fed ends up in exactly one of: a returned packet, ``bytes_discarded`` or
``buffered``. At most ``max_length - 1`` bytes stay buffered between calls.
"""

from __future__ import annotations

from binascii import crc_hqx
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

    __slots__ = ("_buf", "_header", "_max", "_synced", "stats")

    def __init__(self, header: bytes, *, max_length: int = MAX_LENGTH) -> None:
        if len(header) != 2:
            raise ValueError(f"header: expected 2 bytes, got {len(header)}")
        if not BASE_LENGTH <= max_length <= 0xFFFF:
            raise ValueError(f"max_length: {max_length} is outside [{BASE_LENGTH}, 65535]")
        self._header = bytes(header)
        self._max = max_length
        self._buf = bytearray()
        self._synced = True
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
        self._synced = True

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
        # synced: nothing discarded since the last packet (or the start), so a header here
        # is where the next packet must begin; it is waited for even when a complete packet
        # starts inside its span (that one may be its own payload, not a packet)
        synced = self._synced
        while True:
            i = buf.find(header, pos)
            if i < 0:
                # keep a trailing first header byte: the second may arrive next
                keep = n - 1 if n > pos and buf[n - 1] == first else n
                stats.bytes_discarded += keep - pos
                synced = synced and keep == pos
                pos = keep
                break
            if i != pos:
                stats.bytes_discarded += i - pos
                synced = False
            pos = i
            if n - i < 4:
                break
            length = buf[i + 2] | (buf[i + 3] << 8)
            if not BASE_LENGTH <= length <= max_len:
                stats.length_errors += 1
                stats.bytes_discarded += 1
                synced = False
                pos = i + 1
                continue
            if n - i < length:
                if not synced and self._later_packet(i):
                    # a complete valid packet starts inside this candidate's span: the
                    # candidate is a false header and must not hold the valid one back
                    stats.length_errors += 1
                    stats.bytes_discarded += 1
                    pos = i + 1
                    continue
                break
            end = i + length
            packet = buf[i:end]
            if crc_hqx(packet, 0):  # CRC-16/XMODEM (crc.py) over data + CRC is 0 iff it matches
                stats.crc_errors += 1
                stats.bytes_discarded += 1
                synced = False
                pos = i + 1
                continue
            out.append(bytes(packet))
            synced = True
            pos = end
        self._synced = synced
        stats.packets += len(out)
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
