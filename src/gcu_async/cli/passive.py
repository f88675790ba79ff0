"""``gcu-async monitor --passive``: hear a GCU's replies to another host's packets, sending
nothing and taking nothing from that host.

Over UDP a GCU sends every reply from port 2337 to the broadcast address of its subnet, port
2338 (docs/transports.md, "Network topology"): every host of the LAN hears the replies to
every host's packets. A passive listener binds *that broadcast address* on the reply port,
sharing the port with the application (``SO_REUSEPORT``, as the client's transport does on
a fixed local port). Bound so, the kernel hands it only datagrams sent to the broadcast
address. A reply sent by unicast (an emulator answering its sender: ``gcu-async sim``
without ``--reply-to``) reaches the application alone; a listener bound to the wildcard
address would instead join the application's port group, and Linux hands all the unicast
datagrams of one sender to one socket of the group, possibly the listener's, leaving the
application a silent link. So the passive listener never takes a reply meant for someone
else; what it cannot do is hear a GCU that answers by unicast (it then says "no reply
heard").

TCP and serial links cannot be watched so: :func:`passive_refusal` says why.

:class:`PassiveLink` is the sans-I/O part (bytes and times in; telemetry samples, link
health and the GCU conformance report out); :class:`PassiveListener` drives it from a UDP
transport on the event loop.
"""

from __future__ import annotations

import asyncio
import inspect
import ipaddress
import socket
import struct
import sys
from collections.abc import Callable
from types import TracebackType

from gcu_async.client.client import GcuClient
from gcu_async.client.telemetry import Callbacks
from gcu_async.conformance import GcuConformance, GcuReport
from gcu_async.errors import LinkLost
from gcu_async.protocol.deframer import Deframer
from gcu_async.protocol.gcu_frames import GcuSubFrame
from gcu_async.protocol.packets import SUPPORTED_VERSIONS, decode_gcu_packet
from gcu_async.session.events import TelemetrySample
from gcu_async.session.health import HealthTracker, LinkHealth
from gcu_async.transport.base import LinkEvent, Transport
from gcu_async.transport.udp import UdpTransport
from gcu_async.transport.url import open_transport, split_url

SILENCE_TIMEOUT: float = inspect.signature(GcuClient).parameters["silence_timeout"].default
"""Seconds without a reply after which the link counts as down: the client's default, so
the active and the passive monitor call the same silence an outage."""

REFUSED = {
    "tcp": "over TCP the GCU answers only the packets of the connection they came on, so a "
    "connection that sends nothing hears nothing (and may hold the GCU's one client slot: "
    "the simulator serves one connection at a time)",
    "serial": "a serial port has one reader: a second process reading it would take bytes "
    "of the application's replies",
}
"""Why a passive listener is refused, per URL scheme (UDP is the one it works on)."""
ELSEWHERE = ("watch over UDP, where the GCU broadcasts its replies, or record the "
             "application's own link (GcuClient(..., capture=FILE)) and read it with "
             "gcu-async decode --file FILE")  # fmt: skip

RESOLVE_TIMEOUT = 10.0
"""Seconds the GCU's host name may take to resolve."""
_SIOCGIFADDR = 0x8915
_SIOCGIFNETMASK = 0x891B
"""Linux ioctls: an interface's IPv4 address and netmask (<linux/sockios.h>)."""
_IFREQ_INET = struct.Struct("16s4x4s16x")
"""``struct ifreq`` holding a ``sockaddr_in``: the interface's name, (family, port), the
IPv4 address, padding."""


def passive_refusal(url: str) -> str | None:
    """Why ``url`` cannot be watched passively (one line, for a usage error), or ``None``
    when it can: a ``udp://`` URL to an IPv4 GCU on a fixed local port shared with
    ``SO_REUSEPORT``, bound to a broadcast address (derived unless ``local_host`` gives
    it). Opens nothing. Raises ``ValueError`` for a URL that is bad in itself."""
    parts = split_url(url)
    if parts.scheme in REFUSED:
        return f"{parts.scheme}: {REFUSED[parts.scheme]}; {ELSEWHERE}"
    transport = open_transport(url)  # every option checked
    assert isinstance(transport, UdpTransport)
    if not hasattr(socket, "SO_REUSEPORT"):
        return ("this platform has no SO_REUSEPORT: the listener could not share the reply "
                "port with the application")  # fmt: skip
    if transport.local_port == 0:
        return ("local_port=0: the GCU's replies go to a fixed port (2338 unless the URL's "
                "local_port names the application's)")  # fmt: skip
    if not transport.reuse_port:
        return "reuse_port=0 would bind the reply port alone and keep the application off it"
    if _version(parts.host) == 6:
        return "IPv6 has no broadcast: a GCU's replies reach one host only"
    local = transport.local_host
    if local is not None and ipaddress.ip_address(local).is_unspecified:
        return (f"local_host={local} is the wildcard address: bound there the listener could "
                "take unicast replies meant for the application; give the broadcast address "
                "the GCU sends to")  # fmt: skip
    return None


