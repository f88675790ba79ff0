"""Read pcap and pcapng captures into UDP datagrams, TCP segments and serial chunks.

Frames are numbered from 1 in file order, as Wireshark numbers them (every packet record
counts, whatever it carries). Link types: Ethernet (tcpdump/dumpcap on ``lo``), Linux cooked
capture v1 and v2 (``-i any``), BSD loopback (NULL/LOOP), raw IP (``LINKTYPE_RAW``, IPv4,
IPv6: gcu_async's own captures) and :data:`~gcu_async.capture.writer.SERIAL_LINKTYPE`
(gcu_async's serial links, with the pcapng direction flag). Other records, and packets that
are neither UDP nor TCP, are skipped.
"""

from __future__ import annotations

import io
import socket
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from gcu_async.capture import _deps
from gcu_async.capture.writer import FLAG_INBOUND, FLAG_OUTBOUND, SERIAL_LINKTYPE

PCAP_MAGICS = (b"\xd4\xc3\xb2\xa1", b"\xa1\xb2\xc3\xd4", b"\x4d\x3c\xb2\xa1", b"\xa1\xb2\x3c\x4d")
PCAPNG_MAGIC = b"\x0a\x0d\x0d\x0a"
LINKTYPE_NULL, LINKTYPE_EN10MB, LINKTYPE_RAW, LINKTYPE_LOOP = 0, 1, 101, 108
LINKTYPE_LINUX_SLL, LINKTYPE_IPV4, LINKTYPE_IPV6, LINKTYPE_LINUX_SLL2 = 113, 228, 229, 276
_RAW_ALIASES = (12, 14, LINKTYPE_RAW, LINKTYPE_IPV4, LINKTYPE_IPV6)  # DLT_RAW differs by OS


@dataclass(frozen=True)
class Record:
    """One UDP datagram, TCP segment or serial chunk of a capture."""

    frame: int
    """1-based frame number (as Wireshark shows it)."""
    time: float
    """Seconds since the epoch."""
    link: str
    """``"udp"``, ``"tcp"`` or ``"serial"``."""
    src: str
    """``host:port`` (IPv6 in brackets), or for serial ``interface N``."""
    dst: str
    """``host:port``, or for serial ``sent`` / ``received`` / ``unknown`` (the direction
    flag, as seen by the capturing side)."""
    payload: bytes
    seq: int = 0
    """TCP: sequence number of the first payload byte (or of the SYN/FIN)."""
    flags: int = 0
    """TCP flags (SYN 0x02, FIN 0x01, RST 0x04)."""


def is_capture(data: bytes) -> bool:
    """True when ``data`` starts like a pcap or pcapng file."""
    return data[:4] in PCAP_MAGICS or data[:4] == PCAPNG_MAGIC


def read_records(data: bytes) -> Iterator[Record]:
    """Every UDP, TCP and serial record of a pcap or pcapng file, in file order. Raises
    ``ValueError`` when ``data`` is not such a file (or is damaged before the first record)."""
    if data[:4] == PCAPNG_MAGIC:
        packets = _pcapng_packets(data)
    elif data[:4] in PCAP_MAGICS:
        packets = _pcap_packets(data)
    else:
        raise ValueError("not a pcap or pcapng file")
    for frame, (ts, linktype, buf, flags, iface) in enumerate(packets, start=1):
        record = _decode(frame, ts, linktype, buf, flags, iface)
        if record is not None:
            yield record


_Packet = tuple[float, int, bytes, int | None, int]
"""(time, link type, bytes, pcapng direction flags, interface id)"""


def _pcap_packets(data: bytes) -> Iterator[_Packet]:
    dpkt = _deps.dpkt()
    try:
        reader = dpkt.pcap.Reader(io.BytesIO(data))
    except (ValueError, dpkt.dpkt.Error) as exc:
        raise ValueError(f"damaged pcap file: {exc}") from None
    linktype = reader.datalink()
    for ts, buf in reader:
        yield float(ts), linktype, bytes(buf), None, 0


