"""Smoke test of examples/autopilot: MAVLink source → autopilot → simulated GCU.

Both example programs run as subprocesses, exactly as a user starts them, over real
loopback UDP: the source streams a circling flight (examples/autopilot/flight.py) to the
autopilot, which feeds the simulator's heartbeat and points the camera. The checks compare
what reached the simulated GCU with the flight's geometry, not with fixed numbers.
"""

from __future__ import annotations

import asyncio
import contextlib
import copy
import importlib.util
import math
import socket
import sys
import time
from collections.abc import AsyncIterator, Callable
from datetime import datetime, timezone
from pathlib import Path
from types import ModuleType

import pytest

from gcu_async import Attitude, GeoPosition, Mode, Opcode
from gcu_async.protocol import HostPacket, HostSubFrame
from gcu_async.protocol.packets import GcuPacket
from gcu_async.sim import GcuSimulator, SimulatorModel

pytest.importorskip("pymavlink")

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "autopilot"


def _load_flight() -> ModuleType:
    spec = importlib.util.spec_from_file_location("autopilot_flight", EXAMPLE / "flight.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses resolve annotations through sys.modules
    spec.loader.exec_module(module)
    return module


FLIGHT = _load_flight().CirclingFlight()  # the source's default flight


class RecordingModel(SimulatorModel):
    """The simulator's model, keeping the last host packet (to read what the autopilot put
    on the wire: acceleration, velocity and GNSS time are not part of the model's state)."""

    last: HostPacket | None = None

    def handle(self, packet: HostPacket) -> GcuPacket:
        self.last = packet
        return super().handle(packet)


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@contextlib.asynccontextmanager
async def example(
    script: str, *args: str, output: list[str]
) -> AsyncIterator[asyncio.subprocess.Process]:
    """Run an example program; on exit stop it (SIGTERM) if still running and append its
    output to ``output``."""
    proc = await asyncio.create_subprocess_exec(
        sys.executable,
        str(EXAMPLE / script),
        *args,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.STDOUT,
    )
    try:
        yield proc
    finally:
        if proc.returncode is None:
            with contextlib.suppress(ProcessLookupError):
                proc.terminate()
        try:
            out, _ = await asyncio.wait_for(proc.communicate(), 10.0)
        except asyncio.TimeoutError:
            proc.kill()
            out, _ = await proc.communicate()
        output.append(f"--- {script} (exit {proc.returncode}) ---\n{out.decode(errors='replace')}")


async def wait_for(predicate: Callable[[], bool], timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        await asyncio.sleep(0.02)


def angle_diff(a: float, b: float) -> float:
    return abs((a - b + 180.0) % 360.0 - 180.0)


def pointing_error(position: GeoPosition | None, camera: Attitude) -> float:
    """Degrees between the camera's absolute pitch/yaw and the line of sight from the
    aircraft at ``position`` to the target (the circle's centre on the ground)."""
    if position is None:
        return math.inf
    north, east = FLIGHT.local(position.latitude, position.longitude)
    pitch = math.degrees(math.atan2(-FLIGHT.height, math.hypot(north, east)))
    yaw = math.degrees(math.atan2(-east, -north))
    return max(abs(camera.pitch - pitch), angle_diff(camera.yaw, yaw))


TARGET = (FLIGHT.centre_latitude, FLIGHT.centre_longitude, FLIGHT.home_altitude)


@pytest.mark.parametrize("accel_source", ["LOCAL_POSITION_NED", "SCALED_IMU"])
async def test_autopilot_feeds_the_flight_and_points_the_camera(accel_source: str) -> None:
    model = RecordingModel()
    sim = GcuSimulator(model)
    output: list[str] = []
    port = free_udp_port()
    try:
        async with (
            sim.serve_udp("127.0.0.1", 0) as server,
            example(
                "autopilot.py",
                "--mavlink", f"udpin:127.0.0.1:{port}",
                "--gcu", f"{server.url}?local_port=0",
                "--target", ",".join(map(str, TARGET)),
                "--accel-source", accel_source,
                "--duration", "20",  # a bound: the test stops it much earlier
                output=output,
            ) as autopilot,
            example(
                "mavlink_source.py", "--out", f"udpout:127.0.0.1:{port}", "--duration", "20",
                output=output,
            ),
        ):  # fmt: skip
            state = model.state

            def everything_arrived() -> bool:
                last = model.last
                return (
                    state.mode is Mode.GAZE
                    and state.aircraft.satellites > 0  # GPS_RAW_INT and SYSTEM_TIME: 1 Hz
                    and last is not None
                    and isinstance(last.sub, HostSubFrame)
                    and last.sub.gnss_week > 0
                    and last.main.acceleration != (0.0, 0.0, 0.0)
                )

            await wait_for(everything_arrived, timeout=5.0, what="every message type to arrive")
            # the camera slews (at most 180 °/s in the simulator) until it looks at the target
            await wait_for(
                lambda: pointing_error(state.aircraft.position, state.attitude) < 2.0,
                timeout=3.0,
                what="the camera to point at the target",
            )
            # one snapshot (no await in between): everything from the same moment
            aircraft = copy.copy(state.aircraft)  # the model keeps updating its own
            packet = model.last
            camera = state.attitude
            gaze_count = model.executions[Opcode.GAZE_AT_COORDINATES]
            autopilot.terminate()  # SIGTERM: a clean stop, like Ctrl-C
            assert await asyncio.wait_for(autopilot.wait(), 5.0) == 0
    except BaseException:
        print("\n".join(output))
        raise

    assert aircraft.ins_valid
    assert aircraft.satellites == 14
    # position: on the circle, at the flight's height (1e-7 ° ≈ 1 cm on the wire)
    assert aircraft.position is not None
    north, east = FLIGHT.local(aircraft.position.latitude, aircraft.position.longitude)
    assert math.hypot(north, east) == pytest.approx(FLIGHT.radius, abs=0.5)
    assert aircraft.position.altitude == pytest.approx(FLIGHT.home_altitude + FLIGHT.height)
    assert aircraft.relative_altitude == pytest.approx(FLIGHT.height)
    # attitude: banked for the turn, heading along the circle at that position (clockwise)
    bearing = math.degrees(math.atan2(east, north))
    assert aircraft.attitude.roll == pytest.approx(FLIGHT.bank, abs=0.02)
    assert aircraft.attitude.pitch == pytest.approx(FLIGHT.pitch, abs=0.02)
    assert angle_diff(aircraft.attitude.yaw, bearing + 90.0) < 2.0
    # velocity N/E/U: tangential at flight speed, no climb ("down" flipped)
    assert packet is not None
    vel, acc = packet.main.velocity, packet.main.acceleration
    assert math.hypot(vel.north, vel.east) == pytest.approx(FLIGHT.speed, abs=0.05)
    assert angle_diff(math.degrees(math.atan2(vel.east, vel.north)), bearing + 90.0) < 2.0
    assert vel.up == pytest.approx(0.0, abs=0.01)
    # acceleration: gravity-free — only the centripetal v²/r towards the centre, nothing
    # vertical (raw IMU output would be ~9.8 m/s² up)
    assert acc.up == pytest.approx(0.0, abs=0.05)
    assert math.hypot(acc.north, acc.east) == pytest.approx(FLIGHT.centripetal, abs=0.05)
    assert angle_diff(math.degrees(math.atan2(acc.east, acc.north)), bearing + 180.0) < 3.0
    # GNSS week + ms: GPS time (leap seconds applied), so it converts back to now in UTC
    assert isinstance(packet.sub, HostSubFrame)
    sent_time = packet.sub.gnss_time(apply_leap_seconds=True)
    assert abs((datetime.now(timezone.utc) - sent_time).total_seconds()) < 3.0
    # the camera: gaze at the target executed once, and it looks at it
    assert gaze_count == 1
    assert pointing_error(aircraft.position, camera) < 2.0
    log = output[-2] + output[-1]
    assert "camera gazing at" in log
    assert "camera pointed 1 time(s)" in log


async def test_autopilot_does_not_point_without_mavlink_data() -> None:
    """No attitude/position yet: the GCU would refuse to gaze (INS invalid), so the
    autopilot does not try, and says so in its exit status."""
    sim = GcuSimulator()
    output: list[str] = []
    async with (
        sim.serve_udp("127.0.0.1", 0) as server,
        example(
            "autopilot.py",
            "--mavlink", f"udpin:127.0.0.1:{free_udp_port()}",
            "--gcu", f"{server.url}?local_port=0",
            "--target", ",".join(map(str, TARGET)),
            "--duration", "1",
            output=output,
        ) as autopilot,
    ):  # fmt: skip
        status = await asyncio.wait_for(autopilot.wait(), 6.0)
    assert status == 1, output
    assert sim.model.stats.answered > 20  # the heartbeat ran
    assert not sim.model.state.aircraft.ins_valid
    assert sim.model.state.aircraft.position is None
    assert sim.model.executions[Opcode.GAZE_AT_COORDINATES] == 0
    assert sim.model.state.mode is Mode.POINTING_FOLLOW
