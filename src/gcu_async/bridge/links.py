"""One MAVLink connection (a pymavlink ``mavutil`` connection string) driven from asyncio.

pymavlink's connections block, so each link has one reader thread: it waits at most
:data:`POLL_SECONDS` for a message, hands every parsed message to the event loop with
``call_soon_threadsafe``, and checks a stop flag between waits, so :meth:`MavlinkLink.close`
returns within about ``POLL_SECONDS`` plus the join timeout. Writes happen on the event
loop's thread (already-packed bytes: the bridge packs each message once for every link).
Unparseable input is counted and dropped in the thread; nothing it receives can end it.
"""

from __future__ import annotations

import asyncio
import logging
import threading
import time
from collections.abc import Callable
from typing import Any

from gcu_async.bridge._mavlink import mavutil

log = logging.getLogger("gcu_async.bridge")

POLL_SECONDS = 0.1
"""Longest wait of the reader thread for one message (bounds the shutdown)."""
JOIN_SECONDS = 2.0
"""Longest wait for the reader thread when closing."""
SILENCE_SECONDS = 3.0
"""No message for this long counts as a lost MAVLink link (logged; restored on the next)."""


class MavlinkLink:
    """A started link calls ``on_message(link, msg)`` on the loop for every message."""

    def __init__(self, url: str, *, source_system: int, source_component: int) -> None:
        self.url = url
        self._source = (source_system, source_component)
        self._conn: Any = None
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self.received = 0
        self.bad_data = 0
        self.send_errors = 0
        self.last_message: float | None = None
        self.up = False

    async def open(self, on_message: Callable[[MavlinkLink, Any], None]) -> None:
        """Open the connection (in a worker thread: TCP connects block) and start reading."""
        loop = asyncio.get_running_loop()
        system, component = self._source
        self._conn = await asyncio.to_thread(
            mavutil.mavlink_connection, self.url, source_system=system,
            source_component=component, autoreconnect=True)  # fmt: skip
        self._thread = threading.Thread(target=self._read, args=(loop, on_message),
                                        name=f"mavlink {self.url}", daemon=True)  # fmt: skip
        self._thread.start()
        log.info("mavlink %s: open", self.url)

    def _read(self, loop: asyncio.AbstractEventLoop,
              on_message: Callable[[MavlinkLink, Any], None]) -> None:  # fmt: skip
        conn = self._conn
        while not self._stop.is_set():
            try:
                msg = conn.recv_match(blocking=True, timeout=POLL_SECONDS)
            except Exception as exc:  # a hostile byte stream must not end the thread
                self.bad_data += 1
                log.debug("mavlink %s: receive failed: %s", self.url, exc)
                time.sleep(POLL_SECONDS)
                continue
            if msg is None:
                continue
            if msg.get_type() == "BAD_DATA":
                self.bad_data += 1
                continue
            try:
                loop.call_soon_threadsafe(on_message, self, msg)
            except RuntimeError:  # the loop closed
                return

    def note_message(self, now: float) -> None:
        """Count a message (on the loop) and log the link coming up."""
        self.received += 1
        self.last_message = now
        if not self.up:
            self.up = True
            log.warning("mavlink %s: traffic %s", self.url,
                        "restored" if self.received > 1 else "started")  # fmt: skip

    def check_silence(self, now: float) -> None:
        """Log the link as lost after :data:`SILENCE_SECONDS` without a message."""
        if self.up and self.last_message is not None and now - self.last_message > SILENCE_SECONDS:
            self.up = False
            log.warning("mavlink %s: no message for %g s: link lost", self.url, SILENCE_SECONDS)

    def send(self, data: bytes) -> None:
        """Write one packed message (errors are counted and logged at DEBUG: a link whose
        peer is gone keeps the others going)."""
        conn = self._conn
        if conn is None:
            return
        try:
            conn.write(data)
        except (OSError, ValueError) as exc:
            self.send_errors += 1
            log.debug("mavlink %s: send failed: %s", self.url, exc)

    async def close(self) -> None:
        """Stop the reader (bounded: :data:`POLL_SECONDS` + :data:`JOIN_SECONDS`) and close."""
        self._stop.set()
        thread = self._thread
        if thread is not None:
            await asyncio.to_thread(thread.join, JOIN_SECONDS)
            if thread.is_alive():
                log.warning("mavlink %s: reader thread did not stop", self.url)
        conn, self._conn = self._conn, None
        if conn is not None:
            try:
                conn.close()
            except OSError as exc:
                log.debug("mavlink %s: close failed: %s", self.url, exc)
        log.info("mavlink %s: closed", self.url)
