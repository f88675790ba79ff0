""":class:`PacketCapture`: a pcapng file of the packets a client or a simulator exchanges.

One file, one section per time it is opened: interface 0 carries IP packets (link type
``LINKTYPE_RAW``, 101) synthesized from the UDP datagrams and TCP segments the socket
transports exchange (:mod:`~gcu_async.capture.synth`); each serial (or in-memory) link gets
its own interface of link type :data:`SERIAL_LINKTYPE` (``LINKTYPE_USER5``, 152), one record
per read or write with the pcapng direction flag (outbound: written by the capturing side,
inbound: read by it). The Lua dissector registers for that link type and reassembles the
records of each direction. Every record is flushed as it is written, so the file can be
opened while the capture runs, and a crash leaves every packet before it readable.

A capture is opened by the first :meth:`PacketCapture.acquire` and closed by the matching
last :meth:`PacketCapture.release` (the client's transport and each simulator endpoint
acquire it while they run); opened again later, it appends a new section. Writing never
breaks the link it records: an ``OSError`` (disk full, say) is logged once and ends the
capture.
"""

from __future__ import annotations

import logging
import os
import time
from pathlib import Path
from typing import IO, Any

from gcu_async._checks import type_error
from gcu_async.capture import _deps
from gcu_async.capture.synth import Address, TcpFlow, udp_packet

log = logging.getLogger("gcu_async.capture")

RAW_IP_LINKTYPE = 101
"""LINKTYPE_RAW: each record is an IPv4 or IPv6 packet, no link-layer header."""
SERIAL_LINKTYPE = 152
"""LINKTYPE_USER5 (Wireshark's "USER 5", DLT 152): the serial link's bytes as read or written."""
FLAG_INBOUND, FLAG_OUTBOUND = 1, 2
"""pcapng ``epb_flags`` direction values."""
_APPLICATION = "gcu_async"


