"""Which commands the bridge runs, in what order, and which it answers without running
(pure; docs/mavlink-bridge.md, "The bridge contract").

- **Shares** (fair admission): each *station* — a peer the link can tell apart and that
  proved itself a ground station (:meth:`~gcu_async.bridge.links.MavlinkLink.own_share`) —
  has a :class:`Share` of its own: a command budget, room for waiting commands, a memory of
  its commands and a turn; every other peer of a link shares the link's pool, one share.
  What one share sends never spends another's.
- **Retransmission** (MAVLink's command protocol): a COMMAND_LONG is a retransmission of
  an earlier one from the same share and sender to the same component when the command id
  and all seven parameters are identical and its ``confirmation`` is above 0 and at least
  the earlier one's. Any differing parameter, or ``confirmation`` 0, makes a new command.
  COMMAND_INT has no ``confirmation``: an identical COMMAND_INT (frame included) within
  :data:`RECENT_SECONDS` of the first is its retransmission.
- **Kinds**: commands acting on one function of the GCU (the zoom, the pointing, tracking,
  recording, focus, the picture source) share a *slot*. A new command of a slot
  supersedes the commands of that slot still waiting in its share — except a *stop*:
  nothing supersedes a stop, it always gets its turn. Photos have no slot: every one waits
  its turn.
- **Bounds**: at most :data:`MAX_WAITING_PER_SHARE` commands wait per share; a command waits
  at most :data:`COMMAND_WAIT` seconds for its first packet to the GCU.
"""

from __future__ import annotations

import math
from collections import OrderedDict, deque
from collections.abc import Hashable, Iterator
from dataclasses import dataclass, field
from typing import Any

from gcu_async.bridge._mavlink import mavlink
from gcu_async.bridge.commands import CommandIn, GcuCall

COMMAND_WAIT = 2.0
"""Seconds a command may wait, from its arrival at the bridge, for its first packet to the
GCU; after that it is answered TEMPORARILY_REJECTED and never sent (ground stations retry
after 1–3 s: by then they have retried or given up)."""
MAX_WAITING_PER_SHARE = 8
"""Commands waiting from one share (more: TEMPORARILY_REJECTED at once). No bound is
common to all shares, so none can fill another's room; the shares themselves are bounded
(a link's stations and its pool: :meth:`~gcu_async.bridge.links.MavlinkLink.own_share`)."""
RECENT_SECONDS = 5.0
"""How long a finished command is remembered, so that a retransmission of it gets its
answer again instead of running again."""
MAX_REMEMBERED = 256
"""(source, component, command) keys remembered per share. Beyond it the oldest key whose
commands all ended without running is forgotten first; a key with a command that ran (or
may have) is kept for :data:`RECENT_SECONDS` after its answer. (The GCU runs at most one
command per host packet, so those keys stay few: at most 50/s × 5 s over all shares, plus
the waiting.)"""
PER_KEY = 4
"""Commands remembered per (source, component, command) key."""

ZOOM = mavlink.MAV_CMD_SET_CAMERA_ZOOM
SLOTS: dict[int, str] = {
    ZOOM: "zoom",
    mavlink.MAV_CMD_CAMERA_TRACK_POINT: "tracking",
    mavlink.MAV_CMD_CAMERA_TRACK_RECTANGLE: "tracking",
    mavlink.MAV_CMD_CAMERA_STOP_TRACKING: "tracking",
    mavlink.MAV_CMD_VIDEO_START_CAPTURE: "recording",
    mavlink.MAV_CMD_VIDEO_STOP_CAPTURE: "recording",
    mavlink.MAV_CMD_SET_CAMERA_FOCUS: "focus",
    mavlink.MAV_CMD_SET_CAMERA_SOURCE: "source",
    mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW: "pointing",
    mavlink.MAV_CMD_DO_SET_ROI_LOCATION: "pointing",
    mavlink.MAV_CMD_DO_SET_ROI_NONE: "pointing",
}
"""Command id → the slot of the GCU function it acts on (latest intent wins per slot)."""
POINTING = "pointing"
"""The slot gimbal control messages (SET_ATTITUDE, SET_PITCHYAW) share with the commands."""
STOPS = frozenset({mavlink.MAV_CMD_CAMERA_STOP_TRACKING, mavlink.MAV_CMD_VIDEO_STOP_CAPTURE,
                   mavlink.MAV_CMD_DO_SET_ROI_NONE})  # fmt: skip
"""Commands that stop something (plus continuous zoom 0: :func:`is_stop`)."""


