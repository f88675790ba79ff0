"""End-to-end rig for the MAVLink bridge tests: the simulator on UDP loopback, a client, the
bridge, and two pymavlink peers — a ground station and a fake autopilot — each listening on
an ephemeral loopback port the bridge sends to (``udpout``), so no port is guessed.

Every wait is bounded (``timeout``), and the peers poll their non-blocking sockets from the
event loop.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import socket
import time
from collections import Counter
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass
from typing import Any

from gcu_async.bridge import CameraConfig, MavlinkBridge
from gcu_async.bridge._mavlink import mavlink, mavutil
from gcu_async.client.connect import connect
from gcu_async.sim import DEFAULT_FIRMWARE, GcuSimulator, SimulatorModel

SYSTEM = 1
GIMBAL = mavlink.MAV_COMP_ID_GIMBAL
CAMERA = mavlink.MAV_COMP_ID_CAMERA
GCS = (255, mavlink.MAV_COMP_ID_MISSIONPLANNER)
AUTOPILOT = (SYSTEM, mavlink.MAV_COMP_ID_AUTOPILOT1)
NAN = math.nan
HOME_MSL = 50.0
"""Home altitude the fake autopilot reports (m MSL)."""


class Peer:
    """A pymavlink endpoint on 127.0.0.1 (port 0) that keeps every message it receives;
    with ``bridge_port``, a ground station sending to the bridge's ``udpin`` link on that
    port (pymavlink ``udpout``; its first HEARTBEAT, sent at once, binds its port)."""

    def __init__(self, system: int, component: int, *, bridge_port: int | None = None) -> None:
        if bridge_port is None:
            self.conn = mavutil.mavlink_connection("udpin:127.0.0.1:0", source_system=system,
                                                   source_component=component)  # fmt: skip
            # pymavlink's udpin sets SO_REUSEADDR, and Linux hands port 0 to two such
            # sockets alike (the later one then takes every unicast datagram): once bound,
            # the port is this peer's alone.
            self.conn.port.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 0)
        else:
            self.conn = mavutil.mavlink_connection(f"udpout:127.0.0.1:{bridge_port}",
                                                   source_system=system,
                                                   source_component=component)  # fmt: skip
            self.heartbeat()
        self.port: int = self.conn.port.getsockname()[1]
        self.messages: list[Any] = []
        self._seen = 0

    @property
    def url(self) -> str:
        """The connection string the bridge sends to."""
        return f"udpout:127.0.0.1:{self.port}"

    def poll(self) -> None:
        while (msg := self.conn.recv_match(blocking=False)) is not None:
            if msg.get_type() != "BAD_DATA":
                self.messages.append(msg)

    async def wait(self, kind: str, pred: Callable[[Any], bool] = lambda m: True, *,
                   timeout: float = 3.0, new: bool = True) -> Any:  # fmt: skip
        """The first message of type ``kind`` matching ``pred`` (received from now on when
        ``new``); raises TimeoutError after ``timeout`` seconds."""
        start = len(self.messages) if new else 0
        deadline = time.monotonic() + timeout
        index = start
        while True:
            self.poll()
            for msg in self.messages[index:]:
                if msg.get_type() == kind and pred(msg):
                    return msg
            index = len(self.messages)
            if time.monotonic() > deadline:
                seen = Counter(m.get_type() for m in self.messages[start:])
                raise TimeoutError(f"no {kind} matching within {timeout} s on port {self.port}; "
                                   f"received meanwhile: {dict(seen) or 'nothing'}")
            await asyncio.sleep(0.005)

    async def collect(self, seconds: float) -> list[Any]:
        """Everything received during the next ``seconds``."""
        start = len(self.messages)
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.poll()
            await asyncio.sleep(0.005)
        self.poll()
        return self.messages[start:]

    def send(self, msg: Any) -> None:
        self.conn.mav.send(msg)

    def heartbeat(self) -> None:
        self.conn.mav.heartbeat_send(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0,
                                     mavlink.MAV_STATE_ACTIVE)  # fmt: skip

    async def heartbeats(self, period: float = 1.0) -> None:
        """A HEARTBEAT every ``period`` seconds, as ground stations send (until cancelled)."""
        while True:
            self.heartbeat()
            await asyncio.sleep(period)

    async def command_retried(self, component: int, command: int, *params: float,
                              retransmissions: int = 5,
                              interval: float = 1.0) -> tuple[Any, int]:  # fmt: skip
        """Send a COMMAND_LONG as a ground station does: again with ``confirmation`` one
        higher every ``interval`` seconds while no answer came, at most ``retransmissions``
        times; the first final COMMAND_ACK addressed to this station's ids and how many
        times the command went out (TimeoutError ``interval`` after the last try)."""
        start = len(self.messages)
        me = (self.conn.mav.srcSystem, self.conn.mav.srcComponent)
        answered = False
        for confirmation in range(retransmissions + 1):
            if not answered:
                self.command(component, command, *params, confirmation=confirmation)
            end = time.monotonic() + interval
            while time.monotonic() < end:
                self.poll()
                acks = [m for m in self.messages[start:] if m.get_type() == "COMMAND_ACK"
                        and m.get_srcComponent() == component and m.command == command
                        and (m.target_system, m.target_component) == me]  # fmt: skip
                for m in acks:
                    if m.result != mavlink.MAV_RESULT_IN_PROGRESS:
                        return m, confirmation + 1
                answered = answered or bool(acks)  # IN_PROGRESS: stop repeating, wait
                await asyncio.sleep(0.005)
        raise TimeoutError(f"no final answer to command {command} within "
                           f"{(retransmissions + 1) * interval:g} s")

    def command(self, component: int, command: int, *params: float, system: int = SYSTEM,
                confirmation: int = 0) -> None:  # fmt: skip
        values = [*params, *([0.0] * (7 - len(params)))]
        self.conn.mav.command_long_send(system, component, command, confirmation, *values)

    async def ack(self, component: int, command: int, *, timeout: float = 4.0,
                  final: bool = True) -> Any:  # fmt: skip
        """The next COMMAND_ACK from ``component`` for ``command`` (skipping IN_PROGRESS when
        ``final``)."""
        def match(m: Any) -> bool:
            return bool(m.get_srcComponent() == component and m.command == command
                        and not (final and m.result == mavlink.MAV_RESULT_IN_PROGRESS))
        return await self.wait("COMMAND_ACK", match, timeout=timeout, new=False)

    async def run(self, component: int, command: int, *params: float,
                  timeout: float = 4.0) -> Any:  # fmt: skip
        """Send a COMMAND_LONG and return its final COMMAND_ACK."""
        self.messages.clear()
        self.command(component, command, *params)
        return await self.ack(component, command, timeout=timeout)

    def close(self) -> None:
        self.conn.close()


@dataclass
class Rig:
    sim: GcuSimulator
    bridge: MavlinkBridge
    gcs: Peer
    autopilot: Peer
    packet_times: list[float]
    """When the simulator handled each host packet (its clock: ``time.monotonic``)."""

    @property
    def state(self) -> Any:
        return self.sim.model.state

    async def until(self, predicate: Callable[[], bool], timeout: float = 4.0,
                    what: str = "condition") -> None:  # fmt: skip
        deadline = time.monotonic() + timeout
        while not predicate():
            if time.monotonic() > deadline:
                raise TimeoutError(f"{what}: not within {timeout} s")
            await asyncio.sleep(0.01)

    async def fly(self, *, lat: float = 22.5, lon: float = 113.9, relative_alt: float = 100.0,
                  yaw: float = 0.0, seconds: float = 0.0) -> None:  # fmt: skip
        """The fake autopilot sends one round of its stream (then keeps sending for
        ``seconds``)."""
        end = time.monotonic() + seconds
        boot = 1000
        while True:
            boot += 50
            mav = self.autopilot.conn.mav
            mav.heartbeat_send(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
                               0, 0, mavlink.MAV_STATE_ACTIVE)  # fmt: skip
            mav.attitude_send(boot, 0.0, 0.0, math.radians(yaw), 0.0, 0.0, 0.0)
            mav.local_position_ned_send(boot, 0.0, 0.0, -relative_alt, 0.0, 0.0, 0.0)
            mav.global_position_int_send(boot, round(lat * 1e7), round(lon * 1e7),
                                         round((HOME_MSL + relative_alt) * 1000),
                                         round(relative_alt * 1000), 0, 0, 0,
                                         round(yaw * 100) % 36000)  # fmt: skip
            mav.gps_raw_int_send(0, 3, round(lat * 1e7), round(lon * 1e7), 0, 0, 0, 0, 0, 12)
            mav.system_time_send(1_700_000_000_000_000 + boot * 1000, boot)
            if time.monotonic() >= end:
                return
            await asyncio.sleep(0.05)


FIRMWARE = DEFAULT_FIRMWARE
"""The firmware the rig's simulator plays (tests/bridge/conftest.py sets it per test)."""


