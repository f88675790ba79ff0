"""What an :class:`~gcu_async.sim.exchange.Exchange` needs of the simulator it serves.

The simulator imports its servers and exchanges; they import only this module (and
:mod:`gcu_async.sim.server`), never the simulator: :class:`ExchangeHost` says what they use
of it, :class:`SimulatorStats` is what they count.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from gcu_async.sim.faults import FaultInjector
from gcu_async.sim.model import SimulatorModel
from gcu_async.sim.stall import StallSwitch


@dataclass
class SimulatorStats:
    """What the simulator's exchanges counted, over all its servers."""

    replies_sent: int = 0
    send_errors: int = 0
    ignored_while_silent: int = 0
    """Requests that arrived while the GCU was silenced (not processed, not answered)."""
    held_while_stalled: int = 0
    """Requests that reached the model's side during a stall without waiting in an OS
    buffer (held, then processed when the stall ended)."""


class ExchangeHost(Protocol):
    """The parts of a simulator an exchange uses (:class:`~gcu_async.sim.GcuSimulator` has
    them): its model, counters, stall switch, the fault injectors of each direction (looked
    up on every packet, so replacing them acts at once) and the silence switch."""

    model: SimulatorModel
    stats: SimulatorStats
    stalls: StallSwitch
    request_faults: FaultInjector
    reply_faults: FaultInjector

    @property
    def silenced(self) -> bool:
        """True while the simulated GCU neither processes nor answers."""