def is_stop(cmd: CommandIn) -> bool:
    """Does ``cmd`` stop something (zoom stop, stop tracking, stop video, ROI none)?"""
    if cmd.command == ZOOM:
        return cmd.param(1) == mavlink.ZOOM_TYPE_CONTINUOUS and cmd.param(2) == 0.0
    return cmd.command in STOPS


def _same(a: float, b: float) -> bool:
    return a == b or (math.isnan(a) and math.isnan(b))


def same_parameters(a: CommandIn, b: CommandIn) -> bool:
    """Identical command id, frame and parameters (NaN equals NaN)."""
    return (a.command == b.command and a.frame == b.frame
            and all(_same(x, y) for x, y in zip(a.params, b.params, strict=True)))  # fmt: skip


@dataclass(eq=False)
class Entry:
    """One command (or coalesced control message) the bridge took: waiting, running or
    finished. ``cmd`` is None for a control message (no acknowledgement)."""

    cmd: CommandIn | None
    component: int
    share: Hashable
    """The :class:`Share` it came by (its turn, its bound, what it supersedes)."""
    arrival: float
    slot: str | None
    stop: bool = False
    reply: Any = None
    """Where its answers go (the bridge's (link, peer))."""
    call: GcuCall | None = None
    """A control message's call (commands are planned again when their turn comes)."""
    state: str = "waiting"
    """"waiting", "running" or "done"."""
    ran: bool = False
    """Handed to the client: it ran, or may have."""
    confirmation: int = 0
    """Highest ``confirmation`` seen for it (COMMAND_LONG)."""
    result: int | None = None
    param2: int = 0
    done_at: float | None = None
    timer: Any = None
    """The IN_PROGRESS timer handle (cancelled when answered)."""

    @property
    def deadline(self) -> float:
        return self.arrival + COMMAND_WAIT

    @property
    def source(self) -> tuple[int, int] | None:
        return None if self.cmd is None else self.cmd.source


def is_retransmission(new: CommandIn, old: Entry, now: float) -> bool:
    """MAVLink's rule (module docstring): ``new`` repeats ``old``."""
    assert old.cmd is not None
    if not same_parameters(new, old.cmd):
        return False
    if new.frame is None:  # COMMAND_LONG
        return new.confirmation > 0 and new.confirmation >= old.confirmation
    return old.done_at is None or now - old.done_at <= RECENT_SECONDS


@dataclass
class Memory:
    """The commands of each (source, component, command id), newest last; bounded by
    :data:`MAX_REMEMBERED` keys × :data:`PER_KEY` entries."""

    keys: OrderedDict[tuple[tuple[int, int], int, int], deque[Entry]] = field(
        default_factory=OrderedDict)

    def find(self, cmd: CommandIn, component: int, now: float) -> Entry | None:
        """The command ``cmd`` retransmits, if any."""
        entries = self.keys.get((cmd.source, component, cmd.command))
        if not entries:
            return None
        for entry in reversed(entries):
            if entry.done_at is not None and now - entry.done_at > RECENT_SECONDS:
                continue
            if is_retransmission(cmd, entry, now):
                return entry
        return None

    def add(self, entry: Entry, now: float) -> None:
        assert entry.cmd is not None
        key = (entry.cmd.source, entry.component, entry.cmd.command)
        entries = self.keys.get(key)
        if entries is None:
            entries = self.keys[key] = deque()
        else:
            self.keys.move_to_end(key)
        if len(entries) == PER_KEY:  # drop the oldest finished one (never an active one)
            for old in entries:
                if old.state == "done":
                    entries.remove(old)
                    break
        entries.append(entry)
        if len(self.keys) > MAX_REMEMBERED:
            self._evict(now)

    def _evict(self, now: float) -> None:
        """Forget the oldest key whose commands all ended without running, else the oldest
        whose commands were all answered more than :data:`RECENT_SECONDS` ago."""
        for key, entries in self.keys.items():
            if all(e.state == "done" and not e.ran for e in entries):
                del self.keys[key]
                return
        for key, entries in self.keys.items():
            if all(e.done_at is not None and now - e.done_at > RECENT_SECONDS
                   for e in entries):  # fmt: skip
                del self.keys[key]
                return

    def __len__(self) -> int:
        return sum(len(e) for e in self.keys.values())


