"""A deterministic virtual-time rig: the sans-I/O session, the simulator's GCU model and an
adversarial network between them. No sockets, no sleeping, no event loop.

Time only moves from one scheduled event to the next: packet arrivals (each direction has its
own fate per packet: lost, corrupted, duplicated, delayed within a bound), the session's own
wake-ups (:meth:`Session.next_wakeup`) and scripted API calls. Every host packet sent and
every command the model executed is recorded, so the checks in :meth:`Rig.check` can compare
what the session reported with what the GCU did.
"""

from __future__ import annotations

import bisect
import heapq
import itertools
import math
import random
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

from gcu_async.errors import Outcome
from gcu_async.protocol import (
    Command,
    Deframer,
    HostPacket,
    Opcode,
    command_code,
    decode_host_packet,
)
from gcu_async.session import Session, SessionState, Ticket, TicketState
from gcu_async.session.control import REPORTED
from gcu_async.session.pacing import WINDOW
from gcu_async.sim import ExecutionRecord, ManualClock, SimulatorModel


@dataclass(frozen=True)
class Fate:
    """What the network does to one packet."""

    drop: bool = False
    corrupt: bool = False
    delay: float = 0.0
    """Extra delay on top of the base latency, within [0, D]."""
    copy_delay: float | None = None
    """A duplicate arrives this long after the base latency (None: no duplicate)."""


PERFECT = Fate()


@dataclass
class Direction:
    """The fate source of one direction: scripted fates first, then random ones."""

    scripted: list[Fate] = field(default_factory=list)
    loss: float = 0.0
    corrupt: float = 0.0
    duplicate: float = 0.0
    jitter: float = 0.0
    """Probability that a packet gets a random delay in [0, bound]; else none."""
    extreme: float = 0.0
    """Probability that a packet is held the whole bound (the worst case for reordering)."""
    seed: int = 0
    override: Callable[[HostPacket | None, int, Fate], Fate] | None = None
    """Adversarial rule applied on top: (decoded host packet or None, opcode, fate) → fate."""
    blackouts: list[tuple[float, float]] = field(default_factory=list)
    """Intervals [start, end) during which every packet of this direction is lost."""

    def dark(self, now: float) -> bool:
        return any(start <= now < end for start, end in self.blackouts)

    def __post_init__(self) -> None:
        self._rng = random.Random(self.seed)
        self._i = 0

    def next(self, bound: float) -> Fate:
        i, self._i = self._i, self._i + 1
        if i < len(self.scripted):
            fate = self.scripted[i]
            return Fate(fate.drop, fate.corrupt, min(fate.delay, bound),
                        None if fate.copy_delay is None else min(fate.copy_delay, bound))
        r = self._rng
        u = [r.random() for _ in range(6)]
        delay = 0.0
        if u[3] < self.extreme:
            delay = bound
        elif u[4] < self.jitter:
            delay = u[5] * bound
        copy = r.random() * bound if u[2] < self.duplicate else None
        return Fate(u[0] < self.loss, u[1] < self.corrupt, delay, copy)


def corrupt(data: bytes, rng: random.Random) -> bytes:
    buf = bytearray(data)
    buf[rng.randrange(len(buf))] ^= 1 << rng.randrange(8)
    return bytes(buf)


