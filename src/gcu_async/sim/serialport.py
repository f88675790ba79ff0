"""The simulator's serial endpoint: a pseudo-terminal pair, or a real device path.

``serve_pty()`` creates a pty pair (POSIX), puts the follower side in raw mode and publishes its
path (``device_path``) for a client to open like a serial port; the simulator keeps the follower
open too, so clients may open and close it repeatedly. ``serve_serial(path)`` opens an existing
device (8N1, the given baud rate) with pyserial. A pty ignores the baud rate; the real GCU detects
115200/250000/500000/1000000 (docs/protocol-notes.md §12 "Transports"). Replies the other side does
not read are dropped once the terminal buffer is full (counted in ``replies_dropped``). While the
simulator is stalled the endpoint does not read its descriptor: the terminal buffers what the host
writes (a Linux pty took 16 KiB; then the host's writes block).
"""

from __future__ import annotations

import asyncio
import logging
import os
from typing import Any

from gcu_async.protocol.links import DEFAULT_BAUDRATE
from gcu_async.sim.exchange import Exchange
from gcu_async.sim.listen import ListenSpec
from gcu_async.sim.server import ServerParts, SimServer

log = logging.getLogger("gcu_async.sim")

READ_SIZE = 4096


class SerialServer(SimServer):
    """Serial endpoint of a simulator; ``device_path`` is what a client opens."""

    def __init__(
        self, parts: ServerParts, path: str | None = None, baudrate: int = DEFAULT_BAUDRATE
    ) -> None:
        self._parts = parts
        self._path = path
        self.baudrate = baudrate
        self.device_path: str = path or ""
        self._fd: int | None = None
        self._follower_fd: int | None = None
        self._serial: Any = None
        self._exchange: Exchange | None = None
        self._reading = False
        self.replies_dropped = 0

    @property
    def url(self) -> str:
        return f"serial://{self.device_path}"

    async def open(self) -> None:
        if self._fd is not None:
            return
        if self._parts.capture is not None:
            self._parts.capture.acquire()  # OSError if the file cannot be created
        try:
            self._open()
        except BaseException:
            if self._parts.capture is not None:
                self._parts.capture.release()
            raise
        self._exchange = self._parts.new_exchange(True)
        self._reading = False
        self._parts.stalls.join(self)  # pauses at once during a stall
        if not self._parts.stalls.stalled:
            self.resume()

    def _open(self) -> None:
        if self._path is None:
            if not hasattr(os, "openpty"):  # Windows
                raise OSError("serve_pty: pseudo-terminals need a POSIX system")
            import tty  # POSIX only (termios): imported here so the package imports anywhere

            leader, follower = os.openpty()
            try:
                tty.setraw(follower)
                self.device_path = os.ttyname(follower)
            except BaseException:
                os.close(leader)
                os.close(follower)
                raise
            self._fd, self._follower_fd = leader, follower
        else:
            self._serial = _open_device(self._path, self.baudrate)
            self._fd = int(self._serial.fileno())
        os.set_blocking(self._fd, False)

    def pause(self) -> None:
        """Stall member: stop reading the descriptor."""
        if self._fd is not None and self._reading:
            asyncio.get_running_loop().remove_reader(self._fd)
        self._reading = False

    def resume(self) -> None:
        """Stall member: read the descriptor again."""
        if self._fd is not None and not self._reading:
            asyncio.get_running_loop().add_reader(self._fd, self._readable)
            self._reading = True

    def _readable(self) -> None:
        fd, exchange = self._fd, self._exchange
        if fd is None or exchange is None:
            return
        try:
            data = os.read(fd, READ_SIZE)
        except (BlockingIOError, InterruptedError):
            return
        except OSError as exc:  # e.g. EIO from a pty whose other side is gone
            log.debug("serial read: %s", exc)
            return
        if data:
            if self._parts.capture is not None:
                self._parts.capture.serial(self.device_path, data, outbound=False)
            exchange.feed(data, self._write)

    def _write(self, data: bytes) -> None:
        fd = self._fd
        if fd is None:
            return
        view = memoryview(data)
        try:
            while view:
                try:
                    n = os.write(fd, view)
                except (BlockingIOError, InterruptedError):
                    self.replies_dropped += 1
                    return
                view = view[n:]
        finally:
            if self._parts.capture is not None:  # what reached the terminal
                self._parts.capture.serial(self.device_path, data[: len(data) - len(view)],
                                         outbound=True)  # fmt: skip

    async def close(self) -> None:
        self._parts.stalls.leave(self)
        self.pause()
        fd, self._fd = self._fd, None
        if self._exchange is not None:
            self._exchange.close()
        if fd is None:
            return
        if self._parts.capture is not None:
            self._parts.capture.release()
        if self._serial is not None:
            self._serial.close()
            self._serial = None
        else:
            os.close(fd)
        if self._follower_fd is not None:
            os.close(self._follower_fd)
            self._follower_fd = None


def _open_device(path: str, baudrate: int) -> Any:
    import serial  # type: ignore[import-untyped]

    try:
        return serial.Serial(path, baudrate=baudrate, timeout=0, write_timeout=0)
    except serial.SerialException as exc:
        raise OSError(f"{path}: {exc}") from exc


def listen(parts: ServerParts, spec: ListenSpec) -> SerialServer:
    """The ``serial`` listener of the transport registry (docs/architecture.md): the
    device ``spec.path`` at ``spec.baudrate``."""
    return SerialServer(parts, spec.path, spec.baudrate)


def listen_pty(parts: ServerParts, spec: ListenSpec) -> SerialServer:
    """The ``pty`` listener of the transport registry: a new pseudo-terminal."""
    return SerialServer(parts)
