"""A datagram transport that reads every queued datagram per readiness event (not public API).

asyncio's selector datagram transport reads ONE datagram per readiness event. When the loop
is busy (a 20 ms iteration, say) and the peer sends at least one datagram per iteration, the
kernel queue grows without bound and every reply arrives later than the one before. This
transport registers its own reader (``loop.add_reader``) and, per event, calls ``recvfrom``
until the socket is empty (``BlockingIOError``) or :data:`MAX_PER_EVENT` datagrams were read,
so one busy socket cannot starve the loop either.

Sends go straight to ``sock.sendto`` (non-blocking); every ``OSError``, ``BlockingIOError``
(send buffer full: the datagram is dropped, never queued) included, goes to the protocol's
``error_received``, as asyncio reports send errors. Receive errors go there too and never
close the transport; an ICMP port unreachable reported by ``recvfrom``
(``ConnectionRefusedError``, or ``ConnectionResetError`` on Windows) does not even end the
current drain.

Loops without ``add_reader`` (Windows' proactor loop) raise ``NotImplementedError`` from the
constructor; the caller then falls back to ``loop.create_datagram_endpoint``.
"""

from __future__ import annotations

import asyncio
import socket
from typing import Any

MAX_PER_EVENT = 10_000
"""Most datagrams read per readiness event; the rest wait for the next loop iteration."""


class DrainingDatagramTransport(asyncio.DatagramTransport):
    """Datagram transport over a bound, non-blocking ``sock`` for ``protocol``.

    Calls ``protocol.datagram_received`` for each datagram, ``error_received`` for OS
    errors, and ``connection_lost(None)`` (via ``call_soon``) after :meth:`close`; the socket
    is closed then. ``connection_made`` is not called."""

    def __init__(
        self,
        loop: asyncio.AbstractEventLoop,
        sock: socket.socket,
        protocol: asyncio.DatagramProtocol,
        bufsize: int,
    ) -> None:
        super().__init__(extra={"socket": sock, "sockname": sock.getsockname()})
        self._loop = loop
        self._sock = sock
        self._protocol = protocol
        self._view = memoryview(bytearray(bufsize))
        self._closing = False
        self.max_per_event = MAX_PER_EVENT
        self.backlog = False
        """True when the last read stopped at :attr:`max_per_event` (or on an error) with
        datagrams possibly left in the socket."""
        loop.add_reader(sock.fileno(), self._read_ready)  # NotImplementedError: no selector

    def _read_ready(self) -> None:
        self.backlog = not self.read_all()

    def read_all(self) -> bool:
        """Read and deliver every queued datagram (at most :attr:`max_per_event`); True if
        the socket was found empty at the end."""
        recv, view, protocol = self._sock.recvfrom_into, self._view, self._protocol
        for _ in range(self.max_per_event):
            if self._closing:  # a handler closed us: the socket may be gone already
                return False
            try:
                n, addr = recv(view)
            except BlockingIOError:
                return True  # drained
            except InterruptedError:
                return False
            except (ConnectionRefusedError, ConnectionResetError) as exc:
                # ICMP port unreachable for an earlier send, reported by this receive
                # (Windows: WSAECONNRESET; Linux: a connected socket or IP_RECVERR). The
                # report is consumed by the call: the datagrams behind it are read on.
                protocol.error_received(exc)
                continue
            except OSError as exc:
                protocol.error_received(exc)
                return False  # like asyncio; anything left is read at the next event
            protocol.datagram_received(bytes(view[:n]), addr)
        return False

    def sendto(self, data: Any, addr: Any = None) -> None:
        if self._closing:
            return
        try:
            self._sock.sendto(data, addr)
        except OSError as exc:
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

    def get_protocol(self) -> asyncio.BaseProtocol:
        return self._protocol

    def _call_connection_lost(self) -> None:
        try:
            self._protocol.connection_lost(None)
        finally:
            self._sock.close()
