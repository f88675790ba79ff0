"""When did a reply arrive? The optional capability behind the session's reorder proofs.

On a link that may reorder (UDP), the session decides which packet a reply answers from
*when it arrived* (docs/client.md, "The session contract", A4). A busy event loop hands
a reply over later than it arrived, so the driver passes the session a lower bound
(``Session.receive(arrived_after=...)``). Only a transport that can say when its socket
was last empty gives one: such a transport implements :class:`ReadsOnDemand` (UDP's
draining reader); others need not define anything. :func:`arrival_bound` chooses how a
driver gets the bound, and :class:`ArrivalBound` keeps it.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable
from typing import Protocol, runtime_checkable

from gcu_async.transport._datagram import RESOLUTION
from gcu_async.transport.base import Transport

log = logging.getLogger("gcu_async.client")


@runtime_checkable
class ReadsOnDemand(Protocol):
    """A transport that knows when its OS queue was empty (UDP's draining reader)."""

    @property
    def drains(self) -> bool:
        """True when the transport reads on the loop's (level-triggered) readiness events and
        :meth:`empty_at_poll` can tell, in a timer callback, whether the OS queue was empty
        when the loop iteration polled the OS."""

    def empty_at_poll(self, due: float) -> bool:
        """Called first thing in a timer callback whose timer was due at ``due`` (the loop's
        time): True if nothing that reached the OS queue before this iteration polled the
        OS is still undelivered (it may read the queue, delivering, to make sure)."""

    def read_pending(self) -> bool:
        """Read and deliver, right now and synchronously, everything the OS holds; True if
        the queue was then empty (whatever is delivered later arrived after this call
        began), False if this transport cannot tell now."""


class ArrivalBound:
    """A time before which no reply not yet delivered can have arrived.

    ``value`` is what the driver passes as ``Session.receive(arrived_after=...)``. Call
    :meth:`timer_ran` first thing in every timer callback and :meth:`before_send` before
    each poll of the session."""

    __slots__ = ("_clock", "_link", "from_loop", "value")

    def __init__(self, link: ReadsOnDemand, clock: Callable[[], float], value: float,
                 *, from_loop: bool) -> None:  # fmt: skip
        self._link = link
        self._clock = clock
        self.value = value
        self.from_loop = from_loop
        """True: the bound comes for free from the loop's timers (a draining transport on
        a loop that keeps the driver's time); False: from reading the link empty."""

    def timer_ran(self, when: float) -> None:
        """A timer due at ``when`` (the loop's clock) runs now, so this iteration's poll of
        the OS returned at ``when`` minus the clock's resolution or later: once nothing that
        arrived before it is undelivered (:meth:`ReadsOnDemand.empty_at_poll`), what is
        delivered from now on arrived after it."""
        if self.from_loop and self._link.empty_at_poll(when):
            self.value = when - RESOLUTION

    def before_send(self) -> None:
        """Read what waits on the link (replies before sends); if it was then empty, the
        bound moves to the time read before reading."""
        if not self.from_loop:
            now = self._clock()
            if self._link.read_pending():
                self.value = now


def loop_keeps(clock: Callable[[], float], loop: asyncio.AbstractEventLoop) -> bool:
    """True when ``loop``'s time is ``clock`` itself (:func:`time.monotonic` on asyncio's own
    loops): a time on the clock is then a time on the loop."""
    return clock is time.monotonic and type(loop).time is asyncio.BaseEventLoop.time


def arrival_bound(transport: Transport, clock: Callable[[], float],
                  loop: asyncio.AbstractEventLoop) -> ArrivalBound | None:  # fmt: skip
    """How a driver bounds reply arrival on ``transport`` (call it once the link is open).

    ``None`` when the link never reorders (nothing to bound), or cannot be read on demand
    (the session then assumes a responsive loop: logged). Best, for free: a draining
    transport whose loop keeps the driver's time (``clock`` is :func:`time.monotonic`, the
    loop's own ``time``). Else: the link read empty before each send."""
    if transport.ordered:
        return None
    if isinstance(transport, ReadsOnDemand):
        now = clock()
        if transport.drains and loop_keeps(clock, loop):
            return ArrivalBound(transport, clock, now, from_loop=True)
        if transport.read_pending():
            return ArrivalBound(transport, clock, now, from_loop=False)
    log.info("%s cannot be read on demand: reply timing assumes a responsive event loop "
             "(docs/client.md, \"The session contract\")", transport.url)  # fmt: skip
    return None
