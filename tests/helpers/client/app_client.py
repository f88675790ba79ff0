"""An application beside a monitor: a client process of its own that enters Euler control
(pitch −30°, yaw ``argv[2]``), takes a photo, keeps its session 1.5 s more and prints its
link counters as JSON (``sent``, ``received``, ``lost``) once closed, so that a test can
compare what it sent with what the simulator received."""

from __future__ import annotations

import sys

APP = """
import asyncio, json, sys
from gcu_async import connect

async def main() -> None:
    gcu = connect(sys.argv[1], connect_timeout=5)
    async with gcu:
        await gcu.enter_euler_control(roll=0, pitch=-30, yaw=float(sys.argv[2]))
        await gcu.take_photo()
        await asyncio.sleep(1.5)  # the session goes on: heartbeats, a monitor watches
    link = gcu.link
    print(json.dumps({"sent": link.packets_sent, "received": link.packets_received,
                      "lost": link.lost_count}))

asyncio.run(main())
"""


def app_argv(url: str, yaw: float = 45.0) -> list[str]:
    """The application's command line, connecting to ``url``."""
    return [sys.executable, "-c", APP, url, str(yaw)]
