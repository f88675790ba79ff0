"""The bridge works unchanged with a standard SDK: MAVSDK-Python's Gimbal and Camera plugins
(the ``mavsdk`` package ships MAVSDK's C library) drive the simulated gimbal and camera —
angles, rates, region of interest, photo, video, zoom. Skips, saying why, where the
library cannot be loaded or started (docs/testing.md, "Ground stations and SDKs")."""

from __future__ import annotations

import asyncio
import contextlib
import math
import time
from collections.abc import AsyncIterator, Callable
from typing import Any

import pytest

from gcu_async.bridge import CameraConfig, MavlinkBridge
from gcu_async.client.connect import connect
from gcu_async.protocol.enums import Mode, Opcode
from gcu_async.sim import GcuSimulator
from helpers.bridge.rig import AUTOPILOT, Peer, Rig

try:
    from mavsdk import ComponentType
    from mavsdk.asyncio import Configuration, Mavsdk
    from mavsdk.asyncio.plugins.camera import CameraAsync
    from mavsdk.asyncio.plugins.gimbal import GimbalAsync
    from mavsdk.plugins.gimbal import ControlMode, GimbalMode, SendMode
except Exception as exc:  # ImportError, or OSError when the C library cannot load
    pytest.skip(f"MAVSDK-Python is not usable here: {exc!r}", allow_module_level=True)

TIMEOUT = 10.0


async def until(predicate: Callable[[], Any], what: str, timeout: float = TIMEOUT) -> Any:
    deadline = time.monotonic() + timeout
    while not (value := predicate()):
        if time.monotonic() > deadline:
            raise TimeoutError(f"{what}: not within {timeout} s")
        await asyncio.sleep(0.02)
    return value


async def poll(call: Callable[[], Any], accept: Callable[[Any], bool], what: str) -> Any:
    deadline = time.monotonic() + TIMEOUT
    while True:
        value = await call()
        if accept(value):
            return value
        if time.monotonic() > deadline:
            raise TimeoutError(f"{what}: not within {TIMEOUT} s (last {value})")
        await asyncio.sleep(0.1)


@contextlib.asynccontextmanager
async def mavsdk_rig() -> AsyncIterator[tuple[Rig, Any]]:
    """Simulator, bridge (MAVSDK connects to its ``udpin`` link; a pymavlink autopilot on
    the other), MAVSDK's system for it."""
    sim = GcuSimulator()
    autopilot = Peer(*AUTOPILOT)
    unused = Peer(255, 191)  # the Rig's ground-station slot: MAVSDK is the ground station
    try:
        async with sim.serve_udp("127.0.0.1", 0) as server:
            client = connect(server.url, local_port=0, check_support=True)
            bridge = MavlinkBridge(client, ["udpin:127.0.0.1:0", autopilot.url],
                                   camera=CameraConfig(max_zoom=30.0))  # fmt: skip
            async with bridge:
                await autopilot.wait("HEARTBEAT", timeout=5.0)  # it knows where to send
                port = bridge.links[0].local_address[1]  # type: ignore[attr-defined]
                try:
                    config = Configuration.create_with_component_type(
                        ComponentType.GROUND_STATION)
                    mavsdk = Mavsdk(config)
                except Exception as exc:
                    pytest.skip(f"MAVSDK could not start: {exc!r}")
                try:
                    await mavsdk.add_any_connection(f"udpout://127.0.0.1:{port}")
                    systems = await poll(mavsdk.get_systems, bool, "MAVSDK sees the system")
                    rig = Rig(sim, bridge, unused, autopilot, [])
                    yield rig, systems[0]
                finally:
                    mavsdk.destroy()
    finally:
        autopilot.close()
        unused.close()


async def test_mavsdk_gimbal_plugin_drives_the_simulated_gimbal() -> None:
    async with mavsdk_rig() as (rig, system):
        state = rig.state
        gimbal = GimbalAsync(system)
        gimbals = await poll(gimbal.gimbal_list, lambda g: g.gimbals, "gimbal discovered")
        gid = gimbals.gimbals[0].gimbal_id
        await gimbal.take_control(gid, ControlMode.PRIMARY)
        await until(lambda: rig.bridge.view().control.primary != (0, 0), "MAVSDK in control")
        # angles, yaw locked to north
        await gimbal.set_angles(gid, 0.0, -30.0, 20.0, GimbalMode.YAW_LOCK, SendMode.ONCE)
        await until(lambda: state.mode is Mode.EULER_CONTROL
                    and abs(state.attitude.pitch + 30.0) < 0.5
                    and abs(state.attitude.yaw - 20.0) < 0.5, "euler -30/20")
        attitude = await poll(lambda: gimbal.get_attitude(gid),
                              lambda a: abs(a.euler_angle_forward.pitch_deg + 30.0) < 0.5,
                              "MAVSDK reads the attitude back")  # fmt: skip
        assert attitude.gimbal_id == gid
        # rates, following the aircraft's heading
        await gimbal.set_angular_rates(gid, 0.0, 0.0, 10.0, GimbalMode.YAW_FOLLOW,
                                       SendMode.ONCE)  # fmt: skip
        await until(lambda: state.mode is Mode.POINTING_FOLLOW, "pointing follow")
        yaw = state.relative.yaw
        await until(lambda: abs(state.relative.yaw - yaw) > 3.0, "yawing at 10 deg/s")
        # region of interest: needs the autopilot's INS data at the GCU
        feeding = asyncio.ensure_future(rig.fly(seconds=TIMEOUT))
        try:
            await until(lambda: rig.bridge.client.ins_valid, "INS valid")
            await gimbal.set_roi_location(gid, 22.501, 113.9, 0.0)
            await until(lambda: state.mode is Mode.GAZE, "gazing")
            await until(lambda: abs((state.attitude.yaw + 180) % 360 - 180) < 1.0
                        and state.attitude.pitch < -30.0, "looking north and down")
        finally:
            feeding.cancel()
        await gimbal.release_control(gid)


async def test_mavsdk_camera_plugin_takes_photos_records_and_zooms() -> None:
    async with mavsdk_rig() as (rig, system):
        state = rig.state
        camera = CameraAsync(system)
        cameras = await poll(camera.camera_list, lambda c: c.cameras, "camera discovered")
        cid = cameras.cameras[0].component_id
        assert cid == 100
        await camera.take_photo(cid)
        assert state.camera.photos == {1: 1}
        await camera.start_video(cid)
        assert state.camera.recording
        await camera.stop_video(cid)
        assert not state.camera.recording
        assert rig.sim.model.executions[Opcode.RECORD] == 2
        await camera.zoom_range(cid, 50.0)
        await until(lambda: abs(state.zoom[1] - 15.0) < 0.05, "zoom 15x")
        await camera.zoom_in_start(cid)
        await until(lambda: state.zoom[1] > 16.0, "zooming in")
        await camera.zoom_stop(cid)
        held = state.zoom[1]
        await asyncio.sleep(0.3)
        assert math.isclose(state.zoom[1], held, abs_tol=0.2)
