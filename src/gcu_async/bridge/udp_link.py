"""UDP MAVLink links: ``udpout:`` (one peer) and ``udpin:`` (many senders, a destination
policy) — docs/mavlink-bridge.md, "Links".

``udpin`` keeps one parser per sender address, so one sender's junk never costs another's
messages. A sender becomes a **destination** (gets what the bridge sends) only after a valid
MAVLink message from it — a spoofed or junk datagram never turns the bridge into a reflector
— and stops being one after :data:`DESTINATION_EXPIRY_SECONDS` without a valid message. At
most :data:`MAX_DESTINATIONS` destinations are kept and at most :data:`MAX_SENDERS` other
senders' parsers (least recently heard dropped first). A valid sender beyond the
destinations is heard but not written to until one expires — except a *station* (a
HEARTBEAT within :data:`~gcu_async.bridge.links.STATION_SECONDS`), which takes the place of
the longest-silent destination that is not one: stations already there cannot be pushed
out, and senders that never heartbeat cannot keep a station out.

A destination that heartbeats is a station: it holds a command share of its own
(:meth:`UdpInLink.own_share`), and while the inbox is more than half full only stations'
datagrams are queued, so a flood from other addresses cannot crowd them out of the inbox
either (the kernel's socket buffer, before it, drops every sender's alike).
"""

from __future__ import annotations

import asyncio
import logging
import socket
import time
from collections import OrderedDict
from typing import Any

from gcu_async.bridge.links import INBOX_BYTES, MavlinkLink, Peer

log = logging.getLogger("gcu_async.bridge")

MAX_DESTINATIONS = 16
"""Most senders a ``udpin`` link writes to at once."""
DESTINATION_EXPIRY_SECONDS = 10.0
"""A destination without a valid message for this long is dropped (ground stations send a
HEARTBEAT every second)."""
MAX_SENDERS = 256
"""Most other senders (no valid message yet, or beyond :data:`MAX_DESTINATIONS`) whose
parsers a ``udpin`` link keeps."""


class _Datagrams(asyncio.DatagramProtocol):
    def __init__(self, link: _UdpLink) -> None:
        self.link = link
        self.lost: asyncio.Future[str] = asyncio.get_running_loop().create_future()

    def datagram_received(self, data: bytes, addr: Any) -> None:
        self.link.datagram(data, addr)

    def error_received(self, exc: Exception) -> None:  # ICMP: a peer not listening
        self.link.send_errors += 1
        self.link.log_every("icmp", logging.DEBUG, "send failed: %s", exc)

    def connection_lost(self, exc: Exception | None) -> None:
        if not self.lost.done():
            self.lost.set_result(f"socket closed ({exc})" if exc else "socket closed")


class _UdpLink(MavlinkLink):
    _transport: asyncio.DatagramTransport | None = None

    @property
    def local_address(self) -> Any:
        """The bound socket address (``udpin:…:0`` picks a free port)."""
        return None if self._transport is None else self._transport.get_extra_info("sockname")

    def datagram(self, data: bytes, addr: Any) -> None:
        raise NotImplementedError

    def _abort(self) -> None:
        transport, self._transport = self._transport, None
        if transport is not None:
            transport.abort()


class UdpOutLink(_UdpLink):
    """``udpout:HOST:PORT``: a socket connected to the peer; it hears only that peer."""

    _peer: Peer | None = None

    async def _connect(self) -> asyncio.Future[str]:
        loop = asyncio.get_running_loop()
        addr = await self.resolve(self.endpoint.host, self.endpoint.port, socket.SOCK_DGRAM)
        transport, protocol = await loop.create_datagram_endpoint(
            lambda: _Datagrams(self), remote_addr=addr[:2])
        self._abort()
        self._transport = transport
        self._peer = Peer(transport)
        return protocol.lost

    def datagram(self, data: bytes, addr: Any) -> None:
        if self._peer is not None:
            self.feed(self._peer, data, stream=False)

    def destinations(self) -> list[Peer]:
        return [self._peer] if self._peer is not None else []


