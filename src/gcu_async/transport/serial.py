"""Serial transport over pyserial-asyncio: TTL UART, 8 data bits, no parity, 1 stop bit.

docs/protocol-notes.md §12 "Transports": the GCU detects the rate itself among 115200, 250000,
500000 and 1000000 baud; no other rate is accepted. If the device disappears (USB adapter unplugged,
pty peer closed) a :attr:`~LinkEventKind.LOST` event is emitted and, with ``reconnect=True``
(default), the same path is reopened on the :class:`~gcu_async.transport.Backoff` schedule
(by default every 0–2 s until it opens or the transport is closed), then
:attr:`~LinkEventKind.RESTORED`; opt-in bounds that run out, or ``reconnect=False``, end in
:attr:`~LinkEventKind.GAVE_UP` (call :meth:`SerialTransport.open` to start over).

Reading
    pyserial-asyncio reads at most 1024 bytes per readiness event. This transport reads on
    (from the port's non-blocking file descriptor) until the OS has nothing more, up to
    :data:`MAX_READ_PER_EVENT` bytes, and delivers it all in one ``on_data`` call: a busy
    event loop never falls behind the UART.

Writing and backpressure
    :meth:`SerialTransport.send` writes straight to the file descriptor when nothing is
    queued; whatever the OS does not take is queued in pyserial-asyncio's write buffer, and
    while that buffer is not empty further sends are dropped whole and counted in
    ``sends_dropped``: a stalled UART never piles stale packets up in user space.

Reset
    :meth:`SerialTransport.reset` discards pyserial-asyncio's write buffer and the OS output
    and input queues (``tcflush``); the port stays open and no event is emitted. Bytes the
    UART already shifted out (or, on a pseudo-terminal, that reached the other side's line
    discipline) are not recalled.

POSIX only, as pyserial-asyncio's event-driven mode is.
"""

from __future__ import annotations

import asyncio
import os
import random
from urllib.parse import quote

import serial_asyncio  # type: ignore[import-untyped]

from gcu_async.errors import LinkLost
from gcu_async.protocol.links import BAUDRATES, DEFAULT_BAUDRATE
from gcu_async.transport._common import call_guarded, check_reason, link_lost
from gcu_async.transport._reopen import Reopener, Reopening
from gcu_async.transport.backoff import Backoff
from gcu_async.transport.base import LinkEvent, LinkEventKind, Transport

try:
    import termios

    _FLUSH_ERRORS: tuple[type[Exception], ...] = (OSError, termios.error)
except ImportError:  # pragma: no cover - not POSIX
    _FLUSH_ERRORS = (OSError,)


_CLOSE_GRACE = 1.0
"""Seconds :meth:`SerialTransport.close` lets unsent bytes drain before aborting."""
MAX_READ_PER_EVENT = 1 << 20
"""Most bytes read per readiness event (10 s of data at 1,000,000 baud); the rest wait for
the next loop iteration, so one port cannot starve the loop."""
_READ_SIZE = 4096
"""Bytes asked per read: a tty's line discipline hands out at most 4095 at a time."""


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
        self.error: Exception | None = None
        """An error this module met (read, write, flush) before aborting the transport."""
        self.closed: asyncio.Future[None] = asyncio.get_running_loop().create_future()

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport

    def fail(self, exc: Exception) -> None:
        """Abort the transport because of ``exc`` (reported as the loss's reason)."""
        if self.error is None:
            self.error = exc
        if self.transport is not None:
            self.transport.abort()

    def data_received(self, data: bytes) -> None:
        self._owner._data(self, data)

    def connection_lost(self, exc: Exception | None) -> None:
        if not self.closed.done():
            self.closed.set_result(None)
        self._owner._lost(self, exc)


