"""A transport that records what another transport sends and receives in a capture file.

:class:`CapturingTransport` wraps any :class:`~gcu_async.transport.Transport` and behaves
exactly like it (every property and method is the wrapped one's, the arrival hook
:meth:`~gcu_async.transport.Transport.caught_up` included; attributes it does not define,
such as ``local_address`` or ``rx_datagrams``, are read from the wrapped transport), while
writing each datagram, TCP segment or serial chunk to a
:class:`~gcu_async.capture.PacketCapture`:

- UDP: one IP/UDP packet per datagram, between the bound local address (the address the
  OS routes from when bound to a wildcard) and the GCU's address (received datagrams: the
  peer they came from);
- TCP: a handshake when the connection is made (and again after each reconnect), the bytes
  each way with consistent sequence numbers, a FIN on close and an RST on ``reset``;
- serial and every other transport: one record per write and per read on a link of type
  :data:`~gcu_async.capture.SERIAL_LINKTYPE`, named by the device (or the URL).

Bytes the wrapped transport dropped (``sends_dropped`` went up) are not recorded: the
capture holds what went to the OS. :class:`~gcu_async.client.GcuClient` wraps its transport
in one when given ``capture=``.
"""

from __future__ import annotations

from typing import Any

from gcu_async.capture.synth import source_address
from gcu_async.capture.writer import PacketCapture, as_capture
from gcu_async.transport.base import LinkEvent, LinkEventKind, Transport
from gcu_async.transport.serial import SerialTransport
from gcu_async.transport.tcp import TcpTransport
from gcu_async.transport.udp import UdpTransport

Address = tuple[str, int]


def _address(value: Any) -> Address | None:
    if isinstance(value, tuple) and len(value) >= 2:
        return (str(value[0]), int(value[1]))
    return None


class CapturingTransport(Transport):
    """``inner`` with every byte it exchanges written to ``capture``."""

    def __init__(self, inner: Transport, capture: PacketCapture) -> None:
        super().__init__()
        self.inner = inner
        """The wrapped transport."""
        self.ordered = inner.ordered
        self.datagram = inner.datagram
        self.capture = capture
        self._acquired = False
        self._tcp: tuple[Address, Address] | None = None
        """(local, remote) of the TCP connection being recorded."""
        self._udp_local: dict[Address, Address] = {}
        self._link_name = inner.device if isinstance(inner, SerialTransport) else inner.url

    # -- the wrapped transport's face --------------------------------------------------------
    @property
    def url(self) -> str:
        return self.inner.url

    @property
    def connected(self) -> bool:
        return self.inner.connected

    @property
    def sends_dropped(self) -> int:
        return self.inner.sends_dropped

    @sends_dropped.setter
    def sends_dropped(self, value: int) -> None:
        return  # the base class initialises it; the wrapped transport keeps the count

    def __getattr__(self, name: str) -> Any:
        if name == "inner":  # not set yet (during __init__)
            raise AttributeError(name)
        return getattr(self.inner, name)

    def __repr__(self) -> str:
        return f"<CapturingTransport {self.inner!r} -> {str(self.capture.path)!r}>"

    # -- lifecycle -----------------------------------------------------------------------
    async def open(self) -> None:
        if self.inner.connected:
            return
        self.inner.set_handlers(self._received, self._event)
        if not self._acquired:
            self.capture.acquire()
            self._acquired = True
        try:
            await self.inner.open()
        except BaseException:
            self._release()
            raise
        self._tcp_connected()

    async def close(self) -> None:
        try:
            await self.inner.close()
        finally:
            if self._tcp is not None:
                local, remote = self._tcp
                self.capture.tcp_close(local, remote)
                self._tcp = None
            self._release()

    def _release(self) -> None:
        if self._acquired:
            self._acquired = False
            self.capture.release()

    def caught_up(self, due: float | None = None) -> bool:
        return self.inner.caught_up(due)  # what it delivers reaches _received: recorded

    def reset(self, reason: str) -> None:
        self.inner.reset(reason)
        if self._tcp is not None and not self.inner.connected:
            local, remote = self._tcp
            self.capture.tcp_close(local, remote, reset=True)
            self._tcp = None

    # -- traffic -------------------------------------------------------------------------
    def send(self, data: bytes) -> None:
        dropped = self.inner.sends_dropped
        self.inner.send(data)
        if self.inner.sends_dropped == dropped:
            self._record(data, outbound=True)

    def _received(self, data: bytes) -> None:
        self._record(data, outbound=False)
        self._on_data(data)

    def _event(self, event: LinkEvent) -> None:
        if event.kind is LinkEventKind.RESTORED:
            self._tcp_connected()
        elif event.kind is LinkEventKind.LOST and self._tcp is not None:
            local, remote = self._tcp
            self.capture.tcp_close(remote, local, reset=event.detail.startswith("reset"))
            self._tcp = None
        self._on_event(event)

    def _tcp_connected(self) -> None:
        inner = self.inner
        if not isinstance(inner, TcpTransport):
            return
        local = _address(inner.get_extra_info("sockname"))
        remote = _address(inner.get_extra_info("peername"))
        if local is not None and remote is not None and self._tcp != (local, remote):
            self._tcp = (local, remote)
            self.capture.tcp_open(local, remote)

    def _udp_ends(self, inner: UdpTransport, outbound: bool) -> tuple[Address, Address] | None:
        remote = inner.remote_address if outbound else inner.peer
        bound = inner.local_address
        if remote is None or bound is None:
            return None
        local = self._udp_local.get(remote)
        if local is None:
            local = self._udp_local[remote] = (source_address(remote, bound[0]), bound[1])
        return (local, remote) if outbound else (remote, local)

    def _record(self, data: bytes, *, outbound: bool) -> None:
        inner = self.inner
        if isinstance(inner, UdpTransport):
            ends = self._udp_ends(inner, outbound)
            if ends is not None:
                self.capture.udp(ends[0], ends[1], data)
        elif isinstance(inner, TcpTransport):
            if self._tcp is None:
                self._tcp_connected()
            if self._tcp is not None:
                local, remote = self._tcp
                src, dst = (local, remote) if outbound else (remote, local)
                self.capture.tcp(src, dst, data)
        else:
            self.capture.serial(self._link_name, data, outbound=outbound)


def with_capture(transport: Transport, capture: object) -> Transport:
    """``transport`` itself when ``capture`` is ``None``, else a :class:`CapturingTransport`
    writing to ``capture`` (a :class:`~gcu_async.capture.PacketCapture` or a file path;
    anything else is a ``TypeError`` naming ``capture``)."""
    sink = as_capture(capture)
    return transport if sink is None else CapturingTransport(transport, sink)

