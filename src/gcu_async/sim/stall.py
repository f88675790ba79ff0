"""Stalls: a GCU whose firmware freezes for a while, then catches up.

While stalled, every endpoint stops reading its socket or terminal, so the operating system
buffers what the host keeps sending (a UDP socket up to its receive buffer, after which the
kernel drops datagrams; TCP and terminals up to their buffers, after which the host's writes
back up). When the stall ends, reading resumes and every buffered packet is processed and
answered, in arrival order. Packets that reach the model's side while stalled anyway (a
request delayed by fault injection, bytes already read from a stream, the in-memory link,
which has no OS buffer) are held by their :class:`~gcu_async.sim.exchange.Exchange` and
processed, in order, before anything newly read.

A stall is timed on the model's clock. A timer on the running event loop checks that clock
at least every :data:`POLL_SECONDS` (sooner when the stall ends sooner), so with a
:class:`~gcu_async.sim.ManualClock` the stall ends within :data:`POLL_SECONDS` of real time
after the clock has been advanced past its end.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
from typing import Protocol

from gcu_async.sim.clock import Clock

POLL_SECONDS = 0.05
"""Longest real time between two looks at the model clock while stalled."""


class Stallable(Protocol):
    """A part that stops while the GCU is stalled: an endpoint's reader, an exchange."""

    def pause(self) -> None: ...

    def resume(self) -> None: ...


class StallSwitch:
    """Stalls every member for a time of the model clock.

    Members :meth:`join` when they start (one that joins during a stall is paused at once)
    and :meth:`leave` when they close. On the stall's end, members resume in the order they
    joined; resuming never reads synchronously, so whatever members held is processed
    before anything newly read.
    """

    def __init__(self, clock: Clock) -> None:
        self._clock = clock
        self._until = -math.inf
        self._members: dict[Stallable, None] = {}
        self._timer: asyncio.TimerHandle | None = None
        self.stalled = False
        """Is the GCU stalled right now?"""
        self.count = 0
        """Stalls started (extending a running stall does not count)."""

    def stall(self, seconds: float) -> None:
        """Stall for ``seconds`` of the model clock from now (replacing the end of a running
        stall); 0 ends a stall now. Call it on the running event loop."""
        if isinstance(seconds, bool) or not isinstance(seconds, (int, float)) or not (
            0 <= seconds < math.inf
        ):
            raise ValueError(f"seconds: {seconds!r} is outside the allowed range [0, inf)")
        if seconds == 0:
            self._end()
            return
        loop = self._loop()  # before any change: no loop, no stall
        self._until = self._clock.now() + seconds
        if not self.stalled:
            self.stalled = True
            self.count += 1
            for member in list(self._members):
                member.pause()
        self._schedule(loop)

    def join(self, member: Stallable) -> None:
        self._members[member] = None
        if self.stalled:
            member.pause()

    def leave(self, member: Stallable) -> None:
        self._members.pop(member, None)

    # -- internals ----------------------------------------------------------------------------
    @staticmethod
    def _loop() -> asyncio.AbstractEventLoop:
        return asyncio.get_running_loop()

    def _schedule(self, loop: asyncio.AbstractEventLoop) -> None:
        if self._timer is not None:
            self._timer.cancel()
        remaining = self._until - self._clock.now()
        self._timer = loop.call_later(min(max(remaining, 0.0), POLL_SECONDS), self._check)

    def _check(self) -> None:
        self._timer = None
        if not self.stalled:
            return
        if self._clock.now() >= self._until:
            self._end()
        else:
            self._schedule(self._loop())

    def _end(self) -> None:
        self._until = -math.inf
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        if not self.stalled:
            return
        self.stalled = False
        for member in list(self._members):
            member.resume()


class TransportReading:
    """Stall member that pauses reading on an asyncio transport (TCP stream, UDP socket).

    A transport that cannot pause reading keeps reading; its exchange then holds the packets
    instead of the OS. That is one without ``pause_reading``, or one whose ``pause_reading``
    raises ``NotImplementedError``: Python 3.10's selector datagram transport inherits it
    from ``asyncio.ReadTransport`` without implementing it.
    """

    def __init__(self, transport: asyncio.BaseTransport) -> None:
        self._transport = transport

    def pause(self) -> None:
        self._call("pause_reading")

    def resume(self) -> None:
        self._call("resume_reading")

    def _call(self, name: str) -> None:
        method = getattr(self._transport, name, None)
        if method is not None and not self._transport.is_closing():
            with contextlib.suppress(NotImplementedError):
                method()