class Rig:
    """Session + GCU model + network, driven in virtual time."""

    def __init__(
        self,
        session: Session,
        *,
        bound: float = 0.0,
        latency: float = 0.0,
        requests: Direction | None = None,
        replies: Direction | None = None,
        pod: str = "D-90Pro(TA)",
        seed: int = 0,
        stalls: list[tuple[float, float]] | None = None,
        earliest: str = "driver",
        stall_on_late_reply: float = 0.0,
    ) -> None:
        """``stalls``: intervals [start, end) during which the host's event loop is busy:
        replies, wake-ups and calls due inside wait for the end, then run as one batch.
        ``earliest``: the arrival bound passed with replies: "driver" (what GcuClient passes:
        when its last timer was due: a reply its event loop had not delivered by then
        arrived later), "arrival" (exact), or
        "none" (the session assumes replies are processed as they arrive).
        ``stall_on_late_reply``: an adversarial busy loop: when a reply is held by the whole
        bound, the host loop is busy for this long from just before it arrives."""
        self.session = session
        self.stalls = sorted(stalls or [])
        self._longest_stall = max((stop - start for start, stop in self.stalls), default=0.0)
        self.earliest = earliest
        self.stall_on_late_reply = stall_on_late_reply
        self._rx_bound = -math.inf
        self.bound = bound
        self.latency = latency
        self.requests = requests or Direction()
        self.replies = replies or Direction()
        self.clock = ManualClock(0.0)
        self.model = SimulatorModel(pod, clock=self.clock, seed=seed, calibration_seconds=0.3,
                                    record_executions=True)  # fmt: skip
        self.executions = self.model.execution_log
        self._heap: list[tuple[float, int, str, Any]] = []
        self._seq = itertools.count()
        self._rng = random.Random(seed)
        self.sent: list[tuple[float, HostPacket, int | None]] = []
        """(time, packet, mode opcode its valid control values were for)."""
        self.tickets: list[Ticket] = []
        self.events: list[Any] = []
        self.violations: list[str] = []
        self.wakeup = math.inf
        self.polls = 0
        self._window_i = self._window_j = self._window_best = 0
        self._executed_key: Callable[[Command], object] | None = None
        self._executed_seen = 0
        self._executed_by: dict[object, list[ExecutionRecord]] = {}

    @property
    def now(self) -> float:
        return self.clock.now()

    # -- scheduling ------------------------------------------------------------------------
    def at(self, when: float, action: Callable[[], None]) -> None:
        heapq.heappush(self._heap, (when, next(self._seq), "call", action))

    def open(self) -> None:
        self.session.open(self.now)
        self._reschedule()

    def submit(self, command: Command, **kwargs: Any) -> Ticket | None:
        """Submit now; None (and nothing queued) if the session refuses (link down)."""
        try:
            ticket = self.session.submit(command, self.now, **kwargs)
        except ConnectionError:
            return None
        self.tickets.append(ticket)
        self._poll()
        return ticket

    def _stall_end(self, t: float) -> float:
        """``t``, or the end of the host stall(s) it falls into: the first instant from ``t``
        on that no stall covers. Only stalls that start within the longest stall's length
        before ``t`` can cover it (the list grows with the run: no scan from its start)."""
        stalls = self.stalls
        if not stalls or t < stalls[0][0]:
            return t
        longest = self._longest_stall
        while True:
            end = t
            for i in range(bisect.bisect_right(stalls, (t, math.inf)) - 1, -1, -1):
                start, stop = stalls[i]
                if start < t - longest - 1e-9:  # ends before t (the margin: rounding)
                    break
                end = max(end, stop)
            if end == t:
                return t
            t = end

    def run_until(self, end: float) -> None:
        heap = self._heap
        while True:
            wake = self._stall_end(self.wakeup)
            when = min(wake, heap[0][0] if heap else math.inf)
            if when > end:
                break
            self.clock.advance(max(0.0, when - self.now))
            if heap and heap[0][0] <= wake:
                t, seq, kind, payload = heapq.heappop(heap)
                if kind == "gcu":
                    self._gcu_receives(payload)
                    continue
                later = self._stall_end(t)
                if later > t:  # the host is busy: it sees this at the end of the stall
                    heapq.heappush(heap, (later, seq, kind, payload))
                elif kind == "host":
                    self._host_receives(payload[0], arrival=payload[2])
                else:
                    payload()
                    self._reschedule()
            else:
                # the driver's timer: replies it has not seen arrived after it was due
                self._rx_bound = self.wakeup
                self._poll()
        self.clock.advance(max(0.0, end - self.now))

    def _host_receives(self, data: bytes, arrival: float) -> None:
        now = self.now
        earliest = {"driver": self._rx_bound, "arrival": arrival, "none": None}[self.earliest]
        self.session.receive(data, now, datagram=True, arrived_after=earliest)
        self._drain()
        self._reschedule()

    def run_while(self, predicate: Callable[[], bool], limit: float) -> None:
        """Advance in 10 ms steps while ``predicate()`` holds, at most ``limit`` seconds."""
        end = self.now + limit
        while predicate() and self.now < end:
            self.run_until(min(end, self.now + 0.01))

    # -- internals -------------------------------------------------------------------------
    def _poll(self) -> None:
        now = self.now
        data = self.session.poll(now)
        self.polls += 1
        if data is not None:
            packet = decode_host_packet(data)
            mode = self.session.control_mode if packet.main.control_valid else None
            self.sent.append((now, packet, mode))
            self._transmit(self.requests, "gcu", data, packet, (now, mode, data, packet))
        self._drain()
        self._reschedule()
        after = self.session.next_wakeup(now)
        if data is None and after <= now:
            self.violations.append(f"busy wake-up at {now:.6f}")

    def _reschedule(self) -> None:
        self.wakeup = self.session.next_wakeup(self.now)

    def _drain(self) -> None:
        self.events.extend(self.session.events())

    def _transmit(self, direction: Direction, kind: str, data: bytes,
                  packet: HostPacket | None, meta: Any = None) -> None:  # fmt: skip
        fate = direction.next(self.bound)
        if direction.override is not None:
            opcode = command_code(packet.command) if packet is not None else data[69]
            fate = direction.override(packet, opcode, fate)
        if fate.drop or direction.dark(self.now):
            return
        payload = corrupt(data, self._rng) if fate.corrupt else data
        base = self.now + self.latency
        for delay in (fate.delay, fate.copy_delay):
            if delay is not None:
                arrival = base + delay
                if (kind == "host" and self.stall_on_late_reply and self.bound
                        and delay >= self.bound * 0.99):  # fmt: skip
                    stall = (arrival - 1e-6, arrival + self.stall_on_late_reply)
                    bisect.insort(self.stalls, stall)
                    self._longest_stall = max(self._longest_stall, stall[1] - stall[0])
                heapq.heappush(self._heap, (arrival, next(self._seq), kind,
                                            (payload, meta, arrival)))  # fmt: skip

    def _gcu_receives(self, item: tuple[bytes, tuple[float, int | None, bytes, HostPacket],
                                        float]) -> None:  # fmt: skip
        data, (t, mode, sent, sent_packet), _ = item
        meta = (t, mode)
        model = self.model
        deframer = Deframer.for_host_packets()
        for raw in model.split(data, deframer):
            # decoded once when sent: only a corrupted copy that still passes the CRC differs
            packet = sent_packet if raw == sent else decode_host_packet(raw)
            mode_before = model.state.mode
            reply = model.handle_bytes(raw)
            self._check_control(packet, mode_before, meta)
            if reply is not None:
                self._transmit(self.replies, "host", reply, None)

    def _check_control(self, packet: HostPacket, mode_before: Any,
                       meta: tuple[float, int | None]) -> None:  # fmt: skip
        if not packet.main.control_valid:
            return
        t, mode = meta
        if mode is None or REPORTED[mode] is not mode_before:
            self.violations.append(
                f"t={self.now:.4f}: control values valid for mode {mode} reached the GCU in "
                f"mode {mode_before.name} (sent at {t:.4f})"
            )

    # -- checks ----------------------------------------------------------------------------
    def max_in_window(self) -> int:
        """Most host packets sent within any window of WINDOW seconds. ``sent`` only grows:
        each call carries on from where the last one stopped (a contract run checks after
        every step; from the start each time it would be quadratic)."""
        sent, j, best = self.sent, self._window_j, self._window_best
        for i in range(self._window_i, len(sent)):
            t = sent[i][0]
            while sent[j][0] + WINDOW <= t:  # the pacer's own arithmetic
                j += 1
            best = max(best, i - j + 1)
        self._window_i, self._window_j, self._window_best = len(sent), j, best
        return best

    def _executed(self, key: Callable[[Command], object]) -> dict[object, list[ExecutionRecord]]:
        """The executions so far by ``key`` of their command, each new one checked to be its
        key's first (kept between calls with the same ``key``, as :meth:`max_in_window`)."""
        log = self.executions
        if key is not self._executed_key or len(log) < self._executed_seen:
            self._executed_key, self._executed_seen, self._executed_by = key, 0, {}
        by = self._executed_by
        for e in log[self._executed_seen :]:
            k = key(e.command)
            runs = by.setdefault(k, [])
            runs.append(e)
            assert len(runs) == 1, f"executed {len(runs)} times: {k} at {[r.time for r in runs]}"
        self._executed_seen = len(log)
        return by

    def check(self, identity: Callable[[Command], object] | None = None) -> None:
        """Assert the contract over everything that happened so far."""
        assert not self.violations, self.violations[:5]
        limit = math.floor(self.session.config.rate_hz) + 1
        assert self.max_in_window() <= limit, (self.max_in_window(), limit)
        key = identity or _itself
        executed = self._executed(key)
        for t in self.tickets:
            runs = executed.get(key(t.command), [])
            if t.state is TicketState.SUCCEEDED:
                assert len(runs) == 1 and runs[0].status == 0, f"false success: {t}"
            elif t.state is TicketState.FAILED:
                assert len(runs) == 1 and runs[0].status != 0, f"false failure: {t}"
            elif t.state in (TicketState.NOT_SENT, TicketState.SKIPPED):
                assert not runs and t.packets == 0, f"{t.state} but executed: {t}"
            if t.error is not None and t.state is TicketState.NOT_SENT:
                assert getattr(t.error, "outcome", None) is Outcome.NOT_SENT

    def check_counts(self) -> None:
        """The contract for commands that cannot be told apart by their parameters: per
        opcode, executions lie between the commands reported executed (succeeded or failed)
        and those plus the ones whose outcome is unknown."""
        assert not self.violations, self.violations[:5]
        assert self.max_in_window() <= math.floor(self.session.config.rate_hz) + 1
        executed = Counter(int(e.command.OPCODE) for e in self.executions)
        by_state: dict[int, Counter[TicketState]] = {}
        for t in self.tickets:
            by_state.setdefault(t.opcode, Counter())[t.state] += 1
        for opcode in set(executed) | set(by_state):
            states = by_state.get(opcode, Counter())
            known = states[TicketState.SUCCEEDED] + states[TicketState.FAILED]
            assert known <= executed[opcode] <= known + states[TicketState.UNKNOWN], (
                opcode, executed[opcode], dict(states))

    def pending(self) -> bool:
        return self.session.pending > 0 and self.session.state is SessionState.UP


