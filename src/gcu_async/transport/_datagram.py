"""A datagram transport that drains its socket whenever it may be falling behind (not public API).

asyncio's selector datagram transport reads ONE datagram per readiness event. When the loop
is busy (a 20 ms iteration, say) and the peer sends at least one datagram per iteration, the
kernel queue grows without bound and every reply arrives later than the one before. This
transport registers its own reader (``loop.add_reader``), which per readiness event calls
``recvfrom`` until the socket is empty (``BlockingIOError``) or :data:`MAX_PER_EVENT`
datagrams were read (so one busy socket cannot starve the loop either). One event reads a
single datagram instead: the first after a timer found the socket empty without reading it
(:meth:`~DrainingDatagramTransport.caught_up`, which tells a timer callback whether the
socket was empty when its loop iteration polled the OS: the transport's arrival hook,
:meth:`gcu_async.transport.Transport.caught_up`).
That is a reply after a quiet spell, the heartbeat's usual case, and it then costs no
failing ``recvfrom``; whatever else is queued is drained by the next event.

Sends go straight to ``sock.sendto`` (non-blocking); every ``OSError``, ``BlockingIOError``
(send buffer full: the datagram is dropped, never queued) included, goes to the protocol's
``error_received``, as asyncio reports send errors. Receive errors go there too and never
close the transport; an ICMP port unreachable reported by ``recvfrom``
(``ConnectionRefusedError``, or ``ConnectionResetError`` on Windows) does not even end the
current drain.

ICMP errors on Linux
    An unconnected UDP socket on Linux hears nothing of ICMP errors (a GCU not listening
    yet: port unreachable; no route: host unreachable) unless ``IP_RECVERR`` /
    ``IPV6_RECVERR`` is on. :func:`enable_error_queue` turns it on; the kernel then keeps one
    entry per ICMP error in the socket's *error queue* and reports the latest once, as
    ``ECONNREFUSED`` (...) from the next ``sendto`` or ``recvfrom``. This transport reads
    the queue (``recvmsg(MSG_ERRQUEUE)``) whenever a call reports such an error and on a
    readiness event that finds no datagram (epoll signals a non-empty error queue as
    readiness: left unread, the loop would spin), and reports one ``OSError`` per entry,
    naming the ICMP error, who sent it and the datagram's destination; the bare report is
    passed on only when the queue holds no entry for it. A ``sendto`` that fails only
    because it carried such a report did not send its datagram: it is sent again, once.

Loops without ``add_reader`` (Windows' proactor loop) raise ``NotImplementedError`` from the
constructor; the caller then falls back to ``loop.create_datagram_endpoint``.
"""

from __future__ import annotations

import asyncio
import errno
import os
import socket
import struct
import sys
import time
from collections.abc import Callable
from typing import Any

from gcu_async.transport.base import CLOCK_RESOLUTION

MAX_PER_EVENT = 10_000
"""Most datagrams read per readiness event; the rest wait for the next loop iteration."""

# Linux's <linux/in.h>, <linux/in6.h>, <linux/errqueue.h>, <sys/socket.h> (Python 3.10-3.13
# define none of these names in the socket module).
_IP_RECVERR = 11
_IPV6_RECVERR = 25
_MSG_ERRQUEUE = 0x2000
_EXTENDED_ERR = struct.Struct("=IBBBBII")  # ee_errno, ee_origin, ee_type, ee_code, pad, ...
_ORIGIN_ICMP, _ORIGIN_ICMP6 = 2, 3
_ICMP_NAMES = {
    (_ORIGIN_ICMP, 3, 0): "ICMP network unreachable",
    (_ORIGIN_ICMP, 3, 1): "ICMP host unreachable",
    (_ORIGIN_ICMP, 3, 3): "ICMP port unreachable",
    (_ORIGIN_ICMP6, 1, 0): "ICMPv6 no route",
    (_ORIGIN_ICMP6, 1, 3): "ICMPv6 address unreachable",
    (_ORIGIN_ICMP6, 1, 4): "ICMPv6 port unreachable",
}