class PacketCapture:
    """A pcapng capture file at ``path`` (``str`` or ``os.PathLike``).

    Checks at construction that the ``capture`` extra is installed
    (:class:`~gcu_async.capture.CaptureUnavailable` otherwise); the file is created by the
    first :meth:`acquire`.
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        if not isinstance(path, (str, os.PathLike)):
            raise type_error("capture", "a file path (str or os.PathLike) or a PacketCapture", path)
        if not os.fspath(path):
            raise ValueError("capture: the file path is empty")
        self._path = Path(path)
        if self._path.is_dir():
            raise ValueError(f"capture: {str(self._path)!r} is a directory, not a file path")
        _deps.require()
        self._users = 0
        self._sections = 0
        self._file: IO[bytes] | None = None
        self._writer: Any = None
        self._shb: Any = None
        self._serial_ifaces: dict[str, int] = {}
        self._flows: dict[tuple[Address, Address], TcpFlow] = {}
        self.records = 0
        """Packet records written so far (all sections)."""
        self.failed: OSError | None = None
        """The write error that ended the capture, if one did."""

    @property
    def path(self) -> Path:
        return self._path

    @property
    def active(self) -> bool:
        """True while the file is open for writing."""
        return self._writer is not None

    def __repr__(self) -> str:
        state = "open" if self.active else "closed"
        return f"<PacketCapture {str(self._path)!r} {state}, {self.records} records>"

    # -- lifecycle ------------------------------------------------------------------------
    def acquire(self) -> None:
        """Start using the capture; the first user opens the file (``OSError`` if it cannot:
        a missing directory, no permission)."""
        if self._users == 0:
            self._open()
        self._users += 1

    def release(self) -> None:
        """Stop using it; the last user flushes and closes the file."""
        if self._users == 0:
            return
        self._users -= 1
        if self._users == 0:
            self._close()

    def _open(self) -> None:
        pcapng = _deps.pcapng()
        blocks = pcapng.blocks
        mode = "ab" if self._sections else "wb"
        handle = open(self._path, mode)  # noqa: SIM115 - closed by _close()
        try:
            shb = blocks.SectionHeader(options={"shb_userappl": _APPLICATION})
            shb.new_member(blocks.InterfaceDescription, link_type=RAW_IP_LINKTYPE,
                           snaplen=0xFFFF, options={"if_name": "ip",
                           "if_description": "UDP/TCP packets of gcu_async's sockets"})  # fmt: skip
            self._writer = pcapng.FileWriter(handle, shb)
            handle.flush()
        except BaseException:
            handle.close()
            raise
        self._file, self._shb = handle, shb
        self._serial_ifaces = {}
        self._flows = {}
        self._sections += 1
        self.failed = None

    def _close(self) -> None:
        handle, self._file, self._writer = self._file, None, None
        if handle is not None:
            try:
                handle.close()
            except OSError as exc:  # pragma: no cover - a failing close of a local file
                log.warning("capture %s: %s", self._path, exc)

    # -- records ----------------------------------------------------------------------------
    def _write(self, interface: int, data: bytes, flags: int | None = None) -> None:
        if self._writer is None:
            return
        blocks = _deps.pcapng().blocks
        micros = time.time_ns() // 1000
        options: dict[str, Any] = {} if flags is None else {"epb_flags": flags}
        epb = self._shb.new_member(
            blocks.EnhancedPacket, interface_id=interface, packet_data=data, options=options,
            timestamp_high=micros >> 32, timestamp_low=micros & 0xFFFFFFFF,
            captured_len=len(data), packet_len=len(data),
        )  # fmt: skip
        try:
            self._writer.write_block(epb)
            assert self._file is not None
            self._file.flush()
        except OSError as exc:
            self.failed = exc
            log.warning("capture %s stopped: %s", self._path, exc)
            self._close()
            return
        self.records += 1

    def udp(self, src: Address, dst: Address, payload: bytes) -> None:
        """One UDP datagram from ``src`` to ``dst`` (``(host, port)``; IPv4 or IPv6)."""
        if self._writer is not None:
            self._write(0, udp_packet(src, dst, bytes(payload)))

    def tcp_open(self, client: Address, server: Address) -> None:
        """A new TCP connection (its handshake); replaces any earlier one between them."""
        if self._writer is None:
            return
        flow = TcpFlow(client, server)
        self._flows[(client, server)] = flow
        for segment in flow.handshake():
            self._write(0, segment)

    def _flow(self, sender: Address, receiver: Address) -> tuple[TcpFlow | None, bool]:
        """The TCP flow between the two addresses and whether ``sender`` is its client."""
        flow = self._flows.get((sender, receiver))
        if flow is not None:
            return flow, True
        return self._flows.get((receiver, sender)), False

    def tcp(self, src: Address, dst: Address, payload: bytes) -> None:
        """Bytes ``src`` sent to ``dst`` on a TCP connection (opened implicitly, ``src`` as
        the client, if :meth:`tcp_open` was not called)."""
        if self._writer is None or not payload:
            return
        flow, from_client = self._flow(src, dst)
        if flow is None or flow.closed:
            self.tcp_open(src, dst)
            flow, from_client = self._flows[(src, dst)], True
        self._write(0, flow.data(from_client, bytes(payload)))

    def tcp_close(self, closer: Address, peer: Address, *, reset: bool = False) -> None:
        """The end of a TCP connection, closed by ``closer`` (FIN both ways, or an RST)."""
        if self._writer is None:
            return
        flow, from_client = self._flow(closer, peer)
        if flow is None:
            return
        for segment in flow.finish(from_client, reset=reset):
            self._write(0, segment)

    def serial(self, link: str, payload: bytes, *, outbound: bool) -> None:
        """Bytes written (``outbound``) to or read from the serial link named ``link`` (the
        device path, or another name for a non-socket link)."""
        if self._writer is None or not payload:
            return
        interface = self._serial_ifaces.get(link)
        if interface is None:
            blocks = _deps.pcapng().blocks
            idb = self._shb.new_member(blocks.InterfaceDescription, link_type=SERIAL_LINKTYPE,
                                       snaplen=0xFFFF, options={"if_name": link[:200]})  # fmt: skip
            try:
                self._writer.write_block(idb)
            except OSError as exc:
                self.failed = exc
                self._close()
                return
            interface = self._serial_ifaces[link] = idb.interface_id
        self._write(interface, bytes(payload), FLAG_OUTBOUND if outbound else FLAG_INBOUND)


def as_capture(value: object) -> PacketCapture | None:
    """``None``, a :class:`PacketCapture`, or a path made into one (``TypeError`` otherwise)."""
    if value is None or isinstance(value, PacketCapture):
        return value
    if isinstance(value, (str, os.PathLike)):
        return PacketCapture(value)
    raise type_error("capture", "a file path (str or os.PathLike), a PacketCapture or None", value)
