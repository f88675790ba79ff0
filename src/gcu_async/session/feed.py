"""The aircraft feed: what the host packets claim about the aircraft, and for how long.

Host main frame bytes 11–29 and the sub frame carry the aircraft data the gimbal's attitude
solution depends on (docs/protocol-notes.md, "10. Aircraft acceleration excludes gravity"
and "11. Question and answer"). The packets go out at the heartbeat rate whether or not the
data is current, so a packet must claim only what is known *now* (docs/client.md, "Aircraft
data: what the packets claim"):

1. **INS valid** (byte 11, B0) only when attitude, acceleration and velocity have all been
   given and each was given within ``timeout`` seconds; otherwise bytes 12–29 are zeros and
   the bit is clear.
2. **The sub frame** (position, satellites, GNSS time, relative altitude) only while the
   position is given and was given within ``timeout``; otherwise none (all zeros).
3. **GNSS time advances**: the week + ms sent are the ones last given plus the session time
   elapsed since (whole milliseconds, never ahead). Giving the same week + ms again is the
   same reading and keeps its anchor; week = ms = 0 is "no time".
4. **Stale episodes**: a run of consecutive packets that withhold a claim because its data
   is older than ``timeout`` is one episode: counted, one warning when it starts. The next
   update makes the data current again.

No clock of its own: every call takes the session's ``now``.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Iterable, Mapping
from dataclasses import fields, replace
from typing import Any

from gcu_async._checks import type_error
from gcu_async.protocol.aircraft import AircraftState
from gcu_async.protocol.enums import SubFrameRequest
from gcu_async.protocol.gpstime import MS_PER_WEEK
from gcu_async.protocol.host_frame_tables import GNSS_WEEK_MAX, ControlValues
from gcu_async.protocol.host_frames import HostMainFrame, HostSubFrame

log = logging.getLogger("gcu_async.session")

INS_PARTS = ("attitude", "acceleration", "velocity")
"""The parts behind the INS-valid bit."""
PARTS = (*INS_PARTS, "position")
"""The parts whose age is tracked (satellites, relative altitude and GNSS time go with the
position in the sub frame)."""
AIRCRAFT_FIELDS = tuple(f.name for f in fields(AircraftState))
TIMEOUT_MAX = 10.0
"""Seconds; the longest ``aircraft_timeout`` accepted (beyond it a value is no measurement
of the aircraft any more)."""


class AircraftFeed:
    """The aircraft state given by the user, when each part was given, and the frames that
    say what is current (module docstring). ``timeout``: seconds a part stays current."""

    __slots__ = ("_frames", "_given", "_gnss", "_idle", "_name", "_sent_sub", "_stale", "_sub",
                 "episodes", "state", "timeout")  # fmt: skip

    def __init__(self, timeout: float, name: str = "gcu") -> None:
        self.timeout = timeout
        self._name = name
        self.state = AircraftState()
        self._idle = True
        """Nothing was ever given: no claim, nothing stale (the per-packet fast path)."""
        self._given: dict[str, float] = {}
        """Part → session time it was last given."""
        self._gnss: tuple[int, int, float] | None = None
        """(week, ms) as last given and the session time it was given; None: no time."""
        self._sub: HostSubFrame | None = None
        self._sent_sub: HostSubFrame | None = None
        self._frames: dict[tuple[ControlValues | None, bool], HostMainFrame] = {}
        self._stale: tuple[str, ...] = ()
        self.episodes = 0
        """Stale episodes so far (rule 4)."""

    # -- input -------------------------------------------------------------------------------
    def update(self, changes: Mapping[str, Any], now: float) -> AircraftState:
        """Change the named fields of the state (the others keep their value and the time
        they were given), as measured at ``now``; ``TypeError``/``ValueError`` (nothing
        changes) for an unknown field or a bad value. Returns the new state."""
        if not isinstance(changes, Mapping):
            raise type_error("changes", "a mapping of AircraftState fields", changes)
        unknown = sorted(str(k) for k in changes if k not in AIRCRAFT_FIELDS)
        if unknown:
            raise TypeError(f"changes: {', '.join(unknown)}: not AircraftState fields "
                            f"({', '.join(AIRCRAFT_FIELDS)})")  # fmt: skip
        state = replace(self.state, **changes)  # validates
        self.set(state, now, changes)
        return state

    def set(self, state: AircraftState, now: float, given: Iterable[str]) -> None:
        """``state`` is the aircraft state from now on; the parts named in ``given`` were
        measured at ``now`` (the others keep the time they were given)."""
        self.state = state
        self._idle = False
        for name in given:
            if name in PARTS:
                self._given[name] = now
        pair = (state.gnss_week, state.gnss_ms)
        gnss = self._gnss
        if pair == (0, 0):
            self._gnss = None
        elif gnss is None or (gnss[0], gnss[1]) != pair:
            self._gnss = (*pair, now)
        self._sub = self._sent_sub = state.sub_frame()
        self._frames.clear()

    # -- what the next packet claims ---------------------------------------------------------
    def _fresh(self, name: str, now: float) -> bool:
        given = self._given.get(name)
        return given is not None and now - given <= self.timeout

    def ins_valid(self, now: float) -> bool:
        """True if a packet built at ``now`` sets INS valid (rule 1)."""
        return self.state.ins_complete and all(self._fresh(p, now) for p in INS_PARTS)

    def position_valid(self, now: float) -> bool:
        """True if a packet built at ``now`` carries the sub frame (rule 2)."""
        return self.state.position is not None and self._fresh("position", now)

    def stale_parts(self, now: float) -> tuple[str, ...]:
        """The parts whose age withholds a claim at ``now``: the INS parts too old while all
        three are given, the position too old while given."""
        state = self.state
        stale: tuple[str, ...] = ()
        if state.ins_complete:
            stale = tuple(p for p in INS_PARTS if not self._fresh(p, now))
        if state.position is not None and not self._fresh("position", now):
            stale += ("position",)
        return stale

    def gnss_time(self, now: float) -> tuple[int, int]:
        """(week, ms) a sub frame built at ``now`` carries (rule 3): (0, 0) when no time was
        given, or once the time runs past week 32767 (the year 2608)."""
        gnss = self._gnss
        if gnss is None:
            return (0, 0)
        week, ms, given = gnss
        elapsed = now - given
        total = week * MS_PER_WEEK + ms + (math.floor(elapsed * 1000) if elapsed > 0 else 0)
        week, ms = divmod(total, MS_PER_WEEK)
        return (0, 0) if week > GNSS_WEEK_MAX else (week, ms)

    @property
    def stale(self) -> tuple[str, ...]:
        """The stale parts of the current episode (empty: none)."""
        return self._stale

    def check(self, now: float) -> bool:
        """Follow the stale episodes at a packet built at ``now`` (rule 4); True when one
        starts (then one warning is logged)."""
        if self._idle:
            return False
        stale = self.stale_parts(now)
        was = self._stale
        self._stale = stale
        if stale and not was:
            self.episodes += 1
            withheld = []
            if any(p in INS_PARTS for p in stale):
                withheld.append("INS-valid cleared")
            if "position" in stale:
                withheld.append("no sub frame (position, GNSS time)")
            log.warning("%s: aircraft data stale: %s not updated for %g s (aircraft_timeout): "
                        "%s until the next update", self._name, ", ".join(stale),
                        self.timeout, "; ".join(withheld))  # fmt: skip
            return True
        if was and not stale:
            log.info("%s: aircraft data current again", self._name)
        return False

    def frames(self, values: ControlValues | None,
               now: float) -> tuple[HostMainFrame, HostSubFrame | None]:  # fmt: skip
        """The main frame (with the control values ``values``, None = invalid) and sub frame
        of a packet built at ``now``."""
        ins = False if self._idle else self.ins_valid(now)
        key = (values, ins)
        frame = self._frames.get(key)
        if frame is None:
            if len(self._frames) > 8:
                self._frames.clear()
            frame = (self.state.main_frame(values, SubFrameRequest.STANDARD) if ins
                     else HostMainFrame.build(control=values))  # fmt: skip
            self._frames[key] = frame
        sub = self._sub
        if sub is None or not self.position_valid(now):
            return frame, None
        if self._gnss is not None:
            week, ms = self.gnss_time(now)
            sent = self._sent_sub
            if sent is None or sent.gnss_ms != ms or sent.gnss_week != week:
                self._sent_sub = sent = sub._replace(gnss_week=week, gnss_ms=ms)
            sub = sent
        return frame, sub
