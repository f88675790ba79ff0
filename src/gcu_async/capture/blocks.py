"""The block structure of pcap and pcapng files, read as a stream.

Read here rather than with dpkt's ``pcap.Reader`` or python-pcapng's ``FileScanner``
because both read whatever length a record or block header declares in one ``read`` (a
damaged length field makes them read up to 4 GiB, the rest of the file, into memory), raise
a handful of exception types (``dpkt.NeedData``, ``struct.error``, ``CorruptedFile``, ...)
without saying where, and python-pcapng stops without an error on some damage. The
structure is small: a pcap file is a 24-byte header and records of a 16-byte header plus
data; a pcapng file is blocks of ``type, length, body, length``.

**Contract.** :func:`packets` yields the packet records of a file in order and raises
:class:`CaptureError` (a ``ValueError`` naming the record or block number and its byte
offset) at the first structural damage, after every packet before it. Memory is bounded
whatever the input: a packet block is read into memory only when its declared length is at
most :data:`MAX_BLOCK` (larger ones are damage), other blocks are skipped in chunks of
:data:`CHUNK` bytes (seeking over them when the file can seek), and nothing else is kept
but the current section's interfaces (at most :data:`MAX_INTERFACES`).
"""

from __future__ import annotations

import os
import stat
import struct
from collections.abc import Iterator
from dataclasses import dataclass
from typing import BinaryIO, NamedTuple

from gcu_async.errors import GcuError

PCAP_MAGICS = {
    b"\xd4\xc3\xb2\xa1": ("<", 1e-6), b"\xa1\xb2\xc3\xd4": (">", 1e-6),
    b"\x4d\x3c\xb2\xa1": ("<", 1e-9), b"\xa1\xb2\x3c\x4d": (">", 1e-9),
}  # fmt: skip
"""Magic -> (byte order, timestamp unit): microsecond and nanosecond pcap."""
PCAPNG_MAGIC = b"\x0a\x0d\x0d\x0a"
MAX_PACKET = 262_144
"""Longest packet record accepted (Wireshark's limit for the link types read here)."""
MAX_BLOCK = MAX_PACKET + 65_536
"""Longest pcapng packet/section/interface block read into memory: a packet and its options."""
MAX_INTERFACES = 65_536
CHUNK = 1 << 20
"""Bytes read at a time when skipping a block that is not kept."""

_SHB, _IDB, _PB, _SPB, _EPB = 0x0A0D0D0A, 1, 2, 3, 6
_BYTE_ORDER_MAGIC = 0x1A2B3C4D
_SHB_LENGTH = 28
"""Shortest section header block: 12 bytes of framing, byte-order magic, version, length."""
_FLAGS_OPTION, _TSRESOL_OPTION, _TSOFFSET_OPTION = 2, 9, 14


class CaptureError(GcuError, ValueError):
    """A pcap or pcapng file is damaged (or is not one); the message names where."""

    def __init__(self, message: str, *, offset: int, block: int | None = None) -> None:
        super().__init__(message)
        self.offset = offset
        """Byte offset in the file of the damaged record or block (0: the file header)."""
        self.block = block
        """1-based number of the damaged record (pcap) or block (pcapng), if any."""


class Packet(NamedTuple):
    """One packet record: its time, link type, bytes, pcapng direction flags, interface."""

    time: float
    linktype: int
    data: bytes
    flags: int | None
    interface: int


class Source:
    """A binary stream read in order, with the offset of the next byte and a look-ahead
    that is handed back (the first bytes that told pcap from pcapng)."""

    def __init__(self, stream: BinaryIO, head: bytes = b"") -> None:
        self._stream = stream
        self._head = head
        self.offset = 0

    def read(self, n: int) -> bytes:
        """Up to ``n`` bytes (fewer only at the end of the input)."""
        parts: list[bytes] = []
        got = 0
        if self._head:
            part, self._head = self._head[:n], self._head[n:]
            parts.append(part)
            got = len(part)
        while got < n:
            part = self._stream.read(n - got)
            if not part:
                break
            parts.append(part)
            got += len(part)
        data = b"".join(parts)
        self.offset += len(data)
        return data

    def skip(self, n: int) -> int:
        """Pass over up to ``n`` bytes without keeping them; return how many there were."""
        done = min(n, len(self._head))
        self._head = self._head[done:]
        if done < n and self._regular_file():  # seek, but never past the end
            here = self._stream.tell()
            end = self._stream.seek(0, os.SEEK_END)
            step = max(0, min(n - done, end - here))
            self._stream.seek(here + step)
            done += step
        while done < n:
            part = self._stream.read(min(CHUNK, n - done))
            if not part:
                break
            done += len(part)
        self.offset += done
        return done

    def _regular_file(self) -> bool:
        try:
            return stat.S_ISREG(os.fstat(self._stream.fileno()).st_mode)
        except (OSError, ValueError, AttributeError):  # BytesIO has no fileno
            return False