class UdpInLink(_UdpLink):
    """``udpin:HOST:PORT``: listens; writes to the senders it heard valid MAVLink from."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._destinations: dict[Any, Peer] = {}
        self._senders: OrderedDict[Any, Peer] = OrderedDict()
        self._next_sweep = 0.0
        self.senders_dropped = 0
        """Sender parsers dropped to stay within :data:`MAX_SENDERS`."""
        self.destinations_refused = 0
        """Valid messages from senders not made destinations (:data:`MAX_DESTINATIONS`)."""

    async def _connect(self) -> asyncio.Future[str]:
        loop = asyncio.get_running_loop()
        addr = await self.resolve(self.endpoint.host, self.endpoint.port, socket.SOCK_DGRAM)
        transport, protocol = await loop.create_datagram_endpoint(
            lambda: _Datagrams(self), local_addr=addr[:2])
        self._abort()
        self._transport = transport
        self._destinations.clear()
        self._senders.clear()
        log.info("mavlink %s: listening on %s", self.url, self.local_address)
        return protocol.lost

    def datagram(self, data: bytes, addr: Any) -> None:
        peer = self._destinations.get(addr)
        if (self._inbox_bytes > INBOX_BYTES // 2
                and (peer is None or not peer.heartbeating(time.monotonic()))):  # fmt: skip
            self.dropped_in += 1  # the rest of the inbox is the stations'
            return
        if peer is None:
            peer = self._senders.get(addr)
            if peer is None:
                if len(self._senders) >= MAX_SENDERS:
                    self._senders.popitem(last=False)
                    self.senders_dropped += 1
                peer = self._senders[addr] = Peer(self._transport, addr)
            else:
                self._senders.move_to_end(addr)
        self.feed(peer, data, stream=False)

    def heard_valid(self, peer: Peer, now: float) -> None:
        addr = peer.addr
        if addr in self._destinations or peer.transport is not self._transport:
            return
        if len(self._destinations) >= MAX_DESTINATIONS:
            self._sweep(now)
        if len(self._destinations) >= MAX_DESTINATIONS and peer.heartbeating(now):
            self._make_room_for_station(now)
        if len(self._destinations) >= MAX_DESTINATIONS:
            self.destinations_refused += 1
            self.log_every("full", logging.WARNING, "%d destinations already; not writing to "
                           "%s", MAX_DESTINATIONS, addr)  # fmt: skip
            return
        self._senders.pop(addr, None)
        self._destinations[addr] = peer
        self.log_every("new", logging.INFO, "writing to %s", addr)

    def _make_room_for_station(self, now: float) -> None:
        """Demote the longest-silent destination that is not a station (it stays a heard
        sender, its parser kept)."""
        others = [p for p in self._destinations.values() if not p.heartbeating(now)]
        if not others:
            return
        victim = min(others, key=lambda p: p.valid_at or 0.0)
        del self._destinations[victim.addr]
        victim.share = None
        if len(self._senders) >= MAX_SENDERS:
            self._senders.popitem(last=False)
            self.senders_dropped += 1
        self._senders[victim.addr] = victim
        self.log_every("demoted", logging.INFO, "%s sends no HEARTBEAT: its place goes to a "
                       "station", victim.addr)  # fmt: skip

    def own_share(self, peer: Peer, now: float) -> bool:
        """A destination that sent a HEARTBEAT within
        :data:`~gcu_async.bridge.links.STATION_SECONDS` holds a share of its own; every other
        sender shares the link's pool. (The source address is what identifies a sender:
        system and component ids are written by the sender, so any sender can write any.)"""
        return peer.heartbeating(now) and self._destinations.get(peer.addr) is peer

    def _sweep(self, now: float) -> None:
        self._next_sweep = now + 1.0
        expired = [a for a, p in self._destinations.items()
                   if p.valid_at is None or now - p.valid_at > DESTINATION_EXPIRY_SECONDS]
        for addr in expired:
            del self._destinations[addr]
            self.log_every("expired", logging.INFO, "%s silent for %g s: no longer written to",
                           addr, DESTINATION_EXPIRY_SECONDS)  # fmt: skip

    def destinations(self) -> list[Peer]:
        now = time.monotonic()
        if now >= self._next_sweep:
            self._sweep(now)
        return list(self._destinations.values())

    @property
    def destination_addresses(self) -> list[Any]:
        """The sender addresses written to now."""
        return list(self._destinations)
