"""gcu_async — asyncio driver, simulator and sans-I/O codec for XF Robot gimbal GCUs
(GCU private protocol V2.0.6)."""

from gcu_async.client import GcuClient, LinkHealth, TelemetrySample
from gcu_async.client.connect import connect
from gcu_async.errors import (
    CommandError,
    CommandFailed,
    CommandLinkLost,
    CommandTimeout,
    FieldRangeError,
    GcuError,
    LinkLost,
    LocalProtocolError,
    Outcome,
    ProtocolErrorReason,
    RemoteProtocolError,
    UnsupportedCommandError,
    WaitTimeout,
)
from gcu_async.protocol import *  # noqa: F403
from gcu_async.protocol import __all__ as _protocol_all

__version__ = "0.1.0"
"""The package version: the only place it is written (pyproject.toml reads it from here)."""

__all__ = [
    "CommandError", "CommandFailed", "CommandLinkLost", "CommandTimeout", "FieldRangeError",
    "GcuClient", "GcuError", "LinkHealth", "LinkLost", "LocalProtocolError", "Outcome",
    "ProtocolErrorReason", "RemoteProtocolError", "TelemetrySample",
    "UnsupportedCommandError", "WaitTimeout", "__version__", "connect",
    *_protocol_all,
]  # fmt: skip