def _itself(command: Command) -> object:
    return command


def tagged_commands(kind: str, start: int = 0) -> Iterator[Command]:
    """Commands whose parameters make each one unique (so executions can be told apart).

    ``same``: one opcode every time (each needs a null separation); ``mixed``: a rotation of
    opcodes, thermal ones included, with a failing one (fill light is not supported by the
    default pod) now and then."""
    from gcu_async.protocol import (
        AreaTemperature,
        FillLight,
        ImageBox,
        ImagePoint,
        SpotTemperature,
        TemperatureAlarm,
    )

    for i in itertools.count(start):
        x, y = divmod(i, 10000)
        point = ImagePoint((x % 10000) / 10000, y / 10000)
        if kind == "same":
            yield SpotTemperature(True, point)
            continue
        j = i % 4
        if j == 0:
            yield SpotTemperature(True, point)
        elif j == 1:
            yield TemperatureAlarm(True, high=(i % 30000) / 10, low=-1000.0)
        elif j == 2:
            box = ImageBox(0.0, 0.0, 1 - (x % 10000) / 10000, 1.0)
            yield AreaTemperature(True, ImageBox(box.left, y / 10000, box.right, 1.0))
        else:
            yield FillLight(i % 256) if i % 40 == 3 else SpotTemperature(False, point)


def opcode_of(command: Command) -> int:
    return command_code(command)


__all__ = ["PERFECT", "Direction", "Fate", "Opcode", "Rig", "tagged_commands"]
