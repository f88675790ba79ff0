"""The asyncio client: a thin driver of the sans-I/O :mod:`gcu_async.session`."""

from gcu_async.client.client import KEEP, ClientState, GcuClient, Keep
from gcu_async.session import LinkHealth, TelemetrySample

__all__ = ["KEEP", "ClientState", "GcuClient", "Keep", "LinkHealth", "TelemetrySample"]