@dataclass
class Queue:
    """The waiting commands: one FIFO per share, at most :data:`MAX_WAITING_PER_SHARE` in
    each. The next command is the oldest of the share served least recently (a share never
    served first; ties: the share waiting longest): every share with commands waiting gets
    a turn before any gets a second, and a station that sends now and then goes ahead of
    shares a flood keeps busy."""

    shares: dict[Hashable, deque[Entry]] = field(default_factory=dict)
    """Share → its waiting entries, in the order the shares began waiting."""
    served: dict[Hashable, int] = field(default_factory=dict)
    """Share → the turn it was last served in (at most :data:`REMEMBERED_TURNS` idle ones)."""
    turns: int = 0
    size: int = 0

    def __iter__(self) -> Iterator[Entry]:
        for entries in self.shares.values():
            yield from entries

    def refusal(self, entry: Entry) -> str | None:
        """Why ``entry`` cannot wait (its share's room is full), or None."""
        if len(self.shares.get(entry.share, ())) >= MAX_WAITING_PER_SHARE:
            return f"{MAX_WAITING_PER_SHARE} commands from this sender are waiting"
        return None

    def superseded_by(self, entry: Entry) -> list[Entry]:
        """The waiting entries of ``entry``'s share and slot it replaces (never a stop)."""
        if entry.slot is None:
            return []
        return [e for e in self.shares.get(entry.share, ()) if e.slot == entry.slot
                and e.component == entry.component and not e.stop]  # fmt: skip

    def expired(self, now: float) -> list[Entry]:
        """The waiting entries whose :data:`COMMAND_WAIT` is over at ``now``."""
        return [e for e in self if e.deadline <= now]

    def next_deadline(self) -> float:
        """The earliest deadline of a waiting entry (``math.inf``: none waits)."""
        return min((e.deadline for e in self), default=math.inf)

    def push(self, entry: Entry) -> None:
        self.shares.setdefault(entry.share, deque()).append(entry)
        self.size += 1

    def remove(self, entry: Entry) -> None:
        entries = self.shares[entry.share]
        entries.remove(entry)
        self.size -= 1
        if not entries:
            del self.shares[entry.share]

    def pop(self) -> Entry | None:
        """The next entry (the class docstring's order)."""
        if not self.shares:
            return None
        served = self.served
        share = min(self.shares, key=lambda s: served.get(s, -1))
        entries = self.shares[share]
        entry = entries.popleft()
        self.size -= 1
        if not entries:
            del self.shares[share]
        self.turns += 1
        served.pop(share, None)
        served[share] = self.turns  # (so the dict is in the order of service)
        if len(served) > len(self.shares) + REMEMBERED_TURNS:
            self._forget()
        return entry

    def _forget(self) -> None:
        """Forget the idle shares served longest ago: back, they go first, as they would
        have anyway (everyone else was served since)."""
        excess = len(self.served) - len(self.shares) - REMEMBERED_TURNS
        for share in [s for s in self.served if s not in self.shares][:excess]:
            del self.served[share]


REMEMBERED_TURNS = 256
"""Idle shares whose last turn the :class:`Queue` remembers."""


COMMANDS_PER_SECOND = 20.0
"""Commands one share may bring per second (sustained); beyond it (and a burst of
:data:`COMMAND_BURST`) a command is dropped unanswered, as a lossy link would lose it, so a
flood costs the bridge a bounded amount of work however many shares it holds; ground
stations retransmit. (The GCU runs about 20 commands a second, whoever sends them.)"""
COMMAND_BURST = 40.0
CONTROL_INTERVAL = 0.02
"""Gimbal control messages are taken at most once per this many seconds (50 Hz, the GCU's
own rate): the latest one received meanwhile wins, the others are counted, not used."""


MESSAGE_MODE_INTERVAL = 0.5
"""Control messages change the pod's mode at most once per this many seconds (a stream
alternating between yaw lock and follow is a stream of intents, not of mode commands)."""
IMMEDIATE_CALLS = frozenset({"set_angles", "set_rates", "release_control"})
"""Client calls that only change control values (no GCU command, nothing waits)."""


@dataclass
class Budget:
    """A token bucket: ``take(now)`` is True while the rate allows."""

    rate: float = COMMANDS_PER_SECOND
    burst: float = COMMAND_BURST
    tokens: float = COMMAND_BURST
    at: float | None = None

    def take(self, now: float) -> bool:
        if self.at is not None:
            self.tokens = min(self.burst, self.tokens + (now - self.at) * self.rate)
        self.at = now
        if self.tokens >= 1.0:
            self.tokens -= 1.0
            return True
        return False


@dataclass(eq=False)
class Share:
    """What one station (or a link's pool of other peers) is given: its command budget, a
    memory of its commands, and (as a key of the :class:`Queue`) its room and turn."""

    name: str
    """Who it is, for the log (the link and the peer's address, or the link's pool)."""
    budget: Budget = field(default_factory=Budget)
    memory: Memory = field(default_factory=Memory)
    shed: int = 0
    """Its commands dropped over its budget."""
    refused: int = 0
    """Its commands answered TEMPORARILY_REJECTED at once: its room was full."""
