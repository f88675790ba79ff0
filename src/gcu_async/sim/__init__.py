"""The GCU simulator: a sans-I/O model of a GCU with a pod, and servers for it.

- :class:`SimulatorModel` — bytes or :class:`~gcu_async.protocol.HostPacket` in, GCU
  replies out; time from an injectable clock (:class:`ManualClock` for tests).
- :class:`GcuSimulator` — the model behind UDP / TCP / pty / serial / in-memory endpoints,
  with seeded fault injection (:class:`FaultPlan`, :class:`FaultConfig`), ``silence()``
  and ``stall()`` (:class:`StallSwitch`).
- :class:`Firmware` — how the replies are filled: the document (``"v2.0.6"``) or a firmware
  of a real device (:data:`FIRMWARES`), independent of the pod model (:class:`PodProfile`).
- :class:`SimState` — the pod's state (``model.state``), readable and settable by tests:
  :class:`Gimbal`, :class:`CameraState` (``camera.photos`` counts the photos per camera),
  :class:`Rangefinder` and :class:`ReceivedAircraft` (what the host packets reported).

The servers (:class:`UdpServer`, :class:`TcpServer`, :class:`SerialServer`,
:class:`MemoryServer`) are given a :class:`ServerParts`, never the simulator: nothing in
this package imports :mod:`gcu_async.sim.simulator` back (docs/architecture.md).
"""

from gcu_async.sim.aircraft import ReceivedAircraft
from gcu_async.sim.camera import CameraState
from gcu_async.sim.clock import Clock, ManualClock, MonotonicClock
from gcu_async.sim.faults import FaultConfig, FaultDecision, FaultInjector, FaultPlan, FaultStats
from gcu_async.sim.firmware import DEFAULT_FIRMWARE, FIRMWARES, Firmware, firmware_for
from gcu_async.sim.listen import ListenSpec, parse_listen_url
from gcu_async.sim.memory import MemoryServer
from gcu_async.sim.model import DEFAULT_POD, ExecutionRecord, ModelStats, SimulatorModel
from gcu_async.sim.motion import Gimbal
from gcu_async.sim.parts import SimulatorStats
from gcu_async.sim.profiles import PodProfile, profile_for
from gcu_async.sim.rangefinder import Rangefinder
from gcu_async.sim.serialport import SerialServer
from gcu_async.sim.server import ServerParts, SimServer
from gcu_async.sim.simulator import GcuSimulator
from gcu_async.sim.stall import StallSwitch
from gcu_async.sim.state import SimState
from gcu_async.sim.tcp import TcpServer
from gcu_async.sim.udp import UdpServer

__all__ = [
    "DEFAULT_FIRMWARE", "DEFAULT_POD", "FIRMWARES", "CameraState", "Clock", "ExecutionRecord",
    "FaultConfig", "FaultDecision", "FaultInjector", "FaultPlan", "FaultStats", "Firmware",
    "GcuSimulator", "Gimbal", "ListenSpec", "ManualClock", "MemoryServer", "ModelStats",
    "MonotonicClock", "PodProfile", "Rangefinder", "ReceivedAircraft", "SerialServer",
    "ServerParts", "SimServer", "SimState", "SimulatorModel", "SimulatorStats", "StallSwitch",
    "TcpServer", "UdpServer", "firmware_for", "parse_listen_url", "profile_for",
]  # fmt: skip
