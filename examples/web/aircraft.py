"""A stand-in aircraft feed for the simulator demo: a parked aircraft facing a heading.

A real host feeds the GCU what its INS measures (``gcu.update_aircraft`` from the autopilot,
see ``examples/autopilot``); the document calls these bytes very important, so the web
example sends none against a real GCU. With ``--sim --aircraft-heading DEG`` it plays an
aircraft standing still (level, velocity and acceleration zero) facing ``DEG``, so that
"Ahead" (angle control, yaw relative to the aircraft) visibly differs from north.
"""

from __future__ import annotations

import asyncio
import math

from gcu_async import GcuClient

FEED_PERIOD = 0.2
"""Seconds between updates: well inside any staleness limit of the aircraft feed."""


def check_heading(value: float) -> float:
    """A heading in [0, 360) degrees, or ``ValueError`` naming it."""
    if not math.isfinite(value) or not 0.0 <= value < 360.0:
        raise ValueError(f"aircraft heading: {value!r} is outside the allowed range [0, 360) deg")
    return value


async def feed_parked_aircraft(gcu: GcuClient, heading: float) -> None:
    """Send a parked aircraft facing ``heading`` every :data:`FEED_PERIOD` seconds until
    cancelled (works before the client is open: the state waits in the session)."""
    heading = check_heading(heading)
    while True:
        gcu.update_aircraft(attitude=(0.0, 0.0, heading), velocity=(0.0, 0.0, 0.0),
                            acceleration=(0.0, 0.0, 0.0))  # fmt: skip
        await asyncio.sleep(FEED_PERIOD)
