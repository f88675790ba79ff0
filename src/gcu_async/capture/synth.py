"""IP/UDP/TCP packets for a capture: what a packet sniffer on the host would have seen.

A transport hands the capture payloads and socket addresses; Wireshark needs IP packets.
UDP datagrams become one IPv4 or IPv6 packet each. A TCP connection becomes a three-way
handshake, data segments whose sequence and acknowledgement numbers count the bytes each
side sent (so Wireshark reassembles the stream as it would a sniffed one), and a FIN or RST
at its end. Checksums are computed (by dpkt).
"""

from __future__ import annotations

import ipaddress
import socket
from dataclasses import dataclass, field
from typing import Any

from gcu_async.capture import _deps

Address = tuple[str, int]
SYN, FIN, RST, PSH, ACK = 0x02, 0x01, 0x04, 0x08, 0x10
_TTL = 64
_WINDOW = 65535


def _ip(src: str, dst: str, proto: int, payload: Any) -> bytes:
    dpkt = _deps.dpkt()
    a, b = ipaddress.ip_address(src), ipaddress.ip_address(dst)
    if a.version != b.version:  # an IPv4 peer seen on an IPv6 socket: map it
        a = a if a.version == 6 else ipaddress.IPv6Address(f"::ffff:{a}")
        b = b if b.version == 6 else ipaddress.IPv6Address(f"::ffff:{b}")
    if a.version == 4:
        pkt = dpkt.ip.IP(src=a.packed, dst=b.packed, p=proto, ttl=_TTL, data=payload)
        pkt.len = len(pkt)  # dpkt computes the checksums (IP and UDP/TCP) when packed
        return bytes(pkt)
    pkt6 = dpkt.ip6.IP6(src=a.packed, dst=b.packed, nxt=proto, hlim=_TTL, data=payload)
    pkt6.plen = len(bytes(payload))
    return bytes(pkt6)


def udp_packet(src: Address, dst: Address, payload: bytes) -> bytes:
    """One IP packet carrying ``payload`` in a UDP datagram from ``src`` to ``dst``."""
    dpkt = _deps.dpkt()
    udp = dpkt.udp.UDP(sport=src[1], dport=dst[1], data=payload)
    udp.ulen = len(udp)
    return _ip(src[0], dst[0], socket.IPPROTO_UDP, udp)


@dataclass
class TcpFlow:
    """One TCP connection, from ``client`` to ``server``: sequence numbers of both sides."""

    client: Address
    server: Address
    client_seq: int = 1000
    server_seq: int = 5000
    closed: bool = field(default=False)

    def _segment(self, from_client: bool, flags: int, payload: bytes = b"") -> bytes:
        dpkt = _deps.dpkt()
        src, dst = (self.client, self.server) if from_client else (self.server, self.client)
        ours, theirs = self.client_seq, self.server_seq
        seq, ack = (ours, theirs) if from_client else (theirs, ours)
        tcp = dpkt.tcp.TCP(sport=src[1], dport=dst[1], seq=seq % 2**32, ack=ack % 2**32,
                           flags=flags, win=_WINDOW, data=payload)  # fmt: skip
        if not flags & ACK:
            tcp.ack = 0
        advance = len(payload) + (1 if flags & (SYN | FIN) else 0)
        if from_client:
            self.client_seq += advance
        else:
            self.server_seq += advance
        return _ip(src[0], dst[0], socket.IPPROTO_TCP, tcp)

    def handshake(self) -> list[bytes]:
        """SYN, SYN/ACK, ACK."""
        return [
            self._segment(True, SYN),
            self._segment(False, SYN | ACK),
            self._segment(True, ACK),
        ]

    def data(self, from_client: bool, payload: bytes) -> bytes:
        """A PSH/ACK segment carrying ``payload``."""
        return self._segment(from_client, PSH | ACK, payload)

    def finish(self, from_client: bool, reset: bool = False) -> list[bytes]:
        """The end of the connection: FIN/ACK both ways, or one RST."""
        if self.closed:
            return []
        self.closed = True
        if reset:
            return [self._segment(from_client, RST | ACK)]
        return [
            self._segment(from_client, FIN | ACK),
            self._segment(not from_client, FIN | ACK),
            self._segment(from_client, ACK),
        ]


def source_address(peer: Address, bound: str) -> str:
    """The local address packets to ``peer`` leave from: ``bound`` unless it is a wildcard,
    else what the OS routes from (a connected UDP socket tells without sending anything)."""
    try:
        wildcard = ipaddress.ip_address(bound).is_unspecified
    except ValueError:
        return bound
    if not wildcard:
        return bound
    family = socket.AF_INET6 if ":" in peer[0] else socket.AF_INET
    try:
        with socket.socket(family, socket.SOCK_DGRAM) as probe:
            probe.connect(peer)
            return str(probe.getsockname()[0])
    except OSError:
        return "::1" if family == socket.AF_INET6 else "127.0.0.1"
