"""Byte-stream MAVLink links: ``tcp:`` (a client, reconnected in the background), ``tcpin:``
(a server for up to :data:`MAX_TCP_CLIENTS` clients) and serial devices (reopened in the
background when the device goes away) — docs/mavlink-bridge.md, "Links"."""

from __future__ import annotations

import asyncio
import logging
import socket
from typing import Any

import serial  # type: ignore[import-untyped]
import serial_asyncio  # type: ignore[import-untyped]

from gcu_async.bridge.links import MavlinkLink, Peer

log = logging.getLogger("gcu_async.bridge")

MAX_TCP_CLIENTS = 8
"""Most clients a ``tcpin`` link serves at once; further connections are closed at once."""


class _Stream(asyncio.Protocol):
    """One connection: its own parser (the :class:`Peer`), its loss reported to the link."""

    def __init__(self, link: MavlinkLink) -> None:
        self.link = link
        self.peer: Peer | None = None
        self.lost: asyncio.Future[str] = asyncio.get_running_loop().create_future()

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.peer = Peer(transport, stream=True)

    def data_received(self, data: bytes) -> None:
        if self.peer is not None:
            self.link.feed(self.peer, data, stream=True)

    def eof_received(self) -> bool:
        return False  # close our side too: the peer is gone

    def connection_lost(self, exc: Exception | None) -> None:
        if not self.lost.done():
            self.lost.set_result(f"connection lost ({exc})" if exc else "peer closed")


class _OneStream(MavlinkLink):
    _stream: _Stream | None = None

    def destinations(self) -> list[Peer]:
        stream = self._stream
        return [stream.peer] if stream is not None and stream.peer is not None else []

    def _install(self, protocol: _Stream) -> asyncio.Future[str]:
        self._abort()
        self._stream = protocol
        return protocol.lost

    def _abort(self) -> None:
        stream, self._stream = self._stream, None
        if stream is not None and stream.peer is not None:
            _abort(stream.peer.transport)


class TcpLink(_OneStream):
    """``tcp:HOST:PORT``: connects; a peer not there yet or gone is retried every
    :data:`~gcu_async.bridge.links.RETRY_SECONDS`."""

    async def _first_open(self) -> asyncio.Future[str] | None:
        return None  # connecting may take OPEN_TIMEOUT: the owner task does it

    async def _connect(self) -> asyncio.Future[str]:
        loop = asyncio.get_running_loop()
        addr = await self.resolve(self.endpoint.host, self.endpoint.port, socket.SOCK_STREAM)
        _, protocol = await loop.create_connection(lambda: _Stream(self), addr[0], addr[1])
        return self._install(protocol)


class SerialLink(_OneStream):
    """``DEVICE[,BAUD]``: the device opened in a daemon thread (an open can block), reopened
    every :data:`~gcu_async.bridge.links.RETRY_SECONDS` after it goes away."""

    async def _connect(self) -> asyncio.Future[str]:
        loop = asyncio.get_running_loop()
        endpoint = self.endpoint
        port = await self.in_thread(
            lambda: serial.Serial(endpoint.device, baudrate=endpoint.baud), _close_port)
        protocol = _Stream(self)
        try:
            serial_asyncio.SerialTransport(loop, protocol, port)
        except BaseException:
            _close_port(port)
            raise
        return self._install(protocol)


def _abort(transport: Any) -> None:
    """Abort a transport that is not already closing (pyserial-asyncio's cannot be aborted
    twice: it forgets its loop once closed)."""
    if not transport.is_closing():
        transport.abort()


def _close_port(port: Any) -> None:
    try:
        port.close()
    except OSError as exc:  # pragma: no cover - closing a vanished device
        log.debug("mavlink: closing a serial port failed: %s", exc)


class TcpInLink(MavlinkLink):
    """``tcpin:HOST:PORT``: accepts clients; each has its own parser and gets everything the
    bridge sends (a TCP client has proven its address, so no destination rule applies)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._server: asyncio.Server | None = None
        self._clients: set[_Stream] = set()
        self.clients_refused = 0
        """Connections closed at once because :data:`MAX_TCP_CLIENTS` were served."""

    @property
    def local_address(self) -> Any:
        """The listening socket's address (``tcpin:…:0`` picks a free port)."""
        if self._server is None or not self._server.sockets:
            return None
        return self._server.sockets[0].getsockname()

    async def _connect(self) -> asyncio.Future[str]:
        loop = asyncio.get_running_loop()
        addr = await self.resolve(self.endpoint.host, self.endpoint.port, socket.SOCK_STREAM)
        self._server = await loop.create_server(self._accept, addr[0], addr[1])
        log.info("mavlink %s: listening on %s", self.url, self.local_address)
        return loop.create_future()  # the server is never lost; close() ends it

    def _accept(self) -> _Stream:
        protocol = _Client(self)
        return protocol

    def admit(self, client: _Stream) -> bool:
        if len(self._clients) >= MAX_TCP_CLIENTS:
            self.clients_refused += 1
            self.log_every("full", logging.WARNING, "%d clients already; connection refused",
                           MAX_TCP_CLIENTS)  # fmt: skip
            return False
        self._clients.add(client)
        log.info("mavlink %s: client connected", self.url)
        return True

    def gone(self, client: _Stream, reason: str) -> None:
        if client in self._clients:
            self._clients.discard(client)
            log.info("mavlink %s: client %s", self.url, reason)

    def destinations(self) -> list[Peer]:
        return [c.peer for c in self._clients if c.peer is not None]

    def _abort(self) -> None:
        server, self._server = self._server, None
        if server is not None:
            server.close()
        for client in list(self._clients):
            if client.peer is not None:
                _abort(client.peer.transport)
        self._clients.clear()


class _Client(_Stream):
    link: TcpInLink

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        super().connection_made(transport)
        if not self.link.admit(self):
            transport.abort()  # type: ignore[attr-defined]

    def connection_lost(self, exc: Exception | None) -> None:
        super().connection_lost(exc)
        self.link.gone(self, "disconnected" if exc is None else f"lost ({exc})")
