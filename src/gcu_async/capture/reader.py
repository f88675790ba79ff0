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
import struct
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any, BinaryIO

from gcu_async.capture import _deps
from gcu_async.capture.blocks import PCAP_MAGICS, PCAPNG_MAGIC, Packet, Source, packets
from gcu_async.capture.writer import FLAG_INBOUND, FLAG_OUTBOUND, SERIAL_LINKTYPE

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


def read_records(data: bytes | BinaryIO | Source) -> Iterator[Record]:
    """Every UDP, TCP and serial record of a pcap or pcapng file (bytes, or a binary stream
    read as it goes, in bounded memory), in file order. Raises
    :class:`~gcu_async.capture.CaptureError` (a ``ValueError``) naming the record or block
    and its offset at the first damage, after the records before it."""
    if isinstance(data, (bytes, bytearray, memoryview)):
        source = Source(io.BytesIO(bytes(data)))
    elif isinstance(data, Source):
        source = data
    else:
        source = Source(data)
    for frame, packet in enumerate(packets(source), start=1):
        record = _decode(frame, packet)
        if record is not None:
            yield record


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


def _decode(frame: int, packet: Packet) -> Record | None:
    ts, linktype, buf = packet.time, packet.linktype, packet.data
    if linktype == SERIAL_LINKTYPE:
        direction = {FLAG_OUTBOUND: "sent", FLAG_INBOUND: "received"}.get(packet.flags or 0,
                                                                         "unknown")  # fmt: skip
        return Record(frame, ts, "serial", f"interface {packet.interface}", direction, buf)
    dpkt = _deps.dpkt()
    try:  # a damaged packet inside a sound record is skipped, as one that is not UDP/TCP
        ip = _network_layer(linktype, buf)
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
    except (dpkt.dpkt.Error, ValueError, IndexError, struct.error):
        return None
    return None
