"""gcu_async — asyncio driver, simulator and sans-I/O codec for XF Robot gimbal GCUs
(GCU private protocol V2.0.6).

The top level holds what an application needs: the client (:class:`GcuClient`,
:func:`connect`), what it reports (telemetry, link health and events), the exceptions, and
the value types the client takes and returns (docs/architecture.md, "The public surface").
Everything else is imported from its subpackage: the protocol core from
:mod:`gcu_async.protocol`, transports from :mod:`gcu_async.transport`, the simulator from
:mod:`gcu_async.sim`, and so on.
"""

from gcu_async.client import ClientState, GcuClient, LinkHealth, TelemetrySample
from gcu_async.client.connect import connect
from gcu_async.errors import (
    ClientStateError,
    CommandError,
    CommandFailed,
    CommandLinkLost,
    CommandTimeout,
    FieldRangeError,
    GcuError,
    LikelyCause,
    LinkLost,
    LocalProtocolError,
    Outcome,
    ProtocolErrorReason,
    RemoteProtocolError,
    UnsupportedCommandError,
    WaitTimeout,
)
from gcu_async.protocol.aircraft import AircraftState
from gcu_async.protocol.enums import CameraMask, Mode, Opcode, PodModel
from gcu_async.protocol.feedback import Feedback
from gcu_async.protocol.gcu_frames import GcuMainFrame, GcuSubFrame
from gcu_async.protocol.pods import pod_name
from gcu_async.protocol.units import Attitude, GeoPosition, NorthEastUp
from gcu_async.transport.base import LinkEvent, LinkEventKind

__version__ = "0.1.0"
"""The package version: the only place it is written (pyproject.toml reads it from here)."""

__all__ = [  # the client, its reports, the exceptions, the values it takes and returns
    "AircraftState",
    "Attitude",
    "CameraMask",
    "ClientState",
    "ClientStateError",
    "CommandError",
    "CommandFailed",
    "CommandLinkLost",
    "CommandTimeout",
    "Feedback",
    "FieldRangeError",
    "GcuClient",
    "GcuError",
    "GcuMainFrame",
    "GcuSubFrame",
    "GeoPosition",
    "LikelyCause",
    "LinkEvent",
    "LinkEventKind",
    "LinkHealth",
    "LinkLost",
    "LocalProtocolError",
    "Mode",
    "NorthEastUp",
    "Opcode",
    "Outcome",
    "PodModel",
    "ProtocolErrorReason",
    "RemoteProtocolError",
    "TelemetrySample",
    "UnsupportedCommandError",
    "WaitTimeout",
    "__version__",
    "connect",
    "pod_name",
]  # fmt: skip