def packets(source: Source) -> Iterator[Packet]:
    """The packet records of a pcap or pcapng file (see the module's contract)."""
    head = source.read(4)
    if head == PCAPNG_MAGIC:
        yield from _pcapng(source, head)
    elif head in PCAP_MAGICS:
        yield from _pcap(source, head)
    else:
        shown = head.hex(" ") or "nothing"
        raise CaptureError(f"not a pcap or pcapng file (offset 0: {shown})", offset=0)


def _truncated(what: str, n: int, got: int, offset: int, block: int | None) -> CaptureError:
    where = f"{what} at offset {offset}"
    return CaptureError(f"{where}: truncated: {n} bytes needed, {got} present", offset=offset,
                        block=block)  # fmt: skip


def _pcap(source: Source, magic: bytes) -> Iterator[Packet]:
    order, unit = PCAP_MAGICS[magic]
    rest = source.read(20)
    if len(rest) < 20:
        raise _truncated("pcap file header", 24, 4 + len(rest), 0, None)
    major, minor, _zone, _sigfigs, _snaplen, network = struct.unpack(order + "HHiIII", rest)
    if major != 2:
        raise CaptureError(f"pcap file header at offset 0: version {major}.{minor} is not 2.x",
                           offset=0)  # fmt: skip
    linktype = network & 0xFFFF  # the upper bits carry FCS information
    record = struct.Struct(order + "IIII")
    number = 0
    while True:
        number += 1
        start = source.offset
        what = f"record {number}"
        header = source.read(16)
        if not header:
            return
        if len(header) < 16:
            raise _truncated(f"{what} header", 16, len(header), start, number)
        seconds, fraction, caplen, origlen = record.unpack(header)
        if caplen > MAX_PACKET:
            raise CaptureError(f"{what} at offset {start}: captured length {caplen} is more "
                               f"than {MAX_PACKET}", offset=start, block=number)  # fmt: skip
        if origlen == 0:  # what a zero-filled stretch (a sparse or preallocated file) reads as
            raise CaptureError(f"{what} at offset {start}: original length 0 (no packet is 0 "
                               f"bytes long)", offset=start, block=number)  # fmt: skip
        if caplen > origlen:
            raise CaptureError(f"{what} at offset {start}: captured length {caplen} is more "
                               f"than the original length {origlen}", offset=start,
                               block=number)  # fmt: skip
        data = source.read(caplen)
        if len(data) < caplen:
            raise _truncated(what, 16 + caplen, 16 + len(data), start, number)
        yield Packet(seconds + fraction * unit, linktype, data, None, 0)


@dataclass
class _Interface:
    linktype: int
    snaplen: int
    resolution: float = 1e-6
    offset: int = 0


class _Damage(Exception):
    """A problem inside a block's body (turned into a CaptureError naming the block)."""


def _pcapng(source: Source, magic: bytes) -> Iterator[Packet]:
    order = "<"
    interfaces: list[_Interface] = []
    number = 0
    first = magic
    while True:
        number += 1
        start = source.offset
        head = first + source.read(8 - len(first))
        first = b""
        if not head:
            return
        what = f"block {number}"
        if len(head) < 8:
            raise _truncated(f"{what} header", 8, len(head), start, number)
        if head[:4] == PCAPNG_MAGIC:
            bom = source.read(4)
            if len(bom) < 4:
                raise _truncated(f"{what} (section header)", 12, 8 + len(bom), start, number)
            if struct.unpack("<I", bom)[0] == _BYTE_ORDER_MAGIC:
                order = "<"
            elif struct.unpack(">I", bom)[0] == _BYTE_ORDER_MAGIC:
                order = ">"
            else:
                raise CaptureError(f"{what} (section header) at offset {start}: byte-order "
                                   f"magic {bom.hex(' ')} is not 1a 2b 3c 4d in either order",
                                   offset=start, block=number)  # fmt: skip
            head += bom
            interfaces = []
        kind, length = struct.unpack(order + "II", head[:8])
        name = f"{what} (type 0x{kind:08x})"
        shortest = _SHB_LENGTH if kind == _SHB else 12
        if length < shortest or length % 4:
            raise CaptureError(f"{name} at offset {start}: block length {length} is not a "
                               f"multiple of 4 of at least {shortest}",
                               offset=start, block=number)  # fmt: skip
        kept = kind in (_SHB, _IDB, _PB, _SPB, _EPB)
        if not kept:
            body_length = length - 12
            skipped = source.skip(body_length)
            if skipped < body_length:
                raise _truncated(name, length, 8 + skipped, start, number)
            body = b""
        else:
            if length > MAX_BLOCK:
                raise CaptureError(f"{name} at offset {start}: block length {length} is more "
                                   f"than {MAX_BLOCK}", offset=start, block=number)  # fmt: skip
            body = head[8:] + source.read(length - len(head) - 4)
            if len(body) < length - 12:
                raise _truncated(name, length, 8 + len(body), start, number)
        trailer = source.read(4)
        if len(trailer) < 4:
            raise _truncated(name, length, length - 4 + len(trailer), start, number)
        (again,) = struct.unpack(order + "I", trailer)
        if again != length:
            raise CaptureError(f"{name} at offset {start}: block length {length} at its start "
                               f"but {again} at its end", offset=start, block=number)  # fmt: skip
        if not kept:
            continue
        try:
            packet = _block(kind, body, order, interfaces)
        except _Damage as exc:
            raise CaptureError(f"{name} at offset {start}: {exc}", offset=start,
                               block=number) from None  # fmt: skip
        if packet is not None:
            yield packet


