"""The asyncio client: a thin driver of the sans-I/O :mod:`gcu_async.session`."""

from gcu_async.client.client import ClientState, GcuClient
from gcu_async.session import LinkHealth, TelemetrySample

__all__ = ["ClientState", "GcuClient", "LinkHealth", "TelemetrySample"]