def enable_error_queue(sock: socket.socket) -> bool:
    """Linux: have ICMP errors for ``sock``'s datagrams reported (``IP_RECVERR``, or
    ``IPV6_RECVERR`` for an IPv6 socket). Returns whether it was turned on; elsewhere it does
    nothing and returns False."""
    if not sys.platform.startswith("linux"):
        return False
    if sock.family == socket.AF_INET6:
        level, option = socket.IPPROTO_IPV6, _IPV6_RECVERR
    else:
        level, option = socket.IPPROTO_IP, _IP_RECVERR
    try:
        sock.setsockopt(level, option, 1)
    except OSError:
        return False
    return True


def queued_error(ancdata: list[tuple[int, int, bytes]], destination: Any) -> OSError:
    """The ``OSError`` one error-queue entry describes (its ``sock_extended_err`` in
    ``ancdata``, read by ``recvmsg(MSG_ERRQUEUE)``; ``destination``: where the datagram that
    caused it was going)."""
    for level, kind, data in ancdata:
        if (level, kind) not in ((socket.IPPROTO_IP, _IP_RECVERR),
                                 (socket.IPPROTO_IPV6, _IPV6_RECVERR)):  # fmt: skip
            continue
        if len(data) < _EXTENDED_ERR.size:
            break
        code, origin, icmp_type, icmp_code, _, _, _ = _EXTENDED_ERR.unpack_from(data)
        name = _ICMP_NAMES.get((origin, icmp_type, icmp_code))
        if name is None and origin in (_ORIGIN_ICMP, _ORIGIN_ICMP6):
            version = "v6" if origin == _ORIGIN_ICMP6 else ""
            name = f"ICMP{version} type {icmp_type} code {icmp_code}"
        sender = _offender(data[_EXTENDED_ERR.size :])
        where = f" for a datagram to {_address(destination)}" if destination else ""
        by = f" from {sender}" if sender else ""
        what = f"{name}{by}{where}" if name else f"{os.strerror(code)}{where}"
        return OSError(code, what)  # OSError picks the subclass (ConnectionRefusedError, ...)
    return OSError(errno.EIO, f"unreadable error-queue entry for {_address(destination)}")


def _offender(raw: bytes) -> str:
    """The address in a ``sockaddr_in``/``sockaddr_in6`` that follows the extended error."""
    if len(raw) >= 8 and int.from_bytes(raw[:2], sys.byteorder) == socket.AF_INET:
        return socket.inet_ntop(socket.AF_INET, raw[4:8])
    if len(raw) >= 24 and int.from_bytes(raw[:2], sys.byteorder) == socket.AF_INET6:
        return socket.inet_ntop(socket.AF_INET6, raw[8:24])
    return ""


def _address(addr: Any) -> str:
    if isinstance(addr, tuple) and len(addr) >= 2:
        host = str(addr[0])
        return f"[{host}]:{addr[1]}" if ":" in host else f"{host}:{addr[1]}"
    return str(addr)


