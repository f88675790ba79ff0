"""The bridge in front of a GCU that sends its camera yaw signed, as the Z-1Pro does
(firmware 6.7): GIMBAL_DEVICE_ATTITUDE_STATUS carries the heading the client shows, not the
raw value read as U16 (docs/protocol-notes.md, "What real pods do")."""

from __future__ import annotations

import asyncio
import contextlib
import math
from typing import Any

import pytest

from gcu_async.bridge._mavlink import mavlink
from gcu_async.protocol.units import wrap_degrees_180
from gcu_async.sim import firmware_for
from helpers.bridge.rig import bridge_rig

EARTH = mavlink.GIMBAL_DEVICE_FLAGS_YAW_IN_EARTH_FRAME
AIRCRAFT_YAW = 30.0
CAMERA_YAW = -170.0
"""Relative to the aircraft: a heading of 220°, west of north (47536 … 65535 on the wire)."""


def quaternion_yaw(q: list[float]) -> float:
    """The yaw (degrees, ±180) of a MAVLink quaternion [w, x, y, z] (Z-Y-X Euler)."""
    w, x, y, z = q
    return math.degrees(math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))


async def test_attitude_status_yaw_is_the_heading_of_a_signed_yaw() -> None:
    async with bridge_rig("Z-1Pro") as rig:
        rig.sim.model.firmware = firmware_for("z1pro-6.7")
        feed = asyncio.create_task(rig.fly(yaw=AIRCRAFT_YAW, seconds=20.0))
        try:
            client = rig.bridge.client
            await rig.until(lambda: rig.state.aircraft.ins_valid, what="INS valid at the GCU")
            await client.enter_angle_control(yaw=CAMERA_YAW)
            heading = (AIRCRAFT_YAW + CAMERA_YAW) % 360.0
            await client.wait_attitude(yaw=heading, tolerance=0.5, timeout=5.0)
            status = client.status
            assert status.yaw_raw >= 47536  # signed on the wire
            assert [a.field for a in status.anomalies] == ["yaw_raw"]
            assert 0.0 <= status.attitude.yaw < 360.0

            def turned(m: Any) -> bool:
                return bool(m.flags & EARTH) and abs(
                    wrap_degrees_180(quaternion_yaw(m.q) - heading)) < 0.5

            att = await rig.gcs.wait("GIMBAL_DEVICE_ATTITUDE_STATUS", turned, timeout=5.0)
            shown = client.status.attitude.yaw
            assert abs(wrap_degrees_180(quaternion_yaw(att.q) - shown)) < 0.5
            assert math.degrees(att.delta_yaw) == pytest.approx(CAMERA_YAW, abs=0.5)
        finally:
            feed.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await feed
