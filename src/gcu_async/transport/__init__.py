"""Transports: serial, UDP, TCP and in-memory. Bytes in, bytes out; no protocol logic."""

from gcu_async.protocol.links import BAUDRATES
from gcu_async.transport.backoff import Backoff
from gcu_async.transport.base import (
    DataHandler,
    EventHandler,
    LinkEvent,
    LinkEventKind,
    Transport,
)
from gcu_async.transport.memory import MemoryTransport
from gcu_async.transport.serial import SerialTransport
from gcu_async.transport.tcp import TcpTransport
from gcu_async.transport.udp import UdpTransport
from gcu_async.transport.url import open_transport

__all__ = [
    "BAUDRATES", "Backoff", "DataHandler", "EventHandler", "LinkEvent", "LinkEventKind",
    "MemoryTransport", "SerialTransport", "TcpTransport", "Transport", "UdpTransport",
    "open_transport",
]  # fmt: skip