def _options(body: bytes, at: int, order: str) -> dict[int, bytes]:
    """The options from ``at`` to the end of ``body`` (first value of each code)."""
    found: dict[int, bytes] = {}
    while at + 4 <= len(body):
        code, size = struct.unpack_from(order + "HH", body, at)
        if code == 0:
            break
        end = at + 4 + size
        if end > len(body):
            raise _Damage(f"option {code} of {size} bytes runs past the block's end")
        found.setdefault(code, body[at + 4 : end])
        at = end + (-size % 4)
    return found


def _block(kind: int, body: bytes, order: str, interfaces: list[_Interface]) -> Packet | None:
    if kind == _SHB:
        major = struct.unpack_from(order + "H", body, 4)[0]
        if major != 1:
            raise _Damage(f"section version {major} is not 1")
        return None
    if kind == _IDB:
        if len(body) < 8:
            raise _Damage(f"interface description body of {len(body)} bytes is shorter than 8")
        if len(interfaces) >= MAX_INTERFACES:
            raise _Damage(f"more than {MAX_INTERFACES} interfaces in one section")
        linktype, _, snaplen = struct.unpack_from(order + "HHI", body)
        options = _options(body, 8, order)
        iface = _Interface(linktype, snaplen)
        resol = options.get(_TSRESOL_OPTION)
        if resol:
            value = resol[0]
            iface.resolution = 2.0 ** -(value & 0x7F) if value & 0x80 else 10.0**-value
        offset = options.get(_TSOFFSET_OPTION)
        if offset is not None and len(offset) == 8:
            iface.offset = struct.unpack(order + "q", offset)[0]
        interfaces.append(iface)
        return None
    if kind == _SPB:
        if len(body) < 4:
            raise _Damage(f"simple packet body of {len(body)} bytes is shorter than 4")
        iface = _interface(interfaces, 0)
        (origlen,) = struct.unpack_from(order + "I", body)
        caplen = min(origlen, len(body) - 4, iface.snaplen or MAX_PACKET)
        return Packet(0.0, iface.linktype, body[4 : 4 + caplen], None, 0)
    if kind == _EPB:
        fixed, layout = 20, order + "IIIII"
    else:  # the obsolete Packet Block
        fixed, layout = 20, order + "HHIIII"
    if len(body) < fixed:
        raise _Damage(f"packet body of {len(body)} bytes is shorter than {fixed}")
    fields = struct.unpack_from(layout, body)
    number = fields[0]
    high, low, caplen = fields[-4], fields[-3], fields[-2]
    if 20 + caplen > len(body):
        raise _Damage(f"captured length {caplen} is more than the block's {len(body) - 20} "
                      f"bytes of packet data")  # fmt: skip
    iface = _interface(interfaces, number)
    options = _options(body, 20 + caplen + (-caplen % 4), order)
    flags: int | None = None
    raw = options.get(_FLAGS_OPTION)
    if raw is not None and len(raw) == 4:
        flags = struct.unpack(order + "I", raw)[0] & 0x3
    time = ((high << 32) | low) * iface.resolution + iface.offset
    return Packet(time, iface.linktype, body[20 : 20 + caplen], flags, number)


def _interface(interfaces: list[_Interface], number: int) -> _Interface:
    if number >= len(interfaces):
        raise _Damage(f"refers to interface {number}; the section describes {len(interfaces)}")
    return interfaces[number]
