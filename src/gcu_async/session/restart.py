"""Telling a GCU that restarted from one that was only out of reach (docs/client.md, "GCU
restarts").

A GCU that loses power, reboots or has its firmware restarted comes back with its state
reset: its default mode, zoom 1×, recording and laser ranging off. The protocol has no
boot counter, so the session compares what the GCU reported last before a link loss
with what it reports first after it (the first reply with a sub frame), aspect by aspect:
the mode (main frame byte 5), laser ranging (pod status B8), camera 1's zoom (sub frame)
and recording (camera flags B4). A difference counts as a restart unless something the
host did, or a change already under way, explains it:

- a command that acts on the aspect (:data:`ACTS_ON`) ended after, or within
  :data:`REPORT_SETTLE` seconds before, the last reply before the loss: it succeeded but
  its effect may not have been reported yet, or its outcome is ``UNKNOWN`` (every command
  in flight at the loss ends so: it may have executed after the last report, or from
  packets still on their way). A command whose effect is known explains only that effect:
  a mode command the mode it enters, ranging on/off that state; a mode command to Euler
  control does not explain a GCU back in its default mode;
- the zoom was moving: a continuous zoom (zoom in / out) was not stopped, a ``zoom_to``
  ratio had not been reached, or the reported zoom changed within :data:`REPORT_SETTLE`
  seconds before the last reply (all a ``zoom_to_fraction`` target can be judged by: the
  host does not know the maximum it is a fraction of);
- the pod was tracking, or ran click-to-pan or tracking last: it leaves those modes by
  itself.

Nothing else explains a change: no command can be submitted while the link is down. A
restart that leaves every aspect as it was is not detected (and there is nothing to
restore). The pod changing one of these by itself during an outage (recording stopped
by a full card, say) is reported as a restart.
"""

from __future__ import annotations

from collections import deque
from typing import NamedTuple

from gcu_async.protocol.command_base import Command
from gcu_async.protocol.commands import Ranging, ZoomTo
from gcu_async.protocol.enums import CameraFlags, Mode, Opcode, PodStatus
from gcu_async.protocol.gcu_frame_tables import GCU_SUB_SCHEMA
from gcu_async.protocol.gcu_frames import GcuMainFrame, GcuSubFrame
from gcu_async.protocol.host_frame_tables import ControlValues
from gcu_async.session.control import KIND, MODE_CHANGING, REPORTED, ControlState
from gcu_async.session.tickets import TicketState

REPORT_SETTLE = 1.0
"""Seconds a GCU may take to show a command's effect in its reports (a mode at the next
reply, a zoom starting to move within a frame or two, a record toggle in its flags)."""

ACTS_ON: dict[str, frozenset[int]] = {
    "mode": frozenset(MODE_CHANGING),
    "zoom": frozenset({Opcode.ZOOM_IN, Opcode.ZOOM_OUT, Opcode.ZOOM_STOP, Opcode.ZOOM_TO}),
    "recording": frozenset({Opcode.RECORD}),
    "ranging": frozenset({Opcode.RANGING}),
}
"""Each compared aspect and the commands that change it."""

_CONTINUOUS = frozenset({Opcode.ZOOM_IN, Opcode.ZOOM_OUT})
_LEAVES_BY_ITSELF = frozenset({Opcode.CLICK_TO_PAN, Opcode.TRACK})
ZOOM_SCALE = GCU_SUB_SCHEMA.by_name["camera1_zoom_raw"].scale
"""Raw units of camera 1's zoom per 1× (the sub frame's field)."""
_ZOOM_STEP = 1
"""Raw zoom steps (0.1×) a report may differ by without counting as a change."""
_FINISHED = frozenset({TicketState.SUCCEEDED, TicketState.UNKNOWN})
"""Final states of a command that may have acted on the GCU."""
_ENDS_KEPT = 16
"""Commands remembered per aspect (more than can end within :data:`REPORT_SETTLE`)."""