def _version(host: str) -> int | None:
    try:
        return ipaddress.ip_address(host).version
    except ValueError:
        return None  # a name: resolved when the listener opens


async def passive_transport(url: str) -> UdpTransport:
    """The transport of a passive listener on ``url`` (checked by :func:`passive_refusal`),
    not yet open: bound to the URL's ``local_host`` or else to the broadcast address of the
    subnet of this host that holds the GCU's address. Raises :class:`LinkLost` when the
    GCU's name does not resolve (within :data:`RESOLVE_TIMEOUT`) or no subnet here holds
    its address."""
    transport = open_transport(url)
    assert isinstance(transport, UdpTransport)
    if transport.local_host is not None:
        return transport
    host = split_url(url).host
    try:
        if _version(host) is None:
            lookup = asyncio.get_running_loop().getaddrinfo(
                host, None, family=socket.AF_INET, type=socket.SOCK_DGRAM)
            infos = await asyncio.wait_for(lookup, RESOLVE_TIMEOUT)
            host = str(infos[0][4][0])
        broadcast = subnet_broadcast(host)
    except (OSError, TimeoutError, ValueError) as exc:
        raise LinkLost(f"{url}: cannot listen passively: {str(exc) or 'no address in time'}"
                       ) from exc  # fmt: skip
    transport = open_transport(url, local_host=broadcast)
    assert isinstance(transport, UdpTransport)
    return transport


def subnet_broadcast(address: str) -> str:
    """The broadcast address of the subnet of this host's interfaces that holds the IPv4
    ``address`` (``127.255.255.255`` for ``127.0.0.1``; ``192.168.144.255`` for a GCU at
    192.168.144.108 beside an interface in 192.168.144.0/24). Linux only; ``ValueError``
    naming the address otherwise, or when no subnet here holds it."""
    ip = ipaddress.IPv4Address(address)
    if not sys.platform.startswith("linux"):
        raise ValueError(f"finding the broadcast address of {ip}'s subnet needs Linux: give "
                         "it, udp://HOST?local_host=BROADCAST")  # fmt: skip
    networks = interface_networks()
    for network in networks:
        if ip in network and network.prefixlen < 31:
            return str(network.broadcast_address)
    held = ", ".join(str(n) for n in networks) or "none"
    raise ValueError(f"{ip} is on none of this host's subnets ({held}): its broadcast replies "
                     "cannot reach this host")  # fmt: skip


def interface_networks() -> list[ipaddress.IPv4Network]:
    """The IPv4 subnet of each interface of this host that has an address (Linux)."""
    import fcntl  # POSIX only

    def ioctl(sock: socket.socket, request: int, name: str) -> str | None:
        ifreq = _IFREQ_INET.pack(name.encode()[:15], bytes(4))
        try:
            _, address = _IFREQ_INET.unpack(fcntl.ioctl(sock.fileno(), request, ifreq))
        except OSError:  # no IPv4 address
            return None
        return socket.inet_ntoa(address)

    found = []
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        for _, name in socket.if_nameindex():
            address = ioctl(sock, _SIOCGIFADDR, name)
            mask = ioctl(sock, _SIOCGIFNETMASK, name)
            if address is not None and mask is not None:
                found.append(ipaddress.IPv4Network(f"{address}/{mask}", strict=False))
    return found