class SerialTransport(Reopening, Transport):
    """Serial link on ``device`` (e.g. ``/dev/ttyUSB0``) at ``baudrate``, 8N1."""

    def __init__(
        self,
        device: str,
        baudrate: int = DEFAULT_BAUDRATE,
        *,
        reconnect: bool = True,
        backoff: Backoff | None = None,
        rng: random.Random | None = None,
    ) -> None:
        super().__init__()
        if not isinstance(device, str) or not device:
            raise ValueError(f"device: {device!r} is not a device path")
        self._device = device
        self._baudrate = check_baudrate(baudrate)
        self._reopen = Reopener(reconnect, backoff, rng)
        self._proto: _SerialProtocol | None = None
        self._stransport: asyncio.Transport | None = None
        self._fd = -1
        self.bytes_sent = 0
        """Bytes accepted by :meth:`send` (written or queued; dropped sends excluded)."""
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
        missing or cannot be opened. Stops a running reopen task first."""
        if self.connected:
            return
        self._reopen.closing = False
        await self._reopen.stop()
        await self._open_port()

    async def _open_port(self, timeout: float | None = None) -> None:
        loop = asyncio.get_running_loop()
        proto = _SerialProtocol(self)
        try:
            stransport, _ = await serial_asyncio.create_serial_connection(
                loop, lambda: proto, self._device,
                baudrate=self._baudrate, bytesize=8, parity="N", stopbits=1,
                xonxoff=False, rtscts=False, dsrdtr=False,
            )  # fmt: skip
        except OSError as exc:  # serial.SerialException is an OSError
            raise link_lost(f"serial {self._device}", "cannot open", exc) from exc
        assert isinstance(stransport, asyncio.Transport)
        fd = stransport.get_extra_info("serial").fileno()
        os.set_blocking(fd, False)  # pyserial opens it so; send() and reads rely on it
        proto.transport = stransport  # connection_made comes later, via call_soon
        self._proto = proto
        self._stransport = stransport
        self._fd = fd
        await asyncio.sleep(0)  # let pyserial-asyncio register its reader (call_soon)

    def send(self, data: bytes) -> None:
        """Write ``data`` to the port; what the OS does not take at once is queued. While
        anything is queued, ``data`` is dropped whole instead (counted in
        ``sends_dropped``). Raises :class:`LinkLost` if the port is closed or the write
        fails (the port is then closed and a ``LOST`` event follows)."""
        stransport, proto = self._stransport, self._proto
        if stransport is None or proto is None or stransport.is_closing():
            raise LinkLost(f"serial {self._device}: port is closed")
        if stransport.get_write_buffer_size():
            self.sends_dropped += 1
            return
        data = bytes(data)
        try:
            n = os.write(self._fd, data) if data else 0
        except BlockingIOError:
            n = 0
        except OSError as exc:
            proto.fail(exc)
            raise link_lost(f"serial {self._device}", "write failed", exc) from exc
        self.bytes_sent += len(data)
        if n < len(data):
            stransport.write(data[n:])  # pyserial-asyncio writes it when the port is ready

    def reset(self, reason: str) -> None:
        """Discard what is queued for the UART (pyserial-asyncio's write buffer and the OS
        output queue) and what the OS received but nobody read yet (the OS input queue).
        The port stays open; no event is emitted. If the flush fails the device is gone:
        the port is closed and ``LOST`` follows (via the event loop, never from this call).
        Does nothing while closed. Raises TypeError if ``reason`` is not a ``str``."""
        check_reason(reason)
        stransport, proto = self._stransport, self._proto
        if stransport is None or proto is None or stransport.is_closing():
            return
        stransport.flush()  # type: ignore[attr-defined]  # pyserial-asyncio: drop the buffer
        port = stransport.get_extra_info("serial")
        try:
            port.reset_output_buffer()
            port.reset_input_buffer()
        except _FLUSH_ERRORS as exc:
            proto.fail(exc)

    async def close(self) -> None:
        """Stop reopening, close the port and release its fd; returns once released.
        Idempotent."""
        self._reopen.closing = True
        await self._reopen.stop()
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
            data = self._read_rest(proto, data)
            self.bytes_received += len(data)
            call_guarded(self._on_data, data, "data")

    def _read_rest(self, proto: _SerialProtocol, first: bytes) -> bytes:
        """``first`` (pyserial-asyncio's read) plus everything else the OS has right now."""
        chunks, total, fd, cap = [first], len(first), self._fd, MAX_READ_PER_EVENT
        while total < cap:
            try:
                more = os.read(fd, min(_READ_SIZE, cap - total))
            except BlockingIOError:
                break
            except OSError as exc:  # EIO: the device is gone
                proto.fail(exc)
                break
            if not more:  # VMIN=0: "nothing now" (a hang-up shows at the next event)
                break
            chunks.append(more)
            total += len(more)
        return first if len(chunks) == 1 else b"".join(chunks)

    def _lost(self, proto: _SerialProtocol, exc: Exception | None) -> None:
        if proto is not self._proto or self._stransport is None:
            return  # closed by us
        self._stransport = None
        exc = exc if exc is not None else proto.error
        reason = f": {exc}" if exc is not None else ""
        event = LinkEvent(LinkEventKind.LOST, f"serial {self._device}: port lost{reason}")
        call_guarded(self._on_event, event, "event")
        # opening a device node takes no time worth bounding: the timeout is unused
        self._reopen.start(self.url, self._open_port, 1.0, f"serial {self._device}: reopened",
                           self._on_event)  # fmt: skip