def _pcapng_packets(data: bytes) -> Iterator[_Packet]:
    pcapng = _deps.pcapng()
    blocks = pcapng.blocks
    with warnings.catch_warnings():  # questionable options of other writers: still read
        warnings.simplefilter("ignore")
        pcapng.strictness.set_strictness(pcapng.strictness.Strictness.NONE)
        try:
            scanner = iter(pcapng.FileScanner(io.BytesIO(data)))
        except Exception as exc:  # the library raises several types for damaged files
            raise ValueError(f"damaged pcapng file: {exc}") from None
        while True:
            try:
                block = next(scanner)
            except StopIteration:
                return
            except Exception:  # a truncated last block (a capture still being written)
                return
            if not isinstance(block, (blocks.EnhancedPacket, blocks.SimplePacket,
                                      blocks.ObsoletePacket)):  # fmt: skip
                continue
            try:
                interface = block.interface
                linktype, iface = int(interface.link_type), int(interface.interface_id)
                ts = float(block.timestamp) if hasattr(block, "timestamp") else 0.0
            except Exception:
                linktype, iface, ts = -1, 0, 0.0
            flags: int | None = None
            options = getattr(block, "options", None)
            if options is not None and "epb_flags" in options:
                inout = getattr(options["epb_flags"], "inout", "NA")
                flags = {"inbound": FLAG_INBOUND, "outbound": FLAG_OUTBOUND}.get(inout, 0)
            yield ts, linktype, bytes(block.packet_data), flags, iface


def _hostport(packed: bytes, port: int) -> str:
    if len(packed) == 4:
        return f"{socket.inet_ntop(socket.AF_INET, packed)}:{port}"
    return f"[{socket.inet_ntop(socket.AF_INET6, packed)}]:{port}"


def _network_layer(linktype: int, buf: bytes) -> Any:
    """The dpkt IP or IP6 object of a link-layer frame, or None."""
    dpkt = _deps.dpkt()
    if linktype == LINKTYPE_EN10MB:
        frame: Any = dpkt.ethernet.Ethernet(buf)
    elif linktype == LINKTYPE_LINUX_SLL:
        frame = dpkt.sll.SLL(buf)
    elif linktype == LINKTYPE_LINUX_SLL2:
        frame = dpkt.sll2.SLL2(buf)
    elif linktype in (LINKTYPE_NULL, LINKTYPE_LOOP):
        return _raw_ip(buf[4:])
    elif linktype in _RAW_ALIASES:
        return _raw_ip(buf)
    else:
        return None
    inner = frame.data
    return inner if isinstance(inner, (dpkt.ip.IP, dpkt.ip6.IP6)) else None


def _raw_ip(buf: bytes) -> Any:
    dpkt = _deps.dpkt()
    version = buf[0] >> 4 if buf else 0
    if version == 4:
        return dpkt.ip.IP(buf)
    if version == 6:
        return dpkt.ip6.IP6(buf)
    return None


def _decode(
    frame: int, ts: float, linktype: int, buf: bytes, flags: int | None, iface: int
) -> Record | None:
    if linktype == SERIAL_LINKTYPE:
        direction = {FLAG_OUTBOUND: "sent", FLAG_INBOUND: "received"}.get(flags or 0, "unknown")
        return Record(frame, ts, "serial", f"interface {iface}", direction, buf)
    dpkt = _deps.dpkt()
    try:
        ip = _network_layer(linktype, buf)
    except (dpkt.dpkt.Error, ValueError, IndexError):
        return None
    if ip is None:
        return None
    segment = ip.data
    if isinstance(segment, dpkt.udp.UDP):
        return Record(frame, ts, "udp", _hostport(ip.src, segment.sport),
                      _hostport(ip.dst, segment.dport), bytes(segment.data))  # fmt: skip
    if isinstance(segment, dpkt.tcp.TCP):
        return Record(frame, ts, "tcp", _hostport(ip.src, segment.sport),
                      _hostport(ip.dst, segment.dport), bytes(segment.data),
                      seq=int(segment.seq), flags=int(segment.flags))  # fmt: skip
    return None
