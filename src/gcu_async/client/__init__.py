"""The asyncio client: session, command scheduler, telemetry and link health."""

from gcu_async.client.client import GcuClient
from gcu_async.client.health import LinkHealth
from gcu_async.client.scheduler import CommandScheduler, SchedulerStats, Ticket
from gcu_async.client.telemetry import TelemetrySample

__all__ = [
    "CommandScheduler", "GcuClient", "LinkHealth", "SchedulerStats", "TelemetrySample", "Ticket",
]  # fmt: skip