class PassiveLink:
    """What a listener that sends nothing makes of the GCU replies it hears (sans-I/O):
    telemetry samples, link health and, with ``conformance``, the GCU conformance report.

    Feed each datagram with :meth:`receive`; read :meth:`health`. The link is up from a
    reply until ``silence_timeout`` seconds pass without one (then ``lost_count`` counts
    the outage; the next reply counts in ``restored_count``). Having sent nothing, it
    matches no feedback: ``packets_sent``, ``send_errors``, ``unmatched_feedback`` and
    ``ambiguous_feedback`` stay 0.
    """

    def __init__(self, *, silence_timeout: float = SILENCE_TIMEOUT,
                 conformance: GcuConformance | None = None) -> None:  # fmt: skip
        if not silence_timeout > 0:
            raise ValueError(f"silence_timeout: {silence_timeout!r} must be > 0")
        self.silence_timeout = silence_timeout
        self.conformance = conformance
        self._deframer = Deframer.for_gcu_packets()
        self._health = HealthTracker()
        self._up = False
        self._info: GcuSubFrame | None = None

    def receive(self, data: bytes, now: float) -> list[TelemetrySample]:
        """One datagram heard at ``now``: a sample per valid reply in it (its bytes never
        join the next datagram's)."""
        self._settle(now)
        deframer = self._deframer
        samples = []
        for raw in deframer.feed(data) + deframer.flush():
            packet = decode_gcu_packet(raw)  # framed: header, length and CRC are right
            health = self._health
            if packet.version not in SUPPORTED_VERSIONS:
                health.other_versions += 1
            if not self._up:
                self._up = True
                if health.last_reply is not None:  # heard before: back after an outage
                    health.restored_count += 1
            health.on_reply(now)
            if isinstance(packet.sub, GcuSubFrame):
                self._info = packet.sub
            if self.conformance is not None:
                self.conformance.add_packet(packet, now, raw=raw)
            samples.append(TelemetrySample(packet.main, self._info, packet.feedback, now))
        return samples

    def health(self, now: float) -> LinkHealth:
        """The link's health at ``now``."""
        self._settle(now)
        h, d = self._health, self._deframer.stats
        return LinkHealth(
            up=self._up, reply_rate=h.reply_rate(now),
            last_reply_age=None if h.last_reply is None else now - h.last_reply,
            packets_sent=0, packets_received=h.packets_received, send_errors=0,
            crc_errors=d.crc_errors, length_errors=d.length_errors,
            bytes_discarded=d.bytes_discarded, other_versions=h.other_versions,
            unmatched_feedback=0, ambiguous_feedback=0, lost_count=h.lost_count,
            restored_count=h.restored_count,
        )  # fmt: skip

    def _settle(self, now: float) -> None:
        """A silence longer than ``silence_timeout`` since the last reply is an outage."""
        if self._up and self._health.silent_for(now) > self.silence_timeout:
            self._up = False
            self._health.lost_count += 1


class PassiveListener:
    """A :class:`PassiveLink` fed by ``transport`` (open inside ``async with``), with the
    face the monitor reads: :attr:`link`, :meth:`on_telemetry`, :meth:`conformance_report`,
    :attr:`transport`. It never calls the transport's ``send``."""

    def __init__(self, transport: Transport, link: PassiveLink) -> None:
        self.transport = transport
        self._link = link
        self._telemetry: Callbacks[TelemetrySample] = Callbacks("telemetry")

    async def __aenter__(self) -> PassiveListener:
        self.transport.set_handlers(self._received, self._event)
        await self.transport.open()
        return self

    async def __aexit__(self, exc_type: type[BaseException] | None,
                        exc: BaseException | None, tb: TracebackType | None) -> None:  # fmt: skip
        await self.transport.close()

    @property
    def link(self) -> LinkHealth:
        """The link's health now (the event loop's clock)."""
        return self._link.health(asyncio.get_running_loop().time())

    def on_telemetry(self, callback: Callable[[TelemetrySample], None]) -> Callable[[], None]:
        """Call ``callback`` with every reply heard; returns the function that removes it."""
        return self._telemetry.add(callback)

    def conformance_report(self) -> GcuReport:
        """The GCU conformance report of every reply heard (no host opcodes: this host sent
        none)."""
        conformance = self._link.conformance
        return (conformance if conformance is not None else GcuConformance()).report()

    def _received(self, data: bytes) -> None:
        for sample in self._link.receive(data, asyncio.get_running_loop().time()):
            self._telemetry.emit(sample)

    def _event(self, event: LinkEvent) -> None:
        """Transport news: the socket's own errors stay in its ``last_error``."""
