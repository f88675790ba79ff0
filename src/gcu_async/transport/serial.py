"""Serial transport over pyserial-asyncio: TTL UART, 8 data bits, no parity, 1 stop bit.

NOTES §9: the GCU detects the rate itself among 115200, 250000, 500000 and 1000000 baud;
no other rate is accepted. If the device disappears (USB adapter unplugged, pty peer
closed) a :attr:`~LinkEventKind.LOST` event is emitted and the transport stays down; call
:meth:`SerialTransport.open` again to retry.
"""

from __future__ import annotations

import asyncio
from urllib.parse import quote

import serial_asyncio  # type: ignore[import-untyped]

from gcu_async.errors import LinkLost
from gcu_async.transport._common import call_guarded
from gcu_async.transport.base import LinkEvent, LinkEventKind, Transport

BAUDRATES = (115200, 250000, 500000, 1000000)
"""The rates a GCU auto-detects (NOTES §9)."""
DEFAULT_BAUDRATE = 115200

_CLOSE_GRACE = 1.0
"""Seconds :meth:`SerialTransport.close` lets unsent bytes drain before aborting."""


def check_baudrate(value: object) -> int:
    """Return ``value`` if it is one of :data:`BAUDRATES`, else raise ValueError."""
    if isinstance(value, bool) or not isinstance(value, int) or value not in BAUDRATES:
        allowed = ", ".join(str(b) for b in BAUDRATES)
        raise ValueError(f"baudrate: {value!r} is not supported (allowed: {allowed})")
    return value


class _SerialProtocol(asyncio.Protocol):
    def __init__(self, owner: SerialTransport) -> None:
        self._owner = owner
        self.transport: asyncio.Transport | None = None
        self.closed: asyncio.Future[None] = asyncio.get_running_loop().create_future()

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport

    def data_received(self, data: bytes) -> None:
        self._owner._data(self, data)

    def connection_lost(self, exc: Exception | None) -> None:
        if not self.closed.done():
            self.closed.set_result(None)
        self._owner._lost(self, exc)


class SerialTransport(Transport):
    """Serial link on ``device`` (e.g. ``/dev/ttyUSB0``) at ``baudrate``, 8N1."""

    def __init__(self, device: str, baudrate: int = DEFAULT_BAUDRATE) -> None:
        super().__init__()
        if not isinstance(device, str) or not device:
            raise ValueError(f"device: {device!r} is not a device path")
        self._device = device
        self._baudrate = check_baudrate(baudrate)
        self._proto: _SerialProtocol | None = None
        self._stransport: asyncio.Transport | None = None
        self.bytes_sent = 0
        self.bytes_received = 0

    @property
    def url(self) -> str:
        quoted = quote(self._device, safe="/:")
        prefix = "serial://" if self._device.startswith("/") else "serial:"
        return f"{prefix}{quoted}?baudrate={self._baudrate}"

    @property
    def device(self) -> str:
        return self._device

    @property
    def baudrate(self) -> int:
        return self._baudrate

    @property
    def connected(self) -> bool:
        return self._stransport is not None and not self._stransport.is_closing()

    async def open(self) -> None:
        """Open the device (8N1). Raises :class:`LinkLost`, naming the device, if it is
        missing or cannot be opened."""
        if self.connected:
            return
        loop = asyncio.get_running_loop()
        proto = _SerialProtocol(self)
        try:
            stransport, _ = await serial_asyncio.create_serial_connection(
                loop, lambda: proto, self._device,
                baudrate=self._baudrate, bytesize=8, parity="N", stopbits=1,
                xonxoff=False, rtscts=False, dsrdtr=False,
            )  # fmt: skip
        except OSError as exc:  # serial.SerialException is an OSError
            raise LinkLost(f"serial {self._device}: cannot open: {exc}") from exc
        assert isinstance(stransport, asyncio.Transport)
        self._proto = proto
        self._stransport = stransport

    def send(self, data: bytes) -> None:
        """Queue ``data`` for the UART. Raises :class:`LinkLost` if the port is closed."""
        stransport = self._stransport
        if stransport is None or stransport.is_closing():
            raise LinkLost(f"serial {self._device}: port is closed")
        self.bytes_sent += len(data)
        stransport.write(bytes(data))

    async def close(self) -> None:
        """Close the port and release its fd; returns once released. Idempotent."""
        stransport, proto = self._stransport, self._proto
        self._stransport = None
        if stransport is None or proto is None:
            return
        stransport.close()
        await asyncio.wait({proto.closed}, timeout=_CLOSE_GRACE)
        if not proto.closed.done() and stransport.get_write_buffer_size() > 0:
            stransport.abort()  # the peer is not draining: drop what is left
        await asyncio.shield(proto.closed)

    # -- callbacks from _SerialProtocol -----------------------------------------------------

    def _data(self, proto: _SerialProtocol, data: bytes) -> None:
        if proto is self._proto and self._stransport is not None:
            self.bytes_received += len(data)
            call_guarded(self._on_data, data, "data")

    def _lost(self, proto: _SerialProtocol, exc: Exception | None) -> None:
        if proto is not self._proto or self._stransport is None:
            return  # closed by us
        self._stransport = None
        reason = f": {exc}" if exc is not None else ""
        event = LinkEvent(LinkEventKind.LOST, f"serial {self._device}: port lost{reason}")
        call_guarded(self._on_event, event, "event")