class StateChange(NamedTuple):
    """One aspect the GCU reported differently after a loss than before it."""

    aspect: str
    """``"mode"``, ``"zoom"``, ``"recording"`` or ``"ranging"``."""
    before: str
    after: str

    def __str__(self) -> str:
        return f"{self.aspect} {self.before} -> {self.after}"


class Reported(NamedTuple):
    """The compared aspects of one reply."""

    mode_raw: int
    ranging: bool
    zoom_raw: int | None
    """Camera 1's zoom ratio × 10; None without a sub frame."""
    recording: bool | None

    @classmethod
    def of(cls, main: GcuMainFrame, sub: GcuSubFrame | None) -> Reported:
        ranging = bool(main.pod_status_raw & PodStatus.RANGING_ON)
        if sub is None:
            return cls(main.mode_raw, ranging, None, None)
        recording = bool(sub.camera_flags_raw & CameraFlags.RECORDING)
        return cls(main.mode_raw, ranging, sub.camera1_zoom_raw, recording)


def _mode(raw: int) -> str:
    return Mode(raw).name if Mode(raw) is not Mode.UNKNOWN else f"0x{raw:02X}"


def _on(flag: bool | None) -> str:
    return "on" if flag else "off"


def _zoom(raw: int | None) -> str:
    return "?" if raw is None else f"{raw / ZOOM_SCALE:g}x"


