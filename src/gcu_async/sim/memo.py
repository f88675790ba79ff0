"""The reply memo: a repeated request answered from memory while the model is at rest.

A host with nothing to command sends one packet over and over (its heartbeat: the null
command and its aircraft data, 50 times a second); while nothing moves, each gets the reply
the one before got. :class:`~gcu_async.sim.SimulatorModel` keeps the last request it answered
in full, with its reply, when handling it again could change nothing but counters:

- **the request** carried the null command, or repeated the previous packet's opcode (the
  same-opcode rule: not executed, answered with the feedback given before), and not
  calibration (whose repeated status is recomputed from the clock);
- **the pod was at rest** after it (:func:`at_rest`): no calibration running, no zoom
  travelling, the gimbal settled (:meth:`~gcu_async.sim.motion.Gimbal.settled`: no
  click-to-pan, no control rate, no measured rate, every motor where its setpoint holds
  it, in gaze the aim where the setpoints are), the rangefinder steady (off, or on with
  nothing hit: no noise drawn).

The same bytes again are then answered from the memo, with every count the full path keeps:
the model's :class:`~gcu_async.sim.ModelStats`, the aircraft's packet counters, the host
conformance report (which gets the packet and its arrival time as before), the model's time.
Only while the state is what it was: the memo holds a copy of the attributes of every state
object (the :class:`~gcu_async.sim.SimState` and its parts, the gimbal's angle lists and
setpoints, each zoom drive, the executor, the firmware, the profile, the protocol version,
the last opcode and feedback), so whatever a test or an application sets between two packets
sends the next one through the full path. Overriding the model's ``handle``,
``handle_bytes`` or ``encode`` turns the memo off (an override sees every packet).

Time: a reply at rest holds nothing that depends on time (the GCU frames carry no clock).
The host's GNSS time and its sub frame request are bytes of the request: a host whose sub
frame time moves sends a new request every time, and is answered in full.
"""

from __future__ import annotations

from dataclasses import fields
from operator import attrgetter
from typing import Any

from gcu_async.protocol.anomalies import Anomaly
from gcu_async.protocol.packets import HostPacket
from gcu_async.sim.aircraft import ReceivedAircraft
from gcu_async.sim.executor import Executor
from gcu_async.sim.motion import Setpoint
from gcu_async.sim.state import SimState
from gcu_async.sim.zoom import ZoomDrive

COUNTERS = ("packets", "ins_valid_packets", "ins_changes")
"""The aircraft's attributes a repeated packet changes (``ReceivedAircraft.count``): the
only ones the memo does not compare."""
_AIRCRAFT = attrgetter(*(f.name for f in fields(ReceivedAircraft) if f.name not in COUNTERS))
_SETPOINT = attrgetter(*(f.name for f in fields(Setpoint)))
_ZOOM = attrgetter(*(f.name for f in fields(ZoomDrive)))


def at_rest(state: SimState) -> bool:
    """Nothing in ``state`` moves or runs with time: the next packet's physics step, command
    (none) and measurement change nothing."""
    cam = state.camera
    return (
        state.calibration_until is None
        and all(drive.target is None for drive in cam.zoom.values())
        and state.rangefinder.steady
        and state.gimbal.settled(cam.main_zoom)
    )


def _values(state: SimState, executor: Executor, model: tuple[object, ...]) -> list[Any]:
    """Every attribute the model's answer depends on: its state objects' attributes (their
    ``vars``: whatever is set on them), the items of the gimbal's lists and the zoom drives
    (changed in place), and ``model``, the model's own."""
    g, cam = state.gimbal, state.camera
    return [
        *model, *vars(executor).values(), *vars(state).values(), *vars(g).values(),
        *g.relative, *g.rates, *map(_SETPOINT, g.setpoints), *vars(cam).values(), *cam.zoom,
        *map(_ZOOM, cam.zoom.values()), *vars(state.rangefinder).values(),
        _AIRCRAFT(state.aircraft),
    ]  # fmt: skip


class ReplyMemo:
    """One request answered in full, its reply, and the state it was answered in."""

    __slots__ = (
        "_saved",
        "anomalous",
        "frame",
        "ins_valid",
        "other_version",
        "packet",
        "repeated",
        "reply",
        "request",
    )  # fmt: skip

    def __init__(self, request: bytes, packet: HostPacket, reply: bytes, *,
                 frame: tuple[Anomaly, ...], repeated: bool, anomalous: bool,
                 other_version: bool, state: SimState, executor: Executor,
                 model: tuple[object, ...]) -> None:  # fmt: skip
        self.request = request
        self.packet = packet
        """The request decoded."""
        self.reply = reply
        self.frame = frame
        """Its frame anomalies (counted again each time)."""
        self.repeated = repeated
        """Its opcode repeats the previous one (``stats.repeated``); else the null command."""
        self.anomalous = anomalous
        self.other_version = other_version
        self.ins_valid = packet.main.ins_valid
        self._saved = _values(state, executor, model)

    def holds(self, state: SimState, executor: Executor, model: tuple[object, ...]) -> bool:
        """The state is still the one the reply was made in (``model``: the model's own
        attributes the answer depends on, in the order given when the memo was made)."""
        return _values(state, executor, model) == self._saved