@contextlib.asynccontextmanager
async def bridge_rig(pod: str = "D-90Pro(TA)", *, max_zoom: float | None = 30.0,
                     video_url: str | None = "rtsp://127.0.0.1:8554/main",
                     extra_links: tuple[str, ...] = (),
                     **bridge_options: Any) -> AsyncIterator[Rig]:  # fmt: skip
    """The whole chain running; the ground station has seen both heartbeats.
    ``extra_links``: more connection strings for the bridge (after the two peers')."""
    sim = GcuSimulator(SimulatorModel(pod, firmware=FIRMWARE, record_executions=True))
    packet_times: list[float] = []
    handle = sim.model.handle

    def timed_handle(packet: Any) -> Any:
        packet_times.append(time.monotonic())
        return handle(packet)

    sim.model.handle = timed_handle  # type: ignore[method-assign]
    gcs = Peer(*GCS)
    autopilot = Peer(*AUTOPILOT)
    try:
        async with sim.serve_udp("127.0.0.1", 0) as server:
            client = connect(server.url, local_port=0, check_support=True)
            bridge = MavlinkBridge(client, [gcs.url, autopilot.url, *extra_links],
                                   system_id=SYSTEM,
                                   camera=CameraConfig(video_url=video_url, max_zoom=max_zoom),
                                   **bridge_options)  # fmt: skip
            async with bridge:
                await gcs.wait("HEARTBEAT", lambda m: m.get_srcComponent() == GIMBAL
                               and m.system_status == mavlink.MAV_STATE_ACTIVE, timeout=5.0)
                await autopilot.wait("HEARTBEAT", timeout=5.0)
                yield Rig(sim, bridge, gcs, autopilot, packet_times)
    finally:
        gcs.close()
        autopilot.close()