class DrainingDatagramTransport(asyncio.DatagramTransport):
    """Datagram transport over a bound, non-blocking ``sock`` for ``protocol``.

    Calls ``protocol.datagram_received`` (or ``deliver``) for each datagram,
    ``error_received`` for OS errors, and ``connection_lost(None)`` (via ``call_soon``) after
    :meth:`close`; the socket is closed then. ``connection_made`` is not called."""

    def __init__(
        self,
        loop: asyncio.AbstractEventLoop,
        sock: socket.socket,
        protocol: asyncio.DatagramProtocol,
        bufsize: int,
        deliver: Callable[[bytes, Any], None] | None = None,
    ) -> None:
        super().__init__(extra={"socket": sock, "sockname": sock.getsockname()})
        self._loop = loop
        self._sock = sock
        self._protocol = protocol
        self._deliver = protocol.datagram_received if deliver is None else deliver
        """Where each datagram goes (``protocol.datagram_received`` unless given)."""
        self._view = memoryview(bytearray(bufsize))
        self._closing = False
        self.error_queue = enable_error_queue(sock)
        """Whether ICMP errors are read from the socket's error queue (Linux)."""
        self.max_per_event = MAX_PER_EVENT
        self.unread_since: float | None = None
        """None: the last read found the socket empty (or a timer's iteration proved it was,
        :meth:`caught_up`); else the ``time.monotonic()`` at which that read began (it
        stopped after one datagram, at :attr:`max_per_event` or on an error, with datagrams
        possibly left in the socket)."""
        self._quiet = False
        """A timer found the socket empty at its poll since the last readiness event, without
        reading it (:meth:`caught_up`): the next event reads one datagram."""
        loop.add_reader(sock.fileno(), self._read_ready)  # NotImplementedError: no selector

    def _read_ready(self) -> None:
        # a reply after a quiet spell: one datagram; otherwise drain (never fall behind)
        limit = 1 if self._quiet else self.max_per_event
        self._quiet = False
        self._read(time.monotonic(), limit, woken=True)

    def read_all(self) -> bool:
        """Read and deliver every queued datagram (at most :attr:`max_per_event`); True if
        the socket was found empty at the end."""
        return self._read(time.monotonic(), self.max_per_event, woken=False)

    def caught_up(self, due: float | None = None) -> bool:
        """:meth:`gcu_async.transport.Transport.caught_up`: True if nothing that reached the
        socket before this loop iteration polled the OS (``due`` given: a timer callback due
        then) or before this call is still unread.

        asyncio's selector is level-triggered and runs this iteration's I/O callbacks before
        its timers, and a timer due at ``due`` runs only in an iteration whose poll returned
        after ``due - CLOCK_RESOLUTION``. A read that began no later than that was an
        earlier iteration's: had it left a datagram, this iteration's poll would have run
        the reader again. Otherwise (the reader ran in this iteration and may have left
        some, or no ``due``), the socket is read empty now."""
        since = self.unread_since
        if due is not None and (since is None or since <= due - CLOCK_RESOLUTION):
            self.unread_since = None
            self._quiet = True
            return True
        return self.read_all()

    def _read(self, start: float, limit: int, *, woken: bool) -> bool:
        """Read and deliver up to ``limit`` datagrams; True if the socket was found empty.
        ``woken``: called for a readiness event (one that finds no datagram then reads the
        error queue)."""
        self.unread_since = start
        recv, view, protocol = self._sock.recvfrom_into, self._view, self._protocol
        deliver = self._deliver
        for i in range(limit):
            if self._closing:  # a handler closed us: the socket may be gone already
                return False
            try:
                n, addr = recv(view)
            except BlockingIOError:
                if i == 0 and woken and self.error_queue:  # nothing to read: the error queue
                    self.read_errors()
                self.unread_since = None
                return True  # drained
            except InterruptedError:
                return False
            except (ConnectionRefusedError, ConnectionResetError) as exc:
                # ICMP port unreachable for an earlier send, reported by this receive
                # (Windows: WSAECONNRESET; Linux: a connected socket or IP_RECVERR). The
                # report is consumed by the call: the datagrams behind it are read on.
                self._icmp_reported(exc)
                continue
            except OSError as exc:
                protocol.error_received(exc)
                return False  # like asyncio; anything left is read at the next event
            deliver(bytes(view[:n]), addr)
        return False

    def sendto(self, data: Any, addr: Any = None) -> None:
        if self._closing:
            return
        try:
            self._sock.sendto(data, addr)
        except ConnectionRefusedError as exc:  # a pending ICMP report, not about this datagram
            self._icmp_reported(exc)
            try:
                self._sock.sendto(data, addr)
            except OSError as again:
                self._protocol.error_received(again)
        except OSError as exc:
            self._protocol.error_received(exc)

    def read_errors(self) -> int:
        """Report every entry of the socket's error queue (at most :attr:`max_per_event`);
        returns how many there were."""
        recvmsg, protocol = self._sock.recvmsg, self._protocol
        for count in range(self.max_per_event):
            try:
                _, ancdata, _, destination = recvmsg(1, 512, _MSG_ERRQUEUE)
            except BlockingIOError:
                return count
            except OSError as exc:
                protocol.error_received(exc)
                return count
            protocol.error_received(queued_error(ancdata, destination))
        return self.max_per_event

    def _icmp_reported(self, exc: OSError) -> None:
        """A call reported an ICMP error: report the queue's entries (the same error, with
        its details), or the bare report if there is no queue (or it was read already)."""
        if not (self.error_queue and self.read_errors()):
            self._protocol.error_received(exc)

    def is_closing(self) -> bool:
        return self._closing

    def close(self) -> None:
        if self._closing:
            return
        self._closing = True
        self._loop.remove_reader(self._sock.fileno())
        self._loop.call_soon(self._call_connection_lost)

    def abort(self) -> None:
        self.close()

    def _call_connection_lost(self) -> None:
        try:
            self._protocol.connection_lost(None)
        finally:
            self._sock.close()