class RestartWatch:
    """The comparison above, fed by the session: each new sub frame (:meth:`zoom_seen`),
    every finished command, each loss; after a loss, :meth:`compare` the first reply (the
    session calls it while :attr:`pending`)."""

    def __init__(self) -> None:
        self._zoom_changed_at = -float("inf")
        self._ended: dict[str, deque[tuple[float, int | bool | None]]] = {
            aspect: deque(maxlen=_ENDS_KEPT) for aspect in ACTS_ON}
        """Aspect → (when, the value it leads to: None if not known) of the latest commands
        acting on it that ended (succeeded or unknown)."""
        self._zoom_command: Command | None = None
        """The last zoom command that succeeded or may have executed."""
        self._last_mode_command: int | None = None
        self._before: Reported | None = None
        self._excused: frozenset[str] = frozenset()
        self._explained: dict[str, frozenset[int | bool]] = {}
        """Aspect → the values recent commands lead to (a change to one is no restart)."""
        self.pending = False
        """A loss happened and the first report after it has not been compared yet."""
        self.compared: Reported | None = None
        """What was reported last before the loss the latest :meth:`compare` compared."""

    def reset(self) -> None:
        self.__init__()  # type: ignore[misc]

    def zoom_seen(self, previous: GcuSubFrame | None, sub: GcuSubFrame, now: float) -> None:
        """A reply brought a sub frame other than ``previous`` (the last one)."""
        if previous is not None and sub.camera1_zoom_raw != previous.camera1_zoom_raw:
            self._zoom_changed_at = now

    def to_restore(self, changes: tuple[StateChange, ...], control: ControlState
                   ) -> tuple[Command | None, ControlValues | None, float | None]:  # fmt: skip
        """What a driver needs to restore the host's state after a restart found by
        :meth:`compare`: the mode command the GCU confirmed last (if it was in that mode
        before the loss and the mode changed) with its control values, and camera 1's zoom
        (if it changed)."""
        before = self.compared
        assert before is not None
        aspects = {change.aspect for change in changes}
        mode = None
        if ("mode" in aspects and control.command is not None and control.confirmed in KIND
                and REPORTED[control.confirmed] == before.mode_raw):  # fmt: skip
            mode = control.command
        zoom = None
        if "zoom" in aspects and before.zoom_raw is not None:
            zoom = before.zoom_raw / ZOOM_SCALE
        return mode, control.values if mode else None, zoom

    def finished(self, opcode: int, command: Command, state: TicketState, now: float) -> None:
        """A command reached a final state."""
        if state not in _FINISHED:
            return
        for aspect, opcodes in ACTS_ON.items():
            if opcode in opcodes:
                self._ended[aspect].append((now, _leads_to(aspect, opcode, command)))
        if opcode in ACTS_ON["zoom"]:
            self._zoom_command = command
        if opcode in MODE_CHANGING:
            self._last_mode_command = opcode

    def lost(self, main: GcuMainFrame | None, sub: GcuSubFrame | None,
             last_reply: float | None) -> None:  # fmt: skip
        """The link went down; ``main``, ``sub``: what was reported last, at
        ``last_reply``. Remembers them, and what explains a change since."""
        if self.pending or main is None or last_reply is None:
            return  # still waiting for the first report after an earlier loss, or no report
        before = self._before = Reported.of(main, sub)
        self.pending = True
        since = last_reply - REPORT_SETTLE
        excused: set[str] = set()
        self._explained = {}
        for aspect, ends in self._ended.items():
            values = {value for t, value in ends if t >= since}
            if None in values:
                excused.add(aspect)
            elif values:
                self._explained[aspect] = frozenset(v for v in values if v is not None)
        if self._zoom_moving(before, since):
            excused.add("zoom")
        if before.mode_raw == Mode.TRACK or self._last_mode_command in _LEAVES_BY_ITSELF:
            excused.add("mode")
        self._excused = frozenset(excused)

    def _zoom_moving(self, before: Reported, since: float) -> bool:
        if self._zoom_changed_at >= since:
            return True
        command = self._zoom_command
        if command is None:
            return False
        if int(command.OPCODE) in _CONTINUOUS:
            return True
        if isinstance(command, ZoomTo):
            if command.ratio is None:  # a fraction of a maximum the host does not know:
                return False  # the reports, unchanged for REPORT_SETTLE, say it stopped
            target = round(command.ratio * ZOOM_SCALE)
            return before.zoom_raw is None or abs(before.zoom_raw - target) > _ZOOM_STEP
        return False

    def compare(self, main: GcuMainFrame, sub: GcuSubFrame | None) -> tuple[StateChange, ...]:
        """A reply after the loss: the changes that make it a restart (empty: none, or not
        the reply to compare: the first with a sub frame is, when there was one before)."""
        before = self._before
        if before is None or (before.zoom_raw is not None and sub is None):
            return ()
        self._before, self.pending = None, False
        self.compared = before
        return self._changes(before, Reported.of(main, sub))

    def _changes(self, before: Reported, after: Reported) -> tuple[StateChange, ...]:
        changes = []
        excused, explained = self._excused, self._explained
        if ("mode" not in excused and after.mode_raw != before.mode_raw
                and after.mode_raw not in explained.get("mode", ())):  # fmt: skip
            changes.append(StateChange("mode", _mode(before.mode_raw), _mode(after.mode_raw)))
        if ("zoom" not in excused and before.zoom_raw is not None
                and after.zoom_raw is not None
                and abs(after.zoom_raw - before.zoom_raw) > _ZOOM_STEP):  # fmt: skip
            changes.append(StateChange("zoom", _zoom(before.zoom_raw), _zoom(after.zoom_raw)))
        was, now = before.recording, after.recording
        if "recording" not in excused and was is not None and now is not None and now != was:
            changes.append(StateChange("recording", _on(was), _on(now)))
        if ("ranging" not in excused and after.ranging != before.ranging
                and after.ranging not in explained.get("ranging", ())):  # fmt: skip
            changes.append(StateChange("ranging", _on(before.ranging), _on(after.ranging)))
        return tuple(changes)


def _leads_to(aspect: str, opcode: int, command: Command) -> int | bool | None:
    """The value of ``aspect`` that ``command`` leads to, None if not known (a toggle, a
    zoom, a command that changes the mode to one the pod picks)."""
    if aspect == "mode" and opcode in REPORTED:
        return int(REPORTED[opcode])
    if aspect == "ranging" and isinstance(command, Ranging):
        return command.enabled
    return None
