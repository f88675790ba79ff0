"""The client against the simulator playing each firmware over a real UDP socket: a
Z-1Pro (firmware 6.7) sends its camera yaw signed, and commands, telemetry and the waiting
helpers still see one heading in [0°, 360°) (docs/protocol-notes.md, "What real pods do")."""

from __future__ import annotations

import asyncio

import pytest

from gcu_async import CommandFailed, GcuClient, Mode
from gcu_async.client.waiting import angle_error
from gcu_async.protocol.headings import SIGNED_DETAIL
from gcu_async.pytest_plugin import SimHandle
from gcu_async.sim import FIRMWARES

WEST = 220.0
"""A heading west of north: 47536 … 65535 on a signed pod's wire."""


@pytest.fixture(params=sorted(FIRMWARES))
def gcu_sim_firmware(request: pytest.FixtureRequest) -> str:
    return str(request.param)


@pytest.fixture
def gcu_sim_pod() -> str:
    return "Z-1Pro"


async def test_status_shows_the_heading_and_keeps_the_wire_value(
    gcu_sim: SimHandle, gcu_client: GcuClient, gcu_sim_firmware: str
) -> None:
    sample = await gcu_client.reach_attitude(pitch=-10.0, yaw=WEST, timeout=15.0)
    status = sample.status
    assert angle_error(status.attitude.yaw, WEST) <= 0.5
    assert 0.0 <= gcu_client.status.attitude.yaw < 360.0
    signed = FIRMWARES[gcu_sim_firmware].signed_yaw
    assert (status.yaw_raw >= 47536) is signed
    assert [a.detail for a in status.anomalies] == ([SIGNED_DETAIL] if signed else [])
    assert str(status).count(f"yaw {status.attitude.yaw:g} deg") == 1
    assert status.as_dict()["attitude_deg"]["yaw"] == status.attitude.yaw


async def test_omitted_euler_angles_keep_a_west_heading(gcu_client: GcuClient) -> None:
    """enter_euler_control() keeps the current yaw: a heading, never the raw value / 100
    (65.xx or 5xx°, which the command refuses)."""
    await gcu_client.reach_attitude(yaw=WEST, timeout=15.0)
    await gcu_client.enter_euler_control(pitch=-30.0)
    there = await gcu_client.wait_attitude(pitch=-30.0, yaw=WEST, timeout=15.0)
    assert there.status.mode == Mode.EULER_CONTROL
    assert angle_error(there.status.attitude.yaw, WEST) <= 0.5


async def test_angle_control_and_centre(gcu_client: GcuClient, gcu_sim_firmware: str) -> None:
    """Angle control holds a relative yaw; centre, which that mode ignores, fails on the
    document's firmware and is answered success on the Z-1Pro's, the camera staying."""
    await gcu_client.enter_angle_control(yaw=-140.0)
    sample = await gcu_client.wait_attitude(yaw=WEST, timeout=15.0)
    assert sample.status.mode == Mode.ANGLE_CONTROL
    assert sample.status.relative_angles.z == pytest.approx(-140.0, abs=0.5)
    if FIRMWARES[gcu_sim_firmware].centre_ignored_ok:
        await gcu_client.centre()
    else:
        with pytest.raises(CommandFailed, match=r"CENTRE \(0x03\) failed: status 0x01"):
            await gcu_client.centre()
    await asyncio.sleep(0.3)
    assert angle_error(gcu_client.status.attitude.yaw, WEST) <= 0.5


async def test_the_client_collects_the_gcu_conformance_report(
    gcu_sim: SimHandle, gcu_sim_firmware: str
) -> None:
    """``conformance=True``: every reply and host packet goes into the report; the Z-1Pro's
    signed yaw is named, the document's firmware gives none, and commands are timed."""
    async with gcu_sim.client(conformance=True) as gcu:
        await gcu.reach_attitude(yaw=WEST, timeout=15.0)
        await gcu.take_photo()
        report = gcu.conformance_report()
    assert ("main.yaw_raw.signed" in report.keys) is FIRMWARES[gcu_sim_firmware].signed_yaw
    if not FIRMWARES[gcu_sim_firmware].signed_yaw:
        assert report.keys == ()
    assert report.replies > 20 and report.host_packets - report.replies in (0, 1, 2)  # in flight
    assert report.latency["count"] == 2  # the host's opcodes were given: both commands timed


async def test_without_the_option_there_is_no_report(gcu_client: GcuClient) -> None:
    with pytest.raises(ValueError, match="conformance=True"):
        gcu_client.conformance_report()
