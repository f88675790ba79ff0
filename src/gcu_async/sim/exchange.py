"""One peer's path through a running simulator: request faults → model → reply faults.

Servers create one :class:`Exchange` per connection (TCP, serial, memory) or one for all
datagrams (UDP). Delays and reordering use event-loop timers, all cancelled on close.

Delivery bound (per direction): a packet the faults let through is delivered ``d`` seconds
after it entered, with ``0 <= d <= delay + reorder_hold`` of that direction's
:class:`~gcu_async.sim.FaultConfig` (``delay`` drawn uniformly from ``[0, delay]``, plus
``reorder_hold`` when it is reordered); both copies of a duplicate get the same ``d``. That
is the timer's schedule: the event loop adds its own latency. While the simulator is stalled,
packets that reach :meth:`Exchange._process` are held and processed, in order, when the
stall ends (``sim.stats.held_while_stalled``).

Fast path: a datagram that is the request of the model's reply memo (:mod:`gcu_async.sim.memo`,
an idle host's heartbeat) while no fault is configured in either direction and the simulator
is neither stalled nor silenced is answered by :meth:`SimulatorModel.replay` at once: what the
general path does with it (one packet, no discarded byte, no fault drawn, the same counters),
without deframing or routing it.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable

from gcu_async.errors import LinkLost
from gcu_async.protocol.deframer import Deframer
from gcu_async.sim.faults import FaultInjector
from gcu_async.sim.parts import ExchangeHost

log = logging.getLogger("gcu_async.sim")

Deliver = Callable[[bytes], None]


Direction = Callable[[ExchangeHost], FaultInjector]
"""The fault injector of one direction, looked up on every packet (so
:meth:`GcuSimulator.set_faults` acts at once)."""


def _requests(sim: ExchangeHost) -> FaultInjector:
    return sim.request_faults


def _replies(sim: ExchangeHost) -> FaultInjector:
    return sim.reply_faults


class Exchange:
    """Carries bytes from one peer into the model and the replies back."""

    def __init__(self, sim: ExchangeHost, *, stream: bool) -> None:
        self._sim = sim
        self._stream = stream
        self._deframer = Deframer.for_host_packets()
        """The connection's (a stream), or the one every datagram is deframed with (each
        settled at its end: one datagram never runs into the next)."""
        self._longest = self._deframer.max_length
        self._requests: Direction = _requests
        self._replies: Direction = _replies
        self._timers: set[asyncio.TimerHandle] = set()
        self._held: list[tuple[bytes, Deliver]] = []
        self._closed = False
        sim.stalls.join(self)

    def feed(self, data: bytes, send: Deliver) -> None:
        """Bytes from the peer; replies go to ``send`` (a datagram is deframed on its own)."""
        if self._closed:
            return
        sim = self._sim
        model = sim.model
        if not self._stream:
            if (len(data) <= self._longest and not sim.stalls.stalled
                    and not sim.request_faults.config.active
                    and not sim.reply_faults.config.active and not sim.silenced):  # fmt: skip
                reply = model.replay(data)
                if reply is not None:
                    self._send(send, reply)
                    return
            packets = model.split(data, self._deframer, end=True)
        else:
            packets = model.split(data, self._deframer)

        def process(packet: bytes) -> None:
            self._process(packet, send)

        for packet in packets:
            self._route(self._requests, packet, process)

    def close(self) -> None:
        """Cancel every pending delayed packet; count what a stream left half-received."""
        if self._closed:
            return
        self._closed = True
        self._sim.stalls.leave(self)
        self._held.clear()
        for timer in self._timers:
            timer.cancel()
        self._timers.clear()
        if self._stream:
            self._sim.model.discard(self._deframer)

    def pause(self) -> None:
        """Stall member: nothing to do, :meth:`_process` holds packets while stalled."""

    def resume(self) -> None:
        """Stall member: process the held packets, in order."""
        held, self._held = self._held, []
        for packet, send in held:
            self._process(packet, send)

    # -- internals ------------------------------------------------------------------------
    def _process(self, packet: bytes, send: Deliver) -> None:
        if self._closed:
            return
        sim = self._sim
        if sim.stalls.stalled:
            self._held.append((packet, send))
            sim.stats.held_while_stalled += 1
            return
        if sim.silenced:
            sim.stats.ignored_while_silent += 1
            return
        reply = sim.model.handle_bytes(packet)
        if reply is not None:
            self._route(self._replies, reply, lambda data: self._send(send, data))

    def _send(self, send: Deliver, data: bytes) -> None:
        try:
            send(data)
        except (OSError, LinkLost) as exc:
            self._sim.stats.send_errors += 1
            log.debug("reply not sent: %s", exc)
        else:
            self._sim.stats.replies_sent += 1

    def _route(self, direction: Direction, data: bytes, deliver: Deliver) -> None:
        injector = direction(self._sim)
        if not injector.config.active:
            deliver(data)
            return
        decision = injector.decide(len(data))
        if decision.drop:
            return
        data = injector.apply(data, decision)
        delay = decision.delay + (injector.config.reorder_hold if decision.hold else 0.0)
        self._out(deliver, data, decision.copies, delay)

    def _out(self, deliver: Deliver, data: bytes, copies: int, delay: float) -> None:
        for _ in range(copies):
            if delay <= 0:
                deliver(data)
            else:
                self._later(delay, deliver, data)

    def _later(self, delay: float, deliver: Deliver, data: bytes) -> None:
        def fire() -> None:
            self._timers.discard(timer)
            if not self._closed:
                deliver(data)

        timer = self._loop().call_later(delay, fire)
        self._timers.add(timer)

    @staticmethod
    def _loop() -> asyncio.AbstractEventLoop:
        return asyncio.get_running_loop()
