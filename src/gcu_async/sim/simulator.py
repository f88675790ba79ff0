"""``GcuSimulator``: a :class:`SimulatorModel` behind UDP, TCP, serial/pty or in-memory
endpoints, with fault injection, a "silence" switch and a "stall" switch."""

from __future__ import annotations

import importlib
import math
import os
from typing import cast

from gcu_async.capture.writer import PacketCapture, as_capture
from gcu_async.protocol.enums import PodModel
from gcu_async.protocol.links import DEFAULT_BAUDRATE, GCU_TCP_PORT, GCU_UDP_PORT
from gcu_async.sim.clock import Clock
from gcu_async.sim.exchange import Exchange
from gcu_async.sim.faults import FaultConfig, FaultInjector, FaultPlan
from gcu_async.sim.firmware import DEFAULT_FIRMWARE, Firmware
from gcu_async.sim.listen import ListenSpec, parse_listen_url
from gcu_async.sim.memory import MemoryServer
from gcu_async.sim.model import DEFAULT_POD, SimulatorModel
from gcu_async.sim.parts import SimulatorStats
from gcu_async.sim.serialport import SerialServer
from gcu_async.sim.server import ServerParts, SimServer
from gcu_async.sim.stall import StallSwitch
from gcu_async.sim.tcp import TcpServer
from gcu_async.sim.udp import UdpServer
from gcu_async.transport.registry import kind_of

_NEVER = -math.inf
"""The end of a silence that never began."""


class GcuSimulator:
    """A simulated GCU you can reach over the network, a pty or in memory.

    ``faults`` is a :class:`FaultPlan` (requests and replies configured separately) or one
    :class:`FaultConfig` for both directions (see :meth:`FaultPlan.both`). Endpoints of one
    simulator share its model and fault injectors. ``capture`` (a pcapng file path or a
    :class:`~gcu_async.capture.PacketCapture`; needs the ``capture`` extra) records what
    every endpoint receives and sends, as it crosses the socket or terminal (after fault
    injection); the file is open while an endpoint runs. ``pod`` and ``firmware`` are the
    model's (:class:`SimulatorModel`): ``GcuSimulator(pod="Z-1Pro", firmware="z1pro-6.7")``.
    """

    def __init__(
        self,
        model: SimulatorModel | None = None,
        *,
        pod: PodModel | int | str = DEFAULT_POD,
        firmware: Firmware | str = DEFAULT_FIRMWARE,
        faults: FaultPlan | FaultConfig | None = None,
        clock: Clock | None = None,
        seed: int = 0,
        capture: PacketCapture | str | os.PathLike[str] | None = None,
    ) -> None:
        if model is not None and (clock is not None or seed != 0 or pod != DEFAULT_POD
                                  or firmware != DEFAULT_FIRMWARE):  # fmt: skip
            raise ValueError("GcuSimulator: give either model= or pod=/firmware=/clock=/seed=, "
                             "not both")  # fmt: skip
        self.model = model if model is not None else SimulatorModel(
            pod, clock=clock, seed=seed, firmware=firmware)
        self.faults = FaultPlan()
        self.request_faults = FaultInjector(self.faults.requests)
        self.reply_faults = FaultInjector(self.faults.replies)
        self.set_faults(faults)
        self.stats = SimulatorStats()
        self._silent_until = _NEVER
        self.stalls = StallSwitch(self.model.clock)
        """The stall switch every endpoint and exchange of this simulator joins."""
        self.capture = as_capture(capture)
        """Where the endpoints record the packets they exchange (``None``: nowhere)."""

    # -- switches -----------------------------------------------------------------------------
    def set_faults(self, faults: FaultPlan | FaultConfig | None) -> None:
        """Replace the fault injection from the next packet on (``None``: a perfect link).
        Each direction restarts from its configured seed."""
        if isinstance(faults, FaultConfig):
            faults = FaultPlan.both(faults)
        self.faults = faults if faults is not None else FaultPlan()
        self.request_faults = FaultInjector(self.faults.requests)
        self.reply_faults = FaultInjector(self.faults.replies)

    def silence(self, seconds: float) -> None:
        """Stop answering (and processing) for ``seconds`` of the model's clock; 0 ends a
        silence early."""
        if not 0 <= seconds < math.inf:
            raise ValueError(f"seconds: {seconds!r} is outside the allowed range [0, inf)")
        self._silent_until = self.model.clock.now() + seconds if seconds else _NEVER

    @property
    def silenced(self) -> bool:
        until = self._silent_until
        return until != _NEVER and self.model.clock.now() < until

    def stall(self, seconds: float) -> None:
        """Freeze for ``seconds`` of the model's clock: every endpoint stops reading, so the
        OS buffers what the host sends; then everything buffered is processed and answered,
        in order (a GCU whose firmware froze). Unlike :meth:`silence`, nothing is lost while
        it fits the OS buffers. 0 ends a stall early. Call it on the running event loop."""
        self.stalls.stall(seconds)

    @property
    def stalled(self) -> bool:
        return self.stalls.stalled

    # -- endpoints ----------------------------------------------------------------------------
    def _parts(self) -> ServerParts:
        """What a server gets of this simulator: new exchanges, the stalls, the capture."""
        return ServerParts(self._new_exchange, self.stalls, self.capture)

    def _new_exchange(self, stream: bool) -> Exchange:
        return Exchange(self, stream=stream)

    def serve_udp(
        self,
        host: str = "127.0.0.1",
        port: int = GCU_UDP_PORT,
        reply_to: tuple[str, int] | None = None,
        reply_port: int | None = None,
    ) -> UdpServer:
        """UDP endpoint (``async with``); port 0 picks a free port (see ``.address``).
        Replies go to the sender, to the sender's host at ``reply_port``, or to ``reply_to``."""
        return UdpServer(self._parts(), host, port, reply_to, reply_port)

    def serve_tcp(self, host: str = "127.0.0.1", port: int = GCU_TCP_PORT) -> TcpServer:
        """TCP server endpoint (``async with``); port 0 picks a free port."""
        return TcpServer(self._parts(), host, port)

    def serve_pty(self) -> SerialServer:
        """A pseudo-terminal; a client opens ``.device_path`` as its serial port (POSIX)."""
        return SerialServer(self._parts())

    def serve_serial(self, path: str, baudrate: int = DEFAULT_BAUDRATE) -> SerialServer:
        """Answer on an existing serial device (8N1 at ``baudrate``)."""
        return SerialServer(self._parts(), path, baudrate)

    def serve_memory(self) -> MemoryServer:
        """``async with sim.serve_memory() as server`` — ``server.transport`` is an
        in-memory :class:`~gcu_async.transport.memory.MemoryTransport` whose peer is this
        simulator."""
        return MemoryServer(self._parts())

    def serve(self, listen: str | ListenSpec) -> SimServer:
        """The endpoint a listen URL names: ``udp://HOST[:PORT]``, ``tcp://HOST[:PORT]``,
        ``pty`` or ``serial:///dev/ttyX[?baudrate=N]`` (each scheme's factory is its
        :class:`~gcu_async.transport.registry.TransportKind`'s ``listener``)."""
        spec = parse_listen_url(listen) if isinstance(listen, str) else listen
        kind = kind_of(spec.kind, listen=True)
        if kind.listener is None:
            raise ValueError(f"scheme: the simulator cannot listen on {kind.form}")
        module, _, name = kind.listener.partition(":")
        factory = getattr(importlib.import_module(module), name)
        return cast("SimServer", factory(self._parts(), spec))
